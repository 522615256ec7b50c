"""A 40-digit reference for benches/data/ball_on_varying_turntable.lag,
derived by hand (Newton-Euler), independent of lagc's derivation:
  rolling: v = r(w_y, -w_x) + W(t) ez x rho;  m a = F;  I dw/dt = (-r ez) x F
  => x'' = -(W' y + W y')/(1 + m r^2/I),  y'' = (W' x + W x')/(1 + m r^2/I)
     w_x = w_x0 + (m r/I)(y' - y'0), w_y = w_y0 - (m r/I)(x' - x'0), w_z = w_z0
  Euler z-x-z (space frame): th' = w_x cos phi + w_y sin phi,
     psi' = (w_x sin phi - w_y cos phi)/sin th,  phi' = w_z - psi' cos th.
Integrated with DOP853's tableau (SciPy's coefficients) at a fixed step in
mpmath (dps 40); run at h and h/2 to show the reference's own error.

    python3 -m venv v && v/bin/pip install mpmath scipy
    v/bin/python scripts/ball_on_varying_turntable_reference.py SAMPLES STEPS > ref.csv

SAMPLES evenly spaced times over 0 .. 5 (11 as `lagc report`), STEPS fixed
steps between samples (800 for 11 samples: the h/2 solution printed is
within about 1e-15; stderr says the h-to-h/2 difference, 2.6e-13 there;
4 minutes). The columns are the generated binary's: t, x, y, phi, th, psi,
then their derivatives (docs/BENCHMARKS.md section 0, "The ball on a
varying turntable against a hand-derived reference")."""
import sys
import mpmath as mp
from scipy.integrate._ivp import dop853_coefficients as C

mp.mp.dps = 40
m, r, W0, W1, Om = mp.mpf(1), mp.mpf("0.1"), mp.mpf(2), mp.mpf(1), mp.mpf("1.5")
I = mp.mpf(2) / 5 * m * r**2
k = 1 + m * r**2 / I
phi0, th0, psi0 = mp.mpf(0), mp.mpf(1.5707963267948966), mp.mpf(0)
dphi0, dth0, dpsi0 = mp.mpf(3), mp.mpf("-0.5") / r, mp.mpf("-0.3") / r
x0, y0 = mp.mpf("0.2"), mp.mpf(0)
wx0 = dth0 * mp.cos(phi0) + dpsi0 * mp.sin(th0) * mp.sin(phi0)
wy0 = dth0 * mp.sin(phi0) - dpsi0 * mp.sin(th0) * mp.cos(phi0)
wz0 = dphi0 + dpsi0 * mp.cos(th0)
W = lambda t: W0 + W1 * mp.sin(Om * t)
dW = lambda t: W1 * Om * mp.cos(Om * t)
vx0 = r * wy0 - W(0) * y0
vy0 = -r * wx0 + W(0) * x0


def omega(u):
    x, y, vx, vy = u[0], u[1], u[2], u[3]
    return (wx0 + m * r / I * (vy - vy0), wy0 - m * r / I * (vx - vx0), wz0)


def euler_rates(u):
    wx, wy, wz = omega(u)
    phi, th = u[4], u[5]
    dth = wx * mp.cos(phi) + wy * mp.sin(phi)
    dpsi = (wx * mp.sin(phi) - wy * mp.cos(phi)) / mp.sin(th)
    dphi = wz - dpsi * mp.cos(th)
    return dphi, dth, dpsi


def f(t, u):
    x, y, vx, vy = u[0], u[1], u[2], u[3]
    dphi, dth, dpsi = euler_rates(u)
    return [vx, vy, -(dW(t) * y + W(t) * vy) / k, (dW(t) * x + W(t) * vx) / k, dphi, dth, dpsi]


A = [[mp.mpf(float(a)) for a in row] for row in C.A[:12, :12]]
B = [mp.mpf(float(b)) for b in C.B]
Cc = [mp.mpf(float(c)) for c in C.C[:12]]


def step(t, u, h):
    ks = []
    for i in range(12):
        ui = [u[j] + h * sum(A[i][l] * ks[l][j] for l in range(i)) for j in range(7)]
        ks.append(f(t + Cc[i] * h, ui))
    return [u[j] + h * sum(B[i] * ks[i][j] for i in range(12)) for j in range(7)]


def solve(nsteps_per_sample, samples):
    t_end = mp.mpf(5)
    u = [x0, y0, vx0, vy0, phi0, th0, psi0]
    out = [row(0, u)]
    for s in range(1, samples):
        t0 = t_end * (s - 1) / (samples - 1)
        h = t_end / (samples - 1) / nsteps_per_sample
        for i in range(nsteps_per_sample):
            u = step(t0 + i * h, u, h)
        out.append(row(t_end * s / (samples - 1), u))
    return out


def row(t, u):
    dphi, dth, dpsi = euler_rates(u)
    return [t, u[0], u[1], u[4], u[5], u[6], u[2], u[3], dphi, dth, dpsi]


if __name__ == "__main__":
    samples = int(sys.argv[1]); n = int(sys.argv[2])
    a = solve(n, samples)
    b = solve(2 * n, samples)
    diff = max(abs(p - q) / max(abs(q), 1) for ra, rb in zip(a, b) for p, q in zip(ra[1:], rb[1:]))
    print("h vs h/2 largest relative difference:", mp.nstr(diff, 3), file=sys.stderr)
    print("t,x,y,phi,th,psi,x',y',phi',th',psi'")
    for rw in b:
        print(",".join(mp.nstr(v, 25) for v in rw))
