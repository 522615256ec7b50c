#!/usr/bin/env python3
"""lagc against Python: (a) integration against SciPy's solve_ivp at equal
error, (b) derivation against SymPy's LagrangesMethod.

Outside `cargo test`. Creates its own virtual environment under
target/bench-venv (numpy, scipy, sympy from PyPI) on first use and re-runs
itself inside it.

(a) The reduced systems (7) of four examples, written here by hand from
    `lagc derive` (each function says which), go through solve_ivp with
    RK45, DOP853, Radau and LSODA at rtol = 1e-3 .. 1e-12, atol = rtol*1e-2
    (lagc report's ladder), on the same sample times as `lagc report` (11
    evenly spaced; the error is the largest over them of
    |x - exact| / max(|exact|, 1) over the components the model's `exact`
    lines give, the measure of the generated binary). The time is the
    smallest of several calls after a warm-up. lagc's figures come from
    `lagc report EXAMPLE --out target/bench` (run by this script; its times
    are measured inside the generated binary, SciPy's around solve_ivp).
    At equal error (log-log interpolation on each method's lower envelope)
    the ratio  best SciPy time / best lagc time  is reported for error
    levels 1e-3 .. 1e-10 where both sides reach them.

(b) The planar N-link pendulum (N = 3, 5, 8, 12) as benches/data/
    pendulum_N.lag: SymPy builds the Lagrangian and LagrangesMethod forms
    the equations (form_lagranges_equations: mass matrix and forcing, no
    inversion -- lagc does not invert either, it solves A z = b at run
    time). lagc: `cargo bench --bench derive` (parse + check + derive +
    reduce in process, smallest of 10 runs) and the wall time of the
    release binary `lagc derive` (process start, derivation, text, and the
    100-point cross-check). Same run, same machine.

Run time: about 2 minutes for (a), and for (b) SymPy takes ~40 s at
N = 12 alone (about 1 minute for all sizes); first use adds the venv and
the release builds. --quick: N = 3, 5, 8 and fewer repeats (~1 minute).

Usage: python3 scripts/bench_vs_python.py [--quick] [--json OUT]
"""

import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, "target", "bench-venv")
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import gen_pendulum  # noqa: E402
VENV_PYTHON = os.path.join(VENV, "bin", "python")


def ensure_venv():
    """Re-executes inside target/bench-venv, creating it when missing."""
    if os.path.realpath(sys.prefix) == os.path.realpath(VENV):
        return
    if not os.path.exists(VENV_PYTHON):
        subprocess.run([sys.executable, "-m", "venv", VENV], check=True)
        subprocess.run(
            [VENV_PYTHON, "-m", "pip", "install", "-q", "numpy", "scipy", "sympy"],
            check=True,
        )
    os.execv(VENV_PYTHON, [VENV_PYTHON] + sys.argv)


# ---------------------------------------------------------------- (a) ODEs
# Each: (example, right side f(t, y), y0, (t0, t1), exact(t) -> list with
# None where the model gives no exact line). Written from `lagc derive`.


def paper():
    """paper.lag: y = (q1, q2, q1', q2'); (16) q1'' = (a - t/(1+t^2)) q1',
    q2'' = (a t + 1/(1+t^2)) q1'; exact q1', q2' only."""
    a = 0.5

    def f(t, y):
        s = 1.0 + t * t
        return [y[2], y[3], (a - t / s) * y[2], (a * t + 1.0 / s) * y[2]]

    def exact(t):
        v = math.exp(a * t) / math.sqrt(1.0 + t * t)
        return [None, None, v, t * v]

    return "paper", f, [0.0, 0.0, 1.0, 0.0], (0.0, 5.0), exact


def damped_oscillator():
    """damped_oscillator.lag: x'' = (-k x - c x')/m."""
    m, k, c, x0, v0 = 1.0, 4.0, 0.4, 1.0, 0.0
    gam = c / (2 * m)
    w0 = math.sqrt(k / m)
    wd = math.sqrt(w0 * w0 - gam * gam)

    def f(t, y):
        return [y[1], (-k * y[0] - c * y[1]) / m]

    def exact(t):
        e = math.exp(-gam * t)
        return [
            e * (x0 * math.cos(wd * t) + (v0 + gam * x0) / wd * math.sin(wd * t)),
            e * (v0 * math.cos(wd * t) - (gam * v0 + w0 * w0 * x0) / wd * math.sin(wd * t)),
        ]

    return "damped_oscillator", f, [x0, v0], (0.0, 20.0), exact


