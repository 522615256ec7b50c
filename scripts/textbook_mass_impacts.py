#!/usr/bin/env python3
"""The textbook models of variable mass, staging and impacts (tests/data/textbook/,
issue 29) against independent references (closed forms at 30 digits with mpmath,
SciPy DOP853 at rtol 1e-13 for the drag rocket, event-driven exact impacts), both
methods at rtol 1e-6, 1e-9, 1e-12 (atol = rtol/100): the largest error over every
column and sample in units of rtol (relative to the column's largest magnitude,
at least 1) and what the summary said. Run with a python that has numpy, scipy,
mpmath: env LAGC (default target/release/lagc), argument: a comma list of models."""
import math
import mpmath as mp
import numpy as np
from scipy.integrate import solve_ivp

mp.mp.dps = 30
G = 9.81

# 1. two-stage rocket with a coast between the stages
def rocket_two_stage_coast():
    M0, mu1, t1, M2, t2, mu2, t3, w, g = 1000, 8, 60, 300, 70, 2, 130, 2500, 9.81
    def burn(zi, vi, Mi, mu, s):
        Ms = Mi - mu * s
        return (zi + vi * s - g * s**2 / 2 + w * (s + Ms / mu * mp.log(Ms / Mi)),
                vi + w * mp.log(Mi / Ms) - g * s)
    def coast(zi, vi, s):
        return zi + vi * s - g * s**2 / 2, vi - g * s
    z1, v1 = burn(0, 0, M0, mu1, mp.mpf(t1))
    z2, v2 = coast(z1, v1, t2 - t1)
    z3, v3 = burn(z2, v2, M2, mu2, mp.mpf(t3 - t2))
    def f(t):
        t = mp.mpf(t)
        if t < t1: z, v = burn(0, 0, M0, mu1, t)
        elif t < t2: z, v = coast(z1, v1, t - t1)
        elif t < t3: z, v = burn(z2, v2, M2, mu2, t - t2)
        else: z, v = coast(z3, v3, t - t3)
        return [float(z), float(v)]
    return dict(cols=["z", "z'"], times=np.linspace(0, 200, 81)[1:], ref=f)

# 2. rocket with quadratic drag, burnout, coast, fall, land (SciPy DOP853)
def rocket_drag_vertical():
    M0, mu, tb, w, g, k = 50, 1, 20, 1500, 9.81, 0.004
    def rhs(t, y):
        z, v = y
        M = M0 - mu * t if t < tb else M0 - mu * tb
        thrust = mu * w if t < tb else 0.0
        return [v, (thrust - k * v * abs(v)) / M - g]
    kw = dict(method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)
    s1 = solve_ivp(rhs, [0, tb], [0, 0], **kw)
    apex = lambda t, y: y[1]; apex.terminal = True
    s2 = solve_ivp(rhs, [tb, 1000], s1.y[:, -1], events=apex, **kw)
    ta = s2.t_events[0][0]
    land = lambda t, y: y[0]; land.terminal = True
    s3 = solve_ivp(rhs, [ta, 1000], s2.sol(ta), events=land, **kw)
    tl = s3.t_events[0][0]
    def f(t):
        s = s1 if t <= tb else (s2 if t <= ta else s3)
        return list(s.sol(t))
    return dict(cols=["z", "z'"], times=np.linspace(0, tl, 60, endpoint=False)[1:], ref=f,
                stop=tl)

# 3. chain lifted from a heap by a constant force
def chain_lifted_from_heap():
    rho, g, F = 2, 9.81, 20
    v0 = math.sqrt(F / rho)
    f = lambda t: [v0 * t - g * t * t / 6, v0 - g * t / 3]
    return dict(cols=["x", "x'"], times=np.linspace(0.1, 0.9, 41)[1:], ref=f)

# 4. two raindrops: M = M0 + k t and M = M0 exp(lam t), mist at rest
def raindrops_two_laws():
    M0, k, lam, g = mp.mpf("1e-3"), mp.mpf("2e-3"), mp.mpf("0.5"), mp.mpf("9.81")
    def f(t):
        t = mp.mpf(t); u = M0 + k * t
        x1 = g / (2 * k**2) * ((u**2 - M0**2) / 2 - M0**2 * mp.log(u / M0))
        v1 = g / (2 * k) * (u - M0**2 / u)
        x2 = g / lam * t - g / lam**2 * (1 - mp.exp(-lam * t))
        v2 = g / lam * (1 - mp.exp(-lam * t))
        return [float(x1), float(x2), float(v1), float(v2)]
    return dict(cols=["x1", "x2", "x1'", "x2'"], times=np.linspace(0, 10, 41)[1:], ref=f)

