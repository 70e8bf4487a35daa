"""simulate's time history (``t``, ``trajectory``), its size rule, its plots, a Zeno stop, the Python face of a
Result and a scene whose later analysis fails (issue 25, items 1, 6 and 7).

References, each independent of mechgen:

* the double pendulum (two point masses m1, m2 on rigid massless rods l1, l2, angles from the downward
  vertical): its equations of motion derived by hand (e.g. Goldstein, Classical Mechanics, ch. 1 problem 1.19 /
  any text), integrated by scipy's DOP853 at rtol 1e-12;
* the leapfrog on a harmonic oscillator x'' = -w^2 x from (x0, 0): its positions are exactly
  x_k = x0 cos(k theta), cos(theta) = 1 - (w dt)^2 / 2 (the three-term recurrence of Stormer-Verlet);
* the bouncing ball's accumulation time T = t1 (1 + e) / (1 - e), t1 = sqrt(2 h / g) (tests/test_hybrid_events.py).
"""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si

import mechgen
from mechgen.analyses import time_series
from mechgen.cli import main
from mechgen.errors import ConvergenceError

ROOT = Path(__file__).resolve().parents[1]

DOUBLE = '''\
"""Double pendulum: point masses m1, m2 on rods l1, l2; angles a, b from the downward vertical."""
import sympy as sp
from mechgen import Model, Param

model = Model("user_double_pendulum", doc=__doc__)
model.params(Param("m1", 1.0, "kg", positive=True), Param("m2", 0.5, "kg", positive=True),
             Param("l1", 1.0, "m", positive=True), Param("l2", 0.7, "m", positive=True),
             Param("g", 9.81, "m/s^2", positive=True))
model.coordinates("a", "b")


@model.kinetic
def kinetic(q, v, p):
    return (p.m1 + p.m2) * p.l1**2 * v.a**2 / 2 + p.m2 * p.l2**2 * v.b**2 / 2 \\
        + p.m2 * p.l1 * p.l2 * v.a * v.b * sp.cos(q.a - q.b)


@model.potential
def potential(q, p):
    return -(p.m1 + p.m2) * p.g * p.l1 * sp.cos(q.a) - p.m2 * p.g * p.l2 * sp.cos(q.b)


model.output("tip_x", lambda q, p: p.l1 * sp.sin(q.a) + p.l2 * sp.sin(q.b), unit="m")
'''

OSCILLATOR = '''\
"""A unit oscillator: T = m x'^2/2, V = k x^2/2."""
from mechgen import Model, Param

model = Model("user_unit_oscillator", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("k", 4.0, "N/m", positive=True))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2
'''

M1, M2, L1, L2, G = 1.0, 0.5, 1.0, 0.7, 9.81


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("time_history_models")
    for name, text in {"double": DOUBLE, "oscillator": OSCILLATOR}.items():
        (path / f"{name}.py").write_text(text)
    return path


@pytest.fixture(scope="module")
def double(folder):
    return mechgen.compile(str(folder / "double.py"))


def double_pendulum_rhs(t, x):
    """The hand-derived equations: M(a, b) [a'', b''] = f, with
    M = [[(m1 + m2) l1^2, m2 l1 l2 c], [m2 l1 l2 c, m2 l2^2]], c = cos(a - b), s = sin(a - b),
    f = [-m2 l1 l2 s b'^2 - (m1 + m2) g l1 sin a,  m2 l1 l2 s a'^2 - m2 g l2 sin b]."""
    a, b, da, db = x
    c, s = math.cos(a - b), math.sin(a - b)
    M = np.array([[(M1 + M2) * L1**2, M2 * L1 * L2 * c], [M2 * L1 * L2 * c, M2 * L2**2]])
    f = np.array([-M2 * L1 * L2 * s * db**2 - (M1 + M2) * G * L1 * math.sin(a),
                  M2 * L1 * L2 * s * da**2 - M2 * G * L2 * math.sin(b)])
    return np.concatenate([[da, db], np.linalg.solve(M, f)])