def vertical_rocket():
    """vertical_rocket.lag: z'' = -g + mu w/(M0 - mu t)."""
    M0, mu, w, g = 1000.0, 10.0, 2000.0, 9.81

    def f(t, y):
        return [y[1], -g + mu * w / (M0 - mu * t)]

    def exact(t):
        M = M0 - mu * t
        return [
            -g * t * t / 2 + w * (t + M / mu * math.log(M / M0)),
            w * math.log(M0 / M) - g * t,
        ]

    return "vertical_rocket", f, [0.0, 0.0], (0.0, 80.0), exact


def knife_edge():
    """knife_edge.lag: y = (x, y, th, x', y', th');
    x'' = -tan(th) x' th' / (cos(th)^2 (1 + tan(th)^2)),
    y'' = x' th' / (cos(th)^2 (1 + tan(th)^2)), th'' = 0."""
    omega, v0 = 0.5, 1.0

    def f(t, y):
        th = y[2]
        tn = math.tan(th)
        d = math.cos(th) ** 2 * (1.0 + tn * tn)
        return [y[3], y[4], y[5], -tn * y[3] * y[5] / d, y[3] * y[5] / d, 0.0]

    def exact(t):
        th = omega * t
        return [
            v0 * math.sin(th) / omega,
            -v0 * (math.cos(th) - 1.0) / omega,
            th,
            v0 * math.cos(th),
            v0 * math.sin(th),
            omega,
        ]

    return "knife_edge", f, [0.0, 0.0, 0.0, v0, 0.0, omega], (0.0, 2.0), exact


MODELS = [paper, damped_oscillator, vertical_rocket, knife_edge]
SCIPY_METHODS = ["RK45", "DOP853", "Radau", "LSODA"]
TOLERANCES = [10.0 ** -k for k in range(3, 13)]
SAMPLES = 11


def largest_error(ts, ys, exact):
    largest = 0.0
    for i, t in enumerate(ts):
        for value, truth in zip(ys[:, i], exact(t)):
            if truth is not None:
                largest = max(largest, abs(value - truth) / max(abs(truth), 1.0))
    return largest


def scipy_curve(model, method, repeats):
    import numpy as np
    from scipy.integrate import solve_ivp

    _, f, y0, (t0, t1), exact = model
    times = np.linspace(t0, t1, SAMPLES)
    points = []
    for rtol in TOLERANCES:
        best = math.inf
        solution = None
        for _ in range(repeats + 1):  # the first is the warm-up
            start = time.perf_counter()
            solution = solve_ivp(
                f, (t0, t1), y0, method=method, t_eval=times, rtol=rtol, atol=rtol * 1e-2
            )
            best = min(best, time.perf_counter() - start) if _ > 0 else best
        if solution is None or not solution.success:
            continue
        points.append((best, largest_error(solution.t, solution.y, exact)))
    return points


