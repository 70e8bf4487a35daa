"""The compiled event loop (mechgen.runtime.integration.events_c) against closed forms and the Python loop.

References:

* Compliant impacts (mechgen/models/viscoelastic_impact.py, Butcher & Segalman 2000): Kelvin-Voigt and
  Maxwell e = exp(-zeta pi / sqrt(1 - zeta^2)) (their eqs. 4, 16); modified Kelvin-Voigt
  e = exp(-(zeta/beta) atan2(2 zeta beta, 2 zeta^2 - 1)), beta = sqrt(1 - zeta^2) (eqs. 10-11); Hunt-Crossley
  ln((1 + a)/(1 - a e)) = a (1 + e), a = alpha v_in = 3 pi zeta / 2; the standard linear solid's contact
  phase is the linear system s' = A s, s = (x, v, y): x'' = -k1 (x - y), c y' = k1 (x - y) - k2 y (m = 1),
  so its release (F = k1 (x - y) falling through 0) is found on expm(A t) s0.
* Ogive penetration (mechgen/models/ogive_penetration.py, Forrestal et al. 1994): the depth
  P = m / (2 pi a^2 rho N) ln(1 + N rho V1^2 / R) + 4a, V1^2 = (m Vs^2 - 4 pi a^3 R) / (m + 4 pi a^3 N rho).
* Bouncing ball (drop from h at rest, y'' = -g, v -> -cor v at y = 0): the first impact at t1 = sqrt(2h/g)
  with speed u = g t1, then t_k = t1 + (2u/g) (cor + ... + cor^(k-1)), accumulating at
  T = t1 + 2 u cor / (g (1 - cor)).
* A guard oscillating faster than the motion: x = x0 - u t (no force), g = x - A sin(w t) falling: its first
  zero, found by scanning g(t) on a grid finer than the oscillation and refining with brentq.
"""
from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen.errors import InputError
from mechgen.runtime.integration import events_c
from mechgen.runtime.core.budget import Budget, BudgetExceeded
from mechgen.runtime.integration.events import EventRules, integrate_hybrid
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

KERNELS = ["residual", "tangent", "outputs", "rates", "rates_tangent"]


def _impact_system(law: str, backend: str = "c"):
    from mechgen.models.viscoelastic_impact import model

    return mechgen.compile(model, {"law": law}, free=["zeta"], kernels=KERNELS, backend=backend)


def _restitution(traj) -> float:
    leave = next(e for e in traj.events if e.source == 1)
    return -leave.x_before[1]


def _e_kelvin_voigt(z):
    return math.exp(-z * math.pi / math.sqrt(1 - z * z))


def _e_modified(z):
    b = math.sqrt(1 - z * z)
    return math.exp(-(z / b) * math.atan2(2 * z * b, 2 * z * z - 1))


def _e_hunt_crossley(z):
    from scipy.optimize import brentq

    a = 1.5 * math.pi * z
    return brentq(lambda e: math.log((1 + a) / (1 - a * e)) - a * (1 + e), 1e-14, min(1, 1 / a) * (1 - 1e-15),
                  xtol=1e-15)


def _e_standard_linear(z, eps=0.1):
    from scipy.linalg import expm
    from scipy.optimize import brentq

    k1, k2, c = 1 / eps, 1 / (1 - eps), 2 * z / (1 - eps)
    A = np.array([[0, 1, 0], [-k1, 0, k1], [k1 / c, 0, -(k1 + k2) / c]])
    s0 = np.array([0.0, 1.0, 0.0])
    force = lambda t: k1 * ((expm(A * t) @ s0)[0] - (expm(A * t) @ s0)[2])  # noqa: E731
    grid = np.linspace(1e-6, 10, 2001)
    i = next(i for i in range(len(grid) - 1) if force(grid[i]) > 0 >= force(grid[i + 1]))
    t_r = brentq(force, grid[i], grid[i + 1], xtol=1e-15)
    return -(expm(A * t_r) @ s0)[1]


REFERENCE = {"kelvin_voigt": _e_kelvin_voigt, "modified_kelvin_voigt": _e_modified, "maxwell": _e_kelvin_voigt,
             "standard_linear": _e_standard_linear, "hunt_crossley": _e_hunt_crossley}


