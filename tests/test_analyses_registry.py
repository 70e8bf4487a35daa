"""The analysis registry and the Python functions built on it (issue 11, items 2 and 4).

Each public function on a small model is compared with the scene path (``run_scene`` on the same
options: the same outputs and ``Result.to_json()`` equal to the scene JSON's entry) and, for modes
and the Laval rotor, with closed forms: the spring pendulum about its equilibrium r_eq = l0 + m g / k
has omega = sqrt(k/m) and sqrt(g / r_eq); the Laval rotor's tilt modes whirl at
omega_f,b = (+-Ip Omega + sqrt(Ip^2 Omega^2 + 4 Id k_r)) / (2 Id) and its translation at sqrt(k_t / m)
(the model docstring).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen import models
from mechgen.analyses import registry
from mechgen.analyses.result import Result
from mechgen.errors import InputError
from mechgen.pipeline import compile_model
from mechgen.scene.info import lookup_model
from mechgen.scene.load import load_scene
from mechgen.scene.run import run_scene
from mechgen.symbolic.specialize import specialize

ROOT = Path(__file__).resolve().parents[1]
KINDS = ("modes", "stability", "steady", "simulate", "sweep", "campbell", "continuation")


def _scene(path) -> tuple[dict, object]:
    """The scene's results and a system compiled independently with the scene's parameters and kernels."""
    results = run_scene(path)
    scn = load_scene(str(path), lookup_model=lookup_model, model_names=models.names)
    model = models.get(scn.model)
    free = tuple(n for n in scn.free if model.param(n).is_numeric)
    spec = specialize(model, dict(scn.params), free=free, active=scn.active)
    system, _ = compile_model(model, spec, kernels=set(results["build"]["kernels"]), backend=scn.backend)
    return results, system


def _entry(results: dict, name: str) -> dict:
    return next(a for a in results["analyses"] if a["name"] == name)


def _same_as_scene(result: Result, entry: dict) -> None:
    """The Result's JSON is the scene's entry (everything but the wall time), as the JSON writer writes it."""
    ours, theirs = result.to_json(), dict(entry)
    assert set(ours) == {"name", "kind", "outputs", "seconds"} == set(theirs)
    assert ours["kind"] == theirs["kind"] and ours["name"] == theirs["name"]
    assert json.dumps(ours["outputs"], default=float) == json.dumps(theirs["outputs"], default=float)


def test_the_registry_lists_the_seven_kinds_each_with_a_function():
    # the seven of the refactor first, then kinds added since (response: tests/test_response.py, fit:
    # tests/test_fit.py; impact, restitution: tests/test_impacts.py)
    assert registry.kinds()[:len(KINDS)] == KINDS
    assert registry.kinds()[len(KINDS):] == ("response", "fit", "impact", "restitution", "stability_boundary", "spectrum",
                                                    "periodic", "periodic_orbit",
                                                    "cross_section", "symplectic", "rod_statics", "rod_dynamics",
                                                    "phase_boundary", "phase_kinetics", "orr_sommerfeld",
                                                    "shear_curve", "channel_flow", "channel_spectrum",
                                                        "crack_integrals")
    for kind in KINDS:
        record = registry.get(kind)
        assert record.name == kind and record.schema and callable(record.run) and callable(record.summary)
        assert callable(getattr(mechgen, kind)) and getattr(mechgen, kind).__module__ == "mechgen.analyses.public"
    assert [k for k in KINDS if registry.get(k).sweepable] == ["modes", "stability", "steady", "simulate"]
    with pytest.raises(InputError, match="unknown analysis kind 'levitate'"):
        registry.get("levitate")


def test_the_package_names_no_kind_of_its_own():
    """``mechgen.analyses.modes`` is the module, ``mechgen.modes`` the function: neither clobbers the other."""
    import mechgen.analyses as package
    import mechgen.analyses.modes as module

    assert package.modes is module and mechgen.modes is not module
    assert mechgen.Result is Result


def test_spring_pendulum_steady_modes_simulate_match_the_scene_and_the_closed_form():
    results, system = _scene(ROOT / "scenes" / "spring_pendulum.toml")
    equilibrium = mechgen.steady(system, guess={"r": 1.0}, name="equilibrium")
    small = mechgen.modes(system, about=equilibrium, name="small_oscillations")
    swing = mechgen.simulate(system, method="DOP853", t_end=20.0, q0={"r": 1.4, "theta": 0.8}, rtol=1e-10,
                             atol=1e-12, name="swing")
    for result in (equilibrium, small, swing):
        _same_as_scene(result, _entry(results, result.name))
    m, k, l0, g = 1.0, 40.0, 1.0, 9.81
    r_eq = l0 + m * g / k
    assert equilibrium["coordinates"]["r"] == pytest.approx(r_eq, rel=1e-12)
    np.testing.assert_allclose(small["frequencies"], sorted([np.sqrt(k / m), np.sqrt(g / r_eq)]), rtol=1e-10)


def test_laval_rotor_stability_and_sweep_match_the_scene_and_the_whirl_closed_form():
    results, system = _scene(ROOT / "scenes" / "laval_rotor.toml")
    whirl = mechgen.stability(system, name="whirl")
    campbell = mechgen.sweep(system, "stability", grid={"Omega": {"start": 0.0, "stop": 3000.0, "num": 31}},
                             name="campbell")
    _same_as_scene(whirl, _entry(results, "whirl"))
    _same_as_scene(campbell, _entry(results, "campbell"))
    Ip, Id, k_r, k_t, m = 0.2, 0.1, 2.0e4, 4.0e5, 10.0
    for point, freqs in zip(campbell["grid"], campbell["frequencies"]):
        W = point["Omega"]
        root = np.sqrt(Ip**2 * W**2 + 4 * Id * k_r)
        expected = [np.sqrt(k_t / m), (root - Ip * W) / (2 * Id), (root + Ip * W) / (2 * Id)]
        # the reported frequencies are the distinct ones: each is a closed-form value, and each value is reported
        assert all(np.isclose(f, expected, rtol=1e-9).any() for f in freqs)
        assert all(np.isclose(e, freqs, rtol=1e-9).any() for e in expected)
    # the sweep left the system as it was: its stability is still that at the scene's Omega
    np.testing.assert_array_equal(mechgen.stability(system)["frequencies"], whirl["frequencies"])


LAVAL_CAMPBELL = """model = "laval_rotor"
[params]
m = 10.0
Ip = 0.2
Id = 0.1
k_t = 4.0e5
k_r = 2.0e4
[[analysis]]
name = "diagram"
kind = "campbell"
over = { Omega = { start = 0.0, stop = 3000.0, num = 7 } }
count = 4
multiples = [1.0, 2.0]
"""


def test_laval_rotor_campbell_matches_the_scene(tmp_path):
    scene = tmp_path / "campbell.toml"
    scene.write_text(LAVAL_CAMPBELL)
    results, system = _scene(scene)
    diagram = mechgen.campbell(system, over={"Omega": np.linspace(0.0, 3000.0, 7)}, count=4, multiples=[1.0, 2.0],
                               name="diagram")
    _same_as_scene(diagram, _entry(results, "diagram"))
    Ip, Id, k_r = 0.2, 0.1, 2.0e4
    forward = [(np.sqrt(Ip**2 * W**2 + 4 * Id * k_r) + Ip * W) / (2 * Id) for W in diagram["speeds"]]
    assert all(np.isclose(f, row, rtol=1e-9).any() for f, row in zip(forward, diagram["frequencies"]))


BALLOON = """model = "balloon_string"
[params]
h = 10.0
beta = 100.0
lambda0 = -0.5
law = "neo_hookean"
N = 10
[[analysis]]
name = "start"
kind = "steady"
method = "collocation"
bulge = { x = [2.0] }
aliases = { p_e = "tension_start" }
[[analysis]]
name = "branch"
kind = "continuation"
about = "start"
parameter = "lambda0"
stop = -0.3
max_points = 6
method = "gauss"
mesh = 20
stability = false
aliases = { p_e = "tension_start" }
"""


def test_string_continuation_matches_the_scene(tmp_path):
    scene = tmp_path / "balloon.toml"
    scene.write_text(BALLOON)
    results, system = _scene(scene)
    start = mechgen.steady(system, method="collocation", bulge={"x": [2.0]}, aliases={"p_e": "tension_start"},
                           name="start")
    branch = mechgen.continuation(system, about=start, parameter="lambda0", stop=-0.3, max_points=6, method="gauss",
                                  mesh=20, stability=False, aliases={"p_e": "tension_start"}, name="branch")
    _same_as_scene(start, _entry(results, "start"))
    _same_as_scene(branch, _entry(results, "branch"))
    assert branch["points"] == len(branch["branch"]) > 1


def test_bad_options_through_the_python_api_name_the_function_and_the_key():
    _, system = _scene(ROOT / "scenes" / "laval_rotor.toml")
    with pytest.raises(InputError) as err:
        mechgen.modes(system, cout=3)
    assert err.value.key == "cout" and "modes()" in str(err.value) and "about, at, count" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.stability(system, tolerance=-1.0)
    assert err.value.key == "stability.tolerance" and "not positive" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.sweep(system, "stability", grid={"Omega": [0.0, 1.0]}, bogus=1)
    assert err.value.key == "bogus" and "sweep()" in str(err.value) and "tolerance" in str(err.value)
    with pytest.raises(InputError, match="cannot repeat 'campbell'"):
        mechgen.sweep(system, "campbell", grid={"Omega": [0.0, 1.0]})
    with pytest.raises(InputError) as err:
        mechgen.sweep(system, "stability", grid={"k_r": [1.0, 2.0]})
    assert err.value.key == "grid.k_r" and "not free" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.simulate(system, q0={"x": 0.1})
    assert err.value.key == "simulate.t_end" and "missing required key" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.modes(system, about="nothing")
    assert err.value.key == "modes.about"


def test_result_plot_writes_the_kinds_figure(tmp_path):
    pytest.importorskip("matplotlib")
    _, system = _scene(ROOT / "scenes" / "laval_rotor.toml")
    assert mechgen.stability(system, name="whirl").plot(tmp_path) == [tmp_path / "whirl.png"]
    assert (tmp_path / "whirl.png").stat().st_size > 0


def test_a_kind_registered_at_run_time_runs_through_the_scene_the_summary_and_the_python_api(tmp_path):
    """What adding a kind takes: an AnalysisKind registered; the loader, run_scene, the summary and the Python
    API then know it without naming it. The toy kind reports the number of unknowns and M's trace, compared
    with the spring pendulum's M = diag(m, m r^2) at r = ``r``."""
    from mechgen.analyses import schema, summary
    from mechgen.scene.report import summary as scene_summary

    def run(system, options, context):
        mats = system.linear(np.array([options["r"], 0.0]))
        return {"unknowns": system.n, "mass_trace": float(np.trace(mats["M"]))}

    options = {"r": schema.Option(schema.positive, 1.0, doc="the pendulum's length r at which M is evaluated (m)")}
    kind = registry.AnalysisKind("mass_trace", options, run, lambda options, *, internal: {"linear"}, summary.lines)
    registry.register(kind)
    try:
        assert registry.kinds()[-1] == "mass_trace"
        scene = tmp_path / "toy.toml"
        scene.write_text('model = "spring_pendulum"\n[params]\nm = 2.0\n[[analysis]]\nname = "toy"\n'
                         'kind = "mass_trace"\nr = 1.5\n')
        results = run_scene(scene)
        assert _entry(results, "toy")["outputs"] == {"unknowns": 2, "mass_trace": pytest.approx(2.0 + 2.0 * 1.5**2)}
        assert "[mass_trace] toy" in scene_summary(results) and "    unknowns: 2" in scene_summary(results)
        _, system = _scene(scene)
        from mechgen.analyses.public import analysis

        assert analysis("mass_trace", system, r=1.5, name="toy").outputs == _entry(results, "toy")["outputs"]
        scene.write_text(scene.read_text() + "bogus = 1\n")
        with pytest.raises(InputError, match="unknown key 'bogus' for a mass_trace analysis"):
            run_scene(scene)
    finally:
        registry.unregister("mass_trace")
    assert registry.kinds()[:len(KINDS)] == KINDS and "mass_trace" not in registry.kinds()


def test_a_scene_loads_only_the_kinds_it_names():
    """Loading laval_rotor.toml (a stability and a sweep of stability) imports those kinds' modules and no
    other kind's (a start pays for what the scene runs); an unknown kind still lists every kind."""
    import subprocess
    import sys

    code = ("import sys; from mechgen import models; from mechgen.scene.load import load_scene; "
            "from mechgen.scene.info import lookup_model; "
            "load_scene('scenes/laval_rotor.toml', lookup_model=lookup_model, model_names=models.known); "
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('mechgen.analyses.'))))")
    root = Path(__file__).resolve().parent.parent
    loaded = set(subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True,
                                check=True).stdout.split())
    kinds = {m.rsplit(".", 1)[1] for m in registry.MODULES}
    # stability's own module imports modes' (its eigen-solve): the one kind loaded that the scene does not name
    assert {"sweep", "stability"} <= loaded_kinds(loaded, kinds) <= {"sweep", "stability", "modes"}
    with pytest.raises(InputError, match="one of: modes, stability"):
        registry.get("no_such_kind")


def loaded_kinds(modules: set, kinds: set) -> set:
    return {m.rsplit(".", 1)[1] for m in modules} & kinds