# 5. raindrop whose mass grows with the distance fallen, M = M0 + c x:
# (M v)' = M g gives v^2 = 2 g (M^3 - M0^3) / (3 c M^2); t(x) by quadrature.
def raindrop_linear_in_distance():
    M0, c, g = mp.mpf("1e-3"), mp.mpf("2e-3"), mp.mpf("9.81")
    def v(x):
        M = M0 + c * x
        return mp.sqrt(2 * g * (M**3 - M0**3) / (3 * c * M**2))
    def t_of_x(x):
        return mp.quad(lambda s: 1 / v(s), [0, x])
    def f(t):
        t = mp.mpf(t)
        x0 = g * t**2 / 2  # an upper bound: free fall
        x = mp.findroot(lambda x: t_of_x(x) - t, (x0 * mp.mpf("0.01"), x0), solver="anderson")
        return [float(x), float(v(x))]
    return dict(cols=["x", "x'"], times=np.linspace(0, 10, 21)[1:], ref=f)

# 6. cart leaking sand (relative velocity zero), constant force
def cart_leaking_sand():
    M0, mu, F, v0 = 100, 4, 30, 1
    def f(t):
        t = mp.mpf(t); M = M0 - mu * t
        return [float(v0 * t + F / mu * (t + M / mu * mp.log(M / M0))),
                float(v0 + F / mu * mp.log(M0 / M))]
    return dict(cols=["x", "x'"], times=np.linspace(0, 20, 41)[1:], ref=f)

# 7. cart collecting sand at rest, constant force
def cart_collecting_sand():
    M0, mu, F, v0 = 100, 4, 30, 1
    def f(t):
        t = mp.mpf(t); M = M0 + mu * t
        return [float(F * t / mu + (M0 * v0 - F * mp.mpf(M0) / mu) / mu * mp.log(M / M0)),
                float((M0 * v0 + F * t) / M)]
    return dict(cols=["x", "x'"], times=np.linspace(0, 20, 41)[1:], ref=f)

# 8. ball bouncing down four stairs (exact parabolas, events by the quadratic formula)
def ball_down_stairs():
    g, e, h, w, u = mp.mpf("9.81"), mp.mpf("0.6"), mp.mpf("0.2"), mp.mpf("0.5"), mp.mpf(1)
    x0 = mp.mpf("0.1")
    segs = []  # (t0, y0, v0)
    t, y, v = mp.mpf(0), mp.mpf("0.3"), mp.mpf(0)
    T = mp.mpf("2.5")
    while t < T:
        x = x0 + u * t
        kstep = min(int(mp.floor(x / w + mp.mpf("1e-25"))), 3)
        floor = -kstep * h
        # descending root of y + v s - g s^2/2 = floor
        s_land = (v + mp.sqrt(v**2 + 2 * g * (y - floor))) / g
        s_edge = ((kstep + 1) * w - x) / u if kstep < 3 else mp.inf
        segs.append((t, y, v))
        if s_edge < s_land:
            y, v, t = y + v * s_edge - g * s_edge**2 / 2, v - g * s_edge, t + s_edge
        else:
            if s_land < mp.mpf("1e-20"):
                break  # accumulated
            t = t + s_land
            y, v = floor, e * (g * s_land - v)
    def f(tq):
        tq = mp.mpf(tq)
        t0, y0, v0 = [s for s in segs if s[0] <= tq][-1]
        s = tq - t0
        return [float(x0 + u * tq), float(y0 + v0 * s - g * s**2 / 2), float(u), float(v0 - g * s)]
    # accumulation on the last step: from the last bounce with speed V, e V ... geometric
    return dict(cols=["x", "y", "x'", "y'"], times=np.linspace(0, 2.3, 47)[1:], ref=f, segs=segs)

# 9. ball on a vibrating plate y_p = A sin(om t): events by root finding at 30 digits
def ball_on_vibrating_plate():
    g, e, A, om = mp.mpf("9.81"), mp.mpf("0.8"), mp.mpf("0.01"), mp.mpf(20)
    T = mp.mpf("1.5")
    segs = []
    t, y, v = mp.mpf(0), mp.mpf("0.2"), mp.mpf(0)
    while t < T:
        segs.append((t, y, v))
        gap = lambda tt: y + v * (tt - t) - g * (tt - t)**2 / 2 - A * mp.sin(om * tt)
        dt = mp.mpf("1e-4"); ta = t + mp.mpf("1e-12")
        found = None
        while ta < T + 1:
            tb = ta + dt
            if gap(ta) > 0 and gap(tb) <= 0:
                found = mp.findroot(gap, (ta, tb), solver="bisect" if False else "anderson")
                break
            ta = tb
        if found is None or found > T:
            break
        s = found - t
        vb = v - g * s
        vp = A * om * mp.cos(om * found)
        y, v, t = A * mp.sin(om * found), (1 + e) * vp - e * vb, found
    def f(tq):
        tq = mp.mpf(tq)
        t0, y0, v0 = [s for s in segs if s[0] <= tq][-1]
        s = tq - t0
        return [float(y0 + v0 * s - g * s**2 / 2), float(v0 - g * s)]
    return dict(cols=["y", "y'"], times=np.linspace(0, 1.5, 61)[1:], ref=f, segs=segs)

