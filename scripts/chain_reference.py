#!/usr/bin/env python3
"""Reference for tests/it/chains.rs: a chain of N equal links (mass m at
each link's end, length l) hanging from a pin, released at rest straight
at 60 degrees from the vertical, integrated in its link angles (SciPy
DOP853 at rtol 1e-13) from the hand-derived equations
    sum_j c_ij cos(a_i - a_j) a_j'' = -sum_j c_ij sin(a_i - a_j) a_j'^2
                                      - g l m (N - i + 1) sin a_i,
    c_ij = m l^2 (N - max(i, j) + 1)  (1-based: the masses beyond both links),
and printed as the points' Cartesian positions (x_k, y_k) at t = 0.5, 1, 1.5, 2.

    python3 scripts/chain_reference.py [N]
"""
import sys
import numpy as np
from scipy.integrate import solve_ivp

N = int(sys.argv[1]) if len(sys.argv) > 1 else 5
g, l, m = 9.81, 0.5, 1.0
c = np.array([[m * l * l * (N - max(i, j)) for j in range(N)] for i in range(N)])


def rhs(t, s):
    a, w = s[:N], s[N:]
    d = a[:, None] - a[None, :]
    mass = c * np.cos(d)
    force = -(c * np.sin(d)) @ (w * w) - g * l * m * (N - np.arange(N)) * np.sin(a)
    return np.concatenate([w, np.linalg.solve(mass, force)])


a0 = np.full(N, np.radians(60.0))
times = [0.5, 1.0, 1.5, 2.0]
refs = []
for rtol in (1e-13, 3e-14):
    sol = solve_ivp(rhs, (0, 2), np.concatenate([a0, np.zeros(N)]), method='DOP853',
                    rtol=rtol, atol=1e-15, t_eval=times)
    refs.append(sol.y)
print(f"// its own error (rtol 1e-13 against 3e-14): {np.abs(refs[0] - refs[1]).max():.1e}")
for k, t in enumerate(times):
    a = refs[1][:N, k]
    xs, ys = np.cumsum(l * np.sin(a)), np.cumsum(-l * np.cos(a))
    pts = ", ".join(f"({float(x)!r}, {float(y)!r})" for x, y in zip(xs, ys))
    print(f"({t!r}, [{pts}]),")
