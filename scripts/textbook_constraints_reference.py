#!/usr/bin/env python3
"""References for tests/data/textbook_constraints/*.lag (tests/it/textbook_constraints.rs).

Independent of lagc's elimination (equations (4)): the multiplier form
    E_j(q, q', q'') = Q_j + sum_k lam_k n_kj
with Chetaev's normals (SPEC 1.2: lagc's E_i + E_{s+v} dphi_v/dq_i^(k) is this
form with the multipliers eliminated), derived here by SymPy from each model's
Lagrangian as written below (not read from the .lag files):
  velocity constraint g(t, q, q') = 0 (linear or not): n = dg/dq', enforced as D g = 0;
  acceleration constraint h(t, q, q', q'') = 0 (k = 2, linear or not): n = dh/dq'',
  enforced as h = 0.
The unknowns (q'', lam) are solved by Newton with the exact Jacobian at every
evaluation, continued from the previous root (one step when linear), and the
motion integrated by SciPy's DOP853 at rtol 2.3e-14, atol 1e-15.

Writes tests/data/textbook_constraints/<name>.csv: t and the state columns,
41 rows. Run: python3 scripts/textbook_constraints_reference.py  (needs numpy,
scipy, sympy)."""
import os
import sys

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

t = sp.Symbol("t")
OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "textbook_constraints")


def rhs(L, qs, qds, qdds, vel=(), acc=(), Q=None):
    def D(e):
        return (sp.diff(e, t) + sum(sp.diff(e, q) * v for q, v in zip(qs, qds))
                + sum(sp.diff(e, v) * a for v, a in zip(qds, qdds)))
    E = [D(sp.diff(L, v)) - sp.diff(L, q) - (Q[i] if Q else 0) for i, (q, v) in enumerate(zip(qs, qds))]
    normals = [[sp.diff(g, v) for v in qds] for g in vel] + [[sp.diff(h, a) for a in qdds] for h in acc]
    held = [D(g) for g in vel] + list(acc)
    lam = sp.symbols(f"lam0:{len(normals)}")
    eqs = [E[i] - sum(lam[k] * normals[k][i] for k in range(len(normals))) for i in range(len(qs))] + held
    unknowns = list(qdds) + list(lam)
    args = [t] + list(qs) + list(qds) + unknowns
    F = sp.lambdify(args, eqs, "numpy")
    J = sp.lambdify(args, sp.Matrix(eqs).jacobian(unknowns), "numpy")
    n = len(qs)
    root = {"z": np.zeros(len(unknowns))}

    def f(tt, y):
        z = root["z"].copy()
        for _ in range(60):
            a = [tt] + list(y) + list(z)
            dz = np.linalg.solve(np.array(J(*a), dtype=float), np.array(F(*a), dtype=float))
            z = z - dz
            if np.max(np.abs(dz)) <= 1e-15 * max(1.0, np.max(np.abs(z))):
                break
        else:
            raise RuntimeError(f"Newton did not converge at t = {tt}")
        root["z"] = z
        return np.concatenate([y[n:], z[:n]])

    return f, root


x, y, z, th = sp.symbols("x y z th")
xd, yd, zd, thd = sp.symbols("xd yd zd thd")
xdd, ydd, zdd, thdd = sp.symbols("xdd ydd zdd thdd")
G = 9.81


