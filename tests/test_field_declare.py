"""Declaring continua: weak forms equal energies, linearisation about a base state given as data, bad declarations.

The references are independent of the code under test: the same physics declared two
ways, a finite-difference Jacobian of the generated residual, and closed forms.
"""
import numpy as np
import pytest

from mechgen.pipeline import compile_model
from mechgen.errors import ModelError
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.specialize import specialize


def beam(weak: bool) -> Model:
    """Pinned Euler-Bernoulli beam from energies, or from its weak form int rhoA w_tt v + EI w_ss v_ss ds."""
    model = Model("weak_beam" if weak else "energy_beam")
    model.params(Param("EI", 2.0), Param("rhoA", 3.0), Param("L", 1.5))
    model.field("w", discretisation="hermite", N=12)
    if weak:
        model.weak_form(lambda test, u, p: p.rhoA * u.w_tt * test.w + p.EI * u.w_ss * test.w_ss)
    else:
        model.kinetic_density(lambda u, p: p.rhoA / 2 * u.w_t**2)
        model.potential_density(lambda u, p: p.EI / 2 * u.w_ss**2)
    model.boundary(lambda: [fix("w", "start"), fix("w", "end")])
    return model


def test_weak_form_equals_energy():
    mats = {}
    for weak in (False, True):
        model = beam(weak)
        system, _ = compile_model(model, specialize(model, {}), kernels={"linear"})
        mats[weak] = system.linear()
    for k in ("M", "K"):
        assert np.allclose(mats[True][k].toarray(), mats[False][k].toarray(), rtol=1e-13, atol=1e-12)


def stiffening_string() -> Model:
    """A string with cubic stiffening, V = P/2 w_s^2 + k4/4 w_s^4: K about w0 has the local coefficient P + 3 k4 w0_s^2."""
    model = Model("stiffening_string")
    model.params(Param("P", 1.0), Param("k4", 5.0), Param("rhoA", 1.0), Param("L", 1.0))
    model.field("w", discretisation="legendre", N=14)
    model.kinetic_density(lambda u, p: p.rhoA / 2 * u.w_t**2)
    model.potential_density(lambda u, p: p.P / 2 * u.w_s**2 + p.k4 / 4 * u.w_s**4)
    model.boundary(lambda: [fix("w", "start"), fix("w", "end")])
    return model


def test_linearisation_about_a_base_state_given_as_jets():
    model = stiffening_string()
    system, _ = compile_model(model, specialize(model, {}), kernels={"linear", "residual", "tangent"})
    rng = np.random.default_rng(3)
    q0 = 0.1 * rng.standard_normal(system.n)
    from_state = system.linear(q0)["K"]
    # the same base state as data: its jets at the Gauss points (w, w_s)
    disc = system.disc
    s = disc.points
    x = system.reduction.expand(q0)
    jets = np.einsum("eqal,el->eqa", disc.tables, x[disc.dofs])
    from_data = system.linear(jets=jets)["K"]
    assert np.allclose(from_data, from_state, rtol=1e-13, atol=1e-13)
    # independent check: K = dr/dq by central differences of the generated residual
    h = 1e-6
    fd = np.column_stack([(system.residual(q0 + h * e) - system.residual(q0 - h * e)) / (2 * h)
                          for e in np.eye(system.n)])
    assert np.allclose(from_state, fd, rtol=1e-7, atol=1e-7)
    assert not np.allclose(from_state, system.linear()["K"])  # the base state matters
    assert s.shape == jets.shape[:2]


def test_stiffened_frequency_about_a_sine_base_state():
    """About w0 = A sin(pi s): K_loc = P + 3 k4 A^2 pi^2 cos^2(pi s); the Rayleigh quotient of sin(pi s) gives
    omega_1^2 ~ pi^2 (P + 9/4 k4 A^2 pi^2) / rhoA (exact for the projection onto the first sine)."""
    model = stiffening_string()
    model_values = {"discretisation": "sine", "N": 1, "quadrature": 24}  # quartic coefficient: more points
    system, _ = compile_model(model, specialize(model, model_values), kernels={"linear"})
    A = 0.2
    q0 = np.array([A])
    mats = system.linear(q0)
    omega2 = mats["K"][0, 0] / mats["M"][0, 0]
    assert omega2 == pytest.approx(np.pi**2 * (1.0 + 9 / 4 * 5.0 * A**2 * np.pi**2), rel=1e-12)


def test_misspelt_jet_is_a_model_error():
    model = Model("typo")
    model.params(Param("L", 1.0))
    model.field("w")
    model.potential_density(lambda u: u.w_x**2)
    with pytest.raises(ModelError, match="no jet 'w_x'"):
        compile_model(model, specialize(model, {}), kernels={"linear"})


def test_weak_form_must_be_linear_in_the_test_jets():
    model = Model("nonlinear_test")
    model.params(Param("L", 1.0))
    model.field("w")
    model.weak_form(lambda test, u: u.w_s * test.w_s**2)
    with pytest.raises(ModelError, match="not linear in the test jets"):
        compile_model(model, specialize(model, {}), kernels={"linear"})


@pytest.mark.parametrize("name", ["w); import os", "__class__", "lambda", "w-1"])
def test_hostile_field_names_are_refused(name):
    model = Model("hostile")
    model.params(Param("L", 1.0))
    with pytest.raises(ModelError):
        model.field(name)


def test_unused_field_is_an_error():
    model = Model("unused")
    model.params(Param("L", 1.0))
    model.field("v", "w")
    model.potential_density(lambda u: u.w_s**2)
    with pytest.raises(ModelError, match="appear in no density"):
        compile_model(model, specialize(model, {}), kernels={"linear"})
