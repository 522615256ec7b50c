#!/usr/bin/env python3
"""Field method against direct DOP853 on non-affine models, side by side in
one run (issue 10): `lagc report` at rtol 1e-3 ... 1e-11 for every model,
then, per model, the cost of the field at equal error (direct DOP853's time
interpolated at the field's error, log-log), the same at the errors 1e-6
and 1e-9 (both sides interpolated on their lower envelope, against the
bound 2(N+1), N the state dimension), and the field's measured order (the
slope of -log(error) against log(right-side evaluations) over the rungs
with errors in 1e-11 ... 1e-4).

Usage (from the repository root):

    cargo build --release
    python3 scripts/gen_pendulum.py 2 3 5 8
    python3 scripts/field_vs_direct.py [MODEL.lag ...] > target/field-vs-direct.md

REUSE=1 re-reads the last reports' CSV instead of running them again.
LAGC=<path> runs another lagc binary (an older runtime, side by side) and
OUT=<dir> keeps its reports apart; RUNS=<k> times each run as the smallest
of k solves (default 3; more on a loaded machine). NO_GLOBAL_ERROR=1 times
both methods without their global-error estimates (`lagc report
--no-global-error`): the integrators alone. TOLERANCES=<list> replaces the
ladder (e.g. `...,1e-11,3e-12,1e-12` where a model's rungs stop short of
an error of 1e-9 and the ratio there would be extrapolated).

Writes the reports' CSV and SVG into target/field-vs-direct/, and there
field-vs-direct.svg: every model's field/direct time at equal error over
2(N+1) against the error (below 1: within the bound). Prints Markdown
tables (docs/BENCHMARKS.md, section 0).
"""

import csv
import math
import os
import subprocess
import sys

MODELS = [
    "examples/knife_edge.lag",
    "examples/rolling_disk.lag",
    "examples/nonlinear_constraint.lag",
    "benches/data/pendulum_2.lag",
    "benches/data/pendulum_3.lag",
    "benches/data/pendulum_5.lag",
    "benches/data/pendulum_8.lag",
    "benches/data/double_pendulum_mass_loss.lag",
    "tests/data/mass_law_forms/sleigh_mass.lag",
    "tests/data/mass_law_forms/rocket_mass.lag",
    "examples/rolling_disk_3d.lag",
    "examples/ball_on_turntable.lag",
]
TOLERANCES = os.environ.get("TOLERANCES", "1e-3,1e-4,1e-5,1e-6,1e-7,1e-8,1e-9,1e-10,1e-11")
OUT = os.environ.get("OUT", "target/field-vs-direct")
LAGC = os.environ.get("LAGC", "target/release/lagc")


def rows(model):
    name = os.path.basename(model)[:-4]
    if os.environ.get("REUSE") != "1":
        subprocess.run(
            [LAGC, "report", model, "--tolerances", TOLERANCES,
             "--runs", os.environ.get("RUNS", "3"), "--out", OUT]
            + (["--no-global-error"] if os.environ.get("NO_GLOBAL_ERROR") == "1" else []),
            check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(OUT, f"{name}.work-precision.csv")) as f:
        return name, [r for r in csv.DictReader(f) if r["status"] == "ok"]


def interpolate(points, error):
    """log time at log error, linear between the two nearest rungs, or
    extrapolated from the two nearest ends (marked `~`)."""
    points = sorted(set(points))
    if len(points) < 2:
        return None, ""
    pairs = list(zip(points, points[1:]))
    for (e0, t0), (e1, t1) in pairs:
        if e0 <= error <= e1 and e1 > e0:
            w = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), ""
    (e0, t0), (e1, t1) = pairs[0] if error < points[0][0] else pairs[-1]
    if e1 <= e0:
        return None, ""
    w = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
    return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), "~"


def envelope(points):
    """The lower envelope of (error, time): the cheapest run reaching each
    error, so that a rung which bought nothing does not count."""
    best, out = float("inf"), []
    for e, t in sorted(points):
        if t < best:
            out.append((e, t))
            best = t
    return out


def cost_at(points, target):
    """The time to reach an error of `target`: interpolated on the lower
    envelope between the rungs around it; where every rung is already more
    accurate, the cheapest rung (a looser tolerance buys little more: the
    span's few steps are a floor), not an extrapolation below it."""
    env = envelope(points)
    if env and target >= max(e for e, _ in env):
        return min(t for _, t in env), ""
    return interpolate(env, target)


def state_dimension(model):
    """N: the state columns of the model's CSV header (t excluded)."""
    run = subprocess.run([LAGC, "run", model, "--", "--samples", "1"],
                         check=True, capture_output=True, text=True)
    return len(run.stdout.splitlines()[0].split(",")) - 1


