"""The symbolic material library: constitutive laws as sympy expressions, for models to refer to.

String (1D rod) laws
--------------------
A string law gives the strain energy W(lambda) per unit *reference* (undeformed) length as a function
of the stretch lambda = ds/dS (deformed over undeformed length), and from it

* the tension p(lambda) = dW/dlambda, the nominal (first Piola-Kirchhoff) axial force,
* the inverse lambda(p), where it has a closed form,
* the complementary energy W*(p) = p lambda(p) - W(lambda(p)) (the Legendre transform of W), so that
  dW*/dp = lambda(p): the tension-vector (Hamiltonian) form of a steady string uses it.

Units: lambda is dimensionless; W is an energy per unit reference length, so W, p and every material
constant below have the unit of a force (a 3D material of Young's modulus E on a reference section A0 has
the axial stiffness E A0; a Mooney-Rivlin solid's constants C1, C2 enter as A0 C1, A0 C2). A
nondimensional model divides them all by its force scale (the ballooning string: rho A0 omega^2 a^2, so
that its ``stiffness`` is beta = E / (rho omega^2 a^2)). Energies are defined up to an additive constant,
which drops out of every derivative; each law states the constant it uses.

Laws (W(lambda); p(lambda) = W'(lambda)):

* linear:        W = E/2 (lambda - 1)^2;  p = E (lambda - 1)
* neo-Hookean:   W = E/3 (lambda^2/2 + 1/lambda);  p = E/3 (lambda - lambda^-2)
* Mooney-Rivlin: W = C1 (lambda^2 + 2/lambda - 3) + C2 (2 lambda + lambda^-2 - 3);
  p = 2 (lambda - lambda^-2)(C1 + C2/lambda)
* inextensible:  no W; the constraint g = (lambda^2 - 1)/2 = 0, whose multiplier is the tension

The neo-Hookean and Mooney-Rivlin strings are incompressible solids in uniaxial tension
(:func:`uniaxial_incompressible`); every extensible law has the small-strain stiffness
p'(1) = E (Mooney-Rivlin: E = 6 (C1 + C2)), so that all of them reduce to the linear law for small strains.
"""
from __future__ import annotations

from typing import Callable

import sympy as sp

from mechgen.errors import ModelError


def green_strain(lam):
    """The Green-Lagrange axial strain g = (lambda^2 - 1)/2 of a stretch lambda."""
    return (lam**2 - 1) / 2


def uniaxial_incompressible(energy3d: Callable) -> Callable:
    """The string law of an incompressible isotropic solid in uniaxial tension.

    ``energy3d(I1, I2)`` is the strain energy per unit reference volume in the invariants of the right
    Cauchy-Green tensor; the principal stretches of uniaxial tension at constant volume are
    (lambda, lambda^-1/2, lambda^-1/2), so I1 = lambda^2 + 2/lambda and I2 = 2 lambda + lambda^-2, and the
    energy per unit reference length of a section A0 is A0 energy3d(I1, I2) (the constants of ``energy3d``
    carry the factor A0). Returns lambda -> W(lambda).
    """
    def energy(lam):
        return energy3d(lam**2 + 2 / lam, 2 * lam + 1 / lam**2)

    return energy


class StringLaw:
    """A hyperelastic string: W(lambda) per unit reference length and what follows from it (module doc)."""

    #: the law's name in scenes (a model's ``law`` choice)
    name = ""
    #: True when the string cannot stretch: no energy, the tension is the multiplier of :meth:`constraint`
    inextensible = False

    def energy(self, lam):
        """W(lambda), per unit reference length."""
        raise NotImplementedError

    def tension(self, lam):
        """p(lambda) = dW/dlambda, the nominal axial force."""
        x = sp.Dummy("lambda", positive=True)
        return sp.diff(self.energy(x), x).subs(x, lam)

    def stretch(self, p):
        """lambda(p), the inverse of p(lambda), in closed form."""
        raise ModelError(f"the {self.name} string law has no closed-form stretch lambda(p)", key="law",
                         expected="a law with a closed-form inverse (linear, neo_hookean, inextensible) for the "
                                  "tension-vector (Hamiltonian) form")

    def complementary(self, p):
        """W*(p) = p lambda(p) - W(lambda(p)) = integral of lambda(p) dp (up to a constant)."""
        lam = self.stretch(p)
        return p * lam - self.energy(lam)

    def constraint(self, lam):
        """The constraint g(lambda) = 0 the law imposes (0: none)."""
        return 0


