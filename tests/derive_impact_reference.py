"""Symbolic derivations behind tests/impact_reference.py (sympy; run by hand, not collected by pytest).

    python tests/derive_impact_reference.py

1. SLS first-order perturbation in epsilon ([BS] eq. 21): e1(zeta) and tau1(zeta) from the
   residues of u(s) = s (1 + 2 zeta eps s)/p(s), f(s) = (1 + 2 zeta s)/p(s),
   p(s) = 2 zeta eps s^3 + s^2 + 2 zeta s + 1, slow root lam = s0 + eps s1 (see sls_e1).
   Printed: the closed forms agree with the brute-force eps-derivative at sample zetas, and the
   Taylor coefficients at zeta = 1 used by sls_e1 / sls_tau1.
2. Hunt-Crossley small-a series of e from ln((1+a)/(1-a e)) = a (1+e).
3. Small-zeta series of the reconstructed f1, f2 of [BS] eq. 21.
"""
import sympy as sp

z, eps, tau, d, a = sp.symbols("zeta epsilon tau d a")


def first_order_sls():
    beta = sp.sqrt(1 - z ** 2)
    s0 = -z + sp.I * beta
    s1 = -z * s0 ** 3 / (s0 + z)
    lam = sp.Symbol("lam")
    p = 2 * z * eps * lam ** 3 + lam ** 2 + 2 * z * lam + 1
    dp = sp.diff(p, lam)
    Ru = lam * (1 + 2 * z * eps * lam) / dp
    Rf = (1 + 2 * z * lam) / dp
    tau0 = 2 * sp.acos(z) / beta
    e0 = sp.exp(-z * tau0)
    out = {}
    for name, R in (("u", Ru), ("f", Rf)):
        # d/d eps of 2 Re[R(lam(eps), eps) exp(lam(eps) tau)] at eps = 0
        dR = sp.diff(R, eps) + sp.diff(R, lam) * s1
        term = (dR + R * s1 * tau) * sp.exp(lam * tau)
        out[name] = term.subs(eps, 0).subs(lam, s0).subs(tau, tau0)
    e1_closed = (2 * z ** 2 + z * (1 - 2 * z ** 2) * tau0) / beta ** 2
    tau1_closed = z * (2 * (1 - 2 * z ** 2) - z * (3 - 4 * z ** 2) * tau0) / beta ** 2
    for zv in (0.1, 0.37, 0.8):
        u1 = complex(sp.N(2 * out["u"].subs(z, zv)))
        f1 = complex(sp.N(2 * out["f"].subs(z, zv)))
        e0v = float(e0.subs(z, zv))
        # e = -u(tau_r): e1 = -Re(u1)/e0;  tau1 = -f1/f0'(tau0) = Re(f1)/e0
        print(f"zeta={zv}: e1 residue {-u1.real / e0v:.15f} closed {float(e1_closed.subs(z, zv)):.15f};"
              f" tau1 residue {f1.real / e0v:.15f} closed {float(tau1_closed.subs(z, zv)):.15f}")
    q = sp.acos(z) / sp.sqrt(1 - z ** 2)
    e1q = (2 * z / (1 - z ** 2)) * (z + (1 - 2 * z ** 2) * q)
    t1q = z * (2 * (1 - 2 * z ** 2) - z * (3 - 4 * z ** 2) * 2 * q) / (1 - z ** 2)
    print("q   at zeta=1-d:", sp.series(q.subs(z, 1 - d), d, 0, 7))
    print("e1  at zeta=1-d:", sp.series(e1q.subs(z, 1 - d), d, 0, 7))
    print("tau1 at zeta=1-d:", sp.series(t1q.subs(z, 1 - d), d, 0, 7))
    print("e1 small zeta:", sp.series(e1q, z, 0, 6))
    b = sp.sqrt(1 - z ** 2)
    print("f1 = zeta(1-2zeta^2)/beta^3 =", sp.series(z * (1 - 2 * z ** 2) / b ** 3, z, 0, 7))
    print("f2 = 2 zeta^2/beta^2        =", sp.series(2 * z ** 2 / b ** 2, z, 0, 7))


def hunt_crossley_series(order=6):
    cs = sp.symbols(f"c1:{order + 1}")
    e = 1 + sum(c * a ** (i + 1) for i, c in enumerate(cs))
    ser = sp.series(sp.log(1 + a) - sp.log(1 - a * e) - a * (1 + e), a, 0, order + 3).removeO()
    sol = {}
    for k in range(2, order + 3):
        co = sp.expand(ser.coeff(a, k)).subs(sol)
        unknown = [c for c in cs if c in co.free_symbols]
        if unknown:
            sol[unknown[0]] = sp.solve(co, unknown[0])[0]
    print("Hunt-Crossley e(a) =", 1 + sum(sol[c] * a ** (i + 1) for i, c in enumerate(cs)))


if __name__ == "__main__":
    first_order_sls()
    hunt_crossley_series()
