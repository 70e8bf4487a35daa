"""The plane closed forms (mechgen/runtime/plane/closed_forms.py) against their equations, in sympy.

References: Tejeda, Lovell & Engelstad, "In-plane gravity loading of a circular membrane", J. Appl. Mech. 67
(2000) 837 (seed 002, equations rebuilt from the physics: the extraction lost the symbols); Muskhelishvili's
potentials; the Griffith crack's opening (Tada, Paris & Irwin, The Stress Analysis of Cracks Handbook,
crack 5.1); Williams' near-tip functions (Anderson, Fracture Mechanics, table 2.1); Kfouri's point force.

Each symbolic check is exact (simplify to 0); each numeric comparison of the runtime's numpy with a sympy
expression uses rtol 1e-11: both are double-precision evaluations of the same closed form (a few hundred
operations, errors ~1e-14), so 1e-11 is three orders of margin and far below any wrong-term error.
"""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from mechgen.errors import InputError
from mechgen.runtime.plane import closed_forms as cf

x, y = sp.symbols("x y", real=True)
r, th = sp.symbols("r theta", positive=True)
E, nu, mu, rg, R = sp.symbols("E nu mu rho_g R", positive=True)
kap = sp.symbols("kappa", positive=True)
RTOL = 1e-11


def hooke(grad, mu_, kappa_):
    """sigma = lambda* tr(eps) I + 2 mu eps with lambda* = mu (3 - kappa)/(kappa - 1) (plane stress and strain)."""
    eps = (grad + grad.T) / 2
    lam = mu_ * (3 - kappa_) / (kappa_ - 1)
    return lam * eps.trace() * sp.eye(2) + 2 * mu_ * eps


def div(sig):
    return sp.Matrix([sp.diff(sig[0, 0], x) + sp.diff(sig[0, 1], y), sp.diff(sig[1, 0], x) + sp.diff(sig[1, 1], y)])


def grad_of(u):
    return sp.Matrix([[sp.diff(u[0], x), sp.diff(u[0], y)], [sp.diff(u[1], x), sp.diff(u[1], y)]])


def to_polar(sig):
    c, s = sp.cos(th), sp.sin(th)
    Q = sp.Matrix([[c, -s], [s, c]])
    return (Q.T * sig.subs({x: r * c, y: r * s}) * Q).applyfunc(sp.simplify)


# --- the membrane (Tejeda et al.) ----------------------------------------------------------------------

def membrane_sym():
    c = rg * (kap - 1) / (4 * mu * kap)
    u = sp.Matrix([0, c * (x**2 + y**2 - R**2)])
    return u, hooke(grad_of(u), mu, kap)


def test_membrane_equilibrium_and_rim_symbolic():
    """div sigma + f = 0 with f = (0, -rho_g), u = 0 on r = R, for any kappa (plane stress and strain)."""
    u, sig = membrane_sym()
    assert sp.simplify(div(sig) + sp.Matrix([0, -rg])) == sp.zeros(2, 1)
    assert sp.simplify(u.subs({x: R * sp.cos(th), y: R * sp.sin(th)})) == sp.zeros(2, 1)


