"""Cross-section stiffness of a rod, K = int_A D^T C D dA, from the 3D isotropic law (Lame lam, mu).

Seed 001 (Grazioso, "Modeling of a soft link", slides 9-25), rebuilt from the physics. The rod's reference
curve u0(s) (arc length s, so |u0'| = 1) carries the section frame R0 = [t0 n0 b0]; a section point is
X = u0 + R0 p with p = (0, a2, a3) (a2 along the normal n0, towards the centre of curvature, a3 along the
binormal b0). The reference twist is f0 = (e1, (tau0, 0, kappa0)); a configuration H = (R, u) has the twist
f = vee6(H^-1 H') = f0 + eps, eps = (u-strains: extension, shears; w-strains: twist, bendings).

* Convected base vectors: dx/da1 = R N f with N = [I, -hat3(p)], dx/da2 = R e2, dx/da3 = R e3, so the
  Green-Lagrange strains GL_ij = (g_ij - g0_ij)/2 have GL22 = GL33 = GL23 = 0 (rigid sections) and
  gl = [GL11, 2 GL12, 2 GL13] = D eps + O(eps^2) with D = [(N f0)^T N; e2^T N; e3^T N]   (3 x 6).
* Reference metric g0 = [[|N f0|^2, -a3 tau0, a2 tau0], [., 1, 0], [., 0, 1]], det g0 = (1 - a2 kappa0)^2,
  and its inverse G0 (contravariant, slide 16).
* Elasticity tensor C^ijkl = lam G0^ij G0^kl + mu (G0^ik G0^jl + G0^il G0^jk). The rigid-section kinematics
  fixes GL22 = GL33 = GL23 = 0, which would give the axial modulus lam + 2 mu (Poisson locking); the rod
  law instead leaves the section free of transverse stress, S^22 = S^33 = S^23 = 0: the transverse strains
  are condensed out (Schur complement, ``condense=True``, the default). For tau0 = 0 that gives
  C = diag(E/d^2, mu/d, mu/d), d = (1 - a2 kappa0)^2, with E = mu (3 lam + 2 mu)/(lam + mu) = lam_bar + 2 mu,
  lam_bar = lam mu/(lam + mu): the seed's reduced Lame constant in its C11 (slide 17).
* The seed integrates over the parameter area dA = da2 da3 (slides 18, 23: ``measure="parametric"``, the
  default, which gives its curved-beam coefficients c1, c2, c3 of slide 25). The reference volume element
  is sqrt(det g0) da1 da2 da3 = (1 - a2 kappa0) da1 da2 da3; ``measure="reference"`` integrates with it
  (then K_uu11 = E int dA/(1 - a2 kappa0), Winkler's curved bar). The two agree for a straight rod.

Straight rod (kappa0 = tau0 = 0, section centred on the curve, principal axes n0, b0):
K = diag(E A, mu A, mu A, mu I_p, E I_2, E I_3) with I_2 = int a3^2 dA, I_3 = int a2^2 dA, I_p = I_2 + I_3:
no shear correction factor (shear area = A) and torsion by the polar moment (no warping; exact for a circle).
A curved rod (kappa0 != 0) couples extension with bending about b0 and shear along b0 with twist:
K[u1, w3] = -E int a2 dA/(1 - a2 kappa0)^2 and K[u3, w1] = mu int a2 dA/(1 - a2 kappa0)^2 (the seed's c3 terms).
With tau0 != 0 the condensed C (``constitutive_matrix``, ``stiffness_density``) has shear-extension couplings
of order a tau0; it is not the seed's slide-17 C, whose extracted text is garbled there (the two agree at
tau0 = 0), and :func:`cross_section_stiffness` integrates tau0 = 0 only.
Units: lam, mu in Pa, lengths in m; K_uu in N, K_uw in N m, K_ww in N m^2.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from mechgen.symbolic.liegroup import hat3
from mechgen.symbolic.safe import safe_function

A2, A3 = sp.symbols("alpha2 alpha3", real=True)
_LAM, _MU = sp.symbols("lam mu", real=True)


@dataclass(frozen=True)
class Rectangle:
    """A rectangular section centred on the reference curve: a2 in [-width2/2, width2/2] (along n0),
    a3 in [-width3/2, width3/2] (along b0). Widths are sympy expressions or numbers (m)."""

    width2: object
    width3: object


def Square(b) -> Rectangle:  # noqa: N802 - a constructor
    """The square section of side b (seed 001, slide 20)."""
    return Rectangle(b, b)


@dataclass(frozen=True)
class Circle:
    """A solid circular section of radius ``radius`` centred on the reference curve."""

    radius: object


def young_modulus(lam, mu):
    """E = mu (3 lam + 2 mu)/(lam + mu) (Pa)."""
    return mu * (3 * lam + 2 * mu) / (lam + mu)


def reference_twist(kappa0, tau0) -> sp.Matrix:
    """f0 = (e1, (tau0, 0, kappa0)) of an arc-length reference curve (seed 001, slides 6, 9)."""
    return sp.Matrix([1, 0, 0, tau0, 0, kappa0])


def _n_matrix(a2, a3) -> sp.Matrix:
    """N = [I, -hat3(p)], p = (0, a2, a3): dx/da1 = R N f."""
    return sp.eye(3).row_join(-hat3([0, a2, a3]))


def strain_operator(a2, a3, kappa0, tau0) -> sp.Matrix:
    """D (3 x 6) of gl = [GL11, 2 GL12, 2 GL13] = D eps at the section point (a2, a3) (slide 12)."""
    N = _n_matrix(a2, a3)
    Nf0 = N * reference_twist(kappa0, tau0)
    return (Nf0.T * N).col_join(N[1, :]).col_join(N[2, :])


def reference_metric(a2, a3, kappa0, tau0) -> sp.Matrix:
    """The covariant metric g0_ij of the reference configuration in (a1, a2, a3) (3 x 3)."""
    Nf0 = _n_matrix(a2, a3) * reference_twist(kappa0, tau0)
    return sp.Matrix([[Nf0.dot(Nf0), Nf0[1], Nf0[2]], [Nf0[1], 1, 0], [Nf0[2], 0, 1]])


_PAIRS = ((0, 0), (0, 1), (0, 2), (1, 1), (2, 2), (1, 2))   # 11, 12, 13 (kept) then 22, 33, 23 (condensed)


def constitutive_matrix(lam, mu, a2, a3, kappa0, tau0, *, condense: bool = True) -> sp.Matrix:
    """C (3 x 3) with s = [S11, S12, S13] = C gl: the contravariant isotropic law in the convected coordinates,
    the transverse stresses S22 = S33 = S23 = 0 condensed out (``condense``) or the transverse strains held
    at zero (``condense=False``: lam + 2 mu in place of E). Pa per unit metric (module docstring)."""
    G = reference_metric(a2, a3, kappa0, tau0).inv()
    G = G.applyfunc(sp.factor) if sp.sympify(tau0) == 0 else G.applyfunc(sp.cancel)

    def c4(i, j, k, l):
        return lam * G[i, j] * G[k, l] + mu * (G[i, k] * G[j, l] + G[i, l] * G[j, k])

    full = sp.Matrix(6, 6, lambda a, b: c4(*_PAIRS[a], *_PAIRS[b]))   # engineering (Voigt) order
    A = full[:3, :3]
    if condense:
        B, Cc = full[:3, 3:], full[3:, 3:]
        A = A - B * Cc.inv() * B.T
    return A.applyfunc(sp.factor) if sp.sympify(tau0) == 0 else A.applyfunc(sp.cancel)


def stiffness_density(lam, mu, a2, a3, kappa0, tau0, *, condense: bool = True,
                      measure: str = "parametric") -> sp.Matrix:
    """The integrand D^T C D (times sqrt(det g0) for ``measure="reference"``) of K at (a2, a3) (6 x 6, Pa)."""
    D = strain_operator(a2, a3, kappa0, tau0)
    dens = D.T * constitutive_matrix(lam, mu, a2, a3, kappa0, tau0, condense=condense) * D
    if measure == "reference":
        dens = dens * (1 - a2 * kappa0)
    elif measure != "parametric":
        raise ValueError(f"measure must be 'parametric' or 'reference', not {measure!r}")
    return dens


# -- integrals over the section -----------------------------------------------------------------------------

_SERIES_BELOW = sp.Rational(1, 4)
_SERIES_TERMS = 64
_H = sp.Symbol("h", real=True)
_U = sp.Symbol("u", positive=True)


def _f_closed(m: int, n: int) -> sp.Expr:
    """F_mn(h) = int_{-1}^{1} y^m (1 - h y)^-n dy in closed form: with u = 1 - h y,
    h^-(m+1) int_{1-h}^{1+h} (1 - u)^m u^-n du (logs from the u^-1 term; valid for |h| < 1)."""
    total = sp.Integer(0)
    for j in range(m + 1):
        p = j - n
        piece = (sp.log(1 + _H) - sp.log(1 - _H) if p == -1
                 else ((1 + _H) ** (p + 1) - (1 - _H) ** (p + 1)) / (p + 1))
        total += sp.binomial(m, j) * (-1) ** j * piece
    return total / _H ** (m + 1)


def _f_coeffs(m: int, n: int) -> list:
    """Taylor coefficients of F_mn: sum_k binom(n+k-1, k) h^k int y^(m+k) dy, int y^q dy = 2/(q+1) for even q."""
    return [sp.binomial(n + k - 1, k) * (sp.Rational(2, m + k + 1) if (m + k) % 2 == 0 else 0)
            for k in range(_SERIES_TERMS)]


@lru_cache(maxsize=None)
def section_moment(m: int, n: int) -> type:
    """The SafeFunction F_mn(h) = int_{-1}^{1} y^m (1 - h y)^-n dy (series for |h| < 1/4, closed form above)."""
    return safe_function(f"section_F{m}_{n}", sp.Lambda(_H, _f_closed(m, n)), _f_coeffs(m, n), _SERIES_BELOW)


def _z_moment(q: int):
    """int_{-1}^{1} z^q dz."""
    return sp.Rational(2, q + 1) if q % 2 == 0 else sp.Integer(0)


def _disk_moment(a: int, b: int):
    """int over the unit disk of y^a z^b = 2 G((a+1)/2) G((b+1)/2) / ((a+b+2) G((a+b)/2 + 1)) for even a, b,
    = 2 pi (a-1)!! (b-1)!! / (2^((a+b)/2) (a+b+2) ((a+b)/2)!)."""
    if a % 2 or b % 2:
        return sp.Integer(0)
    half = (a + b) // 2
    return (2 * sp.pi * sp.factorial2(a - 1) * sp.factorial2(b - 1)
            / (sp.Integer(2) ** half * (a + b + 2) * sp.factorial(half)))


def _theta_power(e: int) -> sp.Expr:
    """T_e(h) = int_0^pi (1 - h cos t)^e dt: a polynomial for e >= 0, pi s^e P_(-e-1)(1/s) for e < 0
    (s = sqrt(1 - h^2), P_n Legendre; Gradshteyn & Ryzhik 3.661)."""
    if e >= 0:
        return sum(sp.binomial(e, l) * (-_H) ** l * (sp.pi * sp.binomial(l, l // 2) / 2**l if l % 2 == 0 else 0)
                   for l in range(e + 1))
    s = sp.sqrt(1 - _H**2)
    return sp.pi * s**e * sp.legendre(-e - 1, 1 / s)


def _g_closed(m: int, q: int, n: int) -> sp.Expr:
    """G_mqn(h) = int over the unit disk of y^m z^q (1 - h y)^-n, even q: with y = cos t, after the z integral,
    2/(q+1) int_0^pi P(cos t) (1 - h cos t)^-n dt, P(c) = c^m (1 - c^2)^((q+2)/2), and c^j = ((1 - u)/h)^j,
    u = 1 - h c, reduces each power to T_e (valid for |h| < 1)."""
    c = sp.Symbol("c")
    poly = sp.Poly(sp.expand(c**m * (1 - c**2) ** ((q + 2) // 2)), c)
    total = sp.Integer(0)
    for (j,), pj in poly.terms():
        total += pj * _H ** (-j) * sum(sp.binomial(j, i) * (-1) ** i * _theta_power(i - n) for i in range(j + 1))
    return 2 * total / (q + 1)


@lru_cache(maxsize=None)
def disk_moment(m: int, q: int, n: int) -> type:
    """The SafeFunction G_mqn(h) = int over the unit disk of y^m z^q (1 - h y)^-n (series for |h| < 1/2 with
    coefficients binom(n+k-1, k) int y^(m+k) z^q, closed form above)."""
    coeffs = [sp.binomial(n + k - 1, k) * _disk_moment(m + k, q) for k in range(_SERIES_TERMS)]
    return safe_function(f"section_G{m}_{q}_{n}", sp.Lambda(_H, _g_closed(m, q, n)), coeffs, sp.Rational(1, 2))


def _rectangle_moment(m: int, q: int, n: int, h: sp.Expr) -> sp.Expr:
    """int over the square [-1, 1]^2 of y^m z^q (1 - h y)^-n."""
    zq = _z_moment(q)
    if zq == 0:
        return sp.Integer(0)
    return zq * (_z_moment(m) if n == 0 else section_moment(m, n)(h))


def _circle_moment(m: int, q: int, n: int, h: sp.Expr) -> sp.Expr:
    """int over the unit disk of y^m z^q (1 - h y)^-n."""
    if q % 2:
        return sp.Integer(0)
    return _disk_moment(m, q) if n == 0 else disk_moment(m, q, n)(h)


def _integrate(expr: sp.Expr, half2, half3, kappa0, moment) -> sp.Expr:
    """int over the section of expr(a2, a3), a rational function whose denominator is a power of
    (1 - kappa0 a2): with a2 = half2 y, a3 = half3 z and h = kappa0 half2, a sum of monomials
    y^m z^q (1 - h y)^-n, each integrated over the unit section by ``moment(m, q, n, h)``."""
    y, z = sp.symbols("y z", real=True)
    e = sp.cancel(sp.together(expr.xreplace({A2: half2 * y, A3: half3 * z})))
    if e == 0:
        return sp.Integer(0)
    num, den = sp.fraction(e)
    h = sp.Symbol("h_", real=True)
    to_h = {kappa0: h / half2} if kappa0 != 0 else {}
    base_n, const = _power_of_one_minus(sp.factor(den.subs(to_h)), h, y)
    total = sp.Integer(0)
    for (m, q), coeff in sp.Poly(sp.expand(num.subs(to_h)), y, z).terms():
        total += coeff.subs(h, kappa0 * half2) * moment(m, q, base_n, kappa0 * half2)
    return sp.factor_terms(total * half2 * half3 / const)


def _power_of_one_minus(den: sp.Expr, h: sp.Symbol, y: sp.Symbol) -> tuple[int, sp.Expr]:
    """(n, c) with den = c (1 - h y)^n, c free of y."""
    n = sp.degree(den, y) if den.has(y) else 0
    if n == 0:
        return 0, den
    c = sp.cancel(den / (1 - h * y) ** n)
    if c.has(y):
        raise ValueError(f"section integrand denominator {den} is not a power of (1 - kappa0 a2)")
    return int(n), c


def cross_section_stiffness(lam, mu, section, kappa0=0, tau0=0, *, condense: bool = True,
                            measure: str = "parametric") -> sp.Matrix:
    """K = int_A D^T C D dA (6 x 6, ordered [K_uu, K_uw; K_wu, K_ww]) of a section of a rod whose reference
    curve has curvature kappa0 and torsion tau0 (1/m), from the Lame constants lam, mu (Pa).

    ``section``: a :class:`Rectangle` or a :class:`Circle` (tau0 = 0). The integrals are exact: monomials over
    powers of (1 - kappa0 a2) give the :func:`section_moment` functions F_mn(kappa0 w2/2) (rectangle) or the
    :func:`disk_moment` functions G_mqn(kappa0 R) (circle), finite and accurate at kappa0 = 0, defined for
    |kappa0| w2/2 < 1 or |kappa0| R < 1 (the section does not reach the centre of curvature). See the module docstring for
    ``condense`` and ``measure``. A pre-twisted or helical reference (tau0 != 0) has no closed form here:
    integrate :func:`stiffness_density` numerically.
    """
    if sp.sympify(tau0) != 0:
        raise NotImplementedError("cross_section_stiffness integrates in closed form for tau0 = 0 only; "
                                  "use stiffness_density with a quadrature for a twisted reference")
    kappa0 = sp.sympify(kappa0)
    k = sp.Symbol("k_", real=True)  # a plain symbol while integrating, substituted at the end
    dens = stiffness_density(_LAM, _MU, A2, A3, k if kappa0 != 0 else 0, 0, condense=condense, measure=measure)
    kk = k if kappa0 != 0 else sp.Integer(0)
    if isinstance(section, Rectangle):
        half2, half3, moment = sp.sympify(section.width2) / 2, sp.sympify(section.width3) / 2, _rectangle_moment
    elif isinstance(section, Circle):
        half2 = half3 = sp.sympify(section.radius)
        moment = _circle_moment
    else:
        raise TypeError(f"unknown section {section!r}: a Rectangle, Square or Circle")
    K = dens.applyfunc(lambda e: _integrate(e, half2, half3, kk, moment))
    return K.xreplace({k: kappa0, _LAM: sp.sympify(lam), _MU: sp.sympify(mu)})
