"""Cross-section stiffness K = int_A D^T C D dA from the 3D law (mechgen.symbolic.cross_section, issue 15 item 2).

References: the straight-rod stiffness diag(EA, GA2, GA3, GJ, EI2, EI3) (seed 001, slide 18) with
A = b h, I = b h^3/12 (rectangle), A = pi R^2, I = pi R^4/4 (circle); the curved beam of seed 001,
slides 20-25 (circular arc of radius r, square section of side b, beta = kappa0 b = b/r):

    c1 = 4/(4 - beta^2),  c2 = 12/beta^3 (2 ln((2 - beta)/(2 + beta)) + (1 + c1) beta),
    c3 = 1/beta^2 (ln((2 - beta)/(2 + beta)) + c1 beta),
    K_uu = c1 diag(E b^2, mu b^2, mu b^2),  K_ww = diag(mu b^4 (c1 + c2)/12, c1 E b^4/12, c2 E b^4/12),
    K_uw: (u1, w3) = -c3 E b^3, (u3, w1) = c3 mu b^3  (signs lost in the extraction; these follow from D),

evaluated with mpmath at 50 digits; Gauss-Legendre quadrature of the integrand D^T C D (independent of
the closed-form integration); Winkler's curved bar, extension stiffness E int dA/(1 - kappa0 a2)
(Timoshenko, Strength of Materials I, sec. 83) for the reference volume element.
"""
from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechgen.codegen.printing import numpy_code
from mechgen.symbolic import cross_section as cs
from mechgen.symbolic.safe import closed_form

lam, mu, b, h, r, R = sp.symbols("lam mu b h r R", positive=True)
E = cs.young_modulus(lam, mu)


def _seed_coefficients(beta):
    c1 = 4 / (4 - beta**2)
    c2 = 12 / beta**3 * (2 * sp.log((2 - beta) / (2 + beta)) + (1 + c1) * beta)
    c3 = 1 / beta**2 * (sp.log((2 - beta) / (2 + beta)) + c1 * beta)
    return c1, c2, c3


def _seed_K(lam_, mu_, b_, beta):
    c1, c2, c3 = _seed_coefficients(beta)
    E_ = cs.young_modulus(lam_, mu_)
    K = sp.diag(c1 * E_ * b_**2, c1 * mu_ * b_**2, c1 * mu_ * b_**2, mu_ * b_**4 * (c1 + c2) / 12,
                c1 * E_ * b_**4 / 12, c2 * E_ * b_**4 / 12)
    K[0, 5] = K[5, 0] = -c3 * E_ * b_**3
    K[2, 3] = K[3, 2] = c3 * mu_ * b_**3
    return K


@pytest.fixture(scope="module")
def curved():
    return cs.cross_section_stiffness(lam, mu, cs.Square(b), 1 / r)


def test_straight_rectangle_and_circle_give_the_diagonal_of_the_classical_rod():
    K = cs.cross_section_stiffness(lam, mu, cs.Rectangle(b, h))
    A, I2, I3 = b * h, b * h**3 / 12, h * b**3 / 12      # I2 = int a3^2 dA (about n0), I3 = int a2^2 dA
    expect = sp.diag(E * A, mu * A, mu * A, mu * (I2 + I3), E * I2, E * I3)
    assert (K - expect).applyfunc(sp.simplify) == sp.zeros(6, 6)
    Kc = cs.cross_section_stiffness(lam, mu, cs.Circle(R))
    A, I = sp.pi * R**2, sp.pi * R**4 / 4
    expect = sp.diag(E * A, mu * A, mu * A, mu * 2 * I, E * I, E * I)  # GJ = mu pi R^4/2: exact for a circle
    assert (Kc - expect).applyfunc(sp.simplify) == sp.zeros(6, 6)


def test_the_condensed_law_is_the_seeds_with_the_reduced_lame_constant():
    # slide 17 at tau0 = 0: C = diag(C11, C22, C33)/d^2 with C11 = lam_bar + 2 mu, C22 = C33 = mu d,
    # lam_bar = lam mu/(lam + mu), d = (1 - a2 kappa0)^2
    a2, a3, k = sp.symbols("a2 a3 k", real=True)
    d = (1 - a2 * k) ** 2
    lam_bar = lam * mu / (lam + mu)
    C = cs.constitutive_matrix(lam, mu, a2, a3, k, 0)
    assert (C - sp.diag(lam_bar + 2 * mu, mu * d, mu * d) / d**2).applyfunc(sp.simplify) == sp.zeros(3, 3)
    assert sp.simplify(lam_bar + 2 * mu - E) == 0
    # without condensation the rigid section's kinematics gives lam + 2 mu (Poisson locking)
    K = cs.cross_section_stiffness(lam, mu, cs.Square(b), condense=False)
    assert sp.simplify(K[0, 0] - (lam + 2 * mu) * b**2) == 0 and sp.simplify(K[1, 1] - mu * b**2) == 0


