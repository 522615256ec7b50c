#!/usr/bin/env python3
"""References of tests/data/textbook_motion/*.lag (tests/it/textbook_motion.rs),
independent of lagc: closed forms where the motion has one, else the
equations of motion written out by hand here and integrated by SciPy's
DOP853 at rtol 1e-13 (stepped from sample to sample and from switch to
switch, a fresh solve_ivp each piece, so no continuous extension enters;
impacts located by SciPy's events).

- rocket_three_stage_gravity_turn: in burn i, (x, y)'' = mu_i w_i / M(t)
  v/|v| - (0, g); after the third burnout, free flight.
- rocket_gravity_turn_from_pad: the thrust up, tilted, then along the
  velocity (phases on t), then a coast.
- rocket_raising_orbit: the same motion in Cartesian coordinates, burn then
  coast, the polar columns computed from it (th unwrapped).
- rocket_fuel_coordinate: z' = w ln(M(0)/M(t)) - g t with
  M = Md + m0 exp(-k t), z its integral (mpmath's quadrature at 30 digits).
- rocket_stage_dropped_at_altitude: each burn by SciPy, the drop where
  z = H by SciPy's event.
- rocket_sled_on_ramp: along the ramp s' = w ln(M0/M) - g sin(a) t and its
  integral in closed form.
- folded_chain_free_end: x'' = g + x'^2/(L - x), by SciPy.
- ball_on_incline: the normal coordinate n = sin(a) x + cos(a) y bounces as a
  1-D ball under g cos(a); the tangential one falls at g sin(a), untouched.
- ball_against_step: y bounces as a 1-D ball; x is linear, reversed (times e)
  where it reaches the riser at x = s.
- ball_in_circular_bowl: free fall between impacts, each impact where
  x^2 + y^2 = R^2 on the exact parabola (a scan, then bisection).
- ball_in_bowl_with_drag: the same with quadratic drag, each impact by
  SciPy's events (steps of at most 1 ms, so that no late short flight is
  stepped over).
- ball_in_hoop_elastic_long: the same without drag and with e = 1 for 20 s,
  chaotic: exact flights, each impact by mpmath's root at 40 digits.
- ball_thrown_up_quadratic_drag: closed forms rising (tan) and falling
  (tanh), impacts where the fall reaches the floor, at 30 digits.
- kepler_hundred_periods: Kepler's equation E - ecc sin E = n t by Newton.
- elastic_pendulum_chaotic: r'' = r th'^2 - k/m (r - l0) + g cos(th),
  th'' = -(2 r' th' + g sin(th))/r; the run at rtol 1e-13 and one at 3e-14
  are compared and their gap printed: the reference is only as good as it.

Writes NAME.csv (t, the coordinates, their derivatives; at most 41 rows)
next to each model. Needs scipy, numpy, mpmath.

    /work/scratch/refvenv/bin/python scripts/textbook_motion_reference.py [NAME ...]
"""
import math
import os
import sys

import mpmath as mp
import numpy as np
from scipy.integrate import solve_ivp

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "textbook_motion")
G = 9.81
RTOL = 1e-13


def step(rate, t0, t1, y, rtol=RTOL, breaks=()):
    """y at t1 from y at t0, a fresh DOP853 solve for each piece between breaks."""
    cuts = [t0] + [b for b in breaks if t0 < b < t1] + [t1]
    y = np.array(y, dtype=float)
    for a, b in zip(cuts, cuts[1:]):
        if b == a:
            continue
        mid = 0.5 * (a + b)  # the piece's branch of every switch, as lagc keeps it between events
        sol = solve_ivp(lambda tt, yy: rate(tt, yy, mid), (a, b), y, method="DOP853",
                        rtol=rtol, atol=rtol * 1e-3)
        assert sol.success, sol.message
        y = sol.y[:, -1]
    return y


def sampled(rate, ts, y0, rtol=RTOL, breaks=()):
    rows, y = [], np.array(y0, dtype=float)
    for i, tt in enumerate(ts):
        if i > 0:
            y = step(rate, ts[i - 1], tt, y, rtol, breaks)
        rows.append([tt, *y])
    return rows


