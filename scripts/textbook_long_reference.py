#!/usr/bin/env python3
"""References of tests/data/textbook_long/*.lag (tests/it/textbook_long.rs),
independent of lagc: each model's Lagrange equations derived again by SymPy
from its Lagrangian (and generalized force) written out here, then

- chaotic models: integrated at 40 digits by Gragg-Bulirsch-Stoer
  extrapolation (order 24, fixed macro steps landing on every sample), run
  twice (steps H and 2H) and refused unless the two agree to 1e-10
  relative (the gap bounds the coarse run's error; the fine one's, at order
  24, is below it: the double pendulum's gap is 1.3e-11 at 10 s, 0.13 of
  the test's smallest rtol, Henon-Heiles' and the driven pendulum's below
  1e-26): the true motion, past the horizon an f64 run can follow;
- the pendulum: SciPy's DOP853 at rtol 2.3e-14, atol 1e-16, stepped onto
  each sample (a fresh solve_ivp per interval: no continuous extension).

Writes NAME_reference.csv (t, the coordinates, their derivatives; 41 rows)
next to each model. Needs sympy, scipy, numpy, mpmath; about 20 minutes
under no load (the double pendulum's 40-digit run is most of it).

    python3 scripts/textbook_long_reference.py [NAME ...]
"""
import os
import sys

import mpmath as mp
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "textbook_long")
t = sp.Symbol("t")
R = sp.Rational
G = R(981, 100)


def coords(names):
    return list(sp.symbols(names)), list(sp.symbols([n + "d" for n in names]))


def double_pendulum():
    (a, b), (ad, bd) = coords(["a", "b"])
    x1, y1 = sp.sin(a), -sp.cos(a)
    x2, y2 = x1 + sp.sin(b), y1 - sp.cos(b)
    v = lambda e: sp.diff(e, a) * ad + sp.diff(e, b) * bd
    T = (v(x1) ** 2 + v(y1) ** 2 + v(x2) ** 2 + v(y2) ** 2) / 2
    return dict(names=["a", "b"], q=[a, b], qd=[ad, bd], L=T - G * (y1 + y2), Q=None,
                y0=["2", "2.5", "0", "0"], T=10, rows=41, how=("gbs", "0.0125"))


def pendulum():
    (p,), (pd,) = coords(["phi"])
    return dict(names=["phi"], q=[p], qd=[pd], L=pd**2 / 2 + G * sp.cos(p), Q=None,
                y0=["1", "0"], T=2140, rows=41, how=("scipy",))


def henon_heiles():
    (x, y), (xd, yd) = coords(["x", "y"])
    V = (x**2 + y**2) / 2 + x**2 * y - y**3 / 3
    return dict(names=["x", "y"], q=[x, y], qd=[xd, yd], L=(xd**2 + yd**2) / 2 - V, Q=None,
                y0=["0", "-0.15", "0.49", "0"], T=200, rows=41, how=("gbs", "0.125"))


def driven_damped():
    (th,), (thd,) = coords(["th"])
    return dict(names=["th"], q=[th], qd=[thd], L=thd**2 / 2 + sp.cos(th),
                Q=[-thd / 2 + R(3, 2) * sp.cos(R(2, 3) * t)],
                y0=["0.2", "0"], T=100, rows=41, how=("gbs", "0.125"))


MODELS = {
    "double_pendulum_released_high": double_pendulum,
    "pendulum_thousand_periods": pendulum,
    "henon_heiles_chaotic": henon_heiles,
    "driven_damped_pendulum_chaotic": driven_damped,
}


def accelerations(M, module):
    """The Lagrange equations as A(t, q, q') q'' = r(t, q, q')."""
    q, qd = M["q"], M["qd"]
    n = len(q)
    qdd = sp.symbols(f"acc0:{n}")

    def Dt(e):
        return (sp.diff(e, t) + sum(sp.diff(e, a) * b for a, b in zip(q, qd))
                + sum(sp.diff(e, b) * c for b, c in zip(qd, qdd)))

    L, Q = M["L"], M["Q"]
    eqs = [Dt(sp.diff(L, b)) - sp.diff(L, a) - (Q[i] if Q else 0) for i, (a, b) in enumerate(zip(q, qd))]
    A, r = sp.linear_eq_to_matrix([sp.expand(e) for e in eqs], list(qdd))
    return sp.lambdify([t] + q + qd, A, module), sp.lambdify([t] + q + qd, r, module)