def test_the_condensed_twisted_law_leaves_the_section_free_of_transverse_stress():
    # C^ijkl GL_kl with the condensed transverse strains: S22 = S33 = S23 = 0, S1j = (C gl)_j
    vals = {sp.Symbol("a2", real=True): sp.Rational(1, 10), sp.Symbol("a3", real=True): sp.Rational(-1, 7)}
    a2, a3 = vals
    k, t = sp.Rational(1, 3), sp.Rational(2, 5)
    la, m = sp.Integer(3), sp.Integer(2)
    g0 = cs.reference_metric(a2, a3, k, t).xreplace(vals)
    G = g0.inv()
    gl = sp.Matrix([sp.Rational(1, 100), sp.Rational(-3, 200), sp.Rational(1, 50)])   # GL11, 2 GL12, 2 GL13
    # solve for the transverse strains (GL22, GL33, 2 GL23) that make S22 = S33 = S23 = 0
    e22, e33, g23 = sp.symbols("e22 e33 g23")
    GL = sp.Matrix([[gl[0], gl[1] / 2, gl[2] / 2], [gl[1] / 2, e22, g23 / 2], [gl[2] / 2, g23 / 2, e33]])
    S = sp.Matrix(3, 3, lambda i, j: sum(la * G[i, j] * G[p, q] * GL[p, q] + m * (G[i, p] * G[j, q] + G[i, q]
                                          * G[j, p]) * GL[p, q] for p in range(3) for q in range(3)))
    A, rhs = sp.linear_eq_to_matrix([S[1, 1], S[2, 2], S[1, 2]], [e22, e33, g23])
    S = S.subs(dict(zip((e22, e33, g23), A.LUsolve(rhs))))
    C = cs.constitutive_matrix(la, m, vals[a2], vals[a3], k, t)
    assert sp.simplify(sp.Matrix([S[0, 0], S[0, 1], S[0, 2]]) - C * gl) == sp.zeros(3, 1)


def test_curved_square_reproduces_the_seed_coefficients_symbolically(curved):
    K = closed_form(curved)
    diff = (K - _seed_K(lam, mu, b, b / r)).applyfunc(sp.simplify)
    assert diff == sp.zeros(6, 6)
    assert K == K.T


def _lowered(K: sp.Matrix, values: dict) -> np.ndarray:
    """K evaluated through mechgen's numpy printer (symbols renamed to g0, g1, ... as in a kernel)."""
    local = {s: sp.Symbol(f"g{i}", real=True) for i, s in enumerate(values)}
    env = {"np": np, **{local[s].name: np.float64(v) for s, v in values.items()}}
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        return np.array([[float(eval(numpy_code(e.xreplace(local)), env)) for e in row] for row in K.tolist()])


def _gauss(beta: float, lam_: float, mu_: float, b_: float, n: int = 40) -> np.ndarray:
    """K by Gauss-Legendre quadrature of the integrand D^T C D over the square (r = b/beta)."""
    a2, a3, k = sp.symbols("a2 a3 k", real=True)
    dens = sp.lambdify((a2, a3, k), cs.stiffness_density(lam_, mu_, a2, a3, k, 0), "numpy")
    x, w = np.polynomial.legendre.leggauss(n)
    x, w = x * b_ / 2, w * b_ / 2
    return sum(wi * wj * np.array(dens(xi, xj, beta / b_), dtype=float) for xi, wi in zip(x, w)
               for xj, wj in zip(x, w))