def test_membrane_paper_equations_plane_stress_symbolic():
    """The paper's eqs. 21-32 (plane stress, kappa = (3 - nu)/(1 + nu), mu = E/(2(1 + nu))), rebuilt and checked."""
    sub = {kap: (3 - nu) / (1 + nu), mu: E / (2 * (1 + nu))}
    u, sig = membrane_sym()
    u, sig = u.subs(sub), sig.subs(sub)
    # eqs. 30-32 (Cartesian stresses)
    assert sp.simplify(sig[0, 0] - 2 * nu * rg * y / (3 - nu)) == 0
    assert sp.simplify(sig[1, 1] - 2 * rg * y / (3 - nu)) == 0
    assert sp.simplify(sig[0, 1] - (1 - nu) * rg * x / (3 - nu)) == 0
    # eqs. 22-24 (polar stresses) and Michell's route: Airy phi = d1 r^3 sin(theta), V = rho_g r sin(theta),
    # eq. 21 d1 = -(rho_g/2)(1 - nu)/(3 - nu); sigma_r = phi_r/r + phi_tt/r^2 + V, sigma_t = phi_rr + V,
    # tau = -(phi_t/r)_r (eqs. 11, 12, 8).
    pol = to_polar(sig)
    d1 = -rg / 2 * (1 - nu) / (3 - nu)
    phi = d1 * r**3 * sp.sin(th)
    V = rg * r * sp.sin(th)
    airy = [sp.diff(phi, r) / r + sp.diff(phi, th, 2) / r**2 + V, sp.diff(phi, r, 2) + V,
            -sp.diff(sp.diff(phi, th) / r, r)]
    paper = [2 * rg * r * sp.sin(th) / (3 - nu), 2 * nu * rg * r * sp.sin(th) / (3 - nu),
             rg * (1 - nu) * r * sp.cos(th) / (3 - nu)]
    for got, via_airy, eq in zip([pol[0, 0], pol[1, 1], pol[0, 1]], airy, paper):
        assert sp.simplify(got - eq) == 0 and sp.simplify(via_airy - eq) == 0
    # compatibility of the Airy route with a harmonic potential: del^4 phi = 0
    lap = lambda f: sp.diff(f, r, 2) + sp.diff(f, r) / r + sp.diff(f, th, 2) / r**2
    assert sp.simplify(lap(lap(phi))) == 0 and sp.simplify(lap(V)) == 0
    # eqs. 28-29 (u, v polar displacements) and eqs. 25-27 (strains; eps_theta = 0 everywhere)
    c, s = sp.cos(th), sp.sin(th)
    ur = (u[0] * c + u[1] * s).subs({x: r * c, y: r * s})
    ut = (-u[0] * s + u[1] * c).subs({x: r * c, y: r * s})
    k = rg * (1 - nu**2) / (E * (3 - nu))
    assert sp.simplify(ur - k * (r**2 - R**2) * s) == 0 and sp.simplify(ut - k * (r**2 - R**2) * c) == 0
    assert sp.simplify(sp.diff(ur, r) - 2 * k * r * s) == 0
    assert sp.simplify((ur + sp.diff(ut, th)) / r) == 0
    assert sp.simplify(sp.diff(ur, th) / r + sp.diff(ut, r) - ut / r - 2 * k * r * c) == 0


def test_membrane_runtime_matches_sympy():
    mat = cf.PlaneElastic(E=2.1e11, nu=0.27, plane="stress")
    vals = {mu: mat.mu, kap: mat.kappa, rg: 2.3e4, R: 0.1}
    u, sig = membrane_sym()
    fu = sp.lambdify((x, y), u.subs(vals), "numpy")
    fs = sp.lambdify((x, y), sig.subs(vals), "numpy")
    rng = np.random.default_rng(1)
    for px, py in rng.uniform(-0.07, 0.07, (5, 2)):
        f = cf.membrane_field(px, py, 0.1, mat, 2.3e4)
        np.testing.assert_allclose(f.u, np.ravel(fu(px, py)), rtol=RTOL, atol=1e-30)
        np.testing.assert_allclose(f.stress, np.array(fs(px, py), float), rtol=RTOL, atol=1e-20)
        rr, tt = np.hypot(px, py), np.arctan2(py, px)
        pol = cf.membrane_polar_stress(rr, tt, mat, 2.3e4)
        Q = np.array([[np.cos(tt), -np.sin(tt)], [np.sin(tt), np.cos(tt)]])
        sp_ = Q.T @ f.stress @ Q
        np.testing.assert_allclose(pol, [sp_[0, 0], sp_[1, 1], sp_[0, 1]], rtol=RTOL)


