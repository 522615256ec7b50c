#!/usr/bin/env python3
"""Independent references for the holonomic and coupled-constraint examples
(tests/it/holonomic.rs), in minimal coordinates, integrated by SciPy.

- examples/cartesian_pendulum.lag: the pendulum in its angle,
  theta'' = -g/l sin(theta), x = l sin(theta), y = -l cos(theta).
- examples/four_bar_closure.lag and four_bar_velocity.lag: the four-bar
  (uniform crank and rocker, a light coupler) in its crank angle a; the
  closure solved for the rocker c and the coupler b with acos and atan2 (the
  branch of the examples' initial angles), the inertia M(a) and the
  potential V(a) derived by SymPy, then M a'' + M'(a) a'^2 / 2 + V'(a) = 0.

Both at rtol 1e-13 with DOP853; the difference from rtol 1e-12 (printed)
bounds the references' own error. Run: python3 scripts/holonomic_references.py
"""
import math

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp


def pendulum(times, rtol):
    g, l = 9.81, 1.0
    theta0 = math.atan2(0.6, 0.8)
    sol = solve_ivp(lambda t, y: [y[1], -g / l * math.sin(y[0])], (0, times[-1]),
                    [theta0, 0.0], method='DOP853', rtol=rtol, atol=rtol * 0.1,
                    t_eval=times)
    return sol.y[0]


def four_bar(times, rtol):
    l1, l2, l3, d = 1.0, 3.0, 2.5, 3.0
    m1, m3, g = 1.0, 1.5, 9.81
    a = sp.symbols('a')
    ax, ay = l1 * sp.cos(a), l1 * sp.sin(a)
    e = sp.sqrt((ax - d)**2 + ay**2)
    # The branch of b = 0.59, c = 1.55 at a = 1 (the rocker above the ground).
    c = sp.atan2(ay, ax - d) - sp.acos((l3**2 + e**2 - l2**2) / (2 * l3 * e))
    b = sp.atan2(l3 * sp.sin(c) - ay, d + l3 * sp.cos(c) - ax)
    ca = sp.diff(c, a)
    inertia = m1 * l1**2 / 3 + m3 * l3**2 / 3 * ca**2
    potential = g * (m1 * l1 / 2 * sp.sin(a) + m3 * l3 / 2 * sp.sin(c))
    m_f = sp.lambdify(a, inertia, 'math')
    ma_f = sp.lambdify(a, sp.diff(inertia, a), 'math')
    va_f = sp.lambdify(a, sp.diff(potential, a), 'math')
    b_f, c_f = sp.lambdify(a, b, 'math'), sp.lambdify(a, c, 'math')

    def rhs(_, y):
        return [y[1], -(0.5 * ma_f(y[0]) * y[1]**2 + va_f(y[0])) / m_f(y[0])]

    sol = solve_ivp(rhs, (0, times[-1]), [1.0, 3.0], method='DOP853', rtol=rtol,
                    atol=rtol * 0.1, t_eval=times)
    return [(q, b_f(q), c_f(q)) for q in sol.y[0]], (b_f(1.0), c_f(1.0))


def main():
    times = [100.0, 250.0, 500.0, 750.0, 1000.0]
    th, th12 = pendulum(times, 1e-13), pendulum(times, 1e-12)
    print("// cartesian_pendulum: (t, theta)")
    for t, v, w in zip(times, th, th12):
        print(f"    ({t!r}, {float(v)!r}), // rtol 1e-12: {float(v - w):.1e}")
    times = [10.0, 25.0, 50.0, 75.0, 100.0]
    fb, start = four_bar(times, 1e-13)
    fb12, _ = four_bar(times, 1e-12)
    print(f"// four_bar: b, c at a = 1: {start[0]!r}, {start[1]!r}")
    print("// four_bar: (t, a, b, c), angles mod 2 pi")
    for t, (q, bb, cc), (q12, _, _) in zip(times, fb, fb12):
        print(f"    ({t!r}, {float(q)!r}, {float(bb)!r}, {float(cc)!r}), "
              f"// rtol 1e-12: {float(q - q12):.1e}")


if __name__ == '__main__':
    main()