def test_trajectory_matches_hand_derived_double_pendulum(double):
    """Every sample of every coordinate, velocity and output against scipy on the hand-derived equations:
    both run at tight tolerances over 3 s of a moderate swing (no chaos to amplify the errors), so 1e-7
    bounds the sum of the two integrators' errors (mechgen at rtol 1e-11, the reference at 1e-12)."""
    r = mechgen.simulate(double, t_end=3.0, q0={"a": 0.6, "b": -0.4}, v0={"b": 1.0}, method="DOP853",
                         rtol=1e-11, atol=1e-13, samples=61)
    t = r["t"]
    assert isinstance(t, np.ndarray) and t.shape == (61,)
    assert t[0] == 0.0 and t[-1] == pytest.approx(3.0)
    ref = si.solve_ivp(double_pendulum_rhs, (0, 3.0), [0.6, -0.4, 0.0, 1.0], method="DOP853", rtol=1e-12,
                       atol=1e-14, t_eval=t)
    traj = r["trajectory"]
    assert list(traj)[:4] == ["a", "b", "a_dot", "b_dot"]
    for i, name in enumerate(["a", "b", "a_dot", "b_dot"]):
        np.testing.assert_allclose(traj[name], ref.y[i], atol=1e-7, rtol=0)
    np.testing.assert_allclose(traj["tip_x"], L1 * np.sin(ref.y[0]) + L2 * np.sin(ref.y[1]), atol=1e-7, rtol=0)
    assert r["tip_x"] == pytest.approx(traj["tip_x"][-1], abs=1e-15)  # the end value is the last sample
    assert r["energy_series"].shape == (61,)


def test_energy_drift_is_relative_to_the_energy_scale(double, folder):
    """energy_drift = max|E - E0| / max(|T| + |V|); from rest with nothing stored it is 0, not 1e298."""
    r = mechgen.simulate(double, t_end=2.0, q0={"a": 0.6}, method="DOP853", rtol=1e-10, atol=1e-12)
    traj = r["trajectory"]
    E = traj["energy"]
    scale = np.max(np.abs(traj["kinetic_energy"]) + np.abs(traj["potential_energy"]))
    assert r["energy_drift"] == pytest.approx(np.max(np.abs(E - E[0])) / scale, rel=1e-12)
    assert r["energy_drift"] < 1e-8  # a conservative run at rtol 1e-10
    at_rest = mechgen.simulate(mechgen.compile(str(folder / "oscillator.py")), t_end=1.0)
    assert at_rest["energy_drift"] == 0.0


def test_series_rule(double, monkeypatch):
    """On by default below SERIES_VALUES, off above it with a note; series = true/false decides when given."""
    off = mechgen.simulate(double, t_end=0.5, q0={"a": 0.1}, series=False)
    assert "trajectory" not in off and "t" not in off and "a" not in off.keys()
    monkeypatch.setattr(time_series, "SERIES_VALUES", 100)
    big = mechgen.simulate(double, t_end=0.5, q0={"a": 0.1})
    assert "trajectory" not in big and "series = true" in big["series_note"]
    forced = mechgen.simulate(double, t_end=0.5, q0={"a": 0.1}, series=True)
    assert forced["trajectory"]["a"].shape == (201,)


def test_sweep_points_leave_the_trajectory_out(double):
    """A sweep of simulate collects end values per point; a trajectory per point only when asked."""
    r = mechgen.sweep(double, "simulate", grid={"g": [9.0, 10.0]}, t_end=0.2, q0={"a": 0.1})
    assert "trajectory" not in r and len(r["tip_x"]) == 2
    kept = mechgen.sweep(double, "simulate", grid={"g": [9.0, 10.0]}, t_end=0.2, q0={"a": 0.1}, series=True)
    assert len(kept["trajectory"]) == 2


def test_leapfrog_save_every_is_the_exact_verlet_solution(folder):
    """Stormer-Verlet on x'' = -w^2 x: x_k = x0 cos(k theta), cos theta = 1 - (w dt)^2 / 2, exactly (to
    round-off over 400 steps: 1e-12)."""
    osc = mechgen.compile(str(folder / "oscillator.py"))
    dt, w = 0.05, 2.0
    r = mechgen.simulate(osc, method="leapfrog", dt=dt, t_end=20.0, save_every=10, q0={"x": 1.0})
    t = r["t"]
    np.testing.assert_allclose(t, np.arange(0, 401, 10) * dt, rtol=0, atol=1e-12)
    theta = math.acos(1 - (w * dt) ** 2 / 2)
    np.testing.assert_allclose(r["trajectory"]["x"], np.cos(np.arange(0, 401, 10) * theta), rtol=0, atol=1e-12)