def test_membrane_energy_and_reactions():
    """U against int W dA (sympy, exact) and the rim's tractions against the weight (periodic trapezoid: exact
    for the degree-2 trigonometric integrand with 16 nodes)."""
    u, sig = membrane_sym()
    W = (sig.multiply_elementwise((grad_of(u) + grad_of(u).T) / 2)).applyfunc(lambda e: e / 2)
    Wp = sp.simplify(sum(W).subs({x: r * sp.cos(th), y: r * sp.sin(th)}))
    U = sp.integrate(sp.integrate(Wp * r, (th, 0, 2 * sp.pi)), (r, 0, R))
    assert sp.simplify(U - sp.pi * rg**2 * (kap - 1) * R**4 / (16 * mu * kap)) == 0
    for plane in ("stress", "strain"):
        mat = cf.PlaneElastic(E=70e9, nu=0.33, plane=plane)
        got = cf.membrane_strain_energy(0.1, mat, 2.6e4)
        want = float(U.subs({mu: mat.mu, kap: mat.kappa, rg: 2.6e4, R: 0.1}))
        assert got == pytest.approx(want, rel=RTOL)
        th_ = 2 * np.pi * np.arange(16) / 16
        t = cf.membrane_rim_traction(th_, 0.1, mat, 2.6e4)
        np.testing.assert_allclose(t.sum(0) * 0.1 * 2 * np.pi / 16, cf.membrane_rim_reaction(0.1, 2.6e4),
                                   rtol=1e-13, atol=1e-9)


def test_plane_strain_switch_is_true_plane_strain():
    """kappa = 3 - 4 nu gives lambda* = 2 mu nu/(1 - 2 nu), the 3D Lame constant (eps_zz = 0)."""
    mat = cf.PlaneElastic(E=1.0, nu=0.3, plane="strain")
    assert mat.lam == pytest.approx(mat.E * 0.3 / (1.3 * 0.4), rel=1e-14)
    mat = cf.PlaneElastic(E=1.0, nu=0.3, plane="stress")
    assert mat.lam == pytest.approx(0.3 / (1 - 0.09), rel=1e-14)      # E nu/(1 - nu^2)
    assert mat.modulus == pytest.approx(1.0, rel=1e-14)


@pytest.mark.parametrize("kw", [dict(E=1.0, nu=0.3, plane="shell"), dict(E=-1.0, nu=0.3), dict(E=1.0, nu=0.5)])
def test_bad_material_is_refused(kw):
    with pytest.raises(InputError):
        cf.PlaneElastic(**kw)


# --- the annulus ----------------------------------------------------------------------------------------

a_, b_ = sp.symbols("a b", positive=True)


def annulus_polar_sym():
    """u_r, u_theta of the annulus from its potentials, written out in r, theta (logs as log(r/b) + i theta)."""
    co = {"A2": -a_**2 * rg / (2 * (kap + 1)),
          "B2": a_**2 * rg * (2 * kap * b_**2 - (kap - 1) * a_**2) / (2 * kap * (kap + 1) * (a_**4 + kap * b_**4)),
          "D2": a_**4 * b_**2 * rg * (2 * a_**2 + (kap - 1) * b_**2) / (4 * (kap + 1) * (a_**4 + kap * b_**4))}
    co["T2"] = -b_**2 * co["B2"] / (2 * mu)
    A, B, D = sp.I * co["A2"], sp.I * co["B2"], sp.I * co["D2"]
    C = -kap * sp.conjugate(A)
    z, zb = r * sp.exp(sp.I * th), r * sp.exp(-sp.I * th)
    log_z, log_zb = sp.log(r / b_) + sp.I * th, sp.log(r / b_) - sp.I * th
    phi, dphi_c = A * log_z + B * z**2 / 2, sp.conjugate(A) / zb + sp.conjugate(B) * zb
    psi_c = sp.conjugate(C) * log_zb + sp.conjugate(D) / zb**2
    D_h = (kap * phi - z * dphi_c - psi_c) / (2 * mu) + sp.I * co["T2"]
    c = rg * (kap - 1) / (4 * mu * kap)
    D_tot = sp.expand(D_h + sp.I * c * (r**2 - b_**2))
    polar = sp.expand(D_tot * sp.exp(-sp.I * th))            # u_r + i u_theta
    ur = sp.simplify(sp.re(sp.expand_complex(polar)))
    ut = sp.simplify(sp.im(sp.expand_complex(polar)))
    return ur, ut


def polar_stress(ur, ut):
    err, ett = sp.diff(ur, r), (ur + sp.diff(ut, th)) / r
    ert = (sp.diff(ur, th) / r + sp.diff(ut, r) - ut / r) / 2
    lam = mu * (3 - kap) / (kap - 1)
    return lam * (err + ett) + 2 * mu * err, lam * (err + ett) + 2 * mu * ett, 2 * mu * ert


