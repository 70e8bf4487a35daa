"""Rerun safety (issue 11, item 3): compiled systems are immutable, so a scene run twice in one process, or its
analyses run in another order, gives the same numbers.

The second run of each shipped scene also draws its figures, each audited as it is saved (tests/figure_audit.py,
issue 26, item 6): every scene's figures are checked without running any scene a third time."""
import dataclasses
import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

import mechgen

SCENES = sorted((Path(__file__).resolve().parent.parent / "scenes").glob("*.toml"))


def assert_same(a, b, where: str = "outputs") -> None:
    """Exact equality of two results (dicts, lists, arrays, numbers, strings); NaN equals NaN."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{where}: keys {sorted(a)} vs {sorted(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), f"{where}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=where)
    elif isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        pass
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


#: outputs that are wall-time measurements (the symplectic kind's speed), not computed numbers
MEASURED = ("steps_per_second", "bandwidth_fraction", "bandwidth_share")


#: scenes rerun at a smaller size: parameters, and analysis keys by analysis name (the full size runs in its own
#: tests: fpu_large in tests/test_fpu_scenes.py and tests/test_chain_scale.py; balloon_branches in
#: tests/test_balloon.py and tests/test_balloon_loops.py). balloon_branches' multi_loop continuation at 40 points
#: per family and direction (300 in the scene) still follows all three families both ways and locates three
#: balloons at p_e = 5: the same analyses and code paths, 2.5 s instead of 6.7 s a run. balloon_stability's
#: branch at 40 points (still both ways, with eigenvalues, two balloons at p_e = 5; the full scene runs in
#: tests/test_balloon_loops.py): 0.7 s a run saved. Scenes that no other test runs whole stay at full size here.
SMALLER = {"fpu_large": {"params": {"N": 100_000}},
           "balloon_branches": {"analysis": {"multi_loop": {"max_points": 40}}},
           "balloon_stability": {"analysis": {"branch": {"max_points": 40}}}}


#: the shipped scenes that draw nothing: a cross-section's 6 x 6 stiffness, and steady states with a located
#: stability boundary, are numbers, which the summary prints
NO_FIGURES = ("curved_beam_stiffness", "rate_state_slider")


def by_name(results: dict) -> dict:
    return {a["name"]: (a["kind"], {k: v for k, v in a["outputs"].items() if k not in MEASURED})
            for a in results["analyses"]}


@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES, ids=[p.stem for p in SCENES])
def test_every_scene_run_twice_gives_identical_outputs(scene, tmp_path):
    """Identical outputs; then the second run's figures, each complete (titles, labels, legends, no axis scaled to
    round-off)."""
    stem = scene.stem
    if scene.stem in SMALLER:      # the same analyses on a smaller size: rerun identity does not depend on it
        import tomllib

        data = tomllib.loads(scene.read_text())
        smaller = SMALLER[scene.stem]
        data["params"].update(smaller.get("params", {}))
        for name, keys in smaller.get("analysis", {}).items():
            (analysis,) = [a for a in data["analysis"] if a["name"] == name]
            assert set(keys) <= set(analysis), f"{scene.stem}: {name} has no {set(keys) - set(analysis)}"
            analysis.update(keys)
        scene = data
    first = mechgen.run(scene)
    second = mechgen.run(scene)
    for key in ("scene", "model", "backend", "params"):
        assert first[key] == second[key]
    assert [a["name"] for a in first["analyses"]] == [a["name"] for a in second["analyses"]]
    assert_same(by_name(first), by_name(second), first["scene"])
    check_figures(stem, second, tmp_path)


def check_figures(stem: str, results: dict, folder: Path) -> None:
    """The scene's figures drawn from its results (as ``mechgen run --plot`` draws them), each audited."""
    if importlib.util.find_spec("matplotlib") is None:
        return
    from figure_audit import audited_savefig

    from mechgen.scene.plots import plot_results

    with audited_savefig({}) as seen:
        written = plot_results(results, folder)
    assert bool(seen) == (stem not in NO_FIGURES), f"{stem}: figures {sorted(seen)}"
    assert all(path.stat().st_size > 0 for path in written)
    assert {name: found for name, found in seen.items() if found} == {}, stem