def rocket_three_stage():
    M0, mu1, w1, t1 = 5000, 60, 2600, 50
    M2, mu2, w2, t2 = 1600, 15, 3000, 90
    M3, mu3, w3, t3 = 500, 4, 3400, 150

    def rate(tt, s, mid):
        x, y, vx, vy = s
        if mid < t1:
            M, thrust = M0 - mu1 * tt, mu1 * w1
        elif mid < t2:
            M, thrust = M2 - mu2 * (tt - t1), mu2 * w2
        elif mid < t3:
            M, thrust = M3 - mu3 * (tt - t2), mu3 * w3
        else:
            M, thrust = M3 - mu3 * (t3 - t2), 0.0
        v = math.hypot(vx, vy)
        return [vx, vy, thrust / M * vx / v, thrust / M * vy / v - G]

    el = 80 * math.pi / 180
    ts = [250 * i / 40 for i in range(41)]
    return ["x", "y"], sampled(rate, ts, [0, 0, 50 * math.cos(el), 50 * math.sin(el)],
                               breaks=(t1, t2, t3))


def rocket_fuel():
    mp.mp.dps = 30
    Md, k, w, m0 = mp.mpf(200), mp.mpf("0.02"), mp.mpf(2000), mp.mpf(800)
    g = mp.mpf("9.81")
    m = lambda tt: m0 * mp.exp(-k * tt)
    v = lambda tt: w * mp.log((Md + m0) / (Md + m(tt))) - g * tt
    rows = []
    for i in range(41):
        tt = mp.mpf(60) * i / 40
        z = mp.quad(v, [0, tt])
        rows.append([float(tt), float(z), float(m(tt)), float(v(tt)), float(-k * m(tt))])
    return ["z", "m"], rows


def bounce_1d(n0, v0, g, e, tt):
    """Height and velocity at tt of a 1-D ball from height n0 > 0, velocity v0,
    bouncing on 0 with restitution e (closed form: flights by the quadratic formula)."""
    t0, n, v = 0.0, n0, v0
    while True:
        hit = t0 + (v + math.sqrt(v * v + 2 * g * n)) / g  # n + v s - g s^2/2 = 0
        if hit > tt:
            s = tt - t0
            return n + v * s - g * s * s / 2, v - g * s
        vin = v - g * (hit - t0)
        t0, n, v = hit, 0.0, -e * vin


def ball_on_incline():
    e, a = 0.8, 0.3
    gn, gs = G * math.cos(a), G * math.sin(a)
    rows = []
    for i in range(41):
        tt = 3 * i / 40
        nn, vn = bounce_1d(math.cos(a), 0.0, gn, e, tt)  # n(0) = sin(a) 0 + cos(a) 1
        ss, vs = -math.sin(a) + gs * tt * tt / 2, gs * tt  # s = cos(a) x - sin(a) y
        x = math.sin(a) * nn + math.cos(a) * ss
        y = math.cos(a) * nn - math.sin(a) * ss
        vx = math.sin(a) * vn + math.cos(a) * vs
        vy = math.cos(a) * vn - math.sin(a) * vs
        rows.append([tt, x, y, vx, vy])
    return ["x", "y"], rows


def ball_against_step():
    e, s, h, u = 0.7, 2.0, 0.5, 3.0
    hit = s / u
    yh, _ = bounce_1d(1.0, 0.0, G, e, hit)
    assert 0 < yh < h, yh  # the ball meets the riser below its top
    rows = []
    for i in range(41):
        tt = 2 * i / 40
        y, vy = bounce_1d(1.0, 0.0, G, e, tt)
        x, vx = (u * tt, u) if tt < hit else (s - e * u * (tt - hit), -e * u)
        rows.append([tt, x, y, vx, vy])
    return ["x", "y"], rows


