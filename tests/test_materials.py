"""The symbolic material library (mechgen.symbolic.materials) against closed forms and against numerics.

References: the small-strain limit (every extensible law is the linear law to first order in the strain),
the Legendre transform computed by a numerical maximisation (scipy), the cubic of the neo-Hookean inverse
solved by numpy.roots, and the Mooney form of the uniaxial nominal stress of a Mooney-Rivlin solid,
2 (lambda - lambda^-2)(C1 + C2/lambda) (Treloar, The Physics of Rubber Elasticity).
"""
import numpy as np
import pytest
import sympy as sp
from scipy.optimize import minimize_scalar

from mechgen.errors import ModelError
from mechgen.symbolic.materials import (InextensibleString, LinearString, MooneyRivlinString, NeoHookeanString,
                                        green_strain, string_law, uniaxial_incompressible)

E = 100.0  # a nondimensional stiffness (the balloon's beta) for the numerical checks
lam, eps, p, Es = sp.symbols("lambda epsilon p E", positive=True)


def extensible():
    return [NeoHookeanString(Es), LinearString(Es), MooneyRivlinString(Es * sp.Rational(7, 60), Es / 20)]


@pytest.mark.parametrize("law", extensible(), ids=lambda law: law.name)
def test_small_strain_limit_is_the_linear_law(law):
    """p(1 + e) = E e + O(e^2) and W(1 + e) - W(1) = E/2 e^2 + O(e^3): the linear law's to leading order."""
    linear = LinearString(Es)
    tension = sp.series(law.tension(1 + eps), eps, 0, 2).removeO()
    assert sp.simplify(tension - linear.tension(1 + eps)) == 0
    energy = sp.series(law.energy(1 + eps) - law.energy(1), eps, 0, 3).removeO()
    assert sp.simplify(energy - linear.energy(1 + eps)) == 0
    assert sp.simplify(law.tension(1)) == 0  # unstressed at lambda = 1


def test_tension_is_the_closed_form_derivative():
    assert sp.simplify(NeoHookeanString(Es).tension(lam) - Es / 3 * (lam - lam**-2)) == 0
    assert sp.simplify(LinearString(Es).tension(lam) - Es * (lam - 1)) == 0


def test_mooney_rivlin_nominal_stress_is_the_mooney_form():
    c1, c2 = sp.symbols("C1 C2", positive=True)
    law = MooneyRivlinString(c1, c2)
    closed = 2 * (lam - lam**-2) * (c1 + c2 / lam)
    assert sp.simplify(law.tension(lam) - closed) == 0
    # the reduction: I1 = lambda^2 + 2/lambda, I2 = 2 lambda + lambda^-2 of the stretches (lambda, lambda^-1/2 x2)
    stretches = (lam, lam**sp.Rational(-1, 2), lam**sp.Rational(-1, 2))
    i1 = sum(s**2 for s in stretches)
    i2 = sum((stretches[i] * stretches[j]) ** 2 for i, j in ((0, 1), (1, 2), (0, 2)))
    assert sp.simplify(law.energy(lam) - (c1 * (i1 - 3) + c2 * (i2 - 3))) == 0
    assert law.energy(1) == 0
    f = sp.lambdify(lam, law.tension(lam).subs({c1: 0.4, c2: 0.1}))
    for x in (0.6, 1.0, 1.7, 3.0):
        assert f(x) == pytest.approx(2 * (x - x**-2) * (0.4 + 0.1 / x), rel=1e-14)


def test_neo_hookean_is_mooney_rivlin_without_c2_less_its_constant():
    """mu/2 (I1 - 3) with mu = E/3: the library's neo-Hookean W differs by the constant W(1) = E/2 only."""
    nh = NeoHookeanString(Es).energy(lam)
    mr = MooneyRivlinString(Es / 6, 0).energy(lam)
    assert sp.simplify(nh - mr - Es / 2) == 0
    assert sp.simplify(uniaxial_incompressible(lambda i1, i2: Es / 6 * (i1 - 3))(lam) - mr) == 0


@pytest.mark.parametrize("law", [NeoHookeanString(E), LinearString(E)], ids=lambda law: law.name)
def test_complementary_energy_is_the_legendre_transform(law):
    """W*(p) = max over lambda of (p lambda - W(lambda)) (numerical maximisation), dW*/dp = lambda(p) and
    p(lambda(p)) = p."""
    W = sp.lambdify(lam, law.energy(lam))
    pt = sp.Symbol("p", real=True)
    stretch = sp.lambdify(pt, law.stretch(pt))
    dual = sp.lambdify(pt, law.complementary(pt))
    slope = sp.lambdify(pt, sp.diff(law.complementary(pt), pt))
    tension = sp.lambdify(lam, law.tension(lam))
    for tv in (-30.0, -5.0, 0.0, 2.0, 14.7, 80.0):
        best = minimize_scalar(lambda x: -(tv * x - W(x)), bounds=(0.3, 3.0), method="bounded",
                               options={"xatol": 1e-12})
        assert best.x == pytest.approx(stretch(tv), rel=1e-7)
        assert dual(tv) == pytest.approx(-best.fun, rel=1e-12, abs=1e-10)
        assert slope(tv) == pytest.approx(stretch(tv), rel=1e-12)
        assert tension(stretch(tv)) == pytest.approx(tv, rel=1e-12, abs=1e-12)


def test_neo_hookean_inverse_is_the_real_root_of_its_cubic():
    """Cardano's formula against numpy.roots of lambda^3 - 3 q lambda^2 - 1 = 0, down to q^3 near -1/4."""
    pt = sp.Symbol("p", real=True)
    stretch = sp.lambdify(pt, NeoHookeanString(E).stretch(pt))
    for q in (-0.25**(1 / 3) + 1e-6, -0.5, -0.1, 0.0, 0.05, 0.4, 3.0):
        roots = np.roots([1.0, -3.0 * q, 0.0, -1.0])
        real = roots[np.abs(roots.imag) < 1e-7].real
        assert min(abs(real - stretch(E * q))) < 1e-9 * max(1.0, stretch(E * q))


def test_inextensible_law():
    law = InextensibleString()
    assert law.inextensible and law.energy(lam) == 0 and law.stretch(p) == 1 and law.complementary(p) == p
    assert sp.simplify(law.constraint(lam) - (lam**2 - 1) / 2) == 0
    assert LinearString(E).constraint(lam) == 0 and not NeoHookeanString(E).inextensible
    with pytest.raises(ModelError, match="multiplier"):
        law.tension(lam)


def test_green_strain_and_lookup():
    assert sp.expand(green_strain(1 + eps)) == eps + eps**2 / 2
    assert isinstance(string_law("neo_hookean", E), NeoHookeanString)
    assert isinstance(string_law("linear", E), LinearString)
    assert isinstance(string_law("inextensible", E), InextensibleString)
    with pytest.raises(ModelError, match="unknown string law 'rubber'.*neo_hookean, linear, inextensible"):
        string_law("rubber", E)
    with pytest.raises(ModelError, match="no closed-form stretch"):
        MooneyRivlinString(1.0, 0.5).stretch(p)
