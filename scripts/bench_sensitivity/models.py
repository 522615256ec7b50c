"""The benchmark's models, derived here with SymPy from their physics (not
from lagc): each is the right side x' = f(t, x, p) over the state lagc
prints, its sensitivity columns in lagc's order, and the start x0(y0, p)
whose derivatives are the columns' initial values (docs/BENCHMARKS.md §15).

A Lagrangian model is reduced by the multiplier form: with the
constraints written at the acceleration level, A(q, q', t) q'' + c = 0
(a holonomic one differentiated twice, a velocity one once), the
equations E(L) = Q + Aᵀλ and A q'' + c = 0 are solved for q'' and λ. On
the constraints this is the reduced system lagc integrates (its modes
agree there); off them it is the index-1 system, whose flow keeps the
constraints (they are invariant), so the sensitivities of a start on them
are those of the constrained motion.
"""
import sympy as sp

t = sp.Symbol("t")


class Model:
    """state: names as lagc prints them; columns: (name, kind) with kind
    "given" or "param"; f: right side; start: the state at t0 as
    expressions of the stated values (symbols named like the columns) and
    the params; values: every symbol's value."""

    def __init__(self, name, lag, t1, x, f, start, columns, values, event=None):
        self.name, self.lag, self.t1 = name, lag, t1
        self.x, self.f, self.start = list(x), list(f), list(start)
        self.columns, self.values = columns, values
        # (g, R): an impact where g falls through zero, the state reset to R.
        self.event = event

    def column_symbols(self):
        return [sp.Symbol(c) for c in self.columns]

    def state_names(self):
        return [str(s).replace("_d", "'") for s in self.x]


def lagrange(q, L, Q, constraints):
    """q'' of E(L) = Q + Aᵀλ under the acceleration-level constraints
    (expressions in q, q', q'', t, linear in q''). Returns (qd, qdd)
    where qd are the velocity symbols and qdd the accelerations."""
    qd = [sp.Symbol(f"{s}_d") for s in q]
    a = [sp.Symbol(f"{s}_dd") for s in q]
    n, k = len(q), len(constraints)
    lam = sp.symbols(f"lam0:{k}")
    rows = []
    for i in range(n):
        p = sp.diff(L, qd[i])
        dp = sp.diff(p, t) + sum(sp.diff(p, q[j]) * qd[j] + sp.diff(p, qd[j]) * a[j] for j in range(n))
        react = sum(sp.diff(constraints[r], a[i]) * lam[r] for r in range(k))
        rows.append(dp - sp.diff(L, q[i]) - Q[i] - react)
    sol = sp.solve(rows + list(constraints), a + list(lam), dict=True)[0]
    return qd, [sp.simplify(sol[ai]) for ai in a]


def d_dt(expr, q, qd, qdd):
    return sp.diff(expr, t) + sum(sp.diff(expr, q[j]) * qd[j] + sp.diff(expr, qd[j]) * qdd[j]
                                  for j in range(len(q)))


def accel(q):
    return [sp.Symbol(f"{s}_dd") for s in q]


def oscillator():
    # m x'' = -k x - c x'
    x, xd = sp.symbols("x x_d")
    m, k, c = sp.symbols("m k c")
    x0, xd0 = sp.symbols("x0 x'0")
    return Model("oscillator", "scripts/bench_sensitivity/oscillator.lag", 20.0, [x, xd],
                 [xd, -(k * x + c * xd) / m], [x0, xd0], ["x0", "x'0", "m", "k", "c"],
                 {m: 1.0, k: 4.0, c: 0.4, x0: 1.0, xd0: 0.0})