@pytest.fixture(scope="module")
def annulus_sym():
    ur, ut = annulus_polar_sym()
    return ur, ut, polar_stress(ur, ut)


@pytest.mark.slow
def test_annulus_equations_symbolic(annulus_sym):
    """Polar equilibrium with f_r = -rho_g sin(theta), f_theta = -rho_g cos(theta) (the paper's eqs. 4-5),
    sigma_rr = sigma_rt = 0 on r = a, u = 0 on r = b, and the paper's disk in the limit a -> 0."""
    ur, ut, (srr, stt, srt) = annulus_sym
    eq_r = sp.diff(srr, r) + sp.diff(srt, th) / r + (srr - stt) / r - rg * sp.sin(th)
    eq_t = sp.diff(srt, r) + sp.diff(stt, th) / r + 2 * srt / r - rg * sp.cos(th)
    assert sp.simplify(eq_r) == 0 and sp.simplify(eq_t) == 0
    assert sp.simplify(srr.subs(r, a_)) == 0 and sp.simplify(srt.subs(r, a_)) == 0
    assert sp.simplify(ur.subs(r, b_)) == 0 and sp.simplify(ut.subs(r, b_)) == 0
    k = rg * (kap - 1) / (4 * mu * kap)
    assert sp.simplify(sp.limit(ur, a_, 0) - k * (r**2 - b_**2) * sp.sin(th)) == 0


def test_annulus_runtime_matches_sympy(annulus_sym):
    """The runtime (potentials in numpy) against the symbolic field evaluated in 30-digit arithmetic (sympy's
    simplified form cancels badly in doubles: lambdify loses 1e-9 of u there, the runtime 1e-15)."""
    ur, ut, (srr, stt, srt) = annulus_sym
    mat = cf.PlaneElastic(E=1.7e11, nu=0.28, plane="stress")
    vals = {mu: mat.mu, kap: mat.kappa, rg: 2.3e4, a_: 0.03, b_: 0.1}
    exprs = [e.subs(vals) for e in (ur, ut, srr, stt, srt)]
    rng = np.random.default_rng(2)
    for rr, tt in zip(rng.uniform(0.03, 0.1, 4), rng.uniform(-np.pi, np.pi, 4)):
        pt = {r: sp.Float(rr, 30), th: sp.Float(tt, 30)}
        want = [float(sp.N(e.subs(pt), 30)) for e in exprs]
        f = cf.annulus_field(rr * np.cos(tt), rr * np.sin(tt), 0.03, 0.1, mat, 2.3e4)
        c, s = np.cos(tt), np.sin(tt)
        Q = np.array([[c, -s], [s, c]])
        pol_u, pol_s = Q.T @ f.u, Q.T @ f.stress @ Q
        np.testing.assert_allclose(pol_u, want[:2], rtol=RTOL)
        np.testing.assert_allclose([pol_s[0, 0], pol_s[1, 1], pol_s[0, 1]], want[2:], rtol=RTOL,
                                   atol=RTOL * 2.3e4 * 0.1)


def test_annulus_energy_and_reactions():
    """U against a Gauss rule for int W dA (smooth polynomial-times-log field: 40 x 64 points give 1e-13) and
    the rim's resultant against the weight pi (b^2 - a^2) rho_g (periodic trapezoid on trigonometric data)."""
    mat = cf.PlaneElastic(E=1.7e11, nu=0.28, plane="strain")
    a, b, w = 0.03, 0.1, 2.3e4
    t, wt = np.polynomial.legendre.leggauss(40)
    rr = a + (b - a) * (t + 1) / 2
    tt = 2 * np.pi * np.arange(64) / 64
    Rg, Tg = np.meshgrid(rr, tt, indexing="ij")
    f = cf.annulus_field(Rg * np.cos(Tg), Rg * np.sin(Tg), a, b, mat, w)
    U = np.sum(f.energy_density * Rg * (wt[:, None] * (b - a) / 2) * (2 * np.pi / 64))
    assert cf.annulus_strain_energy(a, b, mat, w) == pytest.approx(U, rel=1e-12)
    trac = cf.annulus_rim_traction(tt, a, b, mat, w)
    np.testing.assert_allclose(trac.sum(0) * b * 2 * np.pi / 64, [0.0, np.pi * (b * b - a * a) * w],
                               rtol=1e-12, atol=1e-9)
    top = cf.annulus_field(0.0, a, a, b, mat, w)
    assert top.u[0] == pytest.approx(0.0, abs=1e-25)                 # symmetry about the y axis


