#!/usr/bin/env python3
"""References for tests/data/textbook_loops/*.lag (tests/it/textbook_loops.rs).

Two routes per model, both independent of lagc's elimination (equations (4)):
  1. the Cartesian multiplier form, M q'' = -dV/dq + Q + J^T lam with
     J q'' = -gamma (the holonomic constraints f(t, q) = 0 differentiated
     twice), derived here by SymPy from each model's Lagrangian as written
     below (not read from the .lag files) and solved as one augmented
     linear system at every evaluation (M may be singular: the four-bar's
     mass sits on the coupler alone);
  2. a closed form, or the Lagrangian in minimal coordinates derived by
     SymPy and integrated by itself (not for the four-bar).
Both are integrated by SciPy's DOP853 at rtol 1e-13, atol 1e-14; the script
prints their largest difference and the multiplier route's constraint
residual, and writes route 2 (route 1 for the four-bar) to
tests/data/textbook_loops/<name>.csv: t and the state columns, 41 rows.

The start is lagc's: the dependent positions put on the constraints by
Newton over them alone from the values the file gives, the dependent
velocities from the constraints' derivative (the dependents are those
lagc picks: a coordinate on the left side, else the last declared).

Run: /work/scratch/refvenv/bin/python scripts/textbook_loops_reference.py
Scan: ... scripts/textbook_loops_reference.py --scan target/release/lagc [RTOL ...]
  (each model by both methods at rtol 1e-6, 1e-9, 1e-12, atol = rtol/100, at
  the CSV's times: the largest state-column error relative to max(|x|, 1) in
  rtol, whether the summary said "within" or warned, its largest residual)."""
import os

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

t = sp.Symbol("t")
OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "textbook_loops")
ROWS = 41
TOL = dict(method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)


def multiplier_route(T, V, cons, qs, qds, forces=None):
    """q' -> (q', q'') of M q'' = -V_q + Q + J^T lam, J q'' = -gamma (T quadratic in q', M constant)."""
    n = len(qs)
    M = sp.Matrix(n, n, lambda i, j: sp.diff(T, qds[i], qds[j]))
    assert all(sp.diff(M[i, j], v) == 0 for i in range(n) for j in range(n) for v in list(qs) + [t])
    rhs = [-sp.diff(V, q) + (forces[i] if forces else 0) for i, q in enumerate(qs)]
    J = sp.Matrix([[sp.diff(f, q) for q in qs] for f in cons])
    fdot = [sp.diff(f, t) + sum(sp.diff(f, q) * v for q, v in zip(qs, qds)) for f in cons]
    gamma = [sp.diff(e, t) + sum(sp.diff(e, q) * v for q, v in zip(qs, qds)) for e in fdot]
    args = [t] + list(qs) + list(qds)
    Mf, Jf = sp.lambdify(args, M), sp.lambdify(args, J)
    rf, gf = sp.lambdify(args, rhs), sp.lambdify(args, gamma)
    m = len(cons)

    def f(tt, y):
        a = [tt] + list(y)
        Mn, Jn = np.array(Mf(*a), float), np.array(Jf(*a), float)
        A = np.block([[Mn, -Jn.T], [Jn, np.zeros((m, m))]])
        b = np.concatenate([np.array(rf(*a), float), -np.array(gf(*a), float)])
        return np.concatenate([y[n:], np.linalg.solve(A, b)[:n]])

    residual = sp.lambdify(args, [sp.Matrix(cons), sp.Matrix(fdot)])
    return f, residual


