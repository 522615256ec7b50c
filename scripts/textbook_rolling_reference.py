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


def two_link_arm_pd(out):
    """A 2-link arm with PD joint torques: Lagrange in joint angles by SymPy,
    mass matrix and bias terms checked against the textbook forms, integrated
    by SciPy DOP853 at rtol 1e-13 (needs the reference venv)."""
    import sympy as sp, numpy as np
    from scipy.integrate import solve_ivp
    t=sp.symbols('t'); a=sp.Function('a')(t); b=sp.Function('b')(t)
    m1,m2,l1,l2,g,kp,kd,ar,br=1.5,1,0.8,0.6,9.81,20,3,1,0.5
    I1=m1*l1**2/12; I2=m2*l2**2/12
    x1=l1/2*sp.sin(a); y1=-l1/2*sp.cos(a)
    x2=l1*sp.sin(a)+l2/2*sp.sin(a+b); y2=-l1*sp.cos(a)-l2/2*sp.cos(a+b)
    d=lambda e: sp.diff(e,t)
    T=m1/2*(d(x1)**2+d(y1)**2)+I1/2*d(a)**2+m2/2*(d(x2)**2+d(y2)**2)+I2/2*(d(a)+d(b))**2
    V=g*(m1*y1+m2*y2); L=T-V
    Q=[-kp*(a-ar)-kd*d(a), -kp*(b-br)-kd*d(b)]
    eqs=[sp.simplify(d(sp.diff(L,d(q)))-sp.diff(L,q)-Qi) for q,Qi in zip([a,b],Q)]
    A,B,Ad,Bd,Add,Bdd=sp.symbols('A B Ad Bd Add Bdd')
    sub=lambda e: e.subs({d(d(a)):Add,d(d(b)):Bdd}).subs({d(a):Ad,d(b):Bd}).subs({a:A,b:B})
    E=[sub(e) for e in eqs]
    M=sp.Matrix([[sp.diff(e,v) for v in (Add,Bdd)] for e in E])
    # hand check: textbook mass matrix of the 2-link arm
    lc1,lc2=l1/2,l2/2
    M_hand=sp.Matrix([[m1*lc1**2+I1+m2*(l1**2+lc2**2+2*l1*lc2*sp.cos(B))+I2, m2*(lc2**2+l1*lc2*sp.cos(B))+I2],
                      [m2*(lc2**2+l1*lc2*sp.cos(B))+I2, m2*lc2**2+I2]])
    import random
    for _ in range(5):
        pt={A:random.random(),B:random.random(),Ad:random.random(),Bd:random.random()}
        assert max(abs(float(v)) for v in (M-M_hand).subs(pt))<1e-12
    h=[sp.simplify(e.subs({Add:0,Bdd:0})) for e in E]
    hs=sp.Matrix(h); hhand=sp.Matrix([-m2*l1*lc2*sp.sin(B)*(2*Ad*Bd+Bd**2)+(m1*lc1+m2*l1)*g*sp.sin(A)+m2*lc2*g*sp.sin(A+B)+kp*(A-ar)+kd*Ad,
      m2*l1*lc2*sp.sin(B)*Ad**2+m2*lc2*g*sp.sin(A+B)+kp*(B-br)+kd*Bd])
    for _ in range(5):
        pt={A:random.random(),B:random.random(),Ad:random.random(),Bd:random.random()}
        assert max(abs(float(v)) for v in (hs-hhand).subs(pt))<1e-12
    fM=sp.lambdify((A,B),M,'numpy'); fh=sp.lambdify((A,B,Ad,Bd),hs,'numpy')
    def rhs(t,s):
        acc=np.linalg.solve(np.array(fM(s[0],s[1]),float),-np.array(fh(*s),float).ravel())
        return [s[2],s[3],acc[0],acc[1]]
    ts=[round(0.1*i,12) for i in range(31)]
    sol=solve_ivp(rhs,(0,3),[0.2,-0.3,0,0],method='DOP853',rtol=1e-13,atol=1e-15,t_eval=ts)
    with open(out / 'two_link_arm_pd.csv','w') as f:
        f.write("t,a,b,a',b'\n")
        for i,tt in enumerate(ts): f.write(",".join(repr(float(v)) for v in (tt,*sol.y[:,i]))+"\n")