def test_annulus_bad_radii():
    with pytest.raises(InputError):
        cf.annulus_field(0.0, 0.05, 0.1, 0.1, cf.PlaneElastic(1.0, 0.3), 1.0)


# --- potentials, Griffith, Williams ---------------------------------------------------------------------

def conj_fn(expr_z, z):
    """conj(f(z)) for f with complex coefficients: conjugate everything, z -> x - i y."""
    return sp.conjugate(expr_z.subs(z, x + sp.I * y)).subs({sp.conjugate(x): x, sp.conjugate(y): y})


def test_potential_formulas_are_elasticity_symbolic():
    """For phi, psi with arbitrary complex coefficients (powers -2, -1, 2, 3), the displacement
    2 mu u = kappa phi - z conj(phi') - conj(psi) is in equilibrium (no body force), and the stress formulas
    of fields_from_potentials equal Hooke's law of that displacement. Local power series make this general."""
    z = sp.symbols("z")
    cs = sp.symbols("c0:8", real=True)
    al = [cs[2 * k] + sp.I * cs[2 * k + 1] for k in range(4)]
    phi = al[0] * z**3 + al[1] / z
    psi = al[2] * z**2 + al[3] / z**2
    Phi, Psi = sp.diff(phi, z), sp.diff(psi, z)
    zz = x + sp.I * y
    Dz = (kap * phi.subs(z, zz) - zz * conj_fn(Phi, z) - conj_fn(psi, z)) / (2 * mu)
    u = sp.Matrix([sp.re(sp.expand_complex(Dz)), sp.im(sp.expand_complex(Dz))]).applyfunc(sp.expand)
    sig = hooke(grad_of(u), mu, kap)
    is_zero = lambda e: sp.cancel(sp.together(e)) == 0          # exact for rational functions of x, y
    assert all(is_zero(e) for e in div(sig))
    s_sum = 4 * sp.re(sp.expand_complex(Phi.subs(z, zz)))
    s_dif = sp.expand_complex(2 * ((x - sp.I * y) * sp.diff(Phi, z).subs(z, zz) + Psi.subs(z, zz)))
    sxx, syy, sxy = (s_sum - sp.re(s_dif)) / 2, (s_sum + sp.re(s_dif)) / 2, sp.im(s_dif) / 2
    for got, want in ((sig[0, 0], sxx), (sig[1, 1], syy), (sig[0, 1], sxy)):
        assert is_zero(got - want)
    # and the runtime's implementation of the same formulas
    mat = cf.PlaneElastic(E=3.0, nu=0.25, plane="strain")
    vals = dict(zip(cs, np.linspace(-1, 1, 8)))
    vals.update({mu: mat.mu, kap: mat.kappa})
    fu = sp.lambdify((x, y), u.subs(vals), "numpy")
    fg = sp.lambdify((x, y), grad_of(u).subs(vals), "numpy")
    fs = sp.lambdify((x, y), sig.subs(vals), "numpy")
    num = lambda e: complex(e.subs(vals).subs(z, 0.3 + 0.7j).evalf())
    f = cf.fields_from_potentials(np.array(0.3 + 0.7j), num(phi), num(Phi), num(sp.diff(Phi, z)), num(psi),
                                  num(Psi), mat)
    np.testing.assert_allclose(f.u, np.ravel(fu(0.3, 0.7)), rtol=RTOL)
    np.testing.assert_allclose(f.grad, np.array(fg(0.3, 0.7), float), rtol=RTOL)
    np.testing.assert_allclose(f.stress, np.array(fs(0.3, 0.7), float), rtol=RTOL)