@pytest.mark.parametrize("law", list(REFERENCE))
def test_five_impact_laws_match_the_closed_forms_and_the_python_loop(law):
    system = _impact_system(law).with_params(zeta=0.3)
    x0 = np.array([0.0, 1.0, 0.0])
    run = dict(method="DOP853", rtol=1e-11, atol=1e-13)
    c = integrate_hybrid(system, x0, 20.0, loop="c", **run)
    py = integrate_hybrid(system, x0, 20.0, loop="python", **run)
    assert c.extra.get("loop") == "c" and py.extra.get("loop") != "c"
    assert [(e.source, e.target, e.guard) for e in c.events] == [(e.source, e.target, e.guard) for e in py.events]
    assert [(e.source, e.target, e.guard) for e in c.events] == [(0, 1, "touch"), (1, 0, "release")]
    np.testing.assert_allclose([e.t for e in c.events], [e.t for e in py.events], rtol=1e-9, atol=1e-12)
    e_c, e_py, e_ref = _restitution(c), _restitution(py), REFERENCE[law](0.3)
    assert abs(e_c - e_py) <= 1e-9 * e_ref
    assert abs(e_c - e_ref) <= 1e-9 * e_ref
    assert c.t_final == 20.0 and not c.terminated
    np.testing.assert_allclose(c.x_final, py.x_final, rtol=1e-9, atol=1e-12)


def test_samples_at_t_eval_match_the_python_loop_and_the_flight_line():
    """After release the mass flies at its release speed: x(t) = v_r (t - t_r) (no force in flight)."""
    system = _impact_system("kelvin_voigt").with_params(zeta=0.1)
    times = np.linspace(0.0, 6.0, 61)
    run = dict(method="DOP853", rtol=1e-11, atol=1e-13, t_eval=times)
    c = integrate_hybrid(system, np.array([0.0, 1.0, 0.0]), 6.0, loop="c", **run)
    py = integrate_hybrid(system, np.array([0.0, 1.0, 0.0]), 6.0, loop="python", **run)
    np.testing.assert_array_equal(c.t, times)
    np.testing.assert_array_equal(c.mode, py.mode)
    np.testing.assert_allclose(c.x, py.x, rtol=0, atol=1e-10)
    leave = c.events[1]
    after = times > leave.t
    v_r = leave.x_after[1]
    np.testing.assert_allclose(c.x[after, 0], v_r * (times[after] - leave.t), rtol=0, atol=1e-10)


def test_stop_after_ends_the_run_at_release_as_the_impact_analysis_does():
    system = _impact_system("modified_kelvin_voigt").with_params(zeta=0.3)
    seen = []

    def left_contact(event):
        seen.append(event.guard)
        return event.source == 1

    traj = integrate_hybrid(system, np.array([0.0, 1.0, 0.0]), 60.0, method="DOP853", rtol=1e-11, atol=1e-13,
                            stop_after=left_contact, loop="c")
    assert seen == ["touch", "release"]
    assert traj.terminated and traj.final_mode == 0 and traj.t_final == traj.events[-1].t < 60.0
    assert abs(_restitution(traj) - _e_modified(0.3)) <= 1e-9


@pytest.mark.parametrize("loop", ["c", "python"])
def test_impact_analysis_takes_the_loop_key(loop):
    system = _impact_system("hunt_crossley").with_params(zeta=0.3)
    out = mechgen.impact(system, t_end=60.0, v0={"x": 1.0}, rtol=1e-11, atol=1e-13, loop=loop).outputs
    assert abs(out["restitution"] - _e_hunt_crossley(0.3)) <= 1e-9


def _penetration_depth(m, a, psi, rho, R, Vs):
    N = (8 * psi - 1) / (24 * psi**2)
    v1 = (m * Vs**2 - 4 * math.pi * a**3 * R) / (m + 4 * math.pi * a**3 * N * rho)
    if v1 <= 0:
        return Vs * math.sqrt(m / (math.pi * a * R / 4))
    return m / (2 * math.pi * a**2 * rho * N) * math.log(1 + N * rho * v1 / R) + 4 * a