def _split(text: str) -> tuple[str, list[str]]:
    """(the scene's header, its [[analysis]] blocks in order)."""
    head, *blocks = text.split("\n[[analysis]]")
    return head, ["\n[[analysis]]" + b.rstrip("\n") + "\n" for b in blocks]


def test_laval_analyses_do_not_depend_on_their_order(tmp_path):
    """laval_rotor's analyses (whirl at the scene's spin, then a sweep of the spin to 3000) in the scene's order,
    then in reverse order in one scene, then one by one in reverse order: the same numbers each way."""
    scene = next(p for p in SCENES if p.stem == "laval_rotor")
    head, blocks = _split(scene.read_text())
    assert len(blocks) == 2
    reference = by_name(mechgen.run(scene))
    reversed_scene = tmp_path / "reversed.toml"
    reversed_scene.write_text(head + "".join(reversed(blocks)))
    runs = [by_name(mechgen.run(reversed_scene))]
    for i, block in reversed(list(enumerate(blocks))):
        alone = tmp_path / f"alone_{i}.toml"
        alone.write_text(head + block)
        runs.append(by_name(mechgen.run(alone)))
    again = by_name(mechgen.run(scene))
    assert_same(reference, again, "laval_rotor again")
    for run in runs:
        for name, found in run.items():
            assert_same(reference[name], found, f"laval_rotor {name}")
    # the whirl analysis is at the scene's spin 2 pi 100, not at the sweep's last point 3000
    Ip, Id, k_r, omega = 0.2, 0.1, 2.0e4, 2 * math.pi * 100
    forward = (Ip * omega + math.sqrt(Ip**2 * omega**2 + 4 * Id * k_r)) / (2 * Id)
    assert min(abs(f - forward) for f in reference["whirl"][1]["frequencies"]) < 1e-9 * forward


@pytest.fixture(scope="module")
def systems():
    lumped = mechgen.compile("spring_pendulum", {"m": 2.0, "k": 50.0}, backend="numpy")
    field = mechgen.compile("euler_bernoulli_beam", {"N": 8}, backend="numpy")
    return {"lumped": lumped, "field": field}


@pytest.mark.parametrize("kind", ["lumped", "field"])
def test_writing_to_a_compiled_system_raises(systems, kind):
    system = systems[kind]
    with pytest.raises(ValueError, match="read-only"):
        system.params[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        system.params = np.ones_like(system.params)
    with pytest.raises(dataclasses.FrozenInstanceError):
        system.backend = "c"
    if kind == "field":
        with pytest.raises(dataclasses.FrozenInstanceError):
            system.layout = None
        with pytest.raises(TypeError):
            system.choices["N"] = 16
        with pytest.raises(TypeError):
            system.fixed["bc"] = "clamped-free"


@pytest.mark.parametrize("kind,values", [("lumped", {"k": 80.0}), ("field", {"EI": 3.0, "N": 12, "L": 2.0})])
def test_with_params_leaves_the_old_system_unchanged(systems, kind, values):
    system = systems[kind]
    q = np.array([1.0 + 2.0 * 9.81 / 50.0, 0.0]) if kind == "lumped" else None
    params, before = system.params.copy(), system.linear(q)
    choices = dict(getattr(system, "choices", {}))
    new = system.with_params(**values)
    after = system.linear(q)
    np.testing.assert_array_equal(system.params, params)
    assert dict(getattr(system, "choices", {})) == choices
    for name in ("M", "K"):
        A, B = (x.toarray() if hasattr(x, "toarray") else x for x in (before[name], after[name]))
        np.testing.assert_array_equal(A, B)
    assert new is not system and new.param_values() != system.param_values()
    for name, value in values.items():
        assert new.param_values()[name] == value