def lagc_start(cons, qs, qds, given, dependents, given_velocities):
    """lagc's initial state: Newton on f = 0 over the dependents, then their velocities."""
    q = dict(given)
    dep = [qs.index(d) for d in dependents]
    F = sp.lambdify([t] + list(qs), cons)
    J = sp.lambdify([t] + list(qs), sp.Matrix([[sp.diff(f, qs[j]) for j in dep] for f in cons]))
    x = np.array([q.get(str(s), 0.0) for s in qs], float)
    for _ in range(50):
        dx = np.linalg.solve(np.array(J(0.0, *x), float), np.array(F(0.0, *x), float))
        x[dep] -= dx
        if np.max(np.abs(dx)) < 1e-16:
            break
    fdot = [sp.diff(f, t) + sum(sp.diff(f, qq) * v for qq, v in zip(qs, qds)) for f in cons]
    v = np.array([given_velocities.get(str(s), 0.0) for s in qds], float)
    args = [t] + list(qs) + list(qds)
    Fd = sp.lambdify(args, fdot)
    Jd = sp.Matrix([[sp.diff(f, qds[j]) for j in dep] for f in fdot])
    Jdf = sp.lambdify(args, Jd)
    v[dep] = 0.0
    v[dep] -= np.linalg.solve(np.array(Jdf(0.0, *x, *v), float), np.array(Fd(0.0, *x, *v), float))
    return np.concatenate([x, v])


def integrate(f, y0, span):
    sol = solve_ivp(f, span, y0, **TOL)
    assert sol.success, sol.message
    times = np.linspace(span[0], span[1], ROWS)
    return times, sol.sol(times).T


def minimal_route(T, V, qs, qds, forces=None):
    """Lagrange's equations in minimal coordinates: q' -> (q', q'')."""
    n = len(qs)
    L = T - V
    M = sp.Matrix(n, n, lambda i, j: sp.diff(L, qds[i], qds[j]))
    p = [sp.diff(L, v) for v in qds]
    rest = [sum(sp.diff(p[i], q) * v for q, v in zip(qs, qds)) + sp.diff(p[i], t) - sp.diff(L, qs[i])
            - (forces[i] if forces else 0) for i in range(n)]
    args = [t] + list(qs) + list(qds)
    Mf, rf = sp.lambdify(args, M), sp.lambdify(args, rest)

    def f(tt, y):
        a = [tt] + list(y)
        return np.concatenate([y[n:], np.linalg.solve(np.array(Mf(*a), float), -np.array(rf(*a), float))])

    return f


def write(name, head, times, states):
    path = os.path.join(OUT, f"{name}.csv")
    with open(path, "w") as out:
        out.write(",".join(["t"] + head) + "\n")
        for tt, row in zip(times, states):
            out.write(",".join(repr(float(v)) for v in [tt] + list(row)) + "\n")


def report(name, head, times, cart, other, residual, qs):
    """Largest difference between the routes (relative to max(|x|, 1)) and the residual."""
    scale = np.maximum(np.max(np.abs(other), axis=0), 1.0)
    diff = np.max(np.abs(cart - other) / scale) if other is not None else float("nan")
    n = len(qs)
    res = max(np.max(np.abs(np.concatenate([np.ravel(r) for r in residual(tt, *y)])))
              for tt, y in zip(times, cart))
    print(f"{name:30s} routes differ {diff:.1e}; multiplier route's residual {res:.1e}")


def symbols(names):
    qs = sp.symbols(names)
    qds = sp.symbols([f"{q}_d" for q in names.split()])
    return list(qs), list(qds)