@pytest.mark.parametrize("speed", [50.0, 400.0, 1900.0])
def test_ogive_penetration_depth_matches_the_closed_form(speed):
    from mechgen.models.ogive_penetration import model

    system = mechgen.compile(model, {}, free=["Vs"], kernels=KERNELS).with_params(Vs=speed)
    traj = integrate_hybrid(system, np.array([0.0, speed]), 1.0, method="DOP853", rtol=1e-12, atol=1e-14, loop="c")
    depth = _penetration_depth(0.931, 0.0127, 3.0, 2300.0, 693e6, speed)
    assert traj.terminated and traj.events[-1].guard == "at_rest"
    assert [e.guard for e in traj.events] == (["at_rest"] if speed == 50.0 else ["tunnel_entry", "at_rest"])
    assert abs(traj.x_final[0] - depth) <= 1e-10 * depth


def ball_model() -> Model:
    """A ball dropped on a floor: one mode, the guard y falling with the reset v -> -cor v."""
    model = Model("bouncing_ball", doc="a ball on a floor with a coefficient of restitution")
    model.params(Param("g", 9.81, "m/s^2"), Param("cor", 0.5, ""))
    model.coordinates("y")
    flight = model.mode("flight", initial=True)

    @model.kinetic
    def kinetic(v):
        return v.y**2 / 2

    @model.potential
    def gravity(q, p):
        return p.g * q.y

    @flight.guard(to="flight", direction="falling", reset=lambda v, p: {"y_dot": -p.cor * v.y})
    def floor(q):
        return q.y

    return model


@pytest.fixture(scope="module")
def ball():
    return mechgen.compile(ball_model(), {}, free=["cor"], kernels=["residual", "tangent", "outputs"])


def test_bouncing_ball_event_times_match_the_closed_form(ball):
    h, g, cor = 1.0, 9.81, 0.5
    t1 = math.sqrt(2 * h / g)
    u = g * t1
    expected = [t1 + (2 * u / g) * sum(cor**j for j in range(1, k)) for k in range(1, 9)]
    run = dict(method="DOP853", rtol=1e-11, atol=1e-13)
    t_end = expected[-1] + 1e-3
    c = integrate_hybrid(ball, np.array([h, 0.0]), t_end, loop="c", **run)
    py = integrate_hybrid(ball, np.array([h, 0.0]), t_end, loop="python", **run)
    assert [e.guard for e in c.events] == ["floor"] * 8
    np.testing.assert_allclose([e.t for e in c.events], expected, rtol=1e-9)
    np.testing.assert_allclose([e.t for e in c.events], [e.t for e in py.events], rtol=1e-10)
    np.testing.assert_allclose([e.x_after[1] for e in c.events], [u * cor**k for k in range(1, 9)], rtol=1e-9)


@pytest.mark.parametrize("loop", ["c", "python"])
def test_bouncing_ball_past_its_accumulation_time_is_a_zeno_budget_error(ball, loop):
    h, g, cor = 1.0, 9.81, 0.5
    t1 = math.sqrt(2 * h / g)
    accumulation = t1 + 2 * g * t1 * cor / (g * (1 - cor))
    with pytest.raises(BudgetExceeded) as info:
        integrate_hybrid(ball, np.array([h, 0.0]), 2 * accumulation, method="DOP853", rtol=1e-10, atol=1e-13,
                         rules=EventRules(zeno_events=10), loop=loop)
    err = info.value
    assert err.key == "zeno_events" and "mode flight" in str(err) and "guard floor" in str(err)
    t_reached = float(err.reached.split()[2])
    assert abs(t_reached - accumulation) < 1e-6


def test_max_events_and_step_budgets_end_the_run_with_the_python_loops_messages(ball):
    run = dict(method="DOP853", rtol=1e-10, atol=1e-13)
    messages = {}
    for loop in ("c", "python"):
        with pytest.raises(BudgetExceeded) as info:
            integrate_hybrid(ball, np.array([1.0, 0.0]), 1.3, rules=EventRules(max_events=3), loop=loop, **run)
        messages[loop] = (info.value.key, info.value.message, info.value.reached.split(" of ")[1])
        with pytest.raises(BudgetExceeded) as info:
            integrate_hybrid(ball, np.array([1.0, 0.0]), 1.3, budget=Budget("DOP853 steps", limit=5, key="max_steps"),
                             loop=loop, **run)
        assert info.value.key == "max_steps" and "stopped after 5 steps" in info.value.message
    assert messages["c"] == messages["python"]
    assert messages["c"][0] == "max_events"