s11, s22, s12, a = sp.symbols("sigma11 sigma22 sigma12 a", real=True)
X, Z = sp.symbols("X z")


def griffith_potentials_sym():
    s, g = s22 - sp.I * s12, (s11 - s22) / 2 + sp.I * s12
    Phi = (s * Z / X + g) / 2
    dPhi = -s * a**2 / (2 * X**3)
    Psi = (sp.conjugate(s) * Z / X - sp.conjugate(g)) / 2 - Phi - Z * dPhi
    return Phi, dPhi, Psi


def test_griffith_faces_traction_free_symbolic():
    """sigma_yy + i sigma_xy = Phi + conj(Phi) + conj(z) Phi' + Psi = 0 on both faces, where z = x and
    X = +-i q with q = sqrt(a^2 - x^2) > 0 (a^2 = q^2 + x^2 substituted after conjugation)."""
    Phi, dPhi, Psi = griffith_potentials_sym()
    q = sp.symbols("q", positive=True)
    for side in (1, -1):
        face = {Z: x, X: side * sp.I * q}
        P = Phi.subs(face)
        t = P + sp.conjugate(P) + x * dPhi.subs(face) + Psi.subs(face)
        t = sp.expand_complex(t).subs({sp.conjugate(x): x}).subs(a, sp.sqrt(q**2 + x**2))
        assert sp.simplify(t) == 0


def test_griffith_remote_and_tip_limits_symbolic():
    """Phi -> (s11 + s22)/4, Psi -> (s22 - s11)/2 + i s12 at infinity; 2 sqrt(2 pi) sqrt(z - a) Phi -> K_I - i K_II
    with K = sigma sqrt(pi a); sigma_xx - sigma_yy -> T = s11 - s22 ahead of the tip."""
    Phi, dPhi, Psi = griffith_potentials_sym()
    Xz = sp.sqrt(Z - a) * sp.sqrt(Z + a)
    zr = sp.symbols("zr", positive=True)
    Phi_z, Psi_z = Phi.subs(X, Xz), Psi.subs(X, Xz)
    assert sp.simplify(sp.limit(Phi_z.subs(Z, zr), zr, sp.oo) - (s11 + s22) / 4) == 0
    assert sp.simplify(sp.limit(Psi_z.subs(Z, zr), zr, sp.oo) - ((s22 - s11) / 2 + sp.I * s12)) == 0
    ap, rho = sp.symbols("a_p rho", positive=True)
    K = sp.limit((2 * sp.sqrt(2 * sp.pi) * sp.sqrt(rho) * Phi_z).subs(a, ap).subs(Z, ap + rho), rho, 0)
    assert sp.simplify(K - (s22 - sp.I * s12) * sp.sqrt(sp.pi * ap)) == 0
    # ahead of the tip (z = a + rho real): sigma_xx - sigma_yy = -Re s_dif = -2 Re(z Phi' + Psi)
    dif = (-2 * (Z * dPhi + Psi).subs(X, Xz)).subs(a, ap).subs(Z, ap + rho)
    assert sp.simplify(sp.limit(sp.re(sp.expand_complex(dif)), rho, 0) - (s11 - s22)) == 0


def test_griffith_runtime_faces_remote_opening():
    """The runtime on both faces (signed zeros), far away, and its opening against Tada's
    Delta u = (kappa + 1) sqrt(a^2 - x^2) (sigma12, sigma22)/(2 mu)."""
    for plane in ("strain", "stress"):
        mat = cf.PlaneElastic(E=2.0, nu=0.3, plane=plane)
        crack = cf.GriffithCrack(a=1.5, s11=0.3, s22=1.0, s12=-0.4)
        xs = np.array([-1.2, -0.3, 0.0, 0.7, 1.4])
        up = cf.griffith_field(xs, np.zeros(5), crack, mat)
        lo = cf.griffith_field(xs, -np.zeros(5), crack, mat)
        np.testing.assert_allclose(up.stress[:, :, 1], 0.0, atol=1e-14)
        np.testing.assert_allclose(lo.stress[:, :, 1], 0.0, atol=1e-14)
        open_ = (mat.kappa + 1) * np.sqrt(1.5**2 - xs**2) / (2 * mat.mu)
        np.testing.assert_allclose(up.u - lo.u, np.stack([-0.4 * open_, 1.0 * open_], -1), rtol=1e-12, atol=1e-15)
        out = np.array([-2.0, 1.7, 3.0])           # ahead of the tips: no jump
        np.testing.assert_allclose(cf.griffith_field(out, np.zeros(3), crack, mat).u,
                                   cf.griffith_field(out, -np.zeros(3), crack, mat).u, rtol=1e-13)
        far = cf.griffith_field(3e5, -4e5, crack, mat)       # error O((a/r)^2) ~ 1e-11
        np.testing.assert_allclose(far.stress, [[0.3, -0.4], [-0.4, 1.0]], atol=1e-10)