def double_atwood():
    m1, mp, m2, m3, g, L1, L2 = 4, sp.Rational(1, 2), 1, 2, sp.Rational(981, 100), 3, 2
    qs, qds = symbols("y1 yp y2 y3")
    y1, yp, y2, y3 = qs
    T = sum(m / 2 * v**2 for m, v in zip([m1, mp, m2, m3], qds))
    V = -g * (m1 * y1 + mp * yp + m2 * y2 + m3 * y3)
    cons = [y1 + yp - L1, (y2 - yp) + (y3 - yp) - L2]
    y0 = lagc_start(cons, qs, qds, {"y1": 1, "yp": 2, "y2": 3, "y3": 3}, [yp, y3],
                    {"y1_d": 0.1, "y2_d": 0.2})
    f, residual = multiplier_route(T, V, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 1.5))
    # Closed form: yp = L1 - y1, y3 = L2 + 2 L1 - 2 y1 - y2, then constant accelerations.
    a1, a2 = sp.symbols("a1 a2")
    u1, u2 = sp.symbols("u1 u2")
    Tm = (m1 + mp) / 2 * u1**2 + m2 / 2 * u2**2 + m3 / 2 * (2 * u1 + u2)**2
    Vm = -g * (m1 * y1 + mp * (L1 - y1) + m2 * y2 + m3 * (L2 + 2 * L1 - 2 * y1 - y2))
    eqs = [sp.diff(Tm, u).subs({u1: a1, u2: a2}) + sp.diff(Vm, q) for u, q in [(u1, y1), (u2, y2)]]
    acc = sp.solve(eqs, [a1, a2])
    A1, A2 = float(acc[a1]), float(acc[a2])
    Y1 = y0[0] + y0[4] * times + A1 * times**2 / 2
    Y2 = y0[2] + y0[6] * times + A2 * times**2 / 2
    V1, V2 = y0[4] + A1 * times, y0[6] + A2 * times
    exact = np.column_stack([Y1, L1 - Y1, Y2, L2 + 2 * L1 - 2 * Y1 - Y2, V1, -V1, V2, -2 * V1 - V2])
    print(f"double_atwood accelerations: y1'' = {A1!r} ({acc[a1]}), y2'' = {A2!r} ({acc[a2]})")
    report("double_atwood", None, times, cart, exact, residual, qs)
    write("double_atwood", ["y1", "yp", "y2", "y3", "y1'", "yp'", "y2'", "y3'"], times, exact)


def bead_rotating_parabola(name="bead_rotating_parabola", w=3):
    c, g = 1, sp.Rational(981, 100)
    qs, qds = symbols("x y z")
    x, y, z = qs
    T = sum(v**2 for v in qds) / 2
    V = g * z
    cons = [z - c * (x**2 + y**2), y * sp.cos(w * t) - x * sp.sin(w * t)]
    y0 = lagc_start(cons, qs, qds, {"x": 0.5, "y": 0, "z": 0.25}, [z, y], {"x_d": 0.1})
    f, residual = multiplier_route(T, V, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 4))
    # Minimal: the distance r from the axis along the wire.
    r, rd = sp.symbols("r r_d")
    Tm = (rd**2 * (1 + 4 * c**2 * r**2) + w**2 * r**2) / 2
    fm = minimal_route(Tm, g * c * r**2, [r], [rd])
    _, rm = integrate(fm, [0.5, 0.1], (0, 4))
    R, Rd = rm[:, 0], rm[:, 1]
    cw, sw = np.cos(w * times), np.sin(w * times)
    other = np.column_stack([R * cw, R * sw, R**2, Rd * cw - w * R * sw, Rd * sw + w * R * cw, 2 * R * Rd])
    report(name, None, times, cart, other, residual, qs)
    write(name, ["x", "y", "z", "x'", "y'", "z'"], times, other)


def bead_on_ellipse(name="bead_on_ellipse", given=(1.8, 0.4), xd0=0.0):
    a, b, g = 2, 1, sp.Rational(981, 100)
    qs, qds = symbols("x y")
    x, y = qs
    T = sum(v**2 for v in qds) / 2
    cons = [x**2 / a**2 + y**2 / b**2 - 1]
    y0 = lagc_start(cons, qs, qds, {"x": given[0], "y": given[1]}, [y], {"x_d": xd0})
    f, residual = multiplier_route(T, g * y, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 5))
    # Minimal: x = a sin(th), y = -b cos(th).
    th, thd = sp.symbols("th th_d")
    Tm = (a**2 * sp.cos(th)**2 + b**2 * sp.sin(th)**2) * thd**2 / 2
    fm = minimal_route(Tm, -g * b * sp.cos(th), [th], [thd])
    th0 = np.arctan2(y0[0] / a, -y0[1] / b)
    _, m = integrate(fm, [th0, xd0 / (a * np.cos(th0))], (0, 5))
    Th, Thd = m[:, 0], m[:, 1]
    other = np.column_stack([a * np.sin(Th), -b * np.cos(Th), a * np.cos(Th) * Thd, b * np.sin(Th) * Thd])
    report(name, None, times, cart, other, residual, qs)
    write(name, ["x", "y", "x'", "y'"], times, other)


