#!/usr/bin/env python3
"""The error of lagc runs of tests/data/drag_bounce.lag against an
independent reference: SciPy's DOP853 at rtol 1e-13 on the ball's
equations written by hand (x'' = -k x' v, y'' = -g - k y' v), its
events located by SciPy and the reset y' -> -e y' applied there, until
the bounces' speed falls below 1e-6 (docs/BENCHMARKS.md §10u).

    lagc run tests/data/drag_bounce.lag --method direct --rtol 1e-8 \\
        --atol 1e-10 --samples 41 --summary json > run.csv 2> run.err
    python3 scripts/drag_bounce_reference.py 1e-8 run.csv run.err

prints the largest error over the rows whose times are sample times
(relative to max(|x|, 1), every column, in rtol) and the run's estimate.
Needs numpy and scipy.
"""
import csv
import json
import sys

import numpy as np
from scipy.integrate import solve_ivp

G, K, E = 9.81, 0.05, 0.8
T_END, SAMPLES = 8.0, 41


def reference(times):
    def f(t, s):
        x, y, vx, vy = s
        v = np.hypot(vx, vy)
        return [vx, vy, -K * vx * v, -G - K * vy * v]

    def hit(t, s):
        return s[1]

    hit.terminal = True
    hit.direction = -1
    t0, s0, out = 0.0, [0.0, 1.0, 8.0, 6.0], {}
    while t0 < T_END:
        sol = solve_ivp(f, (t0, T_END), s0, method="DOP853", rtol=1e-13,
                        atol=1e-15, events=hit, dense_output=True)
        for t in times:
            if t0 <= t <= sol.t[-1] and t not in out:
                out[t] = sol.sol(t)
        if sol.status != 1:
            break
        s = sol.y_events[0][0].copy()
        t0 = sol.t_events[0][0]
        s[1], s[3] = 0.0, -E * s[3]
        s0 = s
        if abs(s[3]) < 1e-6:
            break
    return out


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    rtol, run, summary = float(sys.argv[1]), sys.argv[2], sys.argv[3]
    rows = [list(map(float, r)) for r in list(csv.reader(open(run)))[1:]]
    times = list(np.linspace(0.0, T_END, SAMPLES))
    ref = reference(times)
    err = max(max(abs(a - b) / max(abs(b), 1.0) for a, b in zip(row[1:5], ref[row[0]]))
              for row in rows if row[0] in ref)
    line = next(l for l in open(summary) if l.startswith("{"))
    estimate = json.loads(line)["global_error_estimate"]
    print(f"error {err / rtol:.1f} rtol, estimate {estimate / rtol:.1f} rtol")


if __name__ == "__main__":
    main()