def ball_in_bowl():
    R, e, T = 1.0, 0.9, 4.0

    def flight(t0, s0, tt):
        x, y, vx, vy = s0
        d = tt - t0
        return np.array([x + vx * d, y + vy * d - G * d * d / 2, vx, vy - G * d])

    def wall(t0, s0):
        """The first time after t0 the parabola reaches r = R: a scan for the sign
        change, then Newton on x^2 + y^2 - R^2 (exact flight, no integrator)."""
        f = lambda tt: (lambda p: p[0] ** 2 + p[1] ** 2 - R * R)(flight(t0, s0, tt))
        dt, a = 1e-3, t0 + 1e-9
        while f(a + dt) < 0:
            a += dt
        lo, hi = a, a + dt
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
        return 0.5 * (lo + hi)

    bounces, t0, s0 = [], 0.0, np.array([0.3, 0.0, 1.5, 0.0])
    while True:
        th = wall(t0, s0)
        if th > T:
            break
        x, y, vx, vy = flight(t0, s0, th)
        vr = (x * vx + y * vy) / R
        s0 = np.array([x, y, vx - (1 + e) * vr * x / R, vy - (1 + e) * vr * y / R])
        t0 = th
        bounces.append((t0, s0.copy()))
    print(f"ball_in_circular_bowl: {len(bounces)} impacts, at "
          + ", ".join(f"{b[0]:.6f}" for b in bounces))
    rows = []
    for i in range(41):
        tt = T * i / 40
        start = (0.0, np.array([0.3, 0.0, 1.5, 0.0]))
        for b in bounces:
            if b[0] <= tt:
                start = b
        rows.append([tt, *flight(start[0], start[1], tt)])
    return ["x", "y"], rows


def kepler():
    mu, a, ecc = 1.0, 1.0, 0.5
    n = math.sqrt(mu / a**3)
    h = math.sqrt(mu * a * (1 - ecc * ecc))
    rows = []
    for i in range(41):
        tt = 200 * math.pi * i / 40
        M = n * tt
        E = M if ecc < 0.8 else math.pi
        for _ in range(100):
            E -= (E - ecc * math.sin(E) - M) / (1 - ecc * math.cos(E))
        r = a * (1 - ecc * math.cos(E))
        k = math.floor((E + math.pi) / (2 * math.pi))  # whole turns: th unwrapped
        Ew = E - 2 * math.pi * k
        th = 2 * math.atan2(math.sqrt(1 + ecc) * math.sin(Ew / 2),
                            math.sqrt(1 - ecc) * math.cos(Ew / 2)) + 2 * math.pi * k
        Ed = n / (1 - ecc * math.cos(E))
        rows.append([tt, r, th, a * ecc * math.sin(E) * Ed, h / (r * r)])
    return ["r", "th"], rows


def elastic_pendulum():
    m, k, l0 = 1.0, 10.0, 1.0

    def rate(tt, s, mid):
        r, th, rd, thd = s
        return [rd, thd, r * thd * thd - k / m * (r - l0) + G * math.cos(th),
                -(2 * rd * thd + G * math.sin(th)) / r]

    ts = [40 * i / 40 for i in range(41)]
    rows = sampled(rate, ts, [1.5, 3.0, 0.0, 0.0])
    fine = sampled(rate, ts, [1.5, 3.0, 0.0, 0.0], rtol=3e-14)
    scale = [max(1.0, max(abs(r[j]) for r in fine)) for j in range(5)]
    gaps = [max(abs(ra[j] - rb[j]) / scale[j] for j in range(1, 5)) for ra, rb in zip(rows, fine)]
    for tt, gp in zip(ts, gaps):
        if gp > 1e-10:
            print(f"elastic_pendulum_chaotic: reference gap {gp:.2e} at t = {tt}")
    print(f"elastic_pendulum_chaotic: largest gap 1e-13 against 3e-14: {max(gaps):.2e}")
    return ["r", "th"], fine


def rocket_fuel_runs_out():
    mp.mp.dps = 30
    Md, mu, w, m0 = mp.mpf(300), mp.mpf(10), mp.mpf(2500), mp.mpf(590)
    g = mp.mpf("9.81")
    tb = m0 / mu
    M = lambda tt: Md + m0 - mu * min(tt, tb)
    vb = w * mp.log((Md + m0) / Md) - g * tb
    zb = mp.quad(lambda s: w * mp.log((Md + m0) / M(s)) - g * s, [0, tb])
    rows = []
    for i in range(41):
        tt = mp.mpf(100) * i / 40
        if tt <= tb:
            v = w * mp.log((Md + m0) / M(tt)) - g * tt
            z = mp.quad(lambda s: w * mp.log((Md + m0) / M(s)) - g * s, [0, tt])
            rate = -mu if tt < tb else 0
        else:
            d = tt - tb
            v, z, rate = vb - g * d, zb + vb * d - g * d * d / 2, 0
        rows.append([float(tt), float(z), float(m0 - mu * min(tt, tb)), float(v), float(rate)])
    return ["z", "m"], rows