def four_bar_coupler_mass():
    l1, l2, l3, d, m, g = 1, 2, sp.Rational(3, 2), sp.Rational(11, 5), 1, sp.Rational(981, 100)
    qs, qds = symbols("xa ya xb yb")
    xa, ya, xb, yb = qs
    cx, cy = (qds[0] + qds[2]) / 2, (qds[1] + qds[3]) / 2
    T = m / 2 * (cx**2 + cy**2)
    V = m * g * (ya + yb) / 2
    cons = [xa**2 + ya**2 - l1**2, (xb - xa)**2 + (yb - ya)**2 - l2**2, (xb - d)**2 + yb**2 - l3**2]
    y0 = lagc_start(cons, qs, qds, {"xa": 0.5403, "ya": 0.84, "xb": 2.5, "yb": 1.4}, [ya, yb, xb], {})
    f, residual = multiplier_route(T, V, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 4))
    E = [float(T.subs(dict(zip(qds, s[4:]))) + V.subs(dict(zip(qs, s[:4])))) for s in cart]
    print(f"four_bar_coupler_mass: energy {E[0]!r}, spread {max(E) - min(E):.1e}")
    # Minimal: the crank's angle a; B where the circles about A (l2) and D
    # (l3) meet, on the side of the line A D the start has B on.
    a, ad = sp.symbols("a a_d")
    Ax, Ay = l1 * sp.cos(a), l1 * sp.sin(a)
    ex, ey = d - Ax, -Ay
    delta = sp.sqrt(ex**2 + ey**2)
    p = (l2**2 - l3**2 + delta**2) / (2 * delta)
    h = sp.sqrt(l2**2 - p**2)
    e0 = (float(d) - y0[0], -y0[1])
    side = float(np.sign(e0[0] * (y0[3] - y0[1]) - e0[1] * (y0[2] - y0[0])))  # cross(D - A, B - A)
    Bx = Ax + p * ex / delta + side * h * (-ey) / delta
    By = Ay + p * ey / delta + side * h * ex / delta
    Cx, Cy = (Ax + Bx) / 2, (Ay + By) / 2
    Tm = m / 2 * (sp.diff(Cx, a)**2 + sp.diff(Cy, a)**2) * ad**2
    fm = minimal_route(Tm, m * g * Cy, [a], [ad])
    _, mm = integrate(fm, [np.arctan2(y0[1], y0[0]), 0.0], (0, 4))
    pos = sp.lambdify([a], [Ax, Ay, Bx, By])
    vel = sp.lambdify([a, ad], [sp.diff(e, a) * ad for e in (Ax, Ay, Bx, By)])
    other = np.array([list(pos(A)) + list(vel(A, Ad)) for A, Ad in mm], float)
    assert np.max(np.abs(other[0] - y0)) < 1e-12, (other[0], y0)
    report("four_bar_coupler_mass", None, times, cart, other, residual, qs)
    write("four_bar_coupler_mass", ["xa", "ya", "xb", "yb", "xa'", "ya'", "xb'", "yb'"], times, other)


def pendulum_on_sliding_support(name="pendulum_on_sliding_support", bob=(0.6, -0.8)):
    M, m, k, l, g = 2, 1, 10, 1, sp.Rational(981, 100)
    qs, qds = symbols("s x y")
    s, x, y = qs
    T = M / 2 * qds[0]**2 + m / 2 * (qds[1]**2 + qds[2]**2)
    V = k / 2 * s**2 + m * g * y
    cons = [(x - s)**2 + y**2 - l**2]
    y0 = lagc_start(cons, qs, qds, {"s": 0, "x": bob[0], "y": bob[1]}, [y], {}) if bob[1] else np.array(
        [0, bob[0], bob[1], 0, 0, 0], float)  # released level: lagc takes the start as given
    f, residual = multiplier_route(T, V, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 6))
    # Minimal: s and the rod's angle th, x = s + l sin(th), y = -l cos(th).
    th, sd, thd = sp.symbols("th s_d th_d")
    Tm = M / 2 * sd**2 + m / 2 * ((sd + l * sp.cos(th) * thd)**2 + (l * sp.sin(th) * thd)**2)
    fm = minimal_route(Tm, k / 2 * s**2 - m * g * l * sp.cos(th), [s, th], [sd, thd])
    _, mm = integrate(fm, [0.0, np.arctan2(y0[1], -y0[2]), 0.0, 0.0], (0, 6))
    S, Th, Sd, Thd = mm.T
    other = np.column_stack([S, S + np.sin(Th), -np.cos(Th), Sd, Sd + np.cos(Th) * Thd, np.sin(Th) * Thd])
    report(name, None, times, cart, other, residual, qs)
    write(name, ["s", "x", "y", "s'", "x'", "y'"], times, other)


