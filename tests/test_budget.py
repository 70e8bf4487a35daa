"""Work budgets (issue 12, section 5): every loop a user's numbers make long ends with exit 1 naming the analysis,
how far it got and the key to raise; estimates refuse hopeless runs up front; progress bars only on terminals.

The budgets are shown with small limits in the scene (each test runs in seconds); one test shows that the
default limit refuses a leapfrog of 2e9 steps before its first step.
"""
import io
import math
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError
from mechgen.runtime.core.budget import Budget, BudgetExceeded, Progress
from mechgen.runtime.core.integrate import integrate_first_order, leapfrog

ROOT = Path(__file__).resolve().parents[1]

PENDULUM = """model = "spring_pendulum"
backend = "c"
[params]
m = 1.0
k = 40.0
l0 = 1.0
g = 9.81
[[analysis]]
name = "swing"
kind = "simulate"
"""


def _run(tmp_path, text, capsys, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    code = main(["run", str(path)])
    return code, capsys.readouterr().err, str(path)


# --------------------------------------------------------------------------- the Budget itself

class Clock:
    """A clock the test moves by hand."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_budget_counts_units_then_names_the_key_and_how_far():
    budget = Budget("RK45 steps", limit=3, key="max_steps", clock=Clock())
    for _ in range(3):
        budget.spend(1, "t = 1")
    with pytest.raises(BudgetExceeded) as err:
        budget.spend(1, lambda: "t = 2 of t_end = 9")
    assert err.value.key == "max_steps" and "stopped after 3 steps" in str(err.value)
    assert "reached t = 2 of t_end = 9" in str(err.value) and "raise 'max_steps'" in str(err.value)


def test_budget_wall_time_and_projection_from_the_first_units():
    clock = Clock()
    budget = Budget("sweep of modes", unit="points", seconds=10.0, clock=clock)
    clock.now = 1.0
    budget.project(10, 1000)  # the baseline: 10 points in 1 s
    clock.now = 2.0
    budget.project(500, 1000)  # 1 + 1 s x 990 / 490 = 3.0 s for all: within the budget
    with pytest.raises(BudgetExceeded) as err:
        budget.project(100, 1000)  # 1 + 1 s x 990 / 90 = 12 s for all at this rate: more than 10
    assert "1,000 points would take about 12 s" in str(err.value) and err.value.key == "max_seconds"
    clock.now = 10.5
    with pytest.raises(BudgetExceeded, match="wall time"):
        budget.check_time()


def test_a_first_unit_that_builds_something_does_not_set_the_rate():
    """The first point of a sweep builds a library (4 s); the next ones take 0.1 s each: 170 of them take about
    4 + 169 x 0.1 = 21 s, within a 60 s budget (the rate of the first alone would say 680 s)."""
    clock = Clock()
    budget = Budget("restitution impacts", unit="points", seconds=60.0, clock=clock)
    clock.now = 4.0
    budget.project(1, 170)
    for done in range(2, 30):
        clock.now = 4.0 + 0.1 * (done - 1)
        budget.project(done, 170)  # never refused
    clock.now = 4.0 + 0.5 * 29
    with pytest.raises(BudgetExceeded, match="would take about 88 s"):
        budget.project(30, 170)  # 4 + 14.5 x 169 / 29 = 88.5 s: the rate after the first is too slow now


def test_an_accepted_long_estimate_is_said_once_on_stderr(capsys):
    clock = Clock()
    budget = Budget("sweep of stability", unit="points", seconds=600.0, clock=clock)
    clock.now = 1.0
    budget.project(10, 1000)  # the baseline
    clock.now = 2.0
    budget.project(100, 1000)  # 1 + 1 x 990 / 90 = 12 s for all: below NOTICE_ABOVE, nothing said
    assert capsys.readouterr().err == ""
    clock.now = 21.0
    budget.project(110, 1000)  # 1 + 20 x 990 / 100 = 199 s for all: accepted (600 s budget) and announced once
    clock.now = 22.0
    budget.project(111, 1000)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1,000 points will take about 3 min (max_seconds = 600)" in err


def test_budget_error_survives_pickling_with_its_fields():
    import pickle

    exc = BudgetExceeded("x", key="max_steps", reached="t = 1", analysis="simulate 's'")
    back = pickle.loads(pickle.dumps(exc))
    assert (back.key, back.reached, back.analysis, str(back)) == (exc.key, exc.reached, exc.analysis, str(exc))


def test_progress_bar_only_on_a_terminal(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr("sys.stderr", io.StringIO())
    with Progress(10, desc="quiet", delay=0.0) as bar:
        assert not bar.shown
    term = Terminal()
    monkeypatch.setattr("sys.stderr", term)
    with Progress(10, desc="shown", delay=0.0, unit="point") as bar:
        bar.update(5)
    assert "shown:" in term.getvalue() and "/10 [00:00<" in term.getvalue()  # count, elapsed<remaining
    with Progress(10, desc="off", enabled=False) as bar:
        assert not bar.shown


# --------------------------------------------------------------------------- integrators

def test_stepping_scipy_solvers_here_gives_solve_ivps_numbers():
    """x'' = -x from (1, 0): the loop that counts steps takes solve_ivp's steps (identical samples) and both
    match cos t."""
    from scipy.integrate import solve_ivp

    rhs = lambda t, x: np.array([x[1], -x[0]])  # noqa: E731
    t_eval = np.linspace(0.0, 10.0, 11)
    for method in ("RK45", "DOP853", "BDF", "Radau", "LSODA"):
        jac = (lambda t, x: np.array([[0.0, 1.0], [-1.0, 0.0]])) if method in ("BDF", "Radau", "LSODA") else None
        ours = integrate_first_order(rhs, [1.0, 0.0], 10.0, jac=jac, method=method, rtol=1e-10, atol=1e-12,
                                     t_eval=t_eval, budget=Budget("steps", limit=100_000, key="max_steps"))
        kwargs = {"jac": jac} if jac is not None else {}
        ref = solve_ivp(rhs, (0.0, 10.0), [1.0, 0.0], method=method, rtol=1e-10, atol=1e-12, t_eval=t_eval, **kwargs)
        assert np.array_equal(ours.t, ref.t)
        assert np.max(np.abs(ours.x - ref.y.T)) <= 1e-14
        assert np.max(np.abs(ours.x[:, 0] - np.cos(t_eval))) < 1e-6


def test_integrator_step_budget_names_t_reached():
    rhs = lambda t, x: np.array([x[1], -x[0]])  # noqa: E731
    with pytest.raises(BudgetExceeded) as err:
        integrate_first_order(rhs, [1.0, 0.0], 1000.0, method="RK45", budget=Budget("RK45 steps", limit=20,
                                                                                     key="max_steps"))
    assert "of t_end = 1000 after 21 steps" in err.value.reached


def test_leapfrog_refuses_before_the_first_step():
    calls = []
    with pytest.raises(BudgetExceeded) as err:
        leapfrog(lambda q: calls.append(1) or -q, [1.0], [0.0], 0.1, 2_000_000_000,
                 budget=Budget("leapfrog steps", limit=10_000_000, key="max_steps"))
    assert calls == [] and "needs 2,000,000,000 steps" in str(err.value)


# --------------------------------------------------------------------------- simulate scenes

def test_default_budget_refuses_a_leapfrog_of_2e9_steps_up_front(tmp_path, capsys):
    text = (ROOT / "scenes" / "fpu_chain.toml").read_text().replace("t_end = 2000.0", "t_end = 1e8")
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1
    assert "simulate 'recurrence'" in err and "2,000,000,000 steps" in err and "max_steps = 10,000,000" in err
    assert "refused before starting" in err and "raise 'max_steps'" in err and "Traceback" not in err


def test_leapfrog_wall_time_budget_stops_the_run(tmp_path, capsys):
    text = (ROOT / "scenes" / "fpu_chain.toml").read_text() + "max_seconds = 1e-6\n"
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1 and "simulate 'recurrence'" in err and "max_seconds = 1e-06" in err
    assert "reached t = 51.2 of t_end = 2000 after 1,024 steps" in err  # the first check, after 1024 steps


def test_adaptive_step_budget_from_the_scene(tmp_path, capsys):
    text = PENDULUM + 'method = "DOP853"\nt_end = 20.0\nq0 = { r = 1.4, theta = 0.8 }\nmax_steps = 50\n'
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1, err
    assert "simulate 'swing': DOP853 steps: stopped after 50 steps" in err
    assert "of t_end = 20" in err and "raise 'max_steps'" in err  # where it stopped (the compiled loop's t)


def test_explicit_method_on_a_stiff_spring_is_refused_up_front(tmp_path, capsys):
    """k = 1e10, m = 1: the fastest rate is sqrt(k/m) = 1e5/s; RK45 needs at least t_end * 1e5 / 7 steps."""
    text = PENDULUM.replace("k = 40.0", "k = 1e10") + 'method = "RK45"\nt_end = 20.0\nq0 = { r = 1.4, theta = 0.8 }\n'
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1, err
    assert f"needs at least {20.0 * math.sqrt(1e10) / 7:.3g} steps" in err and "max_steps = 100,000" in err
    assert "simulate 'swing'" in err and "BDF and Radau" in err


def test_implicit_method_on_a_stiff_spring_is_refused_by_its_step_size(tmp_path, capsys):
    text = PENDULUM.replace("k = 40.0", "k = 1e10") + ('method = "Radau"\nt_end = 20.0\n'
                                                         'q0 = { r = 1.4, theta = 0.8 }\nmax_steps = 2000\n')
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1, err
    assert "Radau steps: at the step size of the latest step" in err and "10 x max_steps = 2,000" in err
    assert "after 1,024 steps" in err and "raise 'max_steps'" in err


def test_wall_time_budget_of_an_adaptive_run(tmp_path, capsys):
    """max_steps far out of reach: the step-size projection (from a tenth of max_steps on) does not refuse first,
    whichever loop runs (the compiled Radau loop reaches that tenth of the default within 0.05 s)."""
    text = PENDULUM + 't_end = 1e9\nq0 = { r = 1.4 }\nmax_seconds = 0.05\nmax_steps = 1000000000\n'
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1 and "steps: stopped after" in err and "max_seconds = 0.05" in err
    assert "of t_end = 1e+09" in err


def test_rtol_below_what_the_integrators_honour_is_exit_2_at_the_key(tmp_path, capsys):
    text = PENDULUM + "t_end = 2.0\nrtol = 1e-300\natol = 1e-300\n"
    code, err, path = _run(tmp_path, text, capsys)
    assert code == 2 and path in err and "analysis[1].rtol" in err and "2.22e-14" in err


def test_budget_keys_are_checked_like_every_key(tmp_path, capsys):
    code, err, _ = _run(tmp_path, PENDULUM + "t_end = 2.0\nmax_steps = 0\n", capsys)
    assert code == 2 and "analysis[1].max_steps" in err
    code, err, _ = _run(tmp_path, PENDULUM + "t_end = 2.0\nmax_seconds = -1\n", capsys)
    assert code == 2 and "analysis[1].max_seconds" in err and "> 0" in err
    code, err, _ = _run(tmp_path, PENDULUM + "t_end = 2.0\nsamples = 100000000\n", capsys)
    assert code == 2 and "analysis[1].samples" in err and "1000000" in err and "[limits] samples" in err


# --------------------------------------------------------------------------- non-finite and degenerate states

@pytest.fixture(scope="module")
def pendulum():
    return mechgen.compile("spring_pendulum", {"m": 1.0, "k": 40.0, "l0": 1.0, "g": 9.81}, free=["m", "k"])


def test_singular_mass_matrix_names_the_coordinate(pendulum):
    """At r = 0 the polar mass matrix diag(m, m r^2) has no inertia along theta."""
    with pytest.raises(mechgen.errors.ConvergenceError) as err:
        mechgen.simulate(pendulum, t_end=1.0, q0={"r": 0.0, "theta": 0.8})
    text = str(err.value)
    assert "mass matrix M = dr/da is singular" in text and "coordinate 'theta'" in text and "t = 0" in text


def test_zero_mass_is_named(pendulum):
    """m = 0: refused as input (exit 2 at m) where the parameter's bound is checked, else the singular mass
    matrix named (exit 1), never numpy's LinAlgError."""
    try:
        system = pendulum.with_params(m=0.0)
        mechgen.simulate(system, t_end=1.0, q0={"r": 1.4, "theta": 0.8})
    except InputError as exc:
        assert exc.key is not None and exc.key.endswith("m")
    except mechgen.errors.MechgenError as exc:
        assert "mass matrix M = dr/da is zero" in str(exc) and "'r'" in str(exc)
    else:
        pytest.fail("m = 0 ran")


def test_tiny_mass_names_the_fastest_rate(pendulum):
    system = pendulum.with_params(m=1e-300)
    with pytest.raises(mechgen.errors.MechgenError) as err:
        mechgen.simulate(system, t_end=2.0, q0={"r": 1.4, "theta": 0.8})
    assert not isinstance(err.value, InputError)
    assert "d(r_dot)/dt" in str(err.value) and "1e-300" in str(err.value)


def test_huge_start_names_the_kernel_output_and_inputs(pendulum):
    """q0 = 1e300: m r^2 overflows in the tangent's r_a[theta, theta]."""
    with pytest.raises(mechgen.errors.MechgenError) as err:
        mechgen.simulate(pendulum, t_end=2.0, q0={"r": 1e300, "theta": 0.8})
    text = str(err.value)
    assert "kernel 'tangent' output r_a[1, 1] (row 'theta', column 'theta') = inf" in text
    assert "r: 1e+300" in text and "parameters {m: 1, k: 40}" in text


# --------------------------------------------------------------------------- sweeps

BECK = (ROOT / "scenes" / "beck_column.toml").read_text()


def test_sweep_refused_from_the_estimate_of_its_first_points(tmp_path, capsys):
    """1e6 points at about a millisecond each need many minutes; the estimate refuses them once trusted (after
    2 s), well before the 10 s budget runs out, even where a loaded machine makes the first points far slower (a
    first point over the whole budget could only be stopped by the budget itself: there is no rate yet)."""
    text = BECK.replace("num = 26 } }", "num = 1000000 } }\nmax_seconds = 10")
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1, err
    assert "sweep 'load_sweep': sweep of stability: 1,000,000 points would take about" in err
    assert "more than max_seconds = 10" in err and "of 1,000,000 points" in err and "raise 'max_seconds'" in err


def test_sweep_names_the_inner_analysis_key_and_point(tmp_path, capsys):
    text = PENDULUM.replace('name = "swing"\nkind = "simulate"\n', 'name = "grid"\nkind = "sweep"\n') + (
        'over = { k = [40.0, 50.0] }\n'
        'analysis = { kind = "simulate", method = "DOP853", t_end = 20.0, q0 = { r = 1.4 }, max_steps = 30 }\n')
    code, err, _ = _run(tmp_path, text, capsys)
    assert code == 1, err
    assert "sweep 'grid'" in err and "raise 'analysis.max_steps'" in err and "at sweep point {'k': 40.0}" in err


# --------------------------------------------------------------------------- continuation, Newton, response

def test_continuation_wall_time_names_the_points_and_lam():
    """The circle u^2 + lam^2 = 1 continued for 10^6 points under a clock that advances 1 s per reading."""
    from mechgen.runtime.steady.continuation import ParametricEquations, continuation

    circle = ParametricEquations(lambda u, lam: np.array([u[0] ** 2 + lam ** 2 - 1.0]),
                                 lambda u, lam: np.array([[2 * u[0]]]), lambda u, lam: np.array([2 * lam]))
    clock = Clock()

    def tick():
        clock.now += 1.0
        return clock.now

    budget = Budget("continuation", unit="points", seconds=5.0, clock=tick)
    with pytest.raises(BudgetExceeded) as err:
        continuation(circle, [-1.0], 0.0, ds=0.1, max_points=1_000_000, budget=budget)
    assert "max_seconds = 5" in str(err.value) and "branch points, lam = " in err.value.reached


def test_newton_wall_time_on_a_problem_without_a_root():
    """x^2 + 1 = 0 has no real root: with max_iter = 10^9 only the wall-time budget ends the iteration."""
    from mechgen.runtime.steady.newton import newton

    budget = Budget("steady Newton iterations", seconds=0.2)
    with pytest.raises(BudgetExceeded) as err:
        newton(lambda x: x ** 2 + 1.0, lambda x: np.diag(2 * x), [0.3], max_iter=10 ** 9, budget=budget)
    assert "max_seconds = 0.2" in str(err.value) and "Newton iteration" in err.value.reached


def test_newton_names_the_non_finite_kernel_output(pendulum):
    """steady from r = 1e300: m r^2 overflows in the tangent's r_a[theta, theta] (entry 3 of the 2 x 2)."""
    with pytest.raises(mechgen.errors.KernelError) as err:
        mechgen.steady(pendulum, guess={"r": 1e300, "theta": 0.1})
    assert "kernel tangent produced NaN/Inf in output r_a (entry 3 of 4, row-major, = inf)" in str(err.value)
    assert "'q': [1e+300, 0.1]" in str(err.value)


def test_response_refused_from_the_estimate_of_its_first_frequencies(pendulum):
    """1e6 frequencies at tens of microseconds each need far more than 1 s: refused from the estimate once it
    is trusted (after the 1 s budget's worth, min(2 s, max_seconds)); the first frequency alone stays far below
    the budget even on a loaded machine."""
    with pytest.raises(BudgetExceeded) as err:
        mechgen.analysis("response", pendulum, name="frf", input="r", at={"r": 1.2},
                         omega={"start": 0.1, "stop": 100.0, "num": 1_000_000}, max_seconds=1.0)
    assert str(err.value).startswith("response 'frf': response: 1,000,000 frequencies would take about")
    assert err.value.key == "max_seconds"


def test_campbell_solved_at_every_speed_is_refused_from_its_first_speeds():
    """A Laval tilt rotor (M = I_d, G = I_p Omega J, K = k) whose every speed 'takes' 1 s on a hand-moved clock:
    100 speeds project to 100 s, more than a 10 s budget; with a 1000 s budget the diagram is the closed form
    of the forward whirl, (I_p Omega + sqrt(I_p^2 Omega^2 + 4 I_d k)) / (2 I_d) (Friswell et al. 2010, 3.5)."""
    from mechgen.runtime.linear.campbell import campbell

    Id, Ip, k = 1.0, 0.5, 4.0

    def timed(clock):
        def mats(speed):
            clock.now += 1.0
            G = Ip * speed * np.array([[0.0, 1.0], [-1.0, 0.0]])
            return {"M": Id * np.eye(2), "C": G, "K": k * np.eye(2)}
        return mats

    speeds = np.linspace(0.0, 10.0, 100)
    clock = Clock()
    budget = Budget("campbell over Omega", unit="speeds", seconds=10.0, clock=clock)
    with pytest.raises(BudgetExceeded) as err:
        campbell(timed(clock), speeds, 2, method="exact", budget=budget, x_index=[0], y_index=[1])
    assert "100 speeds would take about" in str(err.value) and err.value.key == "max_seconds"
    assert clock.now < 10.0  # refused from the estimate, before the budget itself ran out
    clock = Clock()
    res = campbell(timed(clock), speeds, 2, method="exact", x_index=[0], y_index=[1],
                   budget=Budget("campbell over Omega", unit="speeds", seconds=1000.0, clock=clock))
    forward = (Ip * speeds + np.sqrt(Ip**2 * speeds**2 + 4 * Id * k)) / (2 * Id)
    assert np.allclose(res.frequencies.max(axis=1), forward, rtol=1e-12)
