#!/usr/bin/env python3
"""Independent references for the non-linear implicit constraints
(issue 28 item 4), from equations derived by hand, not by lagc.

1. The constant-speed particle, x'^2 + y'^2 = c^2 in gravity g
   (examples/constant_speed_implicit.lag). Multiplier form (Chetaev):
   x'' - (y'' + g) x'/y' = 0 with y'' = -x' x''/y', i.e.
       x'' = g x' y'/c^2,   y'' = -g x'^2/c^2
   (no division: smooth through the apex y' = 0). Closed form:
       x' = c/cosh(u), y' = -c tanh(u), u = g t/c + tau0.
2. The constant-acceleration orbit, x''^2 + y''^2 = A^2 on a central
   spring (examples/constant_acceleration_orbit.lag): the multiplier form
   gives kk (x y'' - y x'') = 0, so a = -A r/|r| on the branch x''(0) < 0:
       x'' = -A x/r,   y'' = -A y/r.
   Closed form from x = R, y' = R w, A = R w^2: the circle x = R cos(w t).

SciPy integrates the hand-derived equations (DOP853, rtol 1e-13) and the
script prints their distance from the closed forms. Given lagc CSV files
(`--speed FILE`, `--orbit FILE`, `--eccentric FILE`: the examples run with
`--samples N`, the last with `--init "y'=1.2"`), it prints lagc's distance
from the SciPy solution too; `--eccentric` has no closed form.

    python3 scripts/check_constant_speed.py [--speed s.csv] [--orbit o.csv] [--eccentric e.csv]
"""
import argparse
import csv
import math

import numpy as np
from scipy.integrate import solve_ivp

G, C = 9.81, 1.0
TAU0 = -0.5 * math.log(9.0)
R, W = 1.0, 1.0
A = R * W * W


def speed_rhs(t, s):
    x, y, vx, vy = s
    return [vx, vy, G * vx * vy / C**2, -G * vx * vx / C**2]


def speed_exact(t):
    u = G * t / C + TAU0
    return np.array([
        C**2 / G * (math.atan(math.sinh(u)) - math.atan(math.sinh(TAU0))),
        -C**2 / G * (math.log(math.cosh(u)) - math.log(math.cosh(TAU0))),
        C / math.cosh(u),
        -C * math.tanh(u),
    ])


def orbit_rhs(t, s):
    x, y, vx, vy = s
    r = math.hypot(x, y)
    return [vx, vy, -A * x / r, -A * y / r]


def orbit_exact(t):
    return np.array([R * math.cos(W * t), R * math.sin(W * t),
                     -R * W * math.sin(W * t), R * W * math.cos(W * t)])


def integrate(rhs, s0, ts):
    sol = solve_ivp(rhs, (ts[0], ts[-1]), s0, method="DOP853", rtol=1e-13,
                    atol=1e-14, t_eval=ts, dense_output=True)
    assert sol.success, sol.message
    return sol


def lagc_distance(path, sol, columns):
    rows = list(csv.DictReader(open(path)))
    worst = 0.0
    for row in rows:
        t = float(row["t"])
        ref = sol.sol(t)
        got = np.array([float(row[c]) for c in columns])
        worst = max(worst, float(np.max(np.abs(got - ref))))
    return worst, len(rows)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--speed")
    ap.add_argument("--orbit")
    ap.add_argument("--eccentric")
    args = ap.parse_args()
    cols = ["x", "y", "x'", "y'"]

    ts = np.linspace(0.0, 2.0, 2001)
    sol = integrate(speed_rhs, speed_exact(0.0), ts)
    err = max(float(np.max(np.abs(sol.sol(t) - speed_exact(t)))) for t in ts)
    apex = -TAU0 * C / G
    print(f"constant speed: SciPy vs closed form, max error {err:.3e} "
          f"(apex at t = {apex:.9f}, y' there {sol.sol(apex)[3]:.2e})")
    if args.speed:
        d, n = lagc_distance(args.speed, sol, cols)
        print(f"constant speed: lagc ({n} rows) vs SciPy, max difference {d:.3e}")

    ts = np.linspace(0.0, 10.0, 2001)
    sol = integrate(orbit_rhs, orbit_exact(0.0), ts)
    err = max(float(np.max(np.abs(sol.sol(t) - orbit_exact(t)))) for t in ts)
    print(f"orbit: SciPy vs closed form, max error {err:.3e}")
    if args.orbit:
        d, n = lagc_distance(args.orbit, sol, cols)
        print(f"orbit: lagc ({n} rows) vs SciPy, max difference {d:.3e}")

    s0 = [R, 0.0, 0.0, 1.2 * R * W]
    sol = integrate(orbit_rhs, s0, ts)
    r = [math.hypot(*sol.sol(t)[:2]) for t in ts]
    print(f"eccentric orbit (y'(0) = 1.2): r from {min(r):.4f} to {max(r):.4f}")
    if args.eccentric:
        d, n = lagc_distance(args.eccentric, sol, cols)
        print(f"eccentric orbit: lagc ({n} rows) vs SciPy, max difference {d:.3e}")


if __name__ == "__main__":
    main()