def anderson_k_field(rr, tt, KI, KII, mu_, kappa_):
    """Anderson's table 2.1-2.2: the mode I and II near-tip stresses and displacements (independent formulas)."""
    c2, s2, c32, s32 = np.cos(tt / 2), np.sin(tt / 2), np.cos(3 * tt / 2), np.sin(3 * tt / 2)
    f = 1 / np.sqrt(2 * np.pi * rr)
    sxx = KI * f * c2 * (1 - s2 * s32) - KII * f * s2 * (2 + c2 * c32)
    syy = KI * f * c2 * (1 + s2 * s32) + KII * f * s2 * c2 * c32
    sxy = KI * f * c2 * s2 * c32 + KII * f * c2 * (1 - s2 * s32)
    g = np.sqrt(rr / (2 * np.pi)) / (2 * mu_)
    ux = KI * g * c2 * (kappa_ - 1 + 2 * s2**2) + KII * g * s2 * (kappa_ + 1 + 2 * c2**2)
    uy = KI * g * s2 * (kappa_ + 1 - 2 * c2**2) - KII * g * c2 * (kappa_ - 1 - 2 * s2**2)
    return np.array([ux, uy]), np.array([[sxx, sxy], [sxy, syy]])


def test_k_field_matches_anderson():
    mat = cf.PlaneElastic(E=2.0, nu=0.3, plane="strain")
    for rr, tt in ((0.3, 0.4), (1.2, -2.9), (0.05, 3.0)):
        f = cf.k_field(rr * np.cos(tt), rr * np.sin(tt), 1.3, -0.7, mat)
        u, s = anderson_k_field(rr, tt, 1.3, -0.7, mat.mu, mat.kappa)
        np.testing.assert_allclose(f.u, u, rtol=RTOL)
        np.testing.assert_allclose(f.stress, s, rtol=RTOL)


def williams_sym(n, A):
    """sigma_rr - i sigma_rt = Phi + conj(Phi) - e^{2 i theta} (conj(z) Phi' + Psi) of the n-th eigenfunction."""
    lam = sp.Rational(n, 2)
    B = A if n % 2 else -A
    zp = lambda p: r**p * sp.exp(sp.I * p * th)
    Phi, dPhi, Psi = A * zp(lam - 1), A * (lam - 1) * zp(lam - 2), (sp.conjugate(B) - lam * A) * zp(lam - 1)
    return sp.expand(Phi + sp.conjugate(Phi) - sp.exp(2 * sp.I * th) * (r * sp.exp(-sp.I * th) * dPhi + Psi))


@pytest.mark.parametrize("n", [-1, 0, 1, 2, 3])
def test_williams_faces_traction_free_symbolic(n):
    """On theta = +-pi the traction sigma . e_theta vanishes: sigma_tt = sigma_rt = 0 there."""
    A1, A2 = sp.symbols("A1 A2", real=True)
    srr_irt = williams_sym(n, A1 + sp.I * A2)
    lam = sp.Rational(n, 2)
    Phi = (A1 + sp.I * A2) * r**(lam - 1) * sp.exp(sp.I * (lam - 1) * th)
    s_sum = 2 * (Phi + sp.conjugate(Phi))
    for face in (sp.pi, -sp.pi):
        srt = -sp.im(sp.expand_complex(srr_irt.subs(th, face)))
        stt = sp.re(sp.expand_complex((s_sum - srr_irt).subs(th, face)))
        assert sp.simplify(srt) == 0 and sp.simplify(stt) == 0


