#!/usr/bin/env python3
"""The reference of tests/data/ball_in_cylinder.lag (tests/it/turning_points.rs):
a ball rolling without slipping inside a cylinder, its equations derived by
SymPy with a Lagrange multiplier for the rolling constraint (not lagc's
elimination), integrated by SciPy's DOP853 at rtol 2.3e-14, atol 1e-15,
stepped onto each sample time (a fresh solve_ivp per interval: no
continuous extension). Needs sympy, scipy, numpy; a few seconds.

    python3 scripts/ball_in_cylinder_reference.py 201 tests/data/ball_in_cylinder_scipy.csv
"""
import sys

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

g, R, r, m = 9.81, 1.0, 0.2, 1.0
I = 2 / 5 * m * r**2
phi, th, phid, thd, phidd, thdd, lam = sp.symbols("phi th phid thd phidd thdd lam")
# The centre on a circle of radius R - r: speed (R - r)|phi'|, height
# -(R - r) cos(phi); the ball turned by th, rolling: th' = -(R - r)/r phi'.
L = m / 2 * (R - r) ** 2 * phid**2 + I / 2 * thd**2 + m * g * (R - r) * sp.cos(phi)
constraint_normal = {phid: (R - r) / r, thd: 1}  # d/d(q') of th' + (R - r)/r phi'
qs, qds, qdds = (phi, th), (phid, thd), (phidd, thdd)


def dt(e):
    return sum(e.diff(q) * qd + e.diff(qd) * qdd for q, qd, qdd in zip(qs, qds, qdds))


eqs = [dt(L.diff(qd)) - L.diff(q) - lam * constraint_normal[qd] for q, qd in zip(qs, qds)]
eqs.append(thdd + (R - r) / r * phidd)  # the constraint's derivative
solution = sp.solve(eqs, [phidd, thdd, lam], dict=True)[0]
accel = sp.lambdify([phi, th, phid, thd], [solution[phidd], solution[thdd]])


def rhs(_t, y):
    a = accel(*y)
    return [y[2], y[3], a[0], a[1]]


def main():
    samples, out = int(sys.argv[1]), sys.argv[2]
    times = np.linspace(0.0, 10.0, samples)
    y = np.array([np.pi / 3, 0.0, 0.0, 0.0])
    rows = [[0.0, *y]]
    for t0, t1 in zip(times[:-1], times[1:]):
        s = solve_ivp(rhs, (t0, t1), y, method="DOP853", rtol=2.3e-14, atol=1e-15)
        assert s.success, s.message
        y = s.y[:, -1]
        rows.append([t1, *y])
    with open(out, "w") as f:
        f.write("t,phi,th,phi',th'\n")
        for row in rows:
            f.write(",".join(repr(float(v)) for v in row) + "\n")


main()
