#!/usr/bin/env python3
"""References for tests/data/textbook_rolling/: closed forms, written as CSV
(t, x, phi, x', phi') next to each model. Reference only, never a dependency.

disk_on_incline: a uniform disk rolling without slipping, x'' = (2/3) g sin(alpha)
(Newton-Euler: m x'' = m g sin(alpha) - f, (m R^2/2) phi'' = f R, x' = R phi').
"""
import math, sys, pathlib

def disk_on_incline(t, m=2.0, R=0.3, g=9.81, alpha=0.4, x0=0.0, v0=1.0):
    a = 2.0 / 3.0 * g * math.sin(alpha)
    x = x0 + v0 * t + a * t * t / 2
    v = v0 + a * t
    return x, x / R, v, v / R

def main():
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/textbook_rolling")
    with open(out / "disk_on_incline.csv", "w") as f:
        f.write("t,x,phi,x',phi'\n")
        for i in range(31):
            t = round(0.1 * i, 12)
            f.write(",".join(repr(v) for v in (t, *disk_on_incline(t))) + "\n")

if __name__ == "__main__":
    main()