def models():
    P2 = dict(qs=[x, y], qds=[xd, yd], qdds=[xdd, ydd], head="t,x,y,x',y'")
    P3 = dict(qs=[x, y, z], qds=[xd, yd, zd], qdds=[xdd, ydd, zdd], head="t,x,y,z,x',y',z'")
    b, J = 0.5, 0.2
    xc, yc = x + b * sp.cos(th), y + b * sp.sin(th)
    vxc = sp.diff(xc, x) * xd + sp.diff(xc, th) * thd
    vyc = sp.diff(yc, y) * yd + sp.diff(yc, th) * thd
    A, c = 12.0, 0.3
    return {
        # constant_speed_spring.lag and acceleration_perpendicular_spring.lag
        "constant_speed_spring": dict(P2, L=(xd**2 + yd**2) / 2 - 4 * (x**2 + y**2) / 2,
                                      vel=[sp.sqrt(xd**2 + yd**2) - 1], y0=[1, 0, 0, 1], T=6),
        "appell_hamel": dict(P3, L=(xd**2 + yd**2 + zd**2) / 2 - G * z,
                             vel=[zd + sp.Rational(1, 2) * sp.sqrt(xd**2 + yd**2)],
                             y0=[0, 0, 0, 1, 0.5, -0.5 * np.sqrt(1.25)], T=5),
        "constant_kinetic_energy_3d": dict(P3, L=(xd**2 + yd**2 + zd**2) - (x**2 + y**2) / 2 - 2 * z,
                                           vel=[(xd**2 + yd**2 + zd**2) - 3],
                                           y0=[1, 0, 0, 0, 1, -np.sqrt(2)], T=10),
        "acceleration_magnitude_drag": dict(P2, L=(xd**2 + yd**2) / 2 - G * y, Q=[-c * xd, -c * yd],
                                            acc=[xdd**2 + ydd**2 - A**2], y0=[0, 0, 1, 0], T=5,
                                            z0=[-A * c / np.hypot(c, G), -A * G / np.hypot(c, G),
                                                (1 - np.hypot(c, G) / A) / 2]),
        # constant_speed_v1.lag and constant_speed_lets.lag
        "constant_speed_v1": dict(P2, L=(xd**2 + yd**2) / 2 - G * y - 3 * x**2 / 2,
                                  vel=[yd + sp.sqrt(4 - xd**2)], y0=[0, 0, 1.2, -1.6], T=4),
        "speed_set_by_height": dict(P2, L=(xd**2 + yd**2) / 2 - G * y,
                                    vel=[xd**2 + yd**2 - 4 + 6 * y], y0=[0, 0, 1.2, 1.6], T=3),
        "constant_speed_drag_and_push": dict(P2, L=(xd**2 + yd**2) / 2 - G * y,
                                             Q=[-0.7 * xd + 3 * sp.cos(2 * t), -0.7 * yd],
                                             vel=[xd**2 + yd**2 - 4], y0=[0, 0, 1.2, 1.6], T=6),
        # sleigh_constant_speed.lag and sleigh_constant_speed_differentiated.lag:
        # the knife edge and the speed constraint as a user first writes them.
        "sleigh_constant_speed": dict(qs=[x, y, th], qds=[xd, yd, thd], qdds=[xdd, ydd, thdd],
                                      head="t,x,y,th,x',y',th'",
                                      L=(vxc**2 + vyc**2) / 2 + J / 2 * thd**2,
                                      Q=[0, 0, 0.3 * sp.sin(1.5 * t)],
                                      vel=[sp.sin(th) * xd - sp.cos(th) * yd, xd**2 + yd**2 - 1],
                                      y0=[0, 0, 0.3, np.cos(0.3), np.sin(0.3), 1], T=20),
        "gearing_on_height": dict(P2, L=(xd**2 + yd**2) / 2 - G * y - x**2,
                                  acc=[ydd - (1 + sp.Rational(1, 5) * y) * xdd], y0=[1, 0, 0, 0.5], T=10),
    }


def main():
    only = sys.argv[1:]
    for name, m in models().items():
        if only and name not in only:
            continue
        f, root = rhs(m["L"], m["qs"], m["qds"], m["qdds"], m.get("vel", ()), m.get("acc", ()), m.get("Q"))
        if "z0" in m:
            root["z"] = np.array(m["z0"], dtype=float)
        ts = np.linspace(0.0, m["T"], 41)
        s = solve_ivp(f, (0.0, m["T"]), m["y0"], method="DOP853", rtol=2.3e-14, atol=1e-15, t_eval=ts)
        assert s.success, s.message
        path = os.path.join(OUT, name + ".csv")
        with open(path, "w") as out:
            out.write(m["head"] + "\n")
            for tt, row in zip(ts, s.y.T):
                out.write(",".join(repr(float(v)) for v in [tt, *row]) + "\n")
        print(path)


if __name__ == "__main__":
    main()