def lagc_curves(name, runs):
    """lagc report's measurements of one example: {method: [(time, error)]}."""
    out = os.path.join(ROOT, "target", "bench")
    subprocess.run(
        [
            os.path.join(ROOT, "target", "release", "lagc"),
            "report",
            os.path.join(ROOT, "examples", f"{name}.lag"),
            "--out",
            out,
            "--runs",
            str(runs),
            "--samples",
            str(SAMPLES),
        ],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    curves = {}
    with open(os.path.join(out, f"{name}.work-precision.csv")) as data:
        header = data.readline().strip().split(",")
        for line in data:
            row = dict(zip(header, line.strip().split(",")))
            if row["status"] == "ok" and row["error"]:
                curves.setdefault(row["method"], []).append(
                    (float(row["time_s"]), float(row["error"]))
                )
    return curves


def envelope(points):
    """The lower envelope: sorted by decreasing error, each point kept only
    when it is faster than every more accurate point after it (so time
    grows as the error shrinks)."""
    pts = sorted((p for p in points if p[1] > 0), key=lambda p: -p[1])
    kept = []
    for t, e in reversed(pts):  # from the most accurate
        if not kept or t < kept[-1][0]:
            kept.append((t, e))
    return list(reversed(kept))


def time_at(points, error):
    """log-log interpolated time to reach `error`, None outside the curve."""
    pts = envelope(points)
    for (t_a, e_a), (t_b, e_b) in zip(pts, pts[1:]):
        if e_b <= error <= e_a:
            if e_a == e_b:
                return min(t_a, t_b)
            w = (math.log(error) - math.log(e_a)) / (math.log(e_b) - math.log(e_a))
            return math.exp(math.log(t_a) + w * (math.log(t_b) - math.log(t_a)))
    if len(pts) == 1 and pts[0][1] <= error:
        return pts[0][0]
    # More accurate than asked at its cheapest point: that point's time.
    if pts and pts[0][1] <= error:
        return pts[0][0]
    return None


def best_time(curves, error):
    times = [(time_at(p, error), m) for m, p in curves.items()]
    times = [(t, m) for t, m in times if t is not None]
    return min(times) if times else None


def part_a(quick):
    repeats = 2 if quick else 5
    results = []
    for make in MODELS:
        model = make()
        name = model[0]
        ours = lagc_curves(name, 3 if quick else 5)
        theirs = {m: scipy_curve(model, m, repeats) for m in SCIPY_METHODS}
        rows = []
        for k in range(3, 11):
            error = 10.0 ** -k
            a = best_time(ours, error)
            b = best_time(theirs, error)
            if a and b:
                rows.append((error, b[0] / a[0], a[1], a[0], b[1], b[0]))
        results.append({"model": name, "lagc": ours, "scipy": theirs, "equal_error": rows})
        print(f"\n{name}: at equal error, best SciPy time / best lagc time")
        print(f"  {'error':>7}  {'ratio':>8}  {'lagc best':<16} {'time':>9}  {'SciPy best':<10} {'time':>9}")
        for error, ratio, m_a, t_a, m_b, t_b in rows:
            print(
                f"  {error:7.0e}  {ratio:8.1f}  {m_a:<16} {t_a * 1e3:7.3f}ms  {m_b:<10} {t_b * 1e3:7.2f}ms"
            )
        if not rows:
            print("  (no common error level)")
    return results


# ------------------------------------------------------- (b) derivation


def sympy_pendulum(n):
    """The same pendulum as scripts/gen_pendulum.py, by SymPy's mechanics."""
    from sympy.physics.mechanics import LagrangesMethod

    start = time.perf_counter()
    lagrangian, th, _, _ = gen_pendulum.sympy_lagrangian(n)
    method = LagrangesMethod(lagrangian, th)
    method.form_lagranges_equations()
    return time.perf_counter() - start


def lagc_bench():
    """`cargo bench --bench derive`: {N: ms}."""
    out = subprocess.run(
        ["cargo", "bench", "--quiet", "--bench", "derive"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    figures = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[0].isdigit() and parts[2] == "ms":
            figures[int(parts[0])] = float(parts[1])
    return figures


def lagc_binary(n, repeats):
    path = os.path.join(ROOT, "benches", "data", f"pendulum_{n}.lag")
    binary = os.path.join(ROOT, "target", "release", "lagc")
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([binary, "derive", path], check=True, capture_output=True)
        best = min(best, time.perf_counter() - start)
    return best


def part_b(quick):
    sizes = [3, 5, 8] if quick else [3, 5, 8, 12]
    bench = lagc_bench()
    rows = []
    print("\nN-link pendulum: derivation")
    print(f"  {'N':>3} {'SymPy':>10} {'lagc (bench)':>13} {'ratio':>8} {'lagc derive (process)':>22} {'ratio':>8}")
    for n in sizes:
        sympy_s = sympy_pendulum(n)
        lagc_ms = bench.get(n)
        process_s = lagc_binary(n, 3 if quick else 5)
        ratio_bench = sympy_s / (lagc_ms * 1e-3) if lagc_ms else float("nan")
        ratio_process = sympy_s / process_s
        rows.append(
            {"n": n, "sympy_s": sympy_s, "lagc_bench_ms": lagc_ms, "lagc_process_s": process_s}
        )
        print(
            f"  {n:>3} {sympy_s:9.2f}s {lagc_ms or float('nan'):11.2f}ms {ratio_bench:8.0f}"
            f" {process_s * 1e3:20.1f}ms {ratio_process:8.0f}"
        )
    return rows


def main():
    ensure_venv()
    quick = "--quick" in sys.argv
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    results = {"integration": part_a(quick), "derivation": part_b(quick)}
    if "--json" in sys.argv:
        path = sys.argv[sys.argv.index("--json") + 1]
        with open(path, "w") as out:
            json.dump(results, out, indent=1)


if __name__ == "__main__":
    main()
