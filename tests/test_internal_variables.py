"""A model declared in a few lines with an internal variable (a Maxwell dashpot stretch).

Standard linear solid on a mass: spring k1 in parallel with a Maxwell arm (spring k2
in series with a dashpot c); s is the dashpot stretch:

    m x'' + k1 x + k2 (x - s) = 0,    c s' = k2 (x - s).

With y = (x, v, s), y' = A y, the characteristic polynomial is
    c m l^3 + k2 m l^2 + c (k1 + k2) l + k1 k2 = 0
(expand det(l I - A)); its roots are the reference eigenvalues.
"""
import numpy as np
import pytest

from mechgen.pipeline import compile_model
from mechgen.analyses.simulate import run_simulate
from mechgen.analyses.stability import run_stability
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.specialize import specialize


def sls_model() -> Model:
    model = Model("sls_oscillator", doc="mass on a standard linear solid")
    model.params(Param("m", 2.0, "kg"), Param("k1", 3.0, "N/m"), Param("k2", 5.0, "N/m"), Param("c", 0.7, "N s/m"))
    model.coordinates("x")
    model.internal("s", rate=lambda q, z, p: p.k2 * (q.x - z.s) / p.c)
    model.output("position", lambda q: q.x)

    @model.kinetic
    def kinetic(v, p):
        return p.m / 2 * v.x**2

    @model.potential
    def potential(q, z, p):
        return p.k1 / 2 * q.x**2 + p.k2 / 2 * (q.x - z.s) ** 2

    return model


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_first_order_eigenvalues_match_characteristic_polynomial(backend):
    model = sls_model()
    system, _ = compile_model(model, specialize(model, {}), backend=backend)
    out = run_stability(system, {}, {})
    m, k1, k2, c = 2.0, 3.0, 5.0, 0.7
    expected = np.roots([c * m, k2 * m, c * (k1 + k2), k1 * k2])
    found = np.array([complex(re, im) for re, im in out["eigenvalues"]])
    assert len(found) == 3
    for lam in expected:
        assert np.min(np.abs(found - lam)) < 1e-10 * max(1.0, abs(lam))
    assert out["verdict"] == "stable"


@pytest.mark.parametrize("method", ["Radau", "BDF", "DOP853"])
def test_simulation_with_internal_variable_matches_matrix_exponential(method):
    """x(t) of the linear system equals [expm(A t) y0]_0 with A from the equations above."""
    from scipy.linalg import expm

    model = sls_model()
    system, _ = compile_model(model, specialize(model, {}), backend="c")
    t_end = 7.5
    out = run_simulate(system, {"method": method, "t_end": t_end, "q0": {"x": 1.0}, "rtol": 1e-10,
                                "atol": 1e-12}, {})
    m, k1, k2, c = 2.0, 3.0, 5.0, 0.7
    A = np.array([[0, 1, 0], [-(k1 + k2) / m, 0, k2 / m], [k2 / c, 0, -k2 / c]])
    assert out["position"] == pytest.approx((expm(A * t_end) @ [1.0, 0.0, 0.0])[0], abs=1e-7)