def cylinder_on_plank():
    M, m, R, k = 3, 2, sp.Rational(3, 10), 12
    qs, qds = symbols("s x phi")
    s, x, phi = qs
    T = M / 2 * qds[0]**2 + m / 2 * qds[1]**2 + m * R**2 / 4 * qds[2]**2
    cons = [x - R * phi - s]
    y0 = lagc_start(cons, qs, qds, {"s": 0.2, "x": 0, "phi": 0}, [x], {"s_d": 0, "phi_d": 1})
    f, residual = multiplier_route(T, k / 2 * s**2, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 5))
    # Closed form: (M + m/3) s'' = -k s, R phi'' = -2/3 s''.
    Mf, Rf = 3.0, 0.3
    W = np.sqrt(12.0 / (Mf + 2.0 / 3))
    s0, sd0, ph0, phd0 = y0[0], y0[3], y0[2], y0[5]
    S = s0 * np.cos(W * times) + sd0 / W * np.sin(W * times)
    Sd = -s0 * W * np.sin(W * times) + sd0 * np.cos(W * times)
    Ph = ph0 + phd0 * times - 2 / (3 * Rf) * (S - s0 - sd0 * times)
    Phd = phd0 - 2 / (3 * Rf) * (Sd - sd0)
    exact = np.column_stack([S, Rf * Ph + S, Ph, Sd, Rf * Phd + Sd, Phd])
    report("cylinder_on_plank", None, times, cart, exact, residual, qs)
    write("cylinder_on_plank", ["s", "x", "phi", "s'", "x'", "phi'"], times, exact)


def yoyo_moving_hand():
    m, R, r, g, A, w = sp.Rational(1, 5), sp.Rational(1, 20), sp.Rational(1, 100), sp.Rational(981, 100), sp.Rational(1, 10), 6
    I = m * R**2 / 2
    qs, qds = symbols("y phi")
    y, phi = qs
    T = m / 2 * qds[0]**2 + I / 2 * qds[1]**2
    cons = [y - A * sp.sin(w * t) + r * phi]
    y0 = lagc_start(cons, qs, qds, {"y": 0, "phi": 0}, [y], {"phi_d": 0})
    f, residual = multiplier_route(T, m * g * y, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 3))
    # Closed form: (m + I/r^2) y'' = -m g + I/r^2 yh'', yh = A sin(w t).
    mf, If, rf, gf, Af = 0.2, float(I), 0.01, 9.81, 0.1
    ke = If / rf**2
    yh, yhd = Af * np.sin(w * times), Af * w * np.cos(w * times)
    Y = y0[0] + y0[2] * times - gf * mf / (mf + ke) * times**2 / 2 + ke / (mf + ke) * (yh - Af * w * times)
    Yd = y0[2] - gf * mf / (mf + ke) * times + ke / (mf + ke) * (yhd - Af * w)
    exact = np.column_stack([Y, (yh - Y) / rf, Yd, (yhd - Yd) / rf])
    report("yoyo_moving_hand", None, times, cart, exact, residual, qs)
    write("yoyo_moving_hand", ["y", "phi", "y'", "phi'"], times, exact)