def chain_off_heap():
    g, x0 = G, 0.2

    def rate(tt, s, mid):
        x, xd = s
        return [xd, g - xd * xd / x]

    ts = [2 * i / 40 for i in range(41)]
    rows = sampled(rate, ts, [x0, 0.0])
    law = max(abs(x * x * xd * xd - 2 * g * (x**3 - x0**3) / 3) for _, x, xd in rows)
    print(f"chain_off_heap_from_rest: x^2 x'^2 - 2g(x^3 - x0^3)/3 at most {law:.1e}")
    assert law < 1e-9
    return ["x"], rows


def ball_in_bowl_drag():
    R, e, k, T = 1.0, 0.9, 0.3, 4.0

    def rate(tt, s):
        x, y, vx, vy = s
        v = math.hypot(vx, vy)
        return [vx, vy, -k * v * vx, -G - k * v * vy]

    def wall(tt, s):
        return s[0] ** 2 + s[1] ** 2 - R * R

    wall.terminal, wall.direction = True, 1
    ts = [T * i / 40 for i in range(41)]
    t0, s0, hits, rows = 0.0, np.array([0.3, 0.0, 3.0, 0.0]), [], []
    while t0 < T:
        # steps of at most 1 ms: a flight between two late bounces (9 ms) spans
        # several, so SciPy sees its wall function go in and come back out
        sol = solve_ivp(rate, (t0, T), s0, method="DOP853", rtol=RTOL, atol=RTOL * 1e-3,
                        events=wall, max_step=1e-3)
        assert sol.status >= 0, sol.message
        end = sol.t_events[0][0] if sol.status == 1 else T
        # samples in (t0, end]: a fresh solve from t0 to each, no continuous extension
        for tt in ts:
            if t0 < tt <= end or (tt == 0 and t0 == 0):
                y = s0 if tt == t0 else solve_ivp(rate, (t0, tt), s0, method="DOP853",
                                                  rtol=RTOL, atol=RTOL * 1e-3).y[:, -1]
                rows.append([tt, *y])
        if sol.status != 1:
            break
        x, y, vx, vy = solve_ivp(rate, (t0, end), s0, method="DOP853", rtol=RTOL,
                                 atol=RTOL * 1e-3).y[:, -1]
        r = math.hypot(x, y)
        nx, ny = x / r, y / r
        vn = nx * vx + ny * vy
        s0, t0 = np.array([x, y, vx - (1 + e) * vn * nx, vy - (1 + e) * vn * ny]), end
        hits.append(end)
    print(f"ball_in_bowl_with_drag: {len(hits)} impacts, at " + ", ".join(f"{h:.6f}" for h in hits))
    return ["x", "y"], rows


def ball_in_hoop_elastic():
    """Exact flights and impacts at 40 digits (mpmath's root on each parabola):
    the motion is chaotic, an error at 1e-14 grows to 1e-6 in 20 s, past what
    an f64 run can follow."""
    mp.mp.dps = 40
    g, R, e, T = mp.mpf("9.81"), mp.mpf(1), mp.mpf(1), mp.mpf(20)

    def flight(t0, s0, tt):
        x, y, vx, vy = s0
        d = tt - t0
        return [x + vx * d, y + vy * d - g * d * d / 2, vx, vy - g * d]

    def wall(t0, s0):
        f = lambda tt: (lambda p: p[0] ** 2 + p[1] ** 2 - R * R)(flight(t0, s0, tt))
        dt, a = mp.mpf("1e-4"), t0 + mp.mpf("1e-30")
        while f(a + dt) < 0:
            a += dt
        return mp.findroot(f, (a, a + dt), solver="anderson")

    start = (mp.mpf(0), [mp.mpf("0.3"), mp.mpf(0), mp.mpf("1.5"), mp.mpf(0)])
    bounces, (t0, s0) = [], start
    while True:
        th = wall(t0, s0)
        if th > T:
            break
        x, y, vx, vy = flight(t0, s0, th)
        vr = (x * vx + y * vy) / R
        t0, s0 = th, [x, y, vx - (1 + e) * vr * x / R, vy - (1 + e) * vr * y / R]
        bounces.append((t0, s0))
    print(f"ball_in_hoop_elastic_long: {len(bounces)} impacts")
    rows = []
    for i in range(41):
        tt = T * i / 40
        at = start
        for b in bounces:
            if b[0] <= tt:
                at = b
        rows.append([float(tt), *[float(v) for v in flight(at[0], at[1], tt)]])
    return ["x", "y"], rows