def wall_model() -> Model:
    """A mass coasting at constant speed towards a guard that oscillates fast: g = x - A sin(w t)."""
    model = Model("oscillating_guard", doc="a coasting mass and a fast oscillating surface")
    model.params(Param("A", 0.1, "m"), Param("w", 200.0, "rad/s"))
    model.coordinates("x")
    free = model.mode("free", initial=True)

    @model.kinetic
    def kinetic(v):
        return v.x**2 / 2

    @free.terminal(direction="falling")
    def touch(q, p, t):
        return q.x - p.A * sp.sin(p.w * t)

    return model


@pytest.mark.parametrize("u, w", [(0.5, 50.0), (2.0, 200.0)])
def test_a_fast_oscillating_guard_is_found_at_its_first_zero(u, w):
    """The coasting mass's steps grow tenfold each (no force: the error estimate is 0) to many of the guard's
    periods 2 pi / w: the rate-based splitting finds the first zero inside such a step."""
    from scipy.optimize import brentq

    system = mechgen.compile(wall_model(), {}, free=["w"], kernels=["residual", "tangent", "outputs"])
    system = system.with_params(w=w)
    x0, A = 1.0, 0.1
    g = lambda t: x0 - u * t - A * np.sin(w * t)  # noqa: E731
    grid = np.arange(0.0, 3.0, 1e-5)
    values = g(grid)
    i = int(np.flatnonzero((values[:-1] > 0) & (values[1:] <= 0))[0])
    t_ref = brentq(g, grid[i], grid[i + 1], xtol=1e-15)
    run = dict(method="DOP853", rtol=1e-10, atol=1e-12)
    c = integrate_hybrid(system, np.array([x0, -u]), 10.0, loop="c", **run)
    py = integrate_hybrid(system, np.array([x0, -u]), 10.0, loop="python", **run)
    assert c.terminated and [e.guard for e in c.events] == ["touch"]
    assert c.t[-1] - c.t[-3] > 5 * 2 * math.pi / w  # the step with the event spans several periods of g
    assert abs(c.t_final - t_ref) < 1e-9
    assert abs(c.t_final - py.t_final) < 1e-12


def test_the_c_loop_runs_scipys_dop853_coefficients():
    from scipy.integrate._ivp import dop853_coefficients as ref

    lib = events_c.loop_library()
    for name, value in (("mgh_C", ref.C), ("mgh_A", ref.A), ("mgh_B", ref.B), ("mgh_E3", ref.E3),
                        ("mgh_E5", ref.E5), ("mgh_D", ref.D)):
        flat = np.asarray(value, float).ravel()
        got = np.ctypeslib.as_array((ctypes.c_double * flat.size).in_dll(lib, name))
        np.testing.assert_array_equal(got, flat, err_msg=name)


def test_numpy_backend_runs_the_python_loop_and_loop_c_is_refused():
    system = _impact_system("kelvin_voigt", backend="numpy").with_params(zeta=0.3)
    x0 = np.array([0.0, 1.0, 0.0])
    traj = integrate_hybrid(system, x0, 20.0, method="DOP853", rtol=1e-11, atol=1e-13)
    assert traj.extra.get("loop") != "c"
    assert abs(_restitution(traj) - _e_kelvin_voigt(0.3)) <= 1e-9
    with pytest.raises(InputError) as info:
        integrate_hybrid(system, x0, 20.0, method="DOP853", loop="c")
    assert info.value.key == "loop" and "numpy" in str(info.value)
    c_system = _impact_system("kelvin_voigt").with_params(zeta=0.3)
    with pytest.raises(InputError, match="DOP853 only"):
        integrate_hybrid(c_system, x0, 20.0, method="Radau", loop="c")


def test_without_a_compiler_the_loop_falls_back_to_python(monkeypatch, tmp_path):
    from mechgen.codegen import build

    system = _impact_system("kelvin_voigt").with_params(zeta=0.3)  # built while the compiler works
    x0 = np.array([0.0, 1.0, 0.0])
    monkeypatch.setenv("CC", "/nonexistent/cc")
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path))  # an empty cache: the loop library is not there built
    build.reset_compiler_cache()
    events_c.forget_library()
    try:
        assert "cannot be built" in events_c.c_loop_problem(system)
        traj = integrate_hybrid(system, x0, 20.0, method="DOP853", rtol=1e-11, atol=1e-13)
        assert traj.extra.get("loop") != "c"
        assert abs(_restitution(traj) - _e_kelvin_voigt(0.3)) <= 1e-9
        with pytest.raises(InputError, match="cannot be built"):
            integrate_hybrid(system, x0, 20.0, method="DOP853", loop="c")
    finally:
        monkeypatch.undo()
        build.reset_compiler_cache()
        events_c.forget_library()
    assert events_c.c_loop_problem(system) is None