def hanging_chain_3(name="hanging_chain_3", given=(0.3, -0.4, 0.5, -0.85, 0.9, -1.1)):
    m, l, g = 1, sp.Rational(1, 2), sp.Rational(981, 100)
    qs, qds = symbols("x1 y1 x2 y2 x3 y3")
    x1, y1, x2, y2, x3, y3 = qs
    T = m / 2 * sum(v**2 for v in qds)
    V = m * g * (y1 + y2 + y3)
    cons = [x1**2 + y1**2 - l**2, (x2 - x1)**2 + (y2 - y1)**2 - l**2, (x3 - x2)**2 + (y3 - y2)**2 - l**2]
    if any(given[1::2]):
        y0 = lagc_start(cons, qs, qds, dict(zip(map(str, qs), given)), [y1, y2, y3], {})
    else:  # released level: lagc takes the start as given
        y0 = np.concatenate([given, np.zeros(6)])
    f, residual = multiplier_route(T, V, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 3))
    # Minimal: the rods' angles from the downward vertical.
    ths = list(sp.symbols("a1 a2 a3"))
    thds = list(sp.symbols("a1_d a2_d a3_d"))
    px, py, vx, vy, Tm, Vm = 0, 0, 0, 0, 0, 0
    for a, ad in zip(ths, thds):
        px, py = px + l * sp.sin(a), py - l * sp.cos(a)
        vx, vy = vx + l * sp.cos(a) * ad, vy + l * sp.sin(a) * ad
        Tm, Vm = Tm + m / 2 * (vx**2 + vy**2), Vm + m * g * py
    fm = minimal_route(Tm, Vm, ths, thds)
    p = y0[:6].reshape(3, 2)
    links = p - np.vstack([[0.0, 0.0], p[:-1]])
    a0 = np.arctan2(links[:, 0], -links[:, 1])
    _, mm = integrate(fm, np.concatenate([a0, np.zeros(3)]), (0, 3))
    ln = 0.5
    cols_p, cols_v = [], []
    X = Y = VX = VY = 0.0
    for i in range(3):
        a, ad = mm[:, i], mm[:, 3 + i]
        X, Y = X + ln * np.sin(a), Y - ln * np.cos(a)
        VX, VY = VX + ln * np.cos(a) * ad, VY + ln * np.sin(a) * ad
        cols_p += [X, Y]
        cols_v += [VX, VY]
    other = np.column_stack(cols_p + cols_v)
    report(name, None, times, cart, other, residual, qs)
    head = ["x1", "y1", "x2", "y2", "x3", "y3", "x1'", "y1'", "x2'", "y2'", "x3'", "y3'"]
    write(name, head, times, other)




def pendulum_pulled_through_hole():
    l0, v, g = 1, sp.Rational(1, 10), sp.Rational(981, 100)
    qs, qds = symbols("x y")
    x, y = qs
    T = sum(u**2 for u in qds) / 2
    cons = [x**2 + y**2 - (l0 - v * t)**2]
    y0 = lagc_start(cons, qs, qds, {"x": 0.5, "y": -0.866}, [y], {"x_d": 0})
    f, residual = multiplier_route(T, g * y, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 6))
    # Minimal: the angle th from the downward vertical, r = l0 - v t given.
    th, thd = sp.symbols("th th_d")
    r = l0 - v * t
    rd = sp.diff(r, t)
    Tm = ((rd * sp.sin(th) + r * sp.cos(th) * thd)**2 + (-rd * sp.cos(th) + r * sp.sin(th) * thd)**2) / 2
    fm = minimal_route(Tm, -g * r * sp.cos(th), [th], [thd])
    th0 = np.arctan2(y0[0], -y0[1])
    _, m = integrate(fm, [th0, 0.1 * np.tan(th0)], (0, 6))  # x' = 0: r th' cos(th) = -r' sin(th)
    Th, Thd = m[:, 0], m[:, 1]
    R, Rd = 1 - 0.1 * times, -0.1
    other = np.column_stack([R * np.sin(Th), -R * np.cos(Th), Rd * np.sin(Th) + R * np.cos(Th) * Thd,
                             -Rd * np.cos(Th) + R * np.sin(Th) * Thd])
    assert np.max(np.abs(other[0] - y0)) < 1e-14, (other[0], y0)
    report("pendulum_pulled_through_hole", None, times, cart, other, residual, qs)
    write("pendulum_pulled_through_hole", ["x", "y", "x'", "y'"], times, other)


