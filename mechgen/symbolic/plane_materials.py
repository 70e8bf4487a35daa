"""Plane forms of the solid laws: strain energy per unit area (per unit thickness) in the displacement gradient.

With H_ij = du_i/dx_j (:func:`mechgen.symbolic.plane.gradient`), F = I + H, the laws below give W(H) (J/m^3,
i.e. J/m^2 per unit thickness) of a 2D state of

* **plane strain** (eps_33 = 0, or F_33 = 1): the 3D law restricted to in-plane deformations;
* **plane stress** (sigma_33 = 0): the out-of-plane strain eliminated. For laws linear in a strain
  measure (linear elasticity in eps, Saint Venant-Kirchhoff in the Green strain E) this only replaces
  Lame's lambda by lambda* = 2 lambda mu / (lambda + 2 mu) = E nu / (1 - nu^2); for an incompressible
  neo-Hookean sheet F_33 = 1 / det F. A compressible neo-Hookean law has no closed plane-stress form and is
  refused. :func:`mooney_rivlin` (constants C1, C2, and a bulk modulus in plane strain) follows the same rule.

Lame constants from Young's modulus E and Poisson's ratio nu: mu = E / (2 (1 + nu)),
lambda = E nu / ((1 + nu)(1 - 2 nu)). Kolosov's constant kappa = 3 - 4 nu (plane strain),
(3 - nu) / (1 + nu) (plane stress) enters the closed forms of mechgen.runtime.plane.closed_forms.
"""
from __future__ import annotations

import sympy as sp

from mechgen.errors import ModelError

PLANES = ("stress", "strain")


def _plane(plane: str, law: str) -> str:
    if plane not in PLANES:
        raise ModelError(f"{law}: plane {plane!r} is neither 'stress' nor 'strain'", key="plane",
                         expected="'stress' (sigma_33 = 0) or 'strain' (eps_33 = 0)")
    return plane


def lame(E, nu, plane: str) -> tuple:
    """(lambda_eff, mu) of a plane state: lambda* = E nu/(1 - nu^2) in plane stress, E nu/((1+nu)(1-2nu)) in
    plane strain; mu = E/(2(1+nu)) in both (Pa)."""
    mu = E / (2 * (1 + nu))
    if _plane(plane, "lame") == "stress":
        return E * nu / (1 - nu**2), mu
    return E * nu / ((1 + nu) * (1 - 2 * nu)), mu


def small_strain(H: sp.Matrix) -> sp.Matrix:
    """eps = (H + H^T)/2, the infinitesimal strain of a displacement gradient."""
    return (H + H.T) / 2


def green_lagrange(H: sp.Matrix) -> sp.Matrix:
    """E = (F^T F - I)/2 = (H + H^T + H^T H)/2, the Green-Lagrange strain (in-plane block)."""
    return (H + H.T + H.T * H) / 2


def _quadratic(strain: sp.Matrix, lam, mu):
    """mu e:e + lambda/2 (tr e)^2 of a 2 x 2 strain."""
    return mu * sum(strain[i, j] ** 2 for i in range(2) for j in range(2)) + lam / 2 * strain.trace() ** 2


def linear_elastic(H: sp.Matrix, E, nu, plane: str):
    """W = mu eps:eps + lambda*/2 (tr eps)^2 of isotropic linear elasticity (J/m^3), plane stress or strain."""
    lam, mu = lame(E, nu, plane)
    return _quadratic(small_strain(H), lam, mu)


def saint_venant_kirchhoff(H: sp.Matrix, E, nu, plane: str):
    """W = mu E:E + lambda*/2 (tr E)^2 in the Green-Lagrange strain E (J/m^3): geometrically exact, linear in E,
    so that plane stress is again the substitution lambda -> lambda*."""
    lam, mu = lame(E, nu, plane)
    return _quadratic(green_lagrange(H), lam, mu)


def neo_hookean(H: sp.Matrix, E, nu, plane: str):
    """A neo-Hookean solid (J/m^3).

    Plane strain (compressible, F_33 = 1, J = det F): W = mu/2 (tr F^T F + 1 - 3) - mu ln J + lambda/2 (ln J)^2.
    Plane stress (a rubber sheet) is taken incompressible, the only neo-Hookean sheet with a closed form:
    F_33 = 1/J, W = mu/2 (tr F^T F + J^-2 - 3) with mu = E/3 (``nu`` is not used: it is 1/2).
    """
    F = sp.eye(2) + H
    J = F.det()
    I1 = sum(F[i, j] ** 2 for i in range(2) for j in range(2))
    if _plane(plane, "neo_hookean") == "strain":
        lam, mu = lame(E, nu, "strain")
        return mu / 2 * (I1 + 1 - 3) - mu * sp.log(J) + lam / 2 * sp.log(J) ** 2
    return E / 6 * (I1 + J**-2 - 3)


def mooney_rivlin(H: sp.Matrix, C1, C2, plane: str, bulk=None):
    """A Mooney-Rivlin solid (J/m^3), small-strain shear modulus mu = 2 (C1 + C2).

    Plane stress: the incompressible sheet (F_33 = 1/J, J = det F): with C = F^T F (2 x 2),
    I1 = tr C + J^-2, I2 = tr C / J^2 + J^2, W = C1 (I1 - 3) + C2 (I2 - 3) (equibiaxial stretch l:
    C1 (2 l^2 + l^-4 - 3) + C2 (2 l^-2 + l^4 - 3), the classical sheet).
    Plane strain (F_33 = 1): compressible, W = C1 (J^-2/3 I1 - 3) + C2 (J^-4/3 I2 - 3) + bulk/2 (ln J)^2 with
    I1 = tr C + 1, I2 = tr C + J^2 and ``bulk`` the small-strain bulk modulus K (required), so that at small
    strain lambda = K - 2 mu / 3 (3D Lame constants; Pa).
    """
    F = sp.eye(2) + H
    J = F.det()
    trC = sum(F[i, j] ** 2 for i in range(2) for j in range(2))
    if _plane(plane, "mooney_rivlin") == "stress":
        return C1 * (trC + J**-2 - 3) + C2 * (trC / J**2 + J**2 - 3)
    if bulk is None:
        raise ModelError("mooney_rivlin in plane strain needs the bulk modulus", key="bulk",
                         expected="mooney_rivlin(H, C1, C2, 'strain', bulk=K)")
    return (C1 * (J ** sp.Rational(-2, 3) * (trC + 1) - 3) + C2 * (J ** sp.Rational(-4, 3) * (trC + J**2) - 3)
            + bulk / 2 * sp.log(J) ** 2)


def plane_law(name: str, H: sp.Matrix, E, nu, plane: str):
    """The law ``name`` (linear, saint_venant_kirchhoff, neo_hookean) of :data:`LAWS` at H."""
    if name not in LAWS:
        raise ModelError(f"unknown plane law {name!r}", key="law", expected=", ".join(LAWS))
    return LAWS[name](H, E, nu, plane)


LAWS = {"linear": linear_elastic, "saint_venant_kirchhoff": saint_venant_kirchhoff, "neo_hookean": neo_hookean}
