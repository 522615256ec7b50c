#!/usr/bin/env python3
"""The field method as a user gets it (`--method field`, the integrator
`auto`: explicit windows, switching where DOP853 finds stiffness) against
direct DOP853, at equal error (issue 29). `lagc report` and
scripts/field_vs_direct.py pin the field's integrator to `explicit`, so
they do not see the automatic switch; this ladder does.

Each rung: `--rtol R --atol R·1e-2 --samples 11 --repeat 3` (the smallest
solve of three, timed inside the binary), the error the largest relative
difference (|a − b| / max(|b|, 1)) over samples and components to direct
DOP853 at rtol 1e-13. The time at errors 1e-6 and 1e-9 is interpolated
log-log on each method's lower envelope, as in field_vs_direct.py.

Usage (from the repository root, after `cargo build --release -p lagc`):

    python3 scripts/field_auto_ladder.py MODEL.lag [BINARY]

BINARY: a generated crate's binary to use instead of `lagc run` (to
compare two runtimes on one model side by side). INTEGRATOR=<name> passes
`--integrator <name>` to the field runs (`magnus`: exponential windows
from the start, what auto gives only once DOP853 finds stiffness).
"""

import json
import math
import os
import subprocess
import sys

TOLERANCES = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]


def runner(model, binary):
    def run(args):
        command = ([binary] if binary else
                   [os.environ.get("LAGC", "target/release/lagc"), "run", model, "--"])
        p = subprocess.run(command + ["--samples", "11", "--summary", "json"] + args,
                           capture_output=True, text=True)
        if p.returncode != 0:
            return None, None
        rows = [list(map(float, l.split(","))) for l in p.stdout.strip().splitlines()[1:]]
        summary = json.loads([l for l in p.stderr.splitlines() if l.startswith("{")][-1])
        return rows, summary
    return run


def envelope(points):
    best, out = float("inf"), []
    for e, t in sorted(points):
        if t < best:
            out.append((e, t))
            best = t
    return out


def cost_at(points, target):
    env = envelope(points)
    if not env:
        return None, ""
    if target >= max(e for e, _ in env):
        return min(t for _, t in env), ""
    env = sorted(env)
    for (e0, t0), (e1, t1) in zip(env, env[1:]):
        if e0 <= target <= e1:
            w = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), ""
    (e0, t0), (e1, t1) = env[0], env[1] if len(env) > 1 else env[0]
    if e1 <= e0:
        return None, ""
    w = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
    return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), "~"


def main():
    model = sys.argv[1]
    binary = sys.argv[2] if len(sys.argv) > 2 else None
    run = runner(model, binary)
    reference, _ = run(["--method", "direct", "--rtol", "1e-13", "--atol", "1e-15"])
    n = len(reference[0]) - 1

    def error(rows):
        return max(abs(a - b) / max(abs(b), 1.0)
                   for r, s in zip(reference, rows) for a, b in zip(s[1:], r[1:]))

    print("| method | rtol | error | time [ms] | steps (+rejected) | windows | integrator |")
    print("|---|---|---|---|---|---|---|")
    points = {"field": [], "direct": []}
    for method in ("field", "direct"):
        for rtol in TOLERANCES:
            extra = (["--integrator", os.environ["INTEGRATOR"]]
                     if method == "field" and os.environ.get("INTEGRATOR") else [])
            rows, s = run(["--method", method, "--rtol", str(rtol), "--atol", str(rtol * 1e-2),
                           "--repeat", "3"] + extra)
            if rows is None:
                print(f"| {method} | {rtol:g} | failed | | | | |")
                continue
            e, t = error(rows), s["wall_time_s"]
            points[method].append((e, t))
            print(f"| {method} | {rtol:g} | {e:.2e} | {1e3 * t:.3f} | {s['steps']} (+{s['rejected_steps']}) "
                  f"| {s['windows'] if s['windows'] is not None else '-'} | {s['method']} |")
    print()
    print("| error | field [ms] | direct [ms] | field / direct | bound 2(N+1) |")
    print("|---|---|---|---|---|")
    for target in (1e-6, 1e-9):
        ft, fm = cost_at(points["field"], target)
        dt, dm = cost_at(points["direct"], target)
        if ft and dt:
            mark = "~" if fm or dm else ""
            print(f"| {target:g} | {1e3 * ft:.3f} | {1e3 * dt:.3f} | {mark}{ft / dt:.1f} | {2 * (n + 1)} |")


if __name__ == "__main__":
    main()
