#!/usr/bin/env python3
"""The reference of tests/data/pendulum_striking_wall.lag (tests/it/holonomic.rs):
the pendulum in its angle from the downward vertical, th'' = -g/l sin th,
integrated by SciPy's DOP853 at rtol 1e-13, atol 1e-14, its strikes on the
wall x = 0.3 located by solve_ivp's events and reset th' -> -e th' (the
bob's velocity is along the circle, so x' -> -e x' is that reset), mapped to
the bob's Cartesian position and velocity at 21 times. Needs scipy, numpy.

    python3 scripts/pendulum_striking_wall_reference.py tests/data/pendulum_striking_wall_scipy.csv
"""
import sys

import numpy as np
from scipy.integrate import solve_ivp

g, l, e = 9.81, 1.0, 0.8
wall = np.arcsin(0.3 / l)


def rhs(_t, s):
    return [s[1], -g / l * np.sin(s[0])]


def strike(_t, s):
    return s[0] - wall


strike.terminal = True
strike.direction = 1


def main():
    times = np.linspace(0.0, 5.0, 21)
    t, s, rows = 0.0, [np.arcsin(-0.6 / l), 0.0], {}
    while True:
        sol = solve_ivp(rhs, (t, 5.0), s, method="DOP853", rtol=1e-13, atol=1e-14,
                        events=strike, dense_output=True)
        for tt in times:
            if sol.t[0] <= tt <= sol.t[-1] and tt not in rows:
                rows[tt] = sol.sol(tt)
        if sol.status != 1:
            break
        t, s = sol.t_events[0][0], [wall, -e * sol.y_events[0][0][1]]
    with open(sys.argv[1], "w") as out:
        out.write("t,x,y,x',y'\n")
        for tt in times:
            th, om = rows[tt]
            row = (tt, l * np.sin(th), -l * np.cos(th), l * np.cos(th) * om, l * np.sin(th) * om)
            out.write(",".join(repr(float(v)) for v in row) + "\n")


if __name__ == "__main__":
    main()
