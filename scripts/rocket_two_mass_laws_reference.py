#!/usr/bin/env python3
"""Independent reference for benches/data/rocket_two_mass_laws.lag (issue 29):
the equations of motion written by hand from Meshchersky's equation (see the
model's header) and integrated with SciPy's DOP853 and Radau at rtol 1e-13,
compared with `lagc run` (direct DOP853 and the field method) at 7 samples.

Usage (from the repository root, after `cargo build --release -p lagc`):

    python3 scripts/rocket_two_mass_laws_reference.py [RTOL]

Prints the largest relative difference |a - b| / max(|b|, 1) over samples and
components: SciPy DOP853 against Radau (the reference's own spread), and
lagc direct and lagc field (at RTOL, default 1e-12) against SciPy DOP853.
"""

import math
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp

Mc0, mu, wc = 400.0, 2.5, 2400.0
Mb0, a, wb = 150.0, 0.04, 1900.0
g, rho0, H, CdA = 9.81, 1.225, 8000.0, 0.12
k, Ka, Kd = 2.0, 0.5, 200.0
v0, gam0 = 60.0, 1.3
MODEL = "benches/data/rocket_two_mass_laws.lag"


def rhs(t, s):
    x, y, th, vx, vy, w = s
    Mc = Mc0 - mu * t
    Mb = Mb0 * math.exp(-a * t)
    M = Mc + Mb
    sp = math.hypot(vx, vy)
    rho = rho0 * math.exp(-y / H)
    D = 0.5 * rho * CdA * sp
    thrust = mu * wc + a * Mb * wb
    ax = (thrust * math.cos(th) - D * vx) / M
    ay = (thrust * math.sin(th) - D * vy) / M - g
    moment = -Ka * rho * sp * (math.sin(th) * vx - math.cos(th) * vy) - Kd * w
    return [vx, vy, w, ax, ay, moment / (M * k * k)]


def lagc(method, rtol):
    p = subprocess.run(["target/release/lagc", "run", MODEL, "--", "--method", method,
                        "--rtol", str(rtol), "--atol", str(rtol), "--samples", "7"],
                       capture_output=True, text=True, check=True)
    return np.array([list(map(float, l.split(","))) for l in p.stdout.strip().splitlines()[1:]])


def difference(a, b):
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1.0)))


def main():
    rtol = float(sys.argv[1]) if len(sys.argv) > 1 else 1e-12
    times = np.linspace(0.0, 120.0, 7)
    s0 = [0.0, 0.0, 1.35, v0 * math.cos(gam0), v0 * math.sin(gam0), 0.0]
    ref = {}
    for m in ("DOP853", "Radau"):
        sol = solve_ivp(rhs, (0.0, 120.0), s0, method=m, rtol=1e-13, atol=1e-13, t_eval=times)
        ref[m] = np.column_stack([sol.t, sol.y.T])
    print(f"SciPy DOP853 vs Radau (rtol 1e-13): {difference(ref['DOP853'][:, 1:], ref['Radau'][:, 1:]):.2e}")
    for method in ("direct", "field"):
        rows = lagc(method, rtol)
        print(f"lagc {method} at rtol {rtol:g} vs SciPy DOP853: "
              f"{difference(rows[:, 1:], ref['DOP853'][:, 1:]):.2e}")


if __name__ == "__main__":
    main()
