"""The compiled DOP853 loop for smooth lumped models and ``method = "auto"`` (issue 25, item 3;
mechgen.analyses.simulate_flow, mechgen.runtime.integration.smooth_c).

References: scipy's DOP853 (the compiled loop takes its steps: same coefficients, error norm and step control,
so the two agree to rounding, and take the same number of steps), the hand-derived equations of a forced,
damped Duffing oscillator integrated by scipy at rtol 1e-12, and the stiffness rule's own definition on a
system whose rates are known in closed form (eigenvalues of a two-rate linear system).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si

import mechgen
from mechgen.analyses import simulate_flow
from mechgen.runtime.integration.smooth_c import smooth_loop_problem

MODELS = Path(__file__).resolve().parent / "models"  # forced_duffing.py: the forced, damped Duffing oscillator

TWO_RATES = '''\
"""Two decoupled damped coordinates: x'' + c1 x' + k1 x = 0, y'' + c2 y' + k2 y = 0."""
from mechgen import Model, Param

model = Model("user_two_rates", doc=__doc__)
model.params(Param("c1", 1.0), Param("k1", 1.0), Param("c2", 1.0), Param("k2", 1.0))
model.coordinates("x", "y")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2 + v.y**2 / 2


@model.potential
def potential(q, p):
    return p.k1 * q.x**2 / 2 + p.k2 * q.y**2 / 2


@model.dissipation
def dissipation(v, p):
    return p.c1 * v.x**2 / 2 + p.c2 * v.y**2 / 2
'''


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("compiled_flow_models")
    (path / "two_rates.py").write_text(TWO_RATES)
    return path


@pytest.fixture(scope="module")
def duffing(folder):
    system = mechgen.compile(str(MODELS / "forced_duffing.py"))
    if smooth_loop_problem(system) is not None:
        pytest.skip(f"no compiled loop here: {smooth_loop_problem(system)}")
    return system


def duffing_rhs(t, x, m=1.0, c=0.05, k=1.0, k3=0.5, F=0.3, w=1.2):
    return [x[1], (F * math.cos(w * t) - c * x[1] - k * x[0] - k3 * x[0] ** 3) / m]


def test_compiled_loop_is_scipys_dop853_step_for_step(duffing):
    """Same samples to rounding (1e-10 absolute on |x| ~ 1 after 200 s) as scipy's DOP853 stepped in Python."""
    options = dict(t_end=200.0, q0={"x": 0.5}, method="DOP853", rtol=1e-10, atol=1e-12, samples=401)
    c = mechgen.simulate(duffing, **options)
    py = mechgen.simulate(duffing, loop="python", **options)
    assert (c["loop"], py["loop"]) == ("c", "python") and c["method"] == py["method"] == "DOP853"
    np.testing.assert_allclose(c["trajectory"]["x"], py["trajectory"]["x"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(c["trajectory"]["x_dot"], py["trajectory"]["x_dot"], rtol=0, atol=1e-10)


def test_compiled_loop_against_the_hand_derived_duffing(duffing):
    """The forced, damped Duffing oscillator over 50 s at rtol 1e-11 against scipy on its own equation at 1e-13:
    the difference is the integrators' errors, well below 1e-7."""
    r = mechgen.simulate(duffing, t_end=50.0, q0={"x": 0.5}, rtol=1e-11, atol=1e-13, samples=101)
    assert r["method"] == "DOP853" and r["loop"] == "c"  # auto: the damping rate 0.025/s is not stiff
    ref = si.solve_ivp(duffing_rhs, (0, 50.0), [0.5, 0.0], method="DOP853", rtol=1e-13, atol=1e-14,
                       t_eval=r["t"])
    np.testing.assert_allclose(r["trajectory"]["x"], ref.y[0], rtol=0, atol=1e-7)


@pytest.mark.parametrize("c2, k2, expected", [(1.0, 1.0, "DOP853"), (1e6, 1e4, "Radau")])
def test_auto_picks_radau_for_a_fast_decaying_rate(folder, c2, k2, expected):
    """y'' + c2 y' + k2 y = 0 decays at rates (c2 -+ sqrt(c2^2 - 4 k2))/2: with c2 = 1e6, k2 = 1e4 the fast one is
    ~1e6/s, so over t_end = 1 an explicit method needs ~1e6/12 > STIFF_STEPS steps: auto is Radau; with unit
    coefficients DOP853. Both give the closed form x(t) = e^{-t/2}(cos(wd t) + sin(wd t)/(2 wd)) for the slow one."""
    system = mechgen.compile(str(folder / "two_rates.py"), {"c2": c2, "k2": k2})
    r = mechgen.simulate(system, t_end=1.0, q0={"x": 1.0, "y": 1.0}, rtol=1e-10, atol=1e-12)
    assert r["method"] == expected
    wd = math.sqrt(3) / 2
    t = r["t"]
    np.testing.assert_allclose(r["trajectory"]["x"], np.exp(-t / 2) * (np.cos(wd * t) + np.sin(wd * t) / (2 * wd)),
                               rtol=0, atol=1e-8)


def test_auto_runs_cvodes_for_a_stiff_model_on_the_casadi_backend(folder):
    """The stiff case above on the CasADi backend: auto picks SUNDIALS' compiled BDF (cvodes) over scipy's Radau
    stepped in Python; the slow coordinate against the same closed form (1e-7: CVODES at rtol 1e-10)."""
    system = mechgen.compile(str(folder / "two_rates.py"), {"c2": 1e6, "k2": 1e4}, backend="casadi")
    r = mechgen.simulate(system, t_end=1.0, q0={"x": 1.0, "y": 1.0}, rtol=1e-10, atol=1e-12)
    assert r["method"] == "cvodes"
    wd = math.sqrt(3) / 2
    t = r["t"]
    np.testing.assert_allclose(r["trajectory"]["x"], np.exp(-t / 2) * (np.cos(wd * t) + np.sin(wd * t) / (2 * wd)),
                               rtol=0, atol=1e-7)


def test_stiffness_rule_counts_decay_not_oscillation(folder):
    """A fast undamped oscillation (k2 = 1e10: |lambda| = 1e5, Re lambda = 0) is not stiff: DOP853."""
    system = mechgen.compile(str(folder / "two_rates.py"), {"c2": 0.0, "k2": 1e10})
    x0 = np.array([1.0, 1.0, 0.0, 0.0])
    assert simulate_flow.chosen_method(system, x0, 1.0) == "DOP853"


def test_loop_c_refused_where_it_cannot_run(folder):
    """loop = "c" on the numpy backend: exit-2 error at the key, naming why."""
    system = mechgen.compile(str(MODELS / "forced_duffing.py"), backend="numpy")
    with pytest.raises(mechgen.InputError, match="loop"):
        mechgen.simulate(system, t_end=1.0, method="DOP853", loop="c")
    r = mechgen.simulate(system, t_end=1.0, q0={"x": 0.5})
    assert r["loop"] == "python"


def test_a_parameter_change_reaches_the_compiled_loop(duffing):
    """No hidden state: with_params copies share the loop's kernel tables but each run reads its own system's
    parameters (a sweep over F gave the first point's answer at every point when the view was memoised)."""
    grid = [0.0, 0.3, 1.0]
    swept = mechgen.sweep(duffing, "simulate", grid={"F": grid}, t_end=10.0, q0={"x": 0.5}, samples=11)
    for F, x_end in zip(grid, swept["energy"]):
        c = mechgen.simulate(duffing.with_params(F=F), t_end=10.0, q0={"x": 0.5}, samples=11)
        py = mechgen.simulate(duffing.with_params(F=F), t_end=10.0, q0={"x": 0.5}, samples=11, loop="python")
        assert c["loop"] == "c" and py["loop"] == "python"
        assert c["trajectory"]["x"][-1] == pytest.approx(py["trajectory"]["x"][-1], abs=1e-9)
        assert x_end == pytest.approx(c["energy"], rel=1e-12)
    assert len(set(np.round(swept["energy"], 6))) == 3


def test_a_python_sweep_on_processes_needs_no_pickling(duffing):
    """sweep(system, workers=2) from Python: the forked workers inherit the tasks (a compiled system does not
    pickle; this was a TypeError traceback) and give the serial numbers bit for bit."""
    grid = {"w": [0.8, 1.0, 1.2, 1.4]}
    serial = mechgen.sweep(duffing, "simulate", grid=grid, t_end=5.0, q0={"x": 0.5}, samples=2)
    pooled = mechgen.sweep(duffing, "simulate", grid=grid, t_end=5.0, q0={"x": 0.5}, samples=2, workers=2)
    assert pooled["executor"] == "processes" and pooled["failed"] == 0
    np.testing.assert_array_equal(pooled["energy"], serial["energy"])


def test_the_loop_built_for_the_state_size_is_the_generic_loop(duffing, monkeypatch):
    """The loop library built for one state size (its loops unrolled by the compiler) takes the same steps as
    the generic library and gives the same samples, bit for bit: only the loop bounds are constants."""
    from mechgen.runtime.integration import events_c

    options = dict(t_end=60.0, q0={"x": 0.5}, method="DOP853", rtol=1e-9, atol=1e-12, samples=121)
    sized = mechgen.simulate(duffing, **options)
    monkeypatch.setattr(events_c, "SPECIALISE_MAX_STATES", 0)
    generic = mechgen.simulate(duffing, **options)
    assert sized["loop"] == generic["loop"] == "c"
    for key in ("x", "x_dot"):
        np.testing.assert_array_equal(sized["trajectory"][key], generic["trajectory"][key])


def test_repeated_runs_equal_fresh_runs_bit_for_bit_in_any_order(duffing):
    """RepeatedRuns (the loop set up once, for shooting's many short runs) gives exactly the states a fresh
    run of the loop gives, whatever ran before it (another start, another sample count, a run that failed and
    was handed back), against scipy's DOP853 at rtol 1e-12 for the values themselves."""
    from mechgen.runtime.integration.events_c import RepeatedRuns
    from mechgen.runtime.integration.run_options import RunOptions
    from mechgen.runtime.integration.smooth_c import integrate_smooth_c, view_of

    def fresh(x0, times):
        options = RunOptions(method="DOP853", rtol=1e-10, atol=1e-13, t_eval=times, loop="c")
        return integrate_smooth_c(duffing, x0, float(times[-1]), options)[1]

    runs = RepeatedRuns(view_of(duffing), 1e-10, 1e-13, 10**6)
    starts = [np.array([0.5, 0.0]), np.array([-1.2, 0.7]), np.array([2.0, -3.0])]
    grids = [np.array([0.0, 5.0]), np.linspace(0.0, 7.0, 41)]
    first = {(i, j): runs(x0, t) for i, x0 in enumerate(starts) for j, t in enumerate(grids)}
    assert runs(starts[0], grids[0]) is not None
    assert RepeatedRuns(view_of(duffing), 1e-10, 1e-13, 5)(starts[0], grids[0]) is None  # over its step budget
    for (i, j), X in reversed(list(first.items())):
        again = runs(starts[i], grids[j])
        assert np.array_equal(again, X) and np.array_equal(X, fresh(starts[i], grids[j]))
    ref = si.solve_ivp(duffing_rhs, (0.0, 7.0), starts[1], method="DOP853", rtol=1e-12, atol=1e-14,
                       t_eval=grids[1]).y.T
    assert np.max(np.abs(first[(1, 1)] - ref)) < 1e-8  # rtol 1e-10 over 7 s of a unit-size orbit
