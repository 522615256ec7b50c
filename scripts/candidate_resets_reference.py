#!/usr/bin/env python3
"""References of tests/data/candidate_resets/hoop_stop*.lag
(tests/it/candidate_resets.rs), made without lagc: a bead on a hoop of
radius R in its angle th from the bottom (x = R sin th, y = -R cos th),
th'' = -g/R sin th, integrated by SciPy's DOP853 at rtol 1e-13,
atol 1e-14, thrown from the bottom with x' = 6 (th' = 6/R). Its strikes
on the stops y = H (either side: cos th = -H/R, reached going up) are
located by solve_ivp's events and reset th' -> -e th' (the bead's velocity
is along the hoop, so either Cartesian reset with the constraint giving
the other component is that reset). The bead's Cartesian position and
velocity at 41 times over 0..5. Needs scipy, numpy.

    python3 scripts/candidate_resets_reference.py 0.5 tests/data/candidate_resets/hoop_stop_scipy.csv
    python3 scripts/candidate_resets_reference.py 0.12 tests/data/candidate_resets/hoop_stop_near_switch_scipy.csv
"""
import sys

import numpy as np
from scipy.integrate import solve_ivp

g, R, e, v0, t1 = 9.81, 1.0, 0.8, 6.0, 5.0


def main():
    height, path = float(sys.argv[1]), sys.argv[2]

    def rhs(_t, s):
        return [s[1], -g / R * np.sin(s[0])]

    def strike(_t, s):
        # y - H = -R cos th - H, rising into y > H.
        return -R * np.cos(s[0]) - height

    strike.terminal = True
    strike.direction = 1

    times = np.linspace(0.0, t1, 41)
    t, s, rows, strikes = 0.0, [0.0, v0 / R], {}, 0
    while True:
        sol = solve_ivp(rhs, (t, t1), s, method="DOP853", rtol=1e-13, atol=1e-14,
                        events=strike, dense_output=True)
        for tt in times:
            if sol.t[0] <= tt <= sol.t[-1] and tt not in rows:
                rows[tt] = sol.sol(tt)
        if sol.status != 1:
            break
        strikes += 1
        th, om = sol.y_events[0][0]
        t, s = sol.t_events[0][0], [th, -e * om]
    with open(path, "w") as out:
        out.write("t,x,y,x',y'\n")
        for tt in times:
            th, om = rows[tt]
            row = (tt, R * np.sin(th), -R * np.cos(th), R * np.cos(th) * om, R * np.sin(th) * om)
            out.write(",".join(repr(float(v)) for v in row) + "\n")
    print(f"{path}: {strikes} strikes", file=sys.stderr)


if __name__ == "__main__":
    main()
