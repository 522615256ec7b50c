#!/usr/bin/env python3
"""lagc --sensitivity against CVODES forward sensitivities at equal error
(docs/BENCHMARKS.md §13).

Two models (scripts/bench_sensitivity/{oscillator,pendulum}.lag and the same
equations in scripts/bench_sensitivity/cvodes_sens.c), five sensitivity
columns each. Both sides run the ladder rtol = 1e-4 … 1e-12, atol =
1e-2·rtol, sensitivities in the error control on both sides. Error: the
largest |v − ref| / max(|ref|, 1) over the state and the 10 sensitivities
at the end time, against SciPy's DOP853 on the augmented system written
here by hand (an independent route) at rtol 1e-13. Time: the fastest of R
in-process solves after a warm-up (lagc `--repeat R`, which times the
state run and the augmented run both; a loop in the C driver, set-up
included). Cost at lagc's error: the peer's (error, time) points
interpolated in log-log; outside its range, its nearest point (marked).

usage: python3 scripts/bench_sensitivity.py [--sundials PREFIX]
  PREFIX holds include/ and lib/x86_64-linux-gnu/ of libsundials-dev
  (default /usr; `apt-get download libsundials-dev libsundials-cvodes6
  libsundials-nvecserial6 libsundials-sunlinsol3 libsundials-sunmatrix4`
  and `dpkg -x` them into a directory where the package cannot be
  installed).
"""
import argparse, json, math, os, subprocess, sys
import numpy as np
from scipy.integrate import solve_ivp

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HERE = os.path.join(ROOT, "scripts", "bench_sensitivity")
MODELS = {
    # name: (params, t1)
    "oscillator": ((1.0, 4.0, 0.4), 20.0),
    "pendulum": ((9.81, 1.0, 0.1), 10.0),
}


def reference(name):
    p, t1 = MODELS[name]

    def f(t, z):
        x, v = z[0], z[1]
        if name == "pendulum":
            g, l, c = p
            fx = [v, -(g / l) * math.sin(x) - c * v / l**2]
            J = [[0, 1], [-(g / l) * math.cos(x), -c / l**2]]
            dp = [-math.sin(x) / l, g * math.sin(x) / l**2 + 2 * c * v / l**3, -v / l**2]
        else:
            m, k, c = p
            fx = [v, -(k * x + c * v) / m]
            J = [[0, 1], [-k / m, -c / m]]
            dp = [(k * x + c * v) / m**2, -x / m, -v / m]
        out = list(fx)
        for col in range(5):
            s = z[2 + 2 * col: 4 + 2 * col]
            out.append(J[0][0] * s[0] + J[0][1] * s[1])
            out.append(J[1][0] * s[0] + J[1][1] * s[1] + (dp[col - 2] if col >= 2 else 0.0))
        return out

    z0 = [1.0, 0.0] + [1, 0, 0, 1] + [0] * 6
    sol = solve_ivp(f, (0, t1), z0, method="DOP853", rtol=1e-13, atol=1e-15)
    return sol.y[:, -1]


def error(values, ref):
    return max(abs(a - b) / max(abs(b), 1.0) for a, b in zip(values, ref))


def lagc(name, rtol, repeat):
    model = os.path.join(HERE, f"{name}.lag")
    args = [os.path.join(ROOT, "target/release/lagc"), "run", model, "--sensitivity",
            "--method", "direct", "--integrator", "explicit", "--rtol", f"{rtol:g}",
            "--atol", f"{rtol * 1e-2:g}", "--samples", "1", "--repeat", str(repeat),
            "--summary", "json"]
    out = subprocess.run(args, capture_output=True, text=True, check=True)
    row = [float(v) for v in out.stdout.strip().split("\n")[-1].split(",")[1:]]
    summary = json.loads(out.stderr.strip().split("\n")[-2 if "note:" in out.stderr.strip().split("\n")[-1] else -1])
    return summary["wall_time_s"], row


def cvodes(binary, name, kind, rtol, repeat):
    out = subprocess.run([binary, name, kind, f"{rtol:g}", f"{rtol * 1e-2:g}", str(repeat)],
                         capture_output=True, text=True, check=True)
    lines = out.stdout.split()
    return float(lines[0]), [float(v) for v in lines[2:]]


def at_error(points, e):
    """The time at error e on a peer's (error, time) points (log-log)."""
    pts = sorted(points)
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e0 <= e <= e1 and e1 > e0:
            w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), ""
    nearest = min(pts, key=lambda p: abs(math.log(p[0]) - math.log(e)))
    return nearest[1], "*"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sundials", default="/usr")
    a = ap.parse_args()
    lib = os.path.join(a.sundials, "lib/x86_64-linux-gnu")
    binary = os.path.join(ROOT, "target", "cvodes_sens")
    libs = [f"{lib}/libsundials_{n}.a" for n in
            ["cvodes", "nvecserial", "sunlinsoldense", "sunmatrixdense",
             "sunnonlinsolfixedpoint", "sunnonlinsolnewton"]]
    subprocess.run(["gcc", "-O2", "-o", binary, os.path.join(HERE, "cvodes_sens.c"),
                    "-I", os.path.join(a.sundials, "include")] + libs + ["-lm"], check=True)
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    print("| model | rtol | lagc error | lagc (µs) | Adams error | Adams (µs) | BDF error | BDF (µs) | lagc / Adams | lagc / BDF |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in MODELS:
        ref = reference(name)
        ladder = [10.0**-k for k in range(4, 13)]
        runs = {"lagc": [], "adams": [], "bdf": []}
        for rtol in ladder:
            t, v = lagc(name, rtol, 200)
            runs["lagc"].append((rtol, error(v, ref), t))
            for kind in ["adams", "bdf"]:
                t, v = cvodes(binary, name, kind, rtol, 30)
                runs[kind].append((rtol, error(v, ref), t))
        for i, (rtol, e, t) in enumerate(runs["lagc"]):
            cells = [name, f"{rtol:.0e}", f"{e:.1e}", f"{t * 1e6:.0f}"]
            ratios = []
            for kind in ["adams", "bdf"]:
                _, pe, pt = runs[kind][i]
                cells += [f"{pe:.1e}", f"{pt * 1e6:.0f}"]
                peer, mark = at_error([(x[1], x[2]) for x in runs[kind]], e)
                ratios.append(f"{t / peer:.2f}{mark}")
            print("| " + " | ".join(cells + ratios) + " |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