@pytest.mark.parametrize("beta", (1e-7, 1e-3, 0.1, 0.2, 0.4999, 0.5001, 1.0, 1.5, 1.9))
def test_curved_square_numerically_against_the_seed_at_50_digits_and_quadrature(curved, beta):
    lam_, mu_, b_ = 2.0e6, 1.0e6, 0.05
    got = _lowered(curved, {lam: lam_, mu: mu_, b: b_, r: b_ / beta})
    with mpmath.workdps(50):
        ref = _seed_K(sp.Float(lam_, 50), sp.Float(mu_, 50), sp.Float(b_, 50), sp.nsimplify(beta)).evalf(50)
    ref = np.array(ref.tolist(), dtype=float)
    scale = np.sqrt(np.outer(np.diag(ref), np.diag(ref)))
    # closed forms cancel near beta = 0 (c2 loses eps/beta^2): the series branch below beta = 1/2 keeps round-off,
    # the closed form above it 16 eps/(beta/2)^2 <= 6e-14
    rel = 1e-15 if beta < 0.5 else 6e-14
    np.testing.assert_array_less(np.abs(got - ref), rel * scale + 1e-300)
    if beta <= 1.0:   # Gauss-Legendre with 40 points converges geometrically while the pole 1/kappa0 is far
        np.testing.assert_allclose(_gauss(beta, lam_, mu_, b_), ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
    assert np.all(np.linalg.eigvalsh(got) > 0)


def test_straight_limit_of_the_curved_beam_is_the_straight_rod(curved):
    K0 = cs.cross_section_stiffness(lam, mu, cs.Square(b))
    lim = closed_form(curved)
    for i, j in ((0, 0), (3, 3), (5, 5), (0, 5)):
        assert sp.simplify(sp.limit(lim[i, j], r, sp.oo) - K0[i, j]) == 0
    # the section functions at kappa0 = 0 are their series' constants: K is the straight matrix exactly
    assert (curved.subs(r, sp.oo) - K0).applyfunc(sp.simplify) == sp.zeros(6, 6)


def test_reference_volume_element_gives_winklers_curved_bar():
    K = closed_form(cs.cross_section_stiffness(lam, mu, cs.Square(b), 1 / r, measure="reference"))
    beta = b / r
    winkler = E * b * r * sp.log((2 + beta) / (2 - beta))      # E int dA/(1 - a2/r)
    assert sp.simplify(sp.expand_log(K[0, 0] - winkler, force=True)) == 0
    assert sp.simplify(sp.limit(K[0, 0], r, sp.oo) - E * b**2) == 0


def _polar_quadrature(kappa: float, lam_: float, mu_: float, R_: float, n: int = 120) -> np.ndarray:
    """K of the disk of radius R_ by Gauss-Legendre quadrature in polar coordinates (rho, phi) of D^T C D."""
    a2, a3, k = sp.symbols("a2 a3 k", real=True)
    dens = cs.stiffness_density(lam_, mu_, a2, a3, k, 0)
    x, w = np.polynomial.legendre.leggauss(n)
    rho, phi = np.meshgrid((x + 1) * R_ / 2, (x + 1) * np.pi, indexing="ij")
    weight = np.outer(w * R_ / 2, w * np.pi) * rho
    out = np.zeros((6, 6))
    for i in range(6):
        for j in range(6):
            f = sp.lambdify((a2, a3, k), dens[i, j], "numpy")
            vals = np.broadcast_to(f(rho * np.cos(phi), rho * np.sin(phi), kappa), rho.shape)
            out[i, j] = np.sum(weight * vals)
    return out


def test_curved_circle_against_the_closed_form_extension_and_polar_quadrature():
    K = cs.cross_section_stiffness(lam, mu, cs.Circle(R), 1 / r)
    # K_uu11 = E int dA/(1 - a2/r)^2 = 2 pi E R^2 (1 - s)/(h^2 s), h = R/r, s = sqrt(1 - h^2): from
    # int_0^pi dt/(1 - h cos t) = pi/s (Gradshteyn & Ryzhik 3.661) by d/dh (h I1) = I2
    h_, s_ = R / r, sp.sqrt(1 - (R / r) ** 2)
    assert sp.simplify(closed_form(K)[0, 0] - 2 * sp.pi * E * R**2 * (1 - s_) / (h_**2 * s_)) == 0
    assert (K.subs(r, sp.oo) - cs.cross_section_stiffness(lam, mu, cs.Circle(R))).applyfunc(sp.simplify) == \
        sp.zeros(6, 6)
    lam_, mu_, R_ = 2.0e6, 1.0e6, 0.05
    for h in (1e-6, 0.3, 0.49999, 0.50001, 0.8):
        got = _lowered(K, {lam: lam_, mu: mu_, R: R_, r: R_ / h})
        ref = _polar_quadrature(h / R_, lam_, mu_, R_)
        scale = np.sqrt(np.outer(np.diag(ref), np.diag(ref)))
        # the quadrature converges geometrically (the pole at a2 = r is outside the disk): 1e-14 at 120 points
        np.testing.assert_array_less(np.abs(got - ref), 1e-13 * scale + 1e-300)


def test_bad_arguments_are_refused():
    with pytest.raises(NotImplementedError, match="tau0"):
        cs.cross_section_stiffness(lam, mu, cs.Square(b), 1 / r, tau0=1)
    with pytest.raises(TypeError, match="unknown section"):
        cs.cross_section_stiffness(lam, mu, "square", 1 / r)
    with pytest.raises(ValueError, match="measure"):
        cs.stiffness_density(lam, mu, 0, 0, 0, 0, measure="area")
