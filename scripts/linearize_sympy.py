#!/usr/bin/env python3
"""`lagc linearize` against SymPy's `linearize` (sympy.physics.mechanics) on
the same physics derived independently, in other coordinates:

- the spherical pendulum: lagc in two rotation angles
  (examples/spherical_pendulum.lag) and in Cartesian coordinates on the
  sphere, a holonomic constraint (tests/data/v2/spherical_pendulum_cartesian.lag);
  SymPy in the bob's horizontal
  Cartesian coordinates x, y with z = -sqrt(l^2 - x^2 - y^2), by
  LagrangesMethod, linearized at the bottom;
- the double pendulum (examples/double_pendulum_energy.lag): SymPy with
  reference frames and particles, LagrangesMethod, hanging and inverted;
- the thin disk rolling upright (examples/rolling_disk_3d.lag: contact
  point, heading, tilt, spin, two non-holonomic constraints): SymPy's
  rolling-disc model from its documentation (yaw, lean, spin, the body's
  angular velocity in the lean frame as generalized speeds, rolling by the
  centre's velocity from the contact point at rest), KanesMethod,
  linearized about steady upright rolling with spin Omega.
- Chaplygin's sleigh (examples/chaplygin_sleigh.lag): SymPy with the
  sleigh's forward speed and spin as generalized speeds, the lateral
  velocity of the blade constrained to zero (KanesMethod with a
  dependent speed), linearized about straight motion.

The two state vectors differ (SymPy keeps the ignorable coordinates and
uses other velocities), so the eigenvalues are compared, those of lagc
with SymPy's: every non-zero eigenvalue of either must be matched within
1e-8 (relative to the largest) and the rest of both be zero.

Run: cargo build && python3 scripts/linearize_sympy.py [path/to/lagc]
(default target/debug/lagc). Its output is recorded in
docs/linearize_sympy.txt. Exit status 1 when a case disagrees.
"""
import json
import math
import subprocess
import sys

import numpy as np
import sympy as sp
import sympy.physics.mechanics as me

LAGC = sys.argv[1] if len(sys.argv) > 1 else "target/debug/lagc"
TOL = 1e-8


def lagc_eigenvalues(model, at, params=""):
    args = [LAGC, "linearize", model, "--at", at, "--format", "json"]
    if params:
        args += ["--param", params]
    out = subprocess.run(args, capture_output=True, text=True, check=True)
    data = json.loads(out.stdout)
    return np.array([complex(re, im) for re, im in data["eigenvalues"]])


def numeric_eigenvalues(a_matrix, values):
    a = np.array(sp.Matrix(a_matrix).subs(values).evalf(30).tolist(), dtype=float)
    return np.linalg.eigvals(a)


def lagrange_linearize(lagrangian, qs, op):
    t = me.dynamicsymbols._t
    lm = me.LagrangesMethod(lagrangian, qs)
    lm.form_lagranges_equations()
    qds = [q.diff(t) for q in qs]
    qdds = [q.diff(t, 2) for q in qs]
    point = dict(op)
    point.update({qd: 0 for qd in qds if qd not in point})
    point.update({qdd: 0 for qdd in qdds})
    a_matrix, _, _ = lm.linearize(q_ind=qs, qd_ind=qds, A_and_B=True, op_point=point)
    return a_matrix


def spherical(l_value, g_value):
    x, y = me.dynamicsymbols("x y")
    l, g, m = sp.symbols("l g m", positive=True)
    t = me.dynamicsymbols._t
    z = -sp.sqrt(l**2 - x**2 - y**2)
    v2 = x.diff(t) ** 2 + y.diff(t) ** 2 + z.diff(t) ** 2
    lag = m / 2 * v2 - m * g * z
    a_matrix = lagrange_linearize(lag, [x, y], {x: 0, y: 0})
    return numeric_eigenvalues(a_matrix, {l: l_value, g: g_value, m: 1})