def test_zeno_stop_ends_the_ball_at_its_accumulation_time(folder):
    """on_zeno = "stop": the run ends at the accumulation point T = t1 (1 + e)/(1 - e) with the events so far
    (the events' times converge geometrically to T: the last one within e^k t1-size of it); the default is
    still an error."""
    ball = mechgen.compile(str(ROOT / "tests" / "models" / "bouncing_ball.py"))
    t1 = math.sqrt(2 * 1.0 / 9.81)
    T = t1 * 1.8 / 0.2
    options = dict(t_end=2 * T, q0={"y": 1.0}, method="DOP853", rtol=1e-10, atol=1e-12, zeno_events=20,
                   zeno_span=1e-3, max_events=2000)
    with pytest.raises(mechgen.MechgenError, match="on_zeno"):
        mechgen.simulate(ball, **options)
    r = mechgen.simulate(ball, on_zeno="stop", **options)
    assert r["zeno"] is True
    # after k impacts the time left to T is 2 e^k v1 / (g (1 - e)); the stop comes when 21 events fit in 1e-3 s
    assert r["t_final"] == pytest.approx(T, abs=2e-3)
    assert r["t_final"] < T
    times = [e["t"] for e in r["events"]]
    assert times[0] == pytest.approx(t1, rel=1e-8)
    assert r["trajectory"]["y"][-1] == pytest.approx(0.0, abs=1e-6)  # the state where it stopped: on the floor
    assert r["t"][-1] == pytest.approx(r["t_final"])
    assert len(r["mode_series"]) == len(r["t"])


def test_result_face(double):
    """numpy values, a summary repr, a table for notebooks, a KeyError that lists the outputs and the closest."""
    r = mechgen.modes(double)
    assert isinstance(r["frequencies"], np.ndarray)
    assert isinstance(r.outputs["frequencies"], list)  # the JSON face is unchanged
    assert "frequencies:" in repr(r) and repr(r).startswith("Result modes")
    assert "<table>" in r._repr_html_()
    with pytest.raises(KeyError, match="did you mean 'frequencies'.*rigid_modes"):
        r["frequency"]
    assert r.get("nothing", 3) == 3


SCENE_FAILS_LATER = '''\
model = "{model}"
[[analysis]]
name = "free"
kind = "modes"
[[analysis]]
name = "swing"
kind = "simulate"
t_end = 100.0
max_steps = 3
q0 = {{ a = 0.5 }}
'''


def test_a_later_failure_keeps_the_earlier_results(folder, tmp_path, capsys):
    """The modes analysis finished, simulate ran out of steps: exit 1, the modes printed and in the JSON, the
    failed analysis an entry with its error."""
    scene = tmp_path / "fails.toml"
    scene.write_text(SCENE_FAILS_LATER.format(model=(folder / "double.py").as_posix()))
    target = tmp_path / "out.json"
    assert main(["run", str(scene), "--json", str(target)]) == 1
    captured = capsys.readouterr()
    assert "[modes] free" in captured.out and "swing FAILED" in captured.out
    assert "max_steps" in captured.err
    data = json.loads(target.read_text())
    first, failed = data["analyses"]
    assert first["name"] == "free" and len(first["outputs"]["frequencies"]) == 2
    assert failed["name"] == "swing" and "max_steps" in failed["error"] and failed["outputs"] == {}
    with pytest.raises(mechgen.MechgenError) as info:
        mechgen.run(str(scene))
    assert [a["name"] for a in info.value.partial_results["analyses"]] == ["free", "swing"]