def coin_euler_angles(out):
    """A coin rolling on a table in Euler angles: Lagrange's equations with
    multipliers for the two rolling constraints (not lagc's reduction), T
    checked against the textbook form, SciPy DOP853 at rtol 1e-13; energy
    and slip are checked along the reference."""
    import sympy as sp, numpy as np, random
    from scipy.integrate import solve_ivp
    m,R,g=0.01,0.02,9.81
    q=sp.symbols('x y phi th psi'); qd=sp.symbols('xd yd phid thd psid')
    x,y,phi,th,psi=q; xd,yd,phid,thd,psid=qd
    et=sp.Matrix([sp.cos(phi),sp.sin(phi),0]); en=sp.Matrix([-sp.sin(phi),sp.cos(phi),0]); ez=sp.Matrix([0,0,1])
    G=sp.Matrix([x,y,R*sp.cos(th)]); r=-R*(sp.sin(th)*en+sp.cos(th)*ez)
    axle=-sp.cos(th)*en+sp.sin(th)*ez
    w=phid*ez-thd*et+psid*axle
    Gd=G.jacobian(q)*sp.Matrix(qd)
    T=sp.Rational(1,2)*m*Gd.dot(Gd)+m*R**2/8*w.dot(w)+m*R**2/8*(w.dot(axle))**2
    # hand check: T of the rolling coin in Euler angles (textbook form)
    Th=m/2*(xd**2+yd**2+R**2*sp.sin(th)**2*thd**2)+m*R**2/8*(thd**2+phid**2*sp.cos(th)**2)+m*R**2/4*(psid+phid*sp.sin(th))**2
    for _ in range(5):
        pt={s:random.uniform(-2,2) for s in q+qd}
        assert abs(float((T-Th).subs(pt)))<1e-15
    V=m*g*R*sp.cos(th); L=T-V
    slip=Gd+w.cross(r)
    A=sp.Matrix([[sp.diff(slip[k],v) for v in qd] for k in range(2)])
    assert sp.simplify(A*sp.Matrix(qd)-slip[:2,0])==sp.zeros(2,1)
    Mm=sp.hessian(L,qd)
    h=sp.Matrix([sum(sp.diff(L,qd[i],q[j])*qd[j] for j in range(5))-sp.diff(L,q[i]) for i in range(5)])
    Adq=(A*sp.Matrix(qd)).jacobian(q)*sp.Matrix(qd)
    f=sp.lambdify(q+qd,(Mm,h,A,Adq),'numpy')
    def rhs(t,s):
        M,hh,AA,ad=[np.array(v,float) for v in f(*s)]
        K=np.zeros((7,7)); K[:5,:5]=M; K[:5,5:]=-AA.T; K[5:,:5]=AA
        sol=np.linalg.solve(K,np.concatenate([-hh.ravel(),-ad.ravel()]))
        return np.concatenate([s[5:],sol[:5]])
    s0=np.array([0,0,0,0.3,0,R*(20-2*np.sin(0.3)),0.5*R*np.cos(0.3),2,0.5,-20])
    ts=[round(0.05*i,12) for i in range(41)]
    sol=solve_ivp(rhs,(0,2),s0,method='DOP853',rtol=1e-13,atol=1e-15,t_eval=ts)
    fE=sp.lambdify(q+qd,T+V); fs=sp.lambdify(q+qd,slip)
    drift = max(abs(fE(*sol.y[:, i]) - fE(*s0)) for i in range(len(ts)))
    slipmax = max(np.abs(np.array(fs(*sol.y[:, i]), float)).max() for i in range(len(ts)))
    assert drift < 1e-15 and slipmax < 1e-12, (drift, slipmax)
    with open(out / 'coin_euler_angles.csv','w') as fo:
        fo.write("t,x,y,phi,th,psi,x',y',phi',th',psi'\n")
        for i,tt in enumerate(ts): fo.write(",".join(repr(float(v)) for v in (tt,*sol.y[:,i]))+"\n")

def coin_circling_spin(th0=0.3, om=3.0, m=0.01, R=0.02, g=9.81):
    """The spin psi' of the coin circling steadily at lean th0 and precession
    om (tests/data/textbook_rolling/coin_circling.lag): th' = 0, phi' = om,
    x', y' from the rolling constraints, and th'' = 0 in Lagrange's equations
    with multipliers (the same equations as coin_euler_angles), solved by
    Brent's method."""
    import numpy as np
    import sympy as sp
    from scipy.optimize import brentq
    q = sp.symbols('x y phi th psi'); qd = sp.symbols('xd yd phid thd psid')
    x, y, phi, th, psi = q; xd, yd, phid, thd, psid = qd
    et = sp.Matrix([sp.cos(phi), sp.sin(phi), 0]); en = sp.Matrix([-sp.sin(phi), sp.cos(phi), 0])
    ez = sp.Matrix([0, 0, 1])
    G = sp.Matrix([x, y, R * sp.cos(th)]); r = -R * (sp.sin(th) * en + sp.cos(th) * ez)
    axle = -sp.cos(th) * en + sp.sin(th) * ez
    w = phid * ez - thd * et + psid * axle
    Gd = G.jacobian(q) * sp.Matrix(qd)
    T = m / 2 * Gd.dot(Gd) + m * R**2 / 8 * w.dot(w) + m * R**2 / 8 * (w.dot(axle))**2
    L = T - m * g * R * sp.cos(th)
    slip = Gd + w.cross(r)
    A = sp.Matrix([[sp.diff(slip[k], v) for v in qd] for k in range(2)])
    Mm = sp.hessian(L, qd)
    h = sp.Matrix([sum(sp.diff(L, qd[i], q[j]) * qd[j] for j in range(5)) - sp.diff(L, q[i]) for i in range(5)])
    Adq = (A * sp.Matrix(qd)).jacobian(q) * sp.Matrix(qd)
    f = sp.lambdify(q + qd, (Mm, h, A, Adq), 'numpy')

    def lean_acceleration(spin):
        st = np.array([0, 0, 0, th0, 0, 0, 0, om, 0, spin], float)
        M, hh, AA, ad = [np.array(v, float) for v in f(*st)]
        st[5:7] = -np.linalg.solve(AA[:, :2], AA[:, 2:] @ st[7:])
        M, hh, AA, ad = [np.array(v, float) for v in f(*st)]
        K = np.zeros((7, 7)); K[:5, :5] = M; K[:5, 5:] = -AA.T; K[5:, :5] = AA
        return np.linalg.solve(K, np.concatenate([-hh.ravel(), -ad.ravel()]))[3]

    return brentq(lean_acceleration, -100, -1, xtol=1e-15, rtol=1e-15)

def main():
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/textbook_rolling")
    with open(out / "disk_on_incline.csv", "w") as f:
        f.write("t,x,phi,x',phi'\n")
        for i in range(31):
            t = round(0.1 * i, 12)
            f.write(",".join(repr(v) for v in (t, *disk_on_incline(t))) + "\n")

    two_link_arm_pd(out)
    coin_euler_angles(out)
    print('coin_circling spin', repr(coin_circling_spin()))

if __name__ == "__main__":
    main()