def double_pendulum(l1v, l2v, m1v, m2v, gv, a0, b0):
    q1, q2 = me.dynamicsymbols("q1 q2")
    l1, l2, m1, m2, g = sp.symbols("l1 l2 m1 m2 g", positive=True)
    n = me.ReferenceFrame("N")
    o = me.Point("O")
    o.set_vel(n, 0)
    p1 = o.locatenew("P1", l1 * (sp.sin(q1) * n.x - sp.cos(q1) * n.y))
    p1.set_vel(n, p1.pos_from(o).dt(n))
    p2 = p1.locatenew("P2", l2 * (sp.sin(q2) * n.x - sp.cos(q2) * n.y))
    p2.set_vel(n, p2.pos_from(o).dt(n))
    b1, b2 = me.Particle("B1", p1, m1), me.Particle("B2", p2, m2)
    b1.potential_energy = m1 * g * me.dot(p1.pos_from(o), n.y)
    b2.potential_energy = m2 * g * me.dot(p2.pos_from(o), n.y)
    lag = me.Lagrangian(n, b1, b2)
    a_matrix = lagrange_linearize(lag, [q1, q2], {q1: a0, q2: b0})
    return numeric_eigenvalues(a_matrix, {l1: l1v, l2: l2v, m1: m1v, m2: m2v, g: gv})


def kane_linearize(km, bodies, loads, op):
    km.kanes_equations(bodies, loads)
    result = km.linearize(A_and_B=True, op_point=op)
    return result[0]