class LinearString(StringLaw):
    """Linear elastic string: W = E/2 (lambda - 1)^2, p = E (lambda - 1), lambda(p) = 1 + p/E,
    W*(p) = p + p^2/(2 E) (W(1) = 0)."""

    name = "linear"

    def __init__(self, stiffness) -> None:
        self.stiffness = stiffness

    def energy(self, lam):
        return self.stiffness / 2 * (lam - 1) ** 2

    def stretch(self, p):
        return 1 + p / self.stiffness

    def complementary(self, p):
        return p + p**2 / (2 * self.stiffness)


class NeoHookeanString(StringLaw):
    """Incompressible neo-Hookean string: W = E/3 (lambda^2/2 + 1/lambda), p = E/3 (lambda - lambda^-2).

    The uniaxial reduction of mu/2 (I1 - 3) with shear modulus mu = E/3, i.e. Mooney-Rivlin with C1 = E/6,
    C2 = 0, without its additive constant (here W(1) = E/2). The inverse solves
    lambda^3 - 3 q lambda^2 - 1 = 0, q = p/E, by Cardano's formula,
    lambda = q + cbrt(S) + cbrt(q^6 / S), S = 1/2 + q^3 + sqrt(1/4 + q^3) (the second root written without
    cancellation; real for q^3 > -1/4, i.e. down to the compressive tension where p'(lambda) vanishes).
    """

    name = "neo_hookean"

    def __init__(self, stiffness) -> None:
        self.stiffness = stiffness

    def energy(self, lam):
        return self.stiffness / 3 * (lam**2 / 2 + 1 / lam)

    def stretch(self, p):
        q = p / self.stiffness
        S = sp.Rational(1, 2) + q**3 + sp.sqrt(sp.Rational(1, 4) + q**3)
        return q + sp.cbrt(S) + sp.cbrt(q**6 / S)


class MooneyRivlinString(StringLaw):
    """Incompressible Mooney-Rivlin string: the uniaxial reduction of W3 = C1 (I1 - 3) + C2 (I2 - 3),

        W = C1 (lambda^2 + 2/lambda - 3) + C2 (2 lambda + lambda^-2 - 3)   (W(1) = 0),
        p = 2 (lambda - lambda^-2)(C1 + C2/lambda)                         (the Mooney form of Treloar, The
                                                                            Physics of Rubber Elasticity)

    with C1, C2 per unit reference length (A0 times the solid's constants); small-strain stiffness
    E = 6 (C1 + C2). lambda(p) is the root of a quartic: no closed form is offered (``stretch`` raises).
    """

    name = "mooney_rivlin"

    def __init__(self, c1, c2) -> None:
        self.c1, self.c2 = c1, c2

    def energy(self, lam):
        return uniaxial_incompressible(lambda i1, i2: self.c1 * (i1 - 3) + self.c2 * (i2 - 3))(lam)


class InextensibleString(StringLaw):
    """Inextensible string: lambda = 1, no strain energy; the constraint g = (lambda^2 - 1)/2 = 0 carries the
    tension as its multiplier. lambda(p) = 1 and W*(p) = p."""

    name = "inextensible"
    inextensible = True

    def energy(self, lam):
        return sp.Integer(0)

    def tension(self, lam):
        raise ModelError("an inextensible string's tension is the multiplier of its constraint, not a function "
                         "of the stretch", key="law", expected="an extensible law")

    def stretch(self, p):
        return sp.Integer(1)

    def complementary(self, p):
        return p

    def constraint(self, lam):
        return green_strain(lam)


#: the one-constant string laws by scene name
STRING_LAWS = {"neo_hookean": NeoHookeanString, "linear": LinearString, "inextensible": InextensibleString}


def string_law(name: str, stiffness=None) -> StringLaw:
    """The string law called ``name`` (a key of :data:`STRING_LAWS`) with small-strain stiffness ``stiffness``
    (ignored by the inextensible law). Mooney-Rivlin has two constants: build :class:`MooneyRivlinString`."""
    if name not in STRING_LAWS:
        raise ModelError(f"unknown string law {name!r}", key="law", expected="one of " + ", ".join(STRING_LAWS))
    cls = STRING_LAWS[name]
    return cls() if cls is InextensibleString else cls(stiffness)
