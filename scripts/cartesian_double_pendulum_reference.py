#!/usr/bin/env python3
"""The reference of tests/data/cartesian_double_pendulum.lag (tests/it/chains.rs):
the same double pendulum in its two angles (no constraint at all: the rods'
lengths are built into the coordinates), its equations derived by SymPy from
the Lagrangian in the angles, integrated by SciPy's DOP853 at rtol 2.3e-14,
atol 1e-15 stepped onto each sample time (a fresh solve_ivp per interval: no
continuous extension), and mapped to the Cartesian positions and velocities
of the two bobs. Needs sympy, scipy, numpy; a few seconds.

    python3 scripts/cartesian_double_pendulum_reference.py 21 tests/data/cartesian_double_pendulum_scipy.csv
"""
import sys

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

g, m1, m2, l1, l2 = 9.81, 1.0, 2.0, 1.0, 0.7
a, b, ad, bd, add, bdd = sp.symbols("a b ad bd add bdd")
x1, y1 = l1 * sp.sin(a), -l1 * sp.cos(a)
x2, y2 = x1 + l2 * sp.sin(b), y1 - l2 * sp.cos(b)
qs, qds, qdds = (a, b), (ad, bd), (add, bdd)


def dt(e):
    return sum(e.diff(q) * qd + e.diff(qd) * qdd for q, qd, qdd in zip(qs, qds, qdds))


def velocity(e):
    return sum(e.diff(q) * qd for q, qd in zip(qs, qds))


T = m1 / 2 * (velocity(x1) ** 2 + velocity(y1) ** 2) + m2 / 2 * (velocity(x2) ** 2 + velocity(y2) ** 2)
V = m1 * g * y1 + m2 * g * y2
L = T - V
eqs = [dt(L.diff(qd)) - L.diff(q) for q, qd in zip(qs, qds)]
solution = sp.solve(eqs, [add, bdd], dict=True)[0]
accel = sp.lambdify([a, b, ad, bd], [solution[add], solution[bdd]])
cartesian = sp.lambdify(
    [a, b, ad, bd],
    [x1, y1, x2, y2, velocity(x1), velocity(y1), velocity(x2), velocity(y2)],
)


def rhs(_t, y):
    acc = accel(*y)
    return [y[2], y[3], acc[0], acc[1]]


def main():
    samples, path = int(sys.argv[1]), sys.argv[2]
    # The lag file's start: the first rod at (0.8, -0.6), the second level.
    y = [np.arctan2(0.8, 0.6), np.pi / 2, 0.0, 0.0]
    times = np.linspace(0.0, 5.0, samples)
    rows = [[0.0, *cartesian(*y)]]
    for t0, t1 in zip(times[:-1], times[1:]):
        sol = solve_ivp(rhs, (t0, t1), y, method="DOP853", rtol=2.3e-14, atol=1e-15)
        y = sol.y[:, -1]
        rows.append([t1, *cartesian(*y)])
    with open(path, "w") as out:
        out.write("t,x1,y1,x2,y2,x1',y1',x2',y2'\n")
        for row in rows:
            out.write(",".join(repr(float(v)) for v in row) + "\n")


if __name__ == "__main__":
    main()