def ladder_sliding_down_wall():
    m, l, g = 1, 2, sp.Rational(981, 100)
    qs, qds = symbols("xa yb")
    xa, yb = qs
    T = m / 2 * (qds[0]**2 + qds[1]**2) / 4 + m * l**2 / 24 * (qds[0]**2 + qds[1]**2) / l**2
    cons = [xa**2 + yb**2 - l**2]
    y0 = lagc_start(cons, qs, qds, {"xa": 0.2, "yb": 1.99}, [yb], {"xa_d": 0})
    f, residual = multiplier_route(T, m * g * yb / 2, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 2))
    # Minimal: the angle th from the wall, th'' = 3 g/(2 l) sin(th).
    th0 = np.arctan2(y0[0], y0[1])
    _, mm = integrate(lambda tt, s: [s[1], 3 * 9.81 / 4 * np.sin(s[0])], [th0, 0.0], (0, 2))
    Th, Thd = mm.T
    other = np.column_stack([2 * np.sin(Th), 2 * np.cos(Th), 2 * np.cos(Th) * Thd, -2 * np.sin(Th) * Thd])
    report("ladder_sliding_down_wall", None, times, cart, other, residual, qs)
    write("ladder_sliding_down_wall", ["xa", "yb", "xa'", "yb'"], times, other)


def block_on_sliding_wedge():
    M, m, a, g = 3, 1, sp.Rational(1, 2), sp.Rational(981, 100)
    qs, qds = symbols("X x y")
    X, x, y = qs
    T = M / 2 * qds[0]**2 + m / 2 * (qds[1]**2 + qds[2]**2)
    cons = [y - (X - x) * sp.tan(a)]
    y0 = lagc_start(cons, qs, qds, {"X": 0, "x": -1, "y": 0}, [y], {})
    f, residual = multiplier_route(T, m * g * y, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 1))
    # Closed form: constant accelerations.
    s, c, tn = np.sin(0.5), np.cos(0.5), np.tan(0.5)
    AX = -9.81 * s * c / (3 + s**2)
    Ax = -AX * 3  # momentum: M X'' + m x'' = 0
    Ay = (AX - Ax) * tn
    acc = np.array([AX, Ax, Ay])
    pos = y0[:3] + np.outer(times**2 / 2, acc)
    exact = np.column_stack([pos, np.outer(times, acc)])
    report("block_on_sliding_wedge", None, times, cart, exact, residual, qs)
    write("block_on_sliding_wedge", ["X", "x", "y", "X'", "x'", "y'"], times, exact)


def bead_rotating_hoop():
    R, w, g = sp.Rational(1, 2), 6, sp.Rational(981, 100)
    qs, qds = symbols("x y z")
    x, y, z = qs
    T = sum(v**2 for v in qds) / 2
    cons = [x**2 + y**2 + z**2 - R**2, y * sp.cos(w * t) - x * sp.sin(w * t)]
    y0 = lagc_start(cons, qs, qds, {"x": 0.1, "y": 0, "z": -0.49}, [z, y], {"x_d": 0})
    f, residual = multiplier_route(T, g * z, cons, qs, qds)
    times, cart = integrate(f, y0, (0, 10))
    # Minimal: the angle th from the downward vertical, in the hoop's plane.
    th, thd = sp.symbols("th th_d")
    Tm = R**2 * (thd**2 + w**2 * sp.sin(th)**2) / 2
    fm = minimal_route(Tm, -g * R * sp.cos(th), [th], [thd])
    _, mm = integrate(fm, [np.arctan2(y0[0], -y0[2]), 0.0], (0, 10))
    Th, Thd = mm.T
    r, rd = 0.5 * np.sin(Th), 0.5 * np.cos(Th) * Thd
    c, s_ = np.cos(6 * times), np.sin(6 * times)
    other = np.column_stack([r * c, r * s_, -0.5 * np.cos(Th), rd * c - 6 * r * s_, rd * s_ + 6 * r * c,
                             0.5 * np.sin(Th) * Thd])
    report("bead_rotating_hoop", None, times, cart, other, residual, qs)
    write("bead_rotating_hoop", ["x", "y", "z", "x'", "y'", "z'"], times, other)