def slope(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx else float("nan")


def ratio_plot(curves, path):
    """An SVG of field/direct at equal error over 2(N+1), against the
    error, one line per model: below 1 is within issue 10's bound."""
    width, height, left, bottom, top, right = 760, 420, 70, 50, 20, 240
    lo, hi = -12.0, -3.0          # log10 error
    ylo, yhi = 0.0, 2.0           # ratio / bound
    def x(e):
        return left + (math.log10(e) - lo) / (hi - lo) * (width - left - right)
    def y(r):
        r = min(max(r, ylo), yhi)
        return height - bottom - (r - ylo) / (yhi - ylo) * (height - bottom - top)
    colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
               "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#000000", "#aa4499"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{width}" height="{height}" fill="white"/>']
    for k in range(int(lo), int(hi) + 1):
        out.append(f'<line x1="{x(10**k):.1f}" y1="{y(ylo):.1f}" x2="{x(10**k):.1f}" '
                   f'y2="{y(yhi):.1f}" stroke="#ddd"/>')
        out.append(f'<text x="{x(10**k):.1f}" y="{height - bottom + 16}" '
                   f'text-anchor="middle">1e{k}</text>')
    for r in (0.0, 0.5, 1.0, 1.5, 2.0):
        out.append(f'<line x1="{left}" y1="{y(r):.1f}" x2="{width - right}" y2="{y(r):.1f}" '
                   f'stroke="{"#d00" if r == 1.0 else "#ddd"}"/>')
        out.append(f'<text x="{left - 6}" y="{y(r) + 4:.1f}" text-anchor="end">{r:g}</text>')
    out.append(f'<text x="{(left + width - right) / 2:.0f}" y="{height - 12}" '
               f'text-anchor="middle">error (largest over the samples)</text>')
    out.append(f'<text x="16" y="{(height - bottom + top) / 2:.0f}" text-anchor="middle" '
               f'transform="rotate(-90 16 {(height - bottom + top) / 2:.0f})">'
               f'field / DOP853 time at equal error, over 2(N+1)</text>')
    for i, (name, pts) in enumerate(curves):
        c = colours[i % len(colours)]
        path_d = " ".join(f"{x(e):.1f},{y(r):.1f}" for e, r in sorted(pts) if lo <= math.log10(e) <= hi)
        if path_d:
            out.append(f'<polyline points="{path_d}" fill="none" stroke="{c}" stroke-width="1.5"/>')
        out.append(f'<line x1="{width - right + 10}" y1="{top + 10 + 16 * i}" '
                   f'x2="{width - right + 30}" y2="{top + 10 + 16 * i}" stroke="{c}" stroke-width="2"/>')
        out.append(f'<text x="{width - right + 36}" y="{top + 14 + 16 * i}">{name}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    models = sys.argv[1:] or MODELS
    os.makedirs(OUT, exist_ok=True)
    print("| model | rtol | field error | field time [ms] | DOP853 error | DOP853 time [ms] | field/DOP853 at equal error |")
    print("|---|---|---|---|---|---|---|")
    orders, targets, curves = [], [], []
    for model in models:
        name, data = rows(model)
        field = [r for r in data if r["method"] == "field"]
        direct = [r for r in data if r["method"] == "direct DOP853"]
        dpoints = [(float(r["error"]), float(r["time_s"])) for r in direct if float(r["error"]) > 0]
        for r, d in zip(field, direct):
            e, t = float(r["error"]), float(r["time_s"])
            at, mark = interpolate(dpoints, e) if e > 0 else (None, "")
            ratio = f"{mark}{t / at:.1f}" if at else "-"
            print(f"| {name} | {r['rtol']} | {e:.2e} | {1e3 * t:.3f} | "
                  f"{float(d['error']):.2e} | {1e3 * float(d['time_s']):.3f} | {ratio} |")
        fpoints = [(float(r["error"]), float(r["time_s"])) for r in field if float(r["error"]) > 0]
        n = state_dimension(model)
        curve = []
        for e, t in envelope(fpoints):
            dt, mark = cost_at(dpoints, e)
            if dt and not mark:
                curve.append((e, t / dt / (2 * (n + 1))))
        curves.append((name, curve))
        for target in (1e-6, 1e-9):
            ft, fmark = cost_at(fpoints, target)
            dt, dmark = cost_at(dpoints, target)
            targets.append((name, n, target, ft, fmark, dt, dmark))
        # The order over the asymptotic rungs: the loosest rungs (where the
        # step is the span, or a floor of steps) and rounding say nothing.
        def asymptotic(rs):
            return [(math.log(float(r["rhs_evaluations"])), -math.log(float(r["error"])))
                    for r in rs if 1e-11 <= float(r["error"]) <= 1e-4]
        good, dgood = asymptotic(field), asymptotic(direct)
        orders.append((name,
                       slope(*zip(*good)) if len(good) >= 3 else float("nan"),
                       slope(*zip(*dgood)) if len(dgood) >= 3 else float("nan")))
    print()
    print("| model | N | error | field time [ms] | DOP853 time [ms] | ratio | bound 2(N+1) |")
    print("|---|---|---|---|---|---|---|")
    for name, n, target, ft, fmark, dt, dmark in targets:
        if ft and dt:
            mark = "~" if fmark or dmark else ""
            ratio = f"{mark}{ft / dt:.1f}"
            verdict = "" if ft / dt <= 2 * (n + 1) else " (over)"
            print(f"| {name} | {n} | {target:.0e} | {fmark}{1e3 * ft:.3f} | "
                  f"{dmark}{1e3 * dt:.3f} | {ratio}{verdict} | {2 * (n + 1)} |")
    ratio_plot(curves, os.path.join(OUT, "field-vs-direct.svg"))
    print()
    print("| model | field order | DOP853 order |")
    print("|---|---|---|")
    for name, fo, do in orders:
        print(f"| {name} | {fo:.1f} | {do:.1f} |")


if __name__ == "__main__":
    main()