def test_run_into_a_closed_pipe_is_quiet(folder, tmp_path):
    """``mechgen run SCENE | head -1``: no BrokenPipeError traceback."""
    scene = tmp_path / "quiet.toml"
    scene.write_text(f'model = "{(folder / "double.py").as_posix()}"\n[[analysis]]\nkind = "simulate"\n'
                     't_end = 1.0\nq0 = { a = 0.5 }\n')
    run = subprocess.run(f"{sys.executable} -m mechgen.cli run {scene} | head -c 10", shell=True,
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert "Traceback" not in run.stderr and "BrokenPipe" not in run.stderr


def test_plots_are_drawn(double, tmp_path):
    """The default figure is the coordinates against t (and the energy); plot = "phase" a phase portrait."""
    pytest.importorskip("matplotlib")
    r = mechgen.simulate(double, t_end=1.0, q0={"a": 0.5})
    paths = r.plot(tmp_path)
    assert [p.name for p in paths] == ["simulate.png", "simulate_energy.png"]
    phase = mechgen.simulate(double, t_end=1.0, q0={"a": 0.5}, plot="phase").plot(tmp_path, stem="phase")
    assert [p.name for p in phase] == ["phase.png"] and all(p.stat().st_size > 5000 for p in paths + phase)


def test_failed_analysis_error_types_are_kept(double):
    """A failure from Python keeps its type (a budget is a MechgenError; a singular start a ConvergenceError)."""
    with pytest.raises(ConvergenceError):
        mechgen.simulate(mechgen.compile("spring_pendulum"), t_end=1.0)  # r = 0: no inertia along theta


@pytest.mark.parametrize("scene, words", [
    ('model = "spring_pendulm"\n', ["'model'", "did you mean 'spring_pendulum'"]),
    ('model = "spring_pendulum"\n[params]\nkk = 3\n', ["'params.kk'", "did you mean 'k'"]),
    ('model = "spring_pendulum"\n[[analysis]]\nname = "a"\nkind = "simulat"\n', ["did you mean 'simulate'"]),
    ('model = "spring_pendulum"\n[[analysis]]\nname = "a"\nkind = "simulate"\nt_end = 1\nsamles = 3\n',
     ["'analysis[1].samles'", "did you mean 'samples'"]),
    ('model = "spring_pendulum"\n[[analysis]]\nname = "a"\nkind = "simulate"\nt_end = 1\nmethod = "dop853"\n',
     ["'analysis[1].method'", "did you mean 'DOP853'"]),
    ('model = "spring_pendulum"\n[[analysis]]\nname = "a"\nkind = "simulate"\nt_end = 1\nloop = "pyhton"\n',
     ["'analysis[1].loop'", "did you mean 'python'"]),
])
def test_typos_get_the_closest_name(tmp_path, capsys, scene, words):
    """A mistyped model, parameter, kind or key: exit 2, naming the key and suggesting the closest name."""
    path = tmp_path / "typo.toml"
    path.write_text(scene)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words) and "Traceback" not in err


def test_python_typos_get_the_closest_name(double):
    with pytest.raises(mechgen.InputError, match="did you mean 'samples'"):
        mechgen.simulate(double, t_end=1.0, samles=3)
    with pytest.raises(mechgen.InputError, match="did you mean 'm1'"):
        double.with_params(m11=1.0)
    with pytest.raises(mechgen.InputError, match="did you mean 'l0'"):
        mechgen.compile("spring_pendulum", {"l00": 1.0})


def test_docstrings_list_the_schema_options():
    """Each analysis function's docstring names every option of its kind's schema (one source for both)."""
    from mechgen.analyses import public
    from mechgen.analyses.registry import get, kinds

    for kind in kinds():
        function = getattr(public, kind, None)
        if function is None:
            continue
        assert all(f"``{name}``" in function.__doc__ for name in get(kind).schema), kind


def test_a_model_of_internal_variables_only_is_drawn_in_panels(tmp_path):
    """The rate-and-state slider has no coordinates (first-order laws only): its variables get a panel each, and
    no energy figure (its energies are zero)."""
    pytest.importorskip("matplotlib")
    slider = mechgen.compile("rate_state_slider")
    r = mechgen.simulate(slider, t_end=1.0, method="Radau")
    assert "trajectory" in r and not any(name.endswith("_dot") for name in r["trajectory"])
    assert [p.name for p in r.plot(tmp_path)] == ["simulate.png"]


def test_a_continuum_run_draws_its_declared_outputs(tmp_path):
    """A continuum's unknowns are more than the coordinate figure shows (its first 8): the declared outputs (js_fluid's
    flow rate, from rest towards the steady Newton state) get their own figure, <stem>_outputs.png."""
    pytest.importorskip("matplotlib")
    system = mechgen.compile("js_fluid", {"N": 4})
    r = mechgen.simulate(system, t_end=2.0, samples=21)
    paths = r.plot(tmp_path)
    assert [p.name for p in paths] == ["simulate.png", "simulate_outputs.png"]
    assert paths[1].stat().st_size > 5000 and r["trajectory"]["flow_rate"][0] == 0.0