def test_simulate_takes_the_loop_key():
    """The Kelvin-Voigt contact lasts half a damped period: release at pi / (omega_n sqrt(1 - zeta^2))."""
    from mechgen.errors import MechgenError
    from mechgen.models.spring_pendulum import model as pendulum

    zeta = 0.3
    system = _impact_system("kelvin_voigt").with_params(zeta=zeta)
    outs = {loop: mechgen.simulate(system, t_end=5.0, v0={"x": 1.0}, method="DOP853", rtol=1e-11, atol=1e-13,
                                   loop=loop).outputs for loop in ("c", "python")}
    for out in outs.values():
        assert [(e["from"], e["to"], e["guard"]) for e in out["events"]] == [("flight", "contact", "touch"),
                                                                            ("contact", "flight", "release")]
        assert abs(out["events"][1]["t"] - math.pi / math.sqrt(1 - zeta**2)) < 1e-9
    with pytest.raises(MechgenError, match="loop"):
        mechgen.simulate(system, t_end=1.0, v0={"x": 1.0}, loop="fortran")
    # a smooth model takes the key too (its compiled loop: mechgen.runtime.integration.smooth_c), refused where it cannot run
    smooth = mechgen.compile(pendulum, {}, kernels=["residual", "tangent", "outputs"], backend="numpy")
    with pytest.raises(MechgenError, match="loop 'c' cannot run here"):
        mechgen.simulate(smooth, t_end=1.0, q0={"r": 1.0}, loop="c", method="DOP853")


def test_resuming_at_clean_points_changes_nothing(ball, monkeypatch):
    """Buffers grown from one row, a slice of one step and a pause after every event give the very numbers
    of one uninterrupted call (the C loop resumes exactly where it stopped)."""
    run = dict(method="DOP853", rtol=1e-11, atol=1e-13)
    whole = integrate_hybrid(ball, np.array([1.0, 0.0]), 1.3, loop="c", **run)
    monkeypatch.setattr(events_c, "SLICE", 1)
    monkeypatch.setattr(events_c, "FIRST_ROWS", (1, 1))
    pieces = integrate_hybrid(ball, np.array([1.0, 0.0]), 1.3, loop="c", stop_after=lambda e: False,
                              budget=Budget("DOP853 steps", limit=10_000, key="max_steps"), **run)
    assert len(whole.t) > 20 and len(whole.events) >= 5
    np.testing.assert_array_equal(pieces.t, whole.t)
    np.testing.assert_array_equal(pieces.x, whole.x)
    np.testing.assert_array_equal(pieces.mode, whole.mode)
    assert [(e.t, e.guard) for e in pieces.events] == [(e.t, e.guard) for e in whole.events]
    np.testing.assert_array_equal(pieces.x_final, whole.x_final)


def test_a_force_giving_nan_is_a_kernel_error_in_both_loops():
    """y'' = sqrt(y) - 1 from y = 1 moving down: y < 0 (sqrt of a negative: NaN) is reached before t = 3."""
    from mechgen.errors import KernelError

    model = Model("sqrt_spring", doc="a force defined for y >= 0 only")
    model.coordinates("y")

    @model.kinetic
    def kinetic(v):
        return v.y**2 / 2

    @model.forces
    def force(q):
        return {"y": sp.sqrt(q.y) - 1}

    free = model.mode("free", initial=True)

    @free.terminal(direction="rising")
    def far(q):
        return q.y - 10

    system = mechgen.compile(model, {}, kernels=["residual", "tangent", "outputs"])
    for loop in ("c", "python"):
        # the state named is one where the force is NaN: y < 0 (the C loop checks a step's 13 stages at once,
        # through their error norm, and rebuilds the failing stage's state)
        with pytest.raises(KernelError, match=r"NaN/Inf at t = 0\.48\d*, x = \[-"):
            integrate_hybrid(system, np.array([1.0, -2.0]), 3.0, method="DOP853", loop=loop)
