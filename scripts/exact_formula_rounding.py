#!/usr/bin/env python3
"""The f64 rounding of the examples' own exact formulas (issue 29, "no
accuracy floor"): the `exact` lines of saturn_rocket and rocket_near_burnout,
written here by hand as the generated crate evaluates them (f64, the same
operations), against the same formulas in 40-digit mpmath, at the 101 and
1001 sample times of `lagc run --samples N`. The measure is the runtime's:
each component's difference over max(|exact|, 1), the largest.

A run cannot be closer to these formulas than their own rounding:
`w (t + (M0 - mu t)/mu ln((M0 - mu t)/M0))` cancels to ~mu w t^2 / 2 M0 at
small t, so the logarithm's rounding (eps) is multiplied by w M0 / mu.

    python3 scripts/exact_formula_rounding.py
"""

import math

import mpmath as mp

mp.mp.dps = 40

MODELS = {
    # name: (M0, mu, w, g, z0, v0, t_end)
    "saturn_rocket": (2.97e6, 1.29e4, 2.58e3, 9.81, 0.0, 1e-2, 150.0),
    "rocket_near_burnout": (1000.0, 10.0, 2000.0, 9.81, 0.0, 0.0, 1000.0 / 10.0 - 1e-4),
}


def in_f64(p, t):
    M0, mu, w, g, z0, v0, _ = p
    v = v0 + w * math.log(M0 / (M0 - mu * t)) - g * t
    z = z0 + v0 * t - g * t**2 / 2 + w * (t + (M0 - mu * t) / mu * math.log((M0 - mu * t) / M0))
    return z, v


def in_mp(p, t):
    M0, mu, w, g, z0, v0, _ = (mp.mpf(x) for x in p)
    t = mp.mpf(t)
    v = v0 + w * mp.log(M0 / (M0 - mu * t)) - g * t
    z = z0 + v0 * t - g * t**2 / 2 + w * (t + (M0 - mu * t) / mu * mp.log((M0 - mu * t) / M0))
    return z, v


for name, p in MODELS.items():
    for n in (101, 1001):
        worst = (0.0, 0.0)
        for i in range(n):
            t = p[-1] * i / (n - 1)
            e = max(abs(float(a - b)) / max(abs(float(b)), 1.0)
                    for a, b in zip(in_f64(p, t), in_mp(p, t)))
            worst = max(worst, (e, t))
        print(f"{name:22s} {n:5d} samples: the formula's own error {worst[0]:.4e} at t = {worst[1]:g}")