def test_point_force_is_kfouri_and_t_field_is_uniform():
    mat = cf.PlaneElastic(E=2.0, nu=0.3, plane="stress")
    for rr, tt in ((0.4, 0.3), (2.0, -2.5)):
        f = cf.point_force_field(rr * np.cos(tt), rr * np.sin(tt), 1.7, mat)
        c, s = np.cos(tt), np.sin(tt)
        want = -1.7 / (np.pi * rr) * np.array([[c**3, c * c * s], [c * c * s, c * s * s]])
        np.testing.assert_allclose(f.stress, want, rtol=RTOL)
        t = cf.t_field(rr * np.cos(tt), rr * np.sin(tt), -0.6, mat)
        np.testing.assert_allclose(t.stress, [[-0.6, 0.0], [0.0, 0.0]], atol=1e-15)


def test_bueckner_pairing_symbolic():
    """Betti's integral of the n = 1 field (A_1) with the n = -1 field (A_-1) over the unit circle about the tip,
    theta in (-pi, pi), is -(4 pi (kappa + 1)/mu) Re(A_1 conj(A_-1)): the normalisation of bueckner_field.

    On r = 1 every quantity is a Laurent polynomial in w = exp(i theta/2) (conj(w) = 1/w), integrated
    exactly: int w^m dtheta = 2 pi (m = 0), 4 sin(m pi/2)/m (m != 0)."""
    p1, p2, q1, q2 = sp.symbols("p1 p2 q1 q2", real=True)
    w = sp.symbols("w")
    conj = lambda e: sp.conjugate(e).subs(sp.conjugate(w), 1 / w)

    def fields(n, A):
        lam = sp.Rational(n, 2)
        B = A if n % 2 else -A
        zp = lambda p: w**int(2 * p)                         # z^p on r = 1
        phi, Phi, dPhi = A * zp(lam) / lam, A * zp(lam - 1), A * (lam - 1) * zp(lam - 2)
        cpsi = conj(B) - lam * A
        psi, Psi = cpsi * zp(lam) / lam, cpsi * zp(lam - 1)
        z, zb = w**2, w**-2
        D = (kap * phi - z * conj(Phi) - conj(psi)) / (2 * mu)
        # t = sigma . e_r: t_x + i t_y = (sigma_rr + i sigma_rt) e^{i theta}
        srr_m_irt = Phi + conj(Phi) - w**4 * (zb * dPhi + Psi)
        return D, conj(srr_m_irt) * w**2

    D1, t1 = fields(1, p1 + sp.I * p2)
    D2, t2 = fields(-1, q1 + sp.I * q2)
    dot = lambda Da, tb: (Da * conj(tb) + conj(Da) * tb) / 2
    integrand = sp.expand(dot(D1, t2) - dot(D2, t1))
    val = 0
    for (m,), c in sp.Poly(sp.expand(integrand * w**40), w).terms():
        m -= 40
        val += c * (2 * sp.pi if m == 0 else 4 * sp.sin(m * sp.pi / 2) / m)
    assert sp.simplify(val + 4 * sp.pi * (kap + 1) / mu * (p1 * q1 + p2 * q2)) == 0
    # with A_1 = (K_I - i K_II)/(2 sqrt(2 pi)) and A_-1 = -w_B (mode I), i w_B (mode II): B = K_I, K_II
    KI, KII = sp.symbols("K_I K_II", real=True)
    wB = mu / (sp.sqrt(2 * sp.pi) * (kap + 1))
    pair = lambda A1, Am: -4 * sp.pi * (kap + 1) / mu * sp.re(sp.expand_complex(A1 * sp.conjugate(Am)))
    A1 = (KI - sp.I * KII) / (2 * sp.sqrt(2 * sp.pi))
    assert sp.simplify(pair(A1, -wB) - KI) == 0 and sp.simplify(pair(A1, sp.I * wB) - KII) == 0
    mat = cf.PlaneElastic(E=2.0, nu=0.3, plane="strain")
    assert cf.bueckner_weight(mat) == pytest.approx(float(wB.subs({mu: mat.mu, kap: mat.kappa})), rel=1e-15)