def by_gbs(M, H, ts):
    """40 digits, GBS extrapolation of order 2K = 24 on fixed steps H."""
    mp.mp.dps = 40
    fA, fr = accelerations(M, "mpmath")
    n = len(M["q"])
    K = 12

    def f(tt, y):
        args = [tt] + list(y)
        acc = mp.lu_solve(mp.matrix(fA(*args)), mp.matrix(fr(*args)))
        return list(y[n:]) + [acc[i] for i in range(n)]

    def step(tt, y, H):
        table = []
        for j in range(1, K + 1):
            m = 2 * j
            h = H / m
            z0 = y
            z1 = [a + h * b for a, b in zip(z0, f(tt, z0))]
            for i in range(1, m):
                z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, f(tt + i * h, z1))]
            row = [[(a + b + h * c) / 2 for a, b, c in zip(z0, z1, f(tt + H, z1))]]
            for k in range(1, j):
                ratio = (mp.mpf(j) / (j - k)) ** 2 - 1
                row.append([a + (a - b) / ratio for a, b in zip(row[k - 1], table[j - 2][k - 1])])
            table.append(row)
        return table[-1][-1]

    H = mp.mpf(H)
    y = [mp.mpf(v) for v in M["y0"]]
    dt = mp.mpf(M["T"]) / (len(ts) - 1)
    per = int(mp.nint(dt / H))
    assert abs(per * H - dt) < mp.mpf(10) ** -30, "the step must land on the samples"
    rows = [[mp.mpf(0)] + y]
    for s in range(1, len(ts)):
        for i in range(per):
            y = step((s - 1) * dt + i * H, y, H)
        rows.append([s * dt] + y)
        print(f"  t = {float(s * dt):g}", file=sys.stderr, flush=True)
    return rows


def by_scipy(M, ts):
    fA, fr = accelerations(M, "numpy")
    n = len(M["q"])

    def rate(tt, y):
        args = [tt] + list(y)
        acc = np.linalg.solve(np.array(fA(*args), dtype=float), np.array(fr(*args), dtype=float).ravel())
        return np.concatenate([y[n:], acc])

    y = np.array([float(v) for v in M["y0"]])
    rows = [[0.0, *y]]
    for t0, t1 in zip(ts[:-1], ts[1:]):
        s = solve_ivp(rate, (t0, t1), y, method="DOP853", rtol=2.3e-14, atol=1e-16)
        assert s.success, s.message
        y = s.y[:, -1]
        rows.append([t1, *y])
    return rows


def main():
    names = sys.argv[1:] or list(MODELS)
    for name in names:
        M = MODELS[name]()
        ts = np.linspace(0, M["T"], M["rows"])
        if M["how"][0] == "gbs":
            H = M["how"][1]
            print(f"{name}: 40 digits, steps {H} and {2 * float(H)}", file=sys.stderr)
            fine = by_gbs(M, H, ts)
            coarse = by_gbs(M, repr(2 * float(H)), ts)
            gap = max(abs(a - b) / max(abs(a), 1) for r, s in zip(fine, coarse) for a, b in zip(r[1:], s[1:]))
            print(f"{name}: the two steps differ by {mp.nstr(gap, 3)} (relative)", file=sys.stderr)
            assert gap < 1e-10, "the 40-digit reference does not converge: take a smaller step"
            rows = [[float(v) for v in r] for r in fine]
        else:
            rows = by_scipy(M, ts)
        head = ",".join(["t"] + M["names"] + [c + "'" for c in M["names"]])
        path = os.path.join(HERE, f"{name}_reference.csv")
        np.savetxt(path, np.array(rows), delimiter=",", header=head, comments="", fmt="%.17g")
        print(f"{name}: {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