def ball_thrown_up_drag():
    """Closed forms at 30 digits: rising from (y0, v0 > 0),
    y = y0 + ln(cos(a - g s/vt)/cos(a))/k with a = atan(v0/vt), to the apex
    at s = a vt/g; falling from the apex height ya, y = ya - ln(cosh(g s/vt))/k,
    to the floor at s = vt acosh(exp(k ya))/g; there v -> -e v."""
    mp.mp.dps = 30
    g, k, e = mp.mpf("9.81"), mp.mpf("0.1"), mp.mpf("0.8")
    vt = mp.sqrt(g / k)
    phases, t0, y0, v0 = [], mp.mpf(0), mp.mpf("0.5"), mp.mpf(10)
    while t0 < 5:
        a = mp.atan(v0 / vt)
        up = a * vt / g
        ya = y0 - mp.log(mp.cos(a)) / k
        down = vt * mp.acosh(mp.exp(k * ya)) / g
        phases.append((t0, y0, a, up, ya, down))
        t0 = t0 + up + down
        y0, v0 = mp.mpf(0), e * vt * mp.tanh(g * down / vt)
    rows = []
    for i in range(41):
        tt = mp.mpf(5) * i / 40
        t0, y0, a, up, ya, down = [p for p in phases if p[0] <= tt][-1]
        s = tt - t0
        if s <= up:
            y = y0 + mp.log(mp.cos(a - g * s / vt) / mp.cos(a)) / k
            v = vt * mp.tan(a - g * s / vt)
        else:
            u = s - up
            y, v = ya - mp.log(mp.cosh(g * u / vt)) / k, -vt * mp.tanh(g * u / vt)
        rows.append([float(tt), float(y), float(v)])
    print(f"ball_thrown_up_quadratic_drag: {len(phases) - 1} impacts before t = 5")
    return ["y"], rows


def rocket_sled_on_ramp():
    """Along the ramp, s' = w ln(M0/M) - g sin(a) t, s its integral: with
    u = M/M0, integral of ln(1/u) dt is (M0/mu)(u ln u - u + 1)."""
    mp.mp.dps = 30
    M0, mu, w, g, a = mp.mpf(500), mp.mpf(4), mp.mpf(1500), mp.mpf("9.81"), mp.mpf("0.5")
    rows = []
    for i in range(41):
        tt = mp.mpf(60) * i / 40
        u = (M0 - mu * tt) / M0
        v = -w * mp.log(u) - g * mp.sin(a) * tt
        s = w * M0 / mu * (u * mp.log(u) - u + 1) - g * mp.sin(a) * tt**2 / 2
        c, n = mp.cos(a), mp.sin(a)
        rows.append([float(tt), float(s * c), float(s * n), float(v * c), float(v * n)])
    return ["x", "y"], rows


def rocket_stage_at_altitude():
    """Burn 1 below H, z'' = mu1 w1/(M0 - mu1 t) - g; the drop where z = H
    (SciPy's event); then z'' = mu2 w2/(M2 - mu2 t) - g."""
    M0, mu1, w1, M2, mu2, w2, H = 1000, 10, 2000, 250, 2, 2500, 3000

    def below(tt, s):
        return [s[1], mu1 * w1 / (M0 - mu1 * tt) - G]

    def above(tt, s, mid=None):
        return [s[1], mu2 * w2 / (M2 - mu2 * tt) - G]

    def height(tt, s):
        return s[0] - H

    height.terminal, height.direction = True, 1
    sol = solve_ivp(below, (0, 60), [0, 0], method="DOP853", rtol=RTOL, atol=RTOL * 1e-3,
                    events=height)
    tH, sH = sol.t_events[0][0], sol.y_events[0][0]
    print(f"rocket_stage_dropped_at_altitude: the drop at t = {tH!r}")
    rows = []
    for i in range(41):
        tt = 60 * i / 40
        if tt <= tH:
            y = sol.y[:, 0] if tt == 0 else solve_ivp(below, (0, tt), [0, 0], method="DOP853",
                                                     rtol=RTOL, atol=RTOL * 1e-3).y[:, -1]
        else:
            y = step(above, tH, tt, sH)
        rows.append([tt, *y])
    return ["z"], rows


