"""Hard cases: stiff, near-singular, singular, high-speed, large-rotation, no solution, NaN.

Each either converges to its reference or fails with a clear error; none hangs.
"""
import numpy as np
import pytest
import sympy as sp

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.errors import ConvergenceError, InputError, KernelError
from mechgen.analyses.modes import run_modes
from mechgen.analyses.simulate import run_simulate
from mechgen.analyses.stability import run_stability
from mechgen.analyses.steady import run_steady
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.specialize import specialize
from test_models import LAVAL, laval_whirl


def _laval(**values):
    model = models.get("laval_rotor")
    system, _ = compile_model(model, specialize(model, {**LAVAL, **values}), kernels={"linear"}, backend="c")
    return system


def test_high_speed_rotor_keeps_a_stable_verdict():
    """Omega = 1e5 rad/s: backward whirl ~ k_r/(Ip Omega), forward ~ Ip Omega / Id, ten decades apart."""
    out = run_stability(_laval(Omega=1.0e5), {}, {})
    assert out["verdict"] == "stable"
    expected = laval_whirl(1.0e5, **LAVAL)
    found = np.sort(out["frequencies"])
    np.testing.assert_allclose(found[[0, -1]], expected[[0, -1]], rtol=1e-8)


def test_near_singular_mass_gives_the_stiff_frequency():
    """Id = 1e-10 kg m^2: tilt frequency sqrt(k_r / Id) = 1.4e7 rad/s next to sqrt(k_t/m) = 200 rad/s."""
    freqs = run_modes(_laval(Id=1e-10, Omega=0.0), {}, {})["frequencies"]
    assert freqs[-1] == pytest.approx(np.sqrt(LAVAL["k_r"] / 1e-10), rel=1e-8)
    assert freqs[0] == pytest.approx(np.sqrt(LAVAL["k_t"] / LAVAL["m"]), rel=1e-10)


def test_singular_mass_is_a_clear_error():
    with pytest.raises(InputError, match="(?i)positive definite|singular"):
        run_modes(_laval(Id=0.0, Omega=0.0), {}, {})


def test_stiff_spring_pendulum_steps_over_the_fast_mode():
    """k = 1e6 N/m: the spring period (6e-3 s) is 300x shorter than the pendulum's. Started at the
    quasi-static stretch, the spring mode is hardly excited, and Radau with the generated Jacobian
    takes steps far longer than the spring period while following the rigid pendulum of length
    r_eq = l0 + m g / k (reference: theta'' = -(g / r_eq) sin(theta), DOP853 at rtol 1e-12)."""
    from scipy.integrate import solve_ivp

    model = models.get("spring_pendulum")
    system, _ = compile_model(model, specialize(model, {"k": 1.0e6}), backend="c")
    r_eq, theta0, t_end = 1.0 + 9.81e-6, 0.5, 2.0
    out = run_simulate(system, {"method": "Radau", "t_end": t_end, "q0": {"r": r_eq, "theta": theta0},
                                "rtol": 1e-6, "atol": 1e-6, "samples": 3}, {})
    rigid = solve_ivp(lambda t, y: [y[1], -9.81 / r_eq * np.sin(y[0])], (0, t_end), [theta0, 0.0],
                      method="DOP853", rtol=1e-12, atol=1e-12)
    theta = rigid.y[0, -1]
    assert out["x"] == pytest.approx(r_eq * np.sin(theta), abs=1e-4)
    assert out["y"] == pytest.approx(-r_eq * np.cos(theta), abs=1e-4)


def test_pendulum_swinging_over_the_top():
    """Large rotation: theta0 = 3.0 rad with enough speed to loop; energy conserved."""
    model = models.get("spring_pendulum")
    system, _ = compile_model(model, specialize(model, {}), backend="c")
    out = run_simulate(system, {"method": "DOP853", "t_end": 10.0, "q0": {"r": 1.2, "theta": 3.0},
                                "v0": {"theta": 4.0}, "rtol": 1e-11, "atol": 1e-12}, {})
    assert out["energy_drift"] < 1e-8


def _exp_model() -> Model:
    model = Model("no_root", doc="V = x + x^3/3: the force -(1 + x^2) never vanishes")
    model.params(Param("a", 1.0))
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(lambda q, p: p.a * q.x + q.x**3 / 3)
    model.output("log_x", lambda q: sp.log(q.x))
    return model


def test_newton_without_a_root_fails_quickly_with_a_message():
    model = _exp_model()
    system, _ = compile_model(model, specialize(model, {}), backend="c")
    with pytest.raises(ConvergenceError):
        run_steady(system, {"guess": {"x": 0.0}, "max_iter": 30}, {})


def test_nan_in_a_kernel_names_the_kernel():
    model = _exp_model()
    system, _ = compile_model(model, specialize(model, {}), backend="c")
    with pytest.raises(KernelError, match="outputs"):
        system.outputs(np.array([-1.0]))