def rolling_disc(r_value, m_value, g_value, spin):
    # SymPy's documented rolling disc (KanesMethod).
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols("q1 q2 q3 u1 u2 u3")
    q1d, q2d, q3d = me.dynamicsymbols("q1 q2 q3", 1)
    u1d, u2d, u3d = me.dynamicsymbols("u1 u2 u3", 1)
    r, m, g = sp.symbols("r m g")
    n = me.ReferenceFrame("N")
    yaw = n.orientnew("Y", "Axis", [q1, n.z])
    lean = yaw.orientnew("L", "Axis", [q2, yaw.x])
    disc = lean.orientnew("R", "Axis", [q3, lean.y])
    w_qd = disc.ang_vel_in(n)
    disc.set_ang_vel(n, u1 * lean.x + u2 * lean.y + u3 * lean.z)
    contact = me.Point("C")
    contact.set_vel(n, 0)
    centre = contact.locatenew("Dmc", r * lean.z)
    centre.v2pt_theory(contact, n, disc)
    inertia = me.inertia(lean, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    kd = [me.dot(disc.ang_vel_in(n) - w_qd, uv) for uv in lean]
    body = me.RigidBody("D", centre, disc, m, (inertia, centre))
    km = me.KanesMethod(n, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=kd)
    op = {q1: 0, q2: 0, q3: 0, u1: 0, u2: spin, u3: 0,
          q1d: 0, q2d: 0, q3d: spin, u1d: 0, u2d: 0, u3d: 0}
    a_matrix = kane_linearize(km, [body], [(centre, -m * g * yaw.z)], op)
    return numeric_eigenvalues(a_matrix, {r: r_value, m: m_value, g: g_value})


def sleigh(m_value, a_value, j_value, speed):
    # The blade at P (x, y), heading th; the centre of mass a ahead.
    x, y, th = me.dynamicsymbols("x y th")
    v, w, s = me.dynamicsymbols("v w s")  # forward, spin, lateral (dependent)
    m, a, j = sp.symbols("m a J")
    n = me.ReferenceFrame("N")
    body = n.orientnew("B", "Axis", [th, n.z])
    body.set_ang_vel(n, w * n.z)
    o = me.Point("O")
    o.set_vel(n, 0)
    blade = o.locatenew("P", x * n.x + y * n.y)
    blade.set_vel(n, v * body.x + s * body.y)
    centre = blade.locatenew("G", a * body.x)
    centre.v2pt_theory(blade, n, body)
    t = me.dynamicsymbols._t
    vel = x.diff(t) * n.x + y.diff(t) * n.y
    kd = [me.dot(vel, body.x) - v, me.dot(vel, body.y) - s, th.diff(t) - w]
    rigid = me.RigidBody("S", centre, body, m, (me.inertia(body, 0, 0, j), centre))
    km = me.KanesMethod(n, q_ind=[x, y, th], u_ind=[v, w], u_dependent=[s],
                        kd_eqs=kd, velocity_constraints=[s])
    op = {x: 0, y: 0, th: 0, v: speed, w: 0, s: 0}
    op.update({q.diff(t): 0 for q in [x, y, th, v, w, s]})
    op[x.diff(t)] = speed
    a_matrix = kane_linearize(km, [rigid], [], op)
    return numeric_eigenvalues(a_matrix, {m: m_value, a: a_value, j: j_value})


def compare(name, ours, theirs):
    scale = max(1.0, max(abs(ours), default=0.0), max(abs(theirs), default=0.0))
    zero = TOL * scale
    ours_nz = sorted((e for e in ours if abs(e) > zero), key=lambda c: (c.real, c.imag))
    theirs_nz = sorted((e for e in theirs if abs(e) > zero), key=lambda c: (c.real, c.imag))
    ok = len(ours_nz) == len(theirs_nz)
    worst = 0.0
    left = list(theirs_nz)
    for e in ours_nz:
        if not left:
            ok = False
            break
        k = min(range(len(left)), key=lambda i: abs(left[i] - e))
        worst = max(worst, abs(left[k] - e) / scale)
        left.pop(k)
    ok = ok and worst <= TOL
    fmt = lambda es: ", ".join(f"{e.real:+.12f}{e.imag:+.12f}i" for e in es)
    print(f"{name}")
    print(f"  lagc:  {fmt(ours_nz)}  (+{len(ours) - len(ours_nz)} zero)")
    print(f"  sympy: {fmt(theirs_nz)}  (+{len(theirs) - len(theirs_nz)} zero)")
    print(f"  largest difference {worst:.2e} (relative to {scale:.3g}): {'ok' if ok else 'DISAGREE'}")
    return ok


def main():
    good = True
    for l_value, g_value in [(1.5, 9.81), (0.7, 3.0)]:
        good &= compare(
            f"spherical pendulum at the bottom, l = {l_value}, g = {g_value}",
            lagc_eigenvalues("examples/spherical_pendulum.lag", "a=0,b=0,a'=0,b'=0",
                             f"l={l_value},g={g_value}"),
            spherical(l_value, g_value))
        good &= compare(
            f"spherical pendulum on x^2 + y^2 + z^2 = l^2 (holonomic), l = {l_value}, g = {g_value}",
            lagc_eigenvalues("tests/data/v2/spherical_pendulum_cartesian.lag",
                             "x=0,y=0,x'=0,y'=0", f"l={l_value},g={g_value}"),
            spherical(l_value, g_value))
    pi = math.pi
    for params in [(1.0, 1.0, 1.0, 1.0, 9.81), (1.3, 0.7, 2.0, 0.5, 9.81)]:
        p = "l1={},l2={},m1={},m2={},g={}".format(*params)
        for a0, label in [(0.0, "hanging"), (pi, "inverted")]:
            good &= compare(
                f"double pendulum {label}, {p}",
                lagc_eigenvalues("examples/double_pendulum_energy.lag",
                                 f"a={a0!r},b={a0!r},a'=0,b'=0", p),
                double_pendulum(*params, a0, a0))
    for r_value, m_value, g_value, spin in [(1.0, 1.0, 9.81, 4.0), (0.5, 2.0, 9.81, 1.5),
                                            (0.2, 1.0, 3.7, 7.0)]:
        p = f"R={r_value},m={m_value},g={g_value}"
        good &= compare(
            f"thin disk rolling upright, spin {spin}, {p} (critical spin {math.sqrt(g_value / (3 * r_value)):.6f})",
            lagc_eigenvalues("examples/rolling_disk_3d.lag", f"th=0,th'=0,phi'=0,psi'={-spin}", p),
            rolling_disc(r_value, m_value, g_value, spin))
    for speed in [1.0, -2.0]:
        good &= compare(
            f"Chaplygin's sleigh running straight at {speed}",
            lagc_eigenvalues("examples/chaplygin_sleigh.lag", f"th=0,x'={speed},th'=0"),
            sleigh(1.0, 0.01, 0.02, speed))
    print("all agree" if good else "SOME DISAGREE")
    return 0 if good else 1


if __name__ == "__main__":
    sys.exit(main())