def rocket_from_pad():
    """Phases on t: thrust up until t1, tilted by kick until t2, along the
    velocity until tb, none after; each a fresh DOP853 solve."""
    M0, mu, w, t1, t2, kick, tb = 2000, 12, 2400, 8, 12, 0.05, 120

    def rate(tt, s, mid):
        x, y, vx, vy = s
        if mid < t1:
            ex, ey = 0.0, 1.0
        elif mid < t2:
            ex, ey = math.sin(kick), math.cos(kick)
        else:
            v = math.hypot(vx, vy)
            ex, ey = vx / v, vy / v
        thrust = mu * w / (M0 - mu * tt) if mid < tb else 0.0
        return [vx, vy, thrust * ex, thrust * ey - G]

    ts = [200 * i / 40 for i in range(41)]
    return ["x", "y"], sampled(rate, ts, [0, 0, 0, 0], breaks=(t1, t2, tb))


def folded_chain():
    Lc = 2.0

    def rate(tt, s, mid):
        x, xd = s
        return [xd, G + xd * xd / (Lc - x)]

    ts = [0.45 * i / 40 for i in range(41)]
    return ["x"], sampled(rate, ts, [0.0, 0.0])


def rocket_raising_orbit():
    """In Cartesian coordinates: r'' = -k r/|r|^3 + mu w/M v/|v| while t < tb;
    then the polar columns r, th (unwrapped), r', th' from the state."""
    k, M0, mu, w, tb = 1.0, 1.0, 0.01, 2.0, 20.0

    def rate(tt, s, mid):
        x, y, vx, vy = s
        d3 = math.hypot(x, y) ** 3
        v = math.hypot(vx, vy)
        thrust = mu * w / (M0 - mu * tt) if mid < tb else 0.0
        return [vx, vy, -k * x / d3 + thrust * vx / v, -k * y / d3 + thrust * vy / v]

    ts = [40 * i / 40 for i in range(41)]
    rows, turns, last = [], 0.0, 0.0
    for tt, x, y, vx, vy in sampled(rate, ts, [1, 0, 0, 1], breaks=(tb,)):
        r = math.hypot(x, y)
        th = math.atan2(y, x)
        while th + turns < last - math.pi:
            turns += 2 * math.pi
        th += turns
        last = th
        rows.append([tt, r, th, (x * vx + y * vy) / r, (x * vy - y * vx) / (r * r)])
    return ["r", "th"], rows


MODELS = {
    "rocket_three_stage_gravity_turn": rocket_three_stage,
    "rocket_fuel_coordinate": rocket_fuel,
    "ball_on_incline": ball_on_incline,
    "ball_against_step": ball_against_step,
    "ball_in_circular_bowl": ball_in_bowl,
    "kepler_hundred_periods": kepler,
    "elastic_pendulum_chaotic": elastic_pendulum,
    "rocket_fuel_runs_out": rocket_fuel_runs_out,
    "chain_off_heap_from_rest": chain_off_heap,
    "ball_in_bowl_with_drag": ball_in_bowl_drag,
    "ball_in_hoop_elastic_long": ball_in_hoop_elastic,
    "ball_thrown_up_quadratic_drag": ball_thrown_up_drag,
    "rocket_sled_on_ramp": rocket_sled_on_ramp,
    "rocket_stage_dropped_at_altitude": rocket_stage_at_altitude,
    "rocket_gravity_turn_from_pad": rocket_from_pad,
    "folded_chain_free_end": folded_chain,
    "rocket_raising_orbit": rocket_raising_orbit,
}


def main():
    for name in sys.argv[1:] or MODELS:
        names, rows = MODELS[name]()
        head = ["t", *names, *[q + "'" for q in names]]
        with open(os.path.join(HERE, name + ".csv"), "w") as out:
            out.write(",".join(head) + "\n")
            for r in rows:
                out.write(",".join(repr(float(v)) for v in r) + "\n")
        print(f"{name}: {len(rows)} rows")


if __name__ == "__main__":
    main()