# 10/11. three balls on a line, equal masses, restitution e (exact, event-driven)
def cradle(x3_0):
    e, r = mp.mpf("0.9"), mp.mpf("0.05")
    x = [mp.mpf(0), mp.mpf("0.2"), mp.mpf(x3_0)]
    v = [mp.mpf(1), mp.mpf(0), mp.mpf(0)]
    t = mp.mpf(0); T = mp.mpf(1)
    segs = [(t, list(x), list(v))]
    last = None
    while True:
        best = None
        for (i, j) in [(0, 1), (1, 2)]:
            rel = v[i] - v[j]
            if rel > 0:
                s = (x[j] - x[i] - 2 * r) / rel
                if best is None or s < best[0]:
                    best = (s, i, j)
        if best is None or t + best[0] > T:
            break
        s, i, j = best
        t += s
        x = [xi + vi * s for xi, vi in zip(x, v)]
        rel = v[i] - v[j]
        v[i] -= (1 + e) / 2 * rel
        v[j] += (1 + e) / 2 * rel
        segs.append((t, list(x), list(v)))
    def f(tq):
        tq = mp.mpf(tq)
        t0, x0, v0 = [s for s in segs if s[0] <= tq][-1]
        return [float(a + b * (tq - t0)) for a, b in zip(x0, v0)] + [float(b) for b in v0]
    return dict(cols=["x1", "x2", "x3", "x1'", "x2'", "x3'"], times=np.linspace(0, 1, 41)[1:] - 0.0123,
                ref=f, segs=segs)

def newton_cradle_gaps(): return cradle("0.35")
def newton_cradle_touching(): return cradle("0.3")

# 12. block on a spring hitting a wall at x = d (piecewise harmonic, exact)
def spring_block_wall():
    m, k, d, e, v0 = 1, 4, mp.mpf("0.3"), mp.mpf("0.7"), mp.mpf(1)
    om = mp.sqrt(mp.mpf(k) / m)
    T = mp.mpf(6)
    segs = []
    t, x, v = mp.mpf(0), mp.mpf(0), v0
    while True:
        segs.append((t, x, v))
        R = mp.sqrt(x**2 + (v / om)**2)
        if R <= d:
            break
        phi = mp.atan2(v / om, x)  # x = R cos(om s - phi)
        # x' = -R om sin(om s - phi) > 0 at x = d: om s - phi = -acos(d/R) (mod 2 pi)
        th = -mp.acos(d / R) + phi
        s = th / om
        while s <= mp.mpf("1e-20"):
            s += 2 * mp.pi / om
        if t + s > T:
            break
        t += s
        x, v = d, -e * (R * om * mp.sin(mp.acos(d / R)))
    def f(tq):
        tq = mp.mpf(tq)
        t0, x0, vv = [s for s in segs if s[0] <= tq][-1]
        s = tq - t0
        return [float(x0 * mp.cos(om * s) + vv / om * mp.sin(om * s)),
                float(-x0 * om * mp.sin(om * s) + vv * mp.cos(om * s))]
    return dict(cols=["x", "x'"], times=np.linspace(0, 6, 61)[1:], ref=f, segs=segs)


def main():
    import os, subprocess, sys
    refs = sys.modules[__name__]
    LAGC = os.environ.get("LAGC", "target/release/lagc")
    MODELS = sys.argv[1].split(",") if len(sys.argv) > 1 else [
        "rocket_two_stage_coast", "rocket_drag_vertical", "chain_lifted_from_heap",
        "raindrops_two_laws", "raindrop_linear_in_distance", "cart_leaking_sand",
        "cart_collecting_sand", "ball_down_stairs", "ball_on_vibrating_plate",
        "newton_cradle_touching", "spring_block_wall"]
    RTOLS = [1e-6, 1e-9, 1e-12]
    out = {}
    for name in MODELS:
        r = getattr(refs, name)()
        times = r["times"]
        ref = np.array([r["ref"](t) for t in times])
        scale = np.maximum(1.0, np.abs(ref).max(axis=0))
        for method in ["direct", "field"]:
            for rtol in RTOLS:
                args = [LAGC, "run", f"tests/data/textbook/{name}.lag", "--method", method, "--rtol", repr(rtol),
                        "--atol", repr(rtol * 1e-2), "--times", ",".join(repr(float(t)) for t in times)]
                p = subprocess.run(args, capture_output=True, text=True)
                lines = p.stdout.strip().splitlines()
                head = lines[0].split(",") if lines else []
                rows = np.array([[float(v) for v in l.split(",")] for l in lines[1:]]) if len(lines) > 1 else np.zeros((0, 1))
                err = None; worst = None
                if len(rows):
                    n = min(len(rows), len(ref))
                    cols = [head.index(c) for c in r["cols"]]
                    d = np.abs(rows[:n][:, cols] - ref[:n]) / scale
                    err = d.max() / rtol
                    i, j = np.unravel_index(d.argmax(), d.shape)
                    worst = f"{r['cols'][j]}@t={times[i]:.6g}"
                    if n < len(ref): worst += f" (only {n}/{len(ref)} rows)"
                summ = [l for l in p.stderr.splitlines() if l.startswith(("global error", "warning", "stopped", "error"))]
                summ = " | ".join(s[:150] for s in summ)
                print(f"{name:28s} {method:6s} {rtol:.0e} exit={p.returncode} err={err if err is None else f'{err:.3g}'} rtol  worst={worst}  :: {summ}", flush=True)


if __name__ == "__main__":
    main()
