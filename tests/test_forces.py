"""Declared non-conservative forces: a circulatory (follower-type) force gives flutter.

Two unit masses on springs k with the circulatory coupling Q_x = -p y, Q_y = p x
(the linear model of a follower load, Ziegler, Principles of Structural Stability, 1968):

    x'' + k x + p y = 0,   y'' + k y - p x = 0   =>   s^2 = -k +- i p,

so for p != 0 one root pair has Re s > 0 with Im s != 0: flutter. With p = 0 it is stable.
"""
import numpy as np
import pytest

from mechgen.pipeline import compile_model
from mechgen.analyses.stability import run_stability
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.specialize import specialize


def circulatory_model() -> Model:
    model = Model("circulatory_pair", doc="two springs with a circulatory coupling")
    model.params(Param("k", 4.0, "N/m"), Param("P", 0.5, "N/m"))
    model.coordinates("x", "y")
    model.kinetic(lambda v: (v.x**2 + v.y**2) / 2)
    model.potential(lambda q, p: p.k / 2 * (q.x**2 + q.y**2))
    model.forces(lambda q, p: {"x": -p.P * q.y, "y": p.P * q.x})
    return model


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_circulatory_force_flutters_with_closed_form_eigenvalues(backend):
    model = circulatory_model()
    system, _ = compile_model(model, specialize(model, {}, free=("P",)), kernels={"linear"}, backend=backend)
    out = run_stability(system.with_params(P=0.5), {}, {})
    assert out["verdict"] == "flutter"
    expected = np.concatenate([np.sqrt(complex(-4.0, s * 0.5)) * np.array([1, -1]) for s in (1, -1)])
    found = np.array([complex(re, im) for re, im in out["eigenvalues"]])
    for lam in expected:
        assert np.min(np.abs(found - lam)) < 1e-12
    assert run_stability(system.with_params(P=0.0), {}, {})["verdict"] == "stable"
