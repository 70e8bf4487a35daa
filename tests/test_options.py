"""Options objects (ContinuationOptions, IVPOptions, CampbellOptions): an options object and the same options
as keywords give the same result, and both satisfy the closed form (the unit circle u^2 + lam^2 = 1; the
linear BVP y'' = -y, y(0) = 0, y(pi/2) = 1, solved by y = sin s)."""
import math

import numpy as np
import pytest

from mechgen.errors import InputError
from mechgen.runtime.linear.campbell import CampbellOptions
from mechgen.runtime.steady.bvp import BVP, IVPOptions, shoot
from mechgen.runtime.steady.continuation import ContinuationOptions, ParametricEquations, continuation

CIRCLE = ParametricEquations(lambda u, lam: np.array([u[0] ** 2 + lam ** 2 - 1.0]),
                             lambda u, lam: np.array([[2.0 * u[0]]]), lambda u, lam: np.array([2.0 * lam]),
                             name="circle")


def test_continuation_options_object_equals_keywords():
    opts = ContinuationOptions(ds=0.1, ds_max=0.3, max_points=40)
    by_object = continuation(CIRCLE, [-1.0], 0.0, opts)
    by_keywords = continuation(CIRCLE, [-1.0], 0.0, ds=0.1, ds_max=0.3, max_points=40)
    np.testing.assert_array_equal(by_object.u, by_keywords.u)
    np.testing.assert_array_equal(by_object.lam, by_keywords.lam)
    np.testing.assert_allclose(by_object.u[:, 0] ** 2 + by_object.lam ** 2, 1.0, atol=1e-9)
    # a keyword overrides one option of the object
    shorter = continuation(CIRCLE, [-1.0], 0.0, opts, max_points=5)
    assert len(shorter.lam) == 5
    np.testing.assert_array_equal(shorter.lam, by_object.lam[:5])


def test_options_are_checked_and_frozen():
    with pytest.raises(TypeError, match="dss"):
        continuation(CIRCLE, [-1.0], 0.0, dss=0.1)
    with pytest.raises(InputError, match="ds_min"):
        continuation(CIRCLE, [-1.0], 0.0, ContinuationOptions(ds=-0.1))
    with pytest.raises(AttributeError):
        ContinuationOptions().ds = 1.0
    assert CampbellOptions.of(sparse=True) == CampbellOptions(sparse=True)
    with pytest.raises(TypeError):
        CampbellOptions.of(count=3)


def _sine_problem():
    # y = (y0, y1): y0' = y1, y1' = -y0 on [0, pi/2], g = (y0(0), y0(pi/2) - 1)
    return BVP(f=lambda s, y, p: np.array([y[1], -y[0]]), f_y=lambda s, y, p: np.array([[0.0, 1.0], [-1.0, 0.0]]),
               g=lambda ya, yb, p: np.array([ya[0], yb[0] - 1.0]),
               g_ya=lambda ya, yb, p: np.array([[1.0, 0.0], [0.0, 0.0]]),
               g_yb=lambda ya, yb, p: np.array([[0.0, 0.0], [1.0, 0.0]]), interval=(0.0, math.pi / 2), n=2)


def test_shoot_ivp_options_object_equals_keywords():
    problem = _sine_problem()
    by_object = shoot(problem, [0.0, 0.5], ivp=IVPOptions(rtol_ivp=1e-12, ivp_method="Radau"))
    by_keywords = shoot(problem, [0.0, 0.5], rtol_ivp=1e-12, ivp_method="Radau")
    np.testing.assert_array_equal(by_object.y, by_keywords.y)
    assert by_object.y[1, 0] == pytest.approx(1.0, abs=1e-8)  # y'(0) = cos 0
    with pytest.raises(InputError, match="integrator"):
        shoot(problem, [0.0, 0.5], ivp=IVPOptions(ivp_method="Euler"))
