"""Derivation that scales (issue 32): r = M a + h derived piecewise equals the assembled residual's derivatives, and
the n-link pendulum's accelerations equal its closed-form equations of motion."""
import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen import models
from mechgen.bench.multibody import pendulum_model
from mechgen.pipeline import derive
from mechgen.symbolic.specialize import all_free


def _lumped_models():
    """Built-in models whose equations are lumped (each mode of a hybrid one), with coordinates."""
    return [name for name in models.names() if not (models.get(name).is_field or models.get(name).is_lattice)
            and models.get(name).coordinate_names]


def _equations(name):
    """The derived equations of the model (of every mode of a hybrid model)."""
    model = pendulum_model(4) if name == "pendulum4" else models.get(name)
    eqs = derive(model, all_free(model))
    return list(eqs.equations) if hasattr(eqs, "equations") else [eqs]


def _numeric(eqs, exprs, rng):
    """Evaluate a list of matrices at one random state and parameter point (same point for every call)."""
    syms = list(eqs.q + eqs.v + eqs.a + eqs.z + eqs.params) + [eqs.t]
    point = dict(zip(syms, rng.uniform(0.5, 1.5, len(syms))))
    return [np.array(sp.Matrix(m).xreplace(point).evalf(), dtype=float) for m in exprs]


@pytest.mark.parametrize("name", _lumped_models() + ["pendulum4"])
def test_split_equals_the_assembled_residuals_derivatives(name):
    """M = dr/da, h = r(a = 0), dr/dq, dr/dv and D, G, K as derived before (differentiating the assembled residual
    and substituting a = 0), at a random point: equal to round-off."""
    for eqs in _equations(name):
        _check_split(eqs)


def _check_split(eqs):
    r, at_rest = eqs.residual, {ai: 0 for ai in eqs.a}
    M, h = eqs.split()
    new = [M, h, eqs.residual_jacobian("q"), eqs.residual_jacobian("v"), *eqs.linear_matrices().values()]
    C = eqs.jacobian(r, "v").subs(at_rest)
    old = [eqs.jacobian(r, "a"), r.subs(at_rest), eqs.jacobian(r, "q"), eqs.jacobian(r, "v"),
           eqs.jacobian(r, "a").subs(at_rest), (C + C.T) / 2, (C - C.T) / 2, eqs.jacobian(r, "q").subs(at_rest)]
    for a, b in zip(_numeric(eqs, new, np.random.default_rng(1)), _numeric(eqs, old, np.random.default_rng(1))):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12 * (1 + np.abs(b).max()))


def closed_form_accelerations(theta, w, m=1.0, l=1.0, g=9.81):
    """a of the n-link pendulum from its closed-form equations (mechgen.bench.multibody's docstring), written out
    here by hand: sum_j m l^2 c_ij [cos(th_i - th_j) a_j + sin(th_i - th_j) w_j^2] + m g l (n - i) sin th_i = 0."""
    n = len(theta)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    c = n - np.maximum(i, j)
    d = theta[:, None] - theta[None, :]
    M = m * l**2 * c * np.cos(d)
    f = m * l**2 * (c * np.sin(d)) @ (w**2) + m * g * l * (n - np.arange(n)) * np.sin(theta)
    return np.linalg.solve(M, -f)


@pytest.mark.parametrize("n", [3, 7])
def test_pendulum_accelerations_match_the_closed_form(n):
    """The compiled pendulum's accelerations equal the closed form's to 1e-12 (relative) at random states."""
    system = mechgen.compile(pendulum_model(n), kernels=["flow"])
    rng = np.random.default_rng(n)
    for _ in range(3):
        theta, w = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        a, _ = system.acceleration(theta, w)
        ref = closed_form_accelerations(theta, w)
        assert np.allclose(a, ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())
