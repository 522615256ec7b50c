#!/usr/bin/env python3
"""References for tests/data/coupled_nonlinear/*.lag (tests/it/coupled_nonlinear.rs):
groups of velocity constraints solved together, at least one not linear in
its candidates.

Independent of lagc's derivation (equations (4), Cramer, Newton over the
group): the multiplier form with Chetaev's normals, derived here by SymPy
from each model's Lagrangian as written below (not read from the .lag files),

    M(q) q'' + h(q, q') = Q + sum_v lam_v dF_v/dq'      (E_j = Q_j + reactions)
    D F_v = A(q, q') q'' + b(q, q') = 0,  A_vj = dF_v/dq'_j,

solved for (q'', lam) as one linear (KKT) system at every evaluation
(numpy.linalg.solve) and integrated by SciPy's DOP853 at rtol 2.3e-14,
atol 1e-15. The written constraints F = 0 are integrals of this motion (not
kept): the script prints their largest residual along the reference.

Writes tests/data/coupled_nonlinear/<name>.csv: t and the state columns, 41
rows. Run: python3 scripts/coupled_nonlinear_reference.py [NAME...]
(needs numpy, scipy, sympy)."""
import os
import sys

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

t = sp.Symbol("t")
OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "coupled_nonlinear")


def kkt(L, qs, qds, F, Q):
    n, m = len(qs), len(F)
    qdds = sp.symbols(f"a0:{n}")

    def D(e):
        return (sp.diff(e, t) + sum(sp.diff(e, q) * v for q, v in zip(qs, qds))
                + sum(sp.diff(e, v) * a for v, a in zip(qds, qdds)))

    E = [D(sp.diff(L, v)) - sp.diff(L, q) - Q[i] for i, (q, v) in enumerate(zip(qs, qds))]
    at_rest = {a: 0 for a in qdds}
    M = sp.Matrix([[sp.diff(e, a) for a in qdds] for e in E])
    h = sp.Matrix([e.subs(at_rest) for e in E])
    A = sp.Matrix([[sp.diff(f, v) for v in qds] for f in F])
    b = sp.Matrix([D(f).subs(at_rest) for f in F])
    args = [t] + list(qs) + list(qds)
    parts = sp.lambdify(args, [M, h, A, b], "numpy")
    residual = sp.lambdify(args, F, "numpy")

    def f(tt, y):
        Mv, hv, Av, bv = (np.array(p, dtype=float) for p in parts(tt, *y))
        K = np.block([[Mv, -Av.T], [Av, np.zeros((m, m))]])
        rhs = np.concatenate([-hv.ravel(), -bv.ravel()])
        z = np.linalg.solve(K, rhs)
        return np.concatenate([y[n:], z[:n]])

    return f, residual


x, y, z, th, w, a, bb = sp.symbols("x y z th w a b")
xd, yd, zd, thd, wd, ad, bd = sp.symbols("xd yd zd thd wd ad bd")


def models():
    b, J, v = 0.5, 0.2, 1.0
    xc, yc = x + b * sp.cos(th), y + b * sp.sin(th)
    vxc = xd - b * sp.sin(th) * thd
    vyc = yd + b * sp.cos(th) * thd
    s0 = np.sqrt(0.64 / 1.09)
    return {
        # particle_constant_speed_contact.lag: z' = x y' and |v| = 1, gravity, a spring.
        "particle_constant_speed_contact": dict(
            qs=[x, y, z], qds=[xd, yd, zd], head="t,x,y,z,x',y',z'",
            L=(xd**2 + yd**2 + zd**2) / 2 - 9.81 * z - 2 * (x**2 + y**2) / 2,
            Q=[0, 0, 0],
            F=[zd - x * yd, xd**2 + yd**2 + zd**2 - 1],
            y0=[0.3, 0, 0, 0.6, s0, 0.3 * s0], T=5),
        # linear_group_beside_constant_speed.lag: a linear pair solved together,
        # raised beside a non-linear constraint of other coordinates.
        "linear_group_beside_constant_speed": dict(
            qs=[x, y, z, w, a, bb], qds=[xd, yd, zd, wd, ad, bd], head="t,x,y,z,w,a,b,x',y',z',w',a',b'",
            L=(xd**2 + yd**2 + zd**2 + wd**2 + ad**2 + bd**2) / 2 - 9.81 * bb - x**2 - w**2,
            Q=[0] * 6,
            F=[zd - x * yd, wd - zd - yd, ad**2 + bd**2 - 1],
            y0=[0.3, 0, 0, 0, 0, 0, 0.5, 0.4, 0.12, 0.52, 0.6, 0.8], T=3),
        # sleigh_constant_speed.lag's motion, the two constraints as first
        # written (a check against tests/data/textbook_constraints/sleigh_constant_speed.csv,
        # made by another script).
        "sleigh_written": dict(
            qs=[x, y, th], qds=[xd, yd, thd], head="t,x,y,th,x',y',th'",
            L=(vxc**2 + vyc**2) / 2 + J / 2 * thd**2,
            Q=[0, 0, 0.3 * sp.sin(1.5 * t)],
            F=[sp.sin(th) * xd - sp.cos(th) * yd, xd**2 + yd**2 - v**2],
            y0=[0, 0, 0.3, np.cos(0.3), np.sin(0.3), 1], T=20, write=False),
    }


def main():
    only = sys.argv[1:]
    for name, m in models().items():
        if only and name not in only:
            continue
        f, residual = kkt(m["L"], m["qs"], m["qds"], m["F"], m["Q"])
        ts = np.linspace(0.0, m["T"], 41)
        s = solve_ivp(f, (0.0, m["T"]), m["y0"], method="DOP853", rtol=2.3e-14, atol=1e-15, t_eval=ts)
        assert s.success, s.message
        drift = max(np.max(np.abs(residual(tt, *row))) for tt, row in zip(ts, s.y.T))
        print(f"{name}: largest |F| along the reference {drift:.2e}")
        if not m.get("write", True):
            other = os.path.join(OUT, "..", "textbook_constraints", "sleigh_constant_speed.csv")
            ref = np.loadtxt(other, delimiter=",", skiprows=1)
            print(f"  against sleigh_constant_speed.csv: {np.max(np.abs(ref[:, 1:] - s.y.T)):.2e}")
            continue
        path = os.path.join(OUT, name + ".csv")
        with open(path, "w") as out:
            out.write(m["head"] + "\n")
            for tt, row in zip(ts, s.y.T):
                out.write(",".join(repr(float(v)) for v in [tt, *row]) + "\n")
        print(f"  wrote {path}")


if __name__ == "__main__":
    main()