def scan(lagc, rtols):
    """Each model by both methods at `rtols` (atol = rtol/100) against its CSV:
    the largest error over the state columns relative to max(|x|, 1), in rtol,
    and what the summary says (global error, constraint residual)."""
    import subprocess
    for name in NAMES:
        ref = np.loadtxt(os.path.join(OUT, f"{name}.csv"), delimiter=",", skiprows=1)
        times = ",".join(repr(float(v)) for v in ref[:, 0])
        scale = np.maximum(np.max(np.abs(ref), axis=0), 1.0)
        lag = os.path.join(OUT, f"{name}.lag")
        for method in ["direct", "field"]:
            for rtol in rtols:
                run = subprocess.run([lagc, "run", lag, "--method", method, "--rtol", f"{rtol:e}",
                                      "--atol", f"{rtol * 1e-2:e}", "--times", times],
                                     capture_output=True, text=True)
                if run.returncode != 0:
                    print(f"{name:28s} {method:6s} {rtol:.0e} exit {run.returncode}: {run.stderr[-300:]}")
                    continue
                got = np.loadtxt(run.stdout.splitlines(), delimiter=",", skiprows=1)[:, :ref.shape[1]]
                err = np.abs(got - ref) / scale
                worst = np.unravel_index(np.argmax(err), err.shape)
                head = run.stdout.splitlines()[0].split(",")
                summary = [l for l in run.stderr.splitlines() if "global error" in l]
                said = "within" if summary and "within" in summary[0] else ("WARNED" if summary else "?")
                kept = [l for l in run.stderr.splitlines() if l.startswith("constraints kept")]
                res = kept[0].split("largest residual ")[1].split(" ")[0] if kept else "-"
                print(f"{name:28s} {method:6s} {rtol:.0e} err/rtol {err[worst] / rtol:7.2f} "
                      f"({head[worst[1]]} at t = {ref[worst[0], 0]:g}); summary: {said}; residual {res}")


MODELS = [double_atwood, bead_rotating_parabola, bead_on_ellipse, four_bar_coupler_mass,
          pendulum_on_sliding_support, cylinder_on_plank, yoyo_moving_hand, hanging_chain_3,
          lambda: bead_rotating_parabola("bead_rotating_parabola_fast", w=5),
          lambda: bead_on_ellipse("bead_around_ellipse", given=(0, -1), xd0=9.0),
          lambda: pendulum_on_sliding_support("pendulum_on_sliding_support_level", bob=(1, 0)),
          lambda: hanging_chain_3("hanging_chain_3_level", given=(0.5, 0, 1, 0, 1.5, 0)),
          pendulum_pulled_through_hole, ladder_sliding_down_wall, block_on_sliding_wedge,
          bead_rotating_hoop]
NAMES = ["double_atwood", "bead_rotating_parabola", "bead_on_ellipse", "four_bar_coupler_mass",
         "pendulum_on_sliding_support", "cylinder_on_plank", "yoyo_moving_hand", "hanging_chain_3",
         "bead_rotating_parabola_fast", "bead_around_ellipse", "pendulum_on_sliding_support_level",
         "hanging_chain_3_level", "pendulum_pulled_through_hole", "ladder_sliding_down_wall",
         "block_on_sliding_wedge", "bead_rotating_hoop"]

if __name__ == "__main__":
    import sys
    if len(sys.argv) > 1 and sys.argv[1] == "--scan":
        scan(sys.argv[2], [float(r) for r in sys.argv[3:]] or [1e-6, 1e-9, 1e-12])
    else:
        for model in MODELS:
            model()