def pendulum():
    # L = l² a'²/2 + g l cos a, force −c a' on a.
    a = sp.Symbol("a")
    g, l, c = sp.symbols("g l c")
    qd, qdd = lagrange([a], l**2 / 2 * sp.Symbol("a_d")**2 + g * l * sp.cos(a),
                       [-c * sp.Symbol("a_d")], [])
    a0, ad0 = sp.symbols("a0 a'0")
    return Model("pendulum", "scripts/bench_sensitivity/pendulum.lag", 10.0, [a, qd[0]],
                 [qd[0], qdd[0]], [a0, ad0], ["a0", "a'0", "g", "l", "c"],
                 {g: 9.81, l: 1.0, c: 0.1, a0: 1.0, ad0: 0.0})


def vertical_rocket():
    # Meshchersky: M z'' = −M g + μ w with M = M0 − μ t (exhaust at w
    # relative, straight down). z0, v0 are params the start is stated in.
    z, zd = sp.symbols("z z_d")
    M0, mu, w, g, z0, v0 = sp.symbols("M0 mu w g z0 v0")
    zt0, zd0 = sp.symbols("z(t0) z'0")
    vals = {M0: 1000.0, mu: 10.0, w: 2000.0, g: 9.81, z0: 0.0, v0: 0.0}
    # The stated values are the params' values; moving a stated value alone
    # is its own column, so the start is (z(t0) + z0 − z0|value, …): the
    # columns of z(t0) and of z0 are both e_z.
    start = [zt0 + z0 - vals[z0], zd0 + v0 - vals[v0]]
    vals.update({zt0: 0.0, zd0: 0.0})
    return Model("vertical_rocket", "examples/vertical_rocket.lag", 80.0, [z, zd],
                 [zd, mu * w / (M0 - mu * t) - g], start,
                 ["z(t0)", "z'0", "M0", "mu", "w", "g", "z0", "v0"], vals)


def second_order_constraint():
    # L = m (x'² + y'²)/2 − m g y under the acceleration constraint
    # y'' = t x'' (k = 2; the reaction is along its gradient in q'').
    q = sp.symbols("x y")
    m, g, v0, w0 = sp.symbols("m g v0 w0")
    xd, yd = sp.symbols("x_d y_d")
    xdd, ydd = accel(q)
    qd, qdd = lagrange(list(q), m / 2 * (xd**2 + yd**2) - m * g * q[1], [0, 0], [ydd - t * xdd])
    s = sp.symbols("x0 y0 x'0 y'0")
    vals = {m: 1.0, g: 1.0, v0: 1.0, w0: 2.0, s[0]: 0.0, s[1]: 0.0, s[2]: 0.0, s[3]: 0.0}
    start = [s[0], s[1], s[2] + v0, s[3] + w0]
    return Model("second_order_constraint", "examples/second_order_constraint.lag", 5.0,
                 list(q) + qd, qd + qdd, start, ["x0", "y0", "x'0", "y'0", "m", "g", "v0", "w0"], vals)


def cartesian_pendulum():
    # L = (x'² + y'²)/2 − g y on x² + y² = l² (twice differentiated).
    # Start: x, x' stated, y the root near the stated −0.8 (lagc's Newton
    # completes the dependent y; its stated value only picks the root),
    # y' from x x' + y y' = 0.
    q = list(sp.symbols("x y"))
    g, l = sp.symbols("g l")
    xd, yd = sp.symbols("x_d y_d")
    h = q[0]**2 + q[1]**2 - l**2
    hd = sp.diff(h, q[0]) * xd + sp.diff(h, q[1]) * yd
    qd, qdd = lagrange(q, (xd**2 + yd**2) / 2 - g * q[1], [0, 0],
                       [d_dt(hd, q, [xd, yd], accel(q))])
    x0, y0, xd0 = sp.symbols("x0 y0 x'0")
    ys = -sp.sqrt(l**2 - x0**2)
    start = [x0, ys, xd0, -x0 * xd0 / ys]
    return Model("cartesian_pendulum", "scripts/bench_sensitivity/cartesian_pendulum.lag", 10.0,
                 q + qd, qd + qdd, start, ["x0", "y0", "x'0", "g", "l"],
                 {g: 9.81, l: 1.0, x0: 0.6, y0: -0.8, xd0: 0.0})


