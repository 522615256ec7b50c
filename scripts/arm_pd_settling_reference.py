#!/usr/bin/env python3
"""The reference of tests/data/arm_pd_settling.lag (tests/it/settling.rs):
the arm's Lagrange equations derived by SymPy, independently of lagc, and
integrated by SciPy's DOP853 at rtol 2.3e-14, atol 1e-16, stepped onto
each sample time (a fresh solve_ivp per interval: no continuous
extension). Needs sympy, scipy, numpy; about 3 minutes for 101 samples.

    python3 scripts/arm_pd_settling_reference.py 101 tests/data/arm_pd_settling_scipy.csv
"""
import sys

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

l1, l2, m1, m2, g, kp, kd, ar, br = 0.5, 0.4, 2, 1.5, 9.81, 40, 6, 1.0, -0.5
t = sp.symbols("t")
a = sp.Function("a")(t)
b = sp.Function("b")(t)
c1 = sp.Matrix([l1 / 2 * sp.cos(a), l1 / 2 * sp.sin(a)])
e1 = sp.Matrix([l1 * sp.cos(a), l1 * sp.sin(a)])
c2 = e1 + sp.Matrix([l2 / 2 * sp.cos(a + b), l2 / 2 * sp.sin(a + b)])
d = lambda v: v.diff(t)
T = (m1 / 2 * d(c1).dot(d(c1)) + m1 * l1**2 / 24 * a.diff(t) ** 2
     + m2 / 2 * d(c2).dot(d(c2)) + m2 * l2**2 / 24 * (a.diff(t) + b.diff(t)) ** 2)
L = T - g * (m1 * c1[1] + m2 * c2[1])
Qa = kp * (ar - a) - kd * a.diff(t) + g * (m1 * l1 / 2 + m2 * l1) * sp.cos(a)
Qb = kp * (br - b) - kd * b.diff(t)
eqs = [sp.diff(L.diff(q.diff(t)), t) - L.diff(q) - Q for q, Q in ((a, Qa), (b, Qb))]
A, B, AD, BD, ADD, BDD = sp.symbols("A B AD BD ADD BDD")
eqs = [e.subs({a.diff(t, 2): ADD, b.diff(t, 2): BDD}) for e in eqs]
eqs = [e.subs({a.diff(t): AD, b.diff(t): BD}).subs({a: A, b: B}) for e in eqs]
sol = sp.solve(eqs, [ADD, BDD])
fa = sp.lambdify((A, B, AD, BD), sol[ADD])
fb = sp.lambdify((A, B, AD, BD), sol[BDD])


def rate(_t, y):
    return [y[2], y[3], fa(*y), fb(*y)]


def main():
    n, out = int(sys.argv[1]), sys.argv[2]
    ts = np.linspace(0, 5, n)
    y = np.zeros(4)
    rows = [[0.0, *y]]
    for t0, t1 in zip(ts[:-1], ts[1:]):
        s = solve_ivp(rate, (t0, t1), y, method="DOP853", rtol=2.3e-14, atol=1e-16)
        y = s.y[:, -1]
        rows.append([t1, *y])
    np.savetxt(out, np.array(rows), delimiter=",", header="t,a,b,a',b'",
               comments="", fmt="%.17g")


if __name__ == "__main__":
    main()