def chaplygin_sleigh():
    # A body on a knife edge at (x, y), heading th, centre of mass a ahead:
    # L = m |c'|²/2 + J th'²/2, c = (x + a cos th, y + a sin th), blade
    # sideways speed zero: sin(th) x' − cos(th) y' = 0 (differentiated once).
    q = list(sp.symbols("x y th"))
    m, a, J = sp.symbols("m a J")
    qdv = sp.symbols("x_d y_d th_d")
    cx = qdv[0] - a * sp.sin(q[2]) * qdv[2]
    cy = qdv[1] + a * sp.cos(q[2]) * qdv[2]
    L = m / 2 * (cx**2 + cy**2) + J / 2 * qdv[2]**2
    nh = sp.sin(q[2]) * qdv[0] - sp.cos(q[2]) * qdv[1]
    qd, qdd = lagrange(q, L, [0, 0, 0], [d_dt(nh, q, list(qdv), accel(q))])
    s = sp.symbols("x0 y0 th0 x'0 th'0")
    # y' the dependent at the start (cos th0 = 1): y' = tan(th) x'.
    start = [s[0], s[1], s[2], s[3], sp.tan(s[2]) * s[3], s[4]]
    return Model("chaplygin_sleigh", "examples/chaplygin_sleigh.lag", 20.0, q + qd, qd + qdd, start,
                 ["x0", "y0", "th0", "x'0", "th'0", "m", "a", "J"],
                 {m: 1.0, a: 0.01, J: 0.02, s[0]: 0.0, s[1]: 0.0, s[2]: 0.0, s[3]: 0.2, s[4]: 5.0})


def bouncing_ball():
    # y'' = −g; where y falls through 0 the impact y' ← −e y'. Six impacts
    # before t = 3 (the impacts accumulate at 4.06 s).
    y, yd = sp.symbols("y y_d")
    g, e, h0 = sp.symbols("g e h0")
    ys, yds = sp.symbols("y0 y'0")
    vals = {g: 9.81, e: 0.8, h0: 1.0, ys: 0.0, yds: 0.0}
    return Model("bouncing_ball", "scripts/bench_sensitivity/bouncing_ball.lag", 3.0, [y, yd],
                 [yd, -g], [ys + h0, yds], ["y0", "y'0", "g", "e", "h0"], vals,
                 event=(y, [y, -e * yd]))


ALL = [oscillator, pendulum, vertical_rocket, second_order_constraint, cartesian_pendulum,
       chaplygin_sleigh, bouncing_ball]


def sensitivity_system(model):
    """(f, J, F_p, x0, S0) numeric in the params: f and the Jacobian J =
    ∂f/∂x, F_p the columns' ∂f/∂(column) (zero for a stated value), x0 and
    S0 = ∂x0/∂(column) at the values."""
    cols = model.column_symbols()
    sub = model.values
    f = sp.Matrix(model.f)
    J = f.jacobian(model.x)
    Fp = sp.Matrix.hstack(*[sp.diff(f, c) for c in cols])
    x0 = sp.Matrix(model.start)
    S0 = x0.jacobian(cols)
    return (f.subs(sub), J.subs(sub), Fp.subs(sub), x0.subs(sub).evalf(17), S0.subs(sub).evalf(17))


def event_system(model):
    """The impact's pieces, numeric in the params: g, its partials g_x
    (a row), g_t and g_(column); the reset R, R_x and R_(column)."""
    g, R = model.event
    cols = model.column_symbols()
    sub = model.values
    R = sp.Matrix(R)
    gx = sp.Matrix([g]).jacobian(model.x)
    gp = sp.Matrix([[sp.diff(g, c) for c in cols]])
    Rp = sp.Matrix.hstack(*[sp.diff(R, c) for c in cols])
    return (sp.sympify(g).subs(sub), gx.subs(sub), sp.diff(g, t), gp.subs(sub), R.subs(sub),
            R.jacobian(model.x).subs(sub), Rp.subs(sub))
