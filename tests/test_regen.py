"""Compile planning and cached model facts: what `mechgen run` plans is what `mechgen regen` writes.

References: the planned requests against the ones built from the imported model and
:func:`mechgen.symbolic.specialize.specialize` (the derived path); the cached ModelInfo against
the one read off the imported model.
"""
import shutil
from pathlib import Path

import pytest

from mechgen import models
from mechgen.codegen.lower_liegroup import generated_texts
from mechgen.pipeline import GENERATED, committed_paths, read_committed, request_of
from mechgen.regen import planned_requests
from mechgen.scene.info import cached_info, info_from_json, info_of_model, model_info
from mechgen.scene.plan import derive_with

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("name", models.names())
def test_model_info_round_trips_and_the_committed_one_is_current(name):
    info = info_of_model(models.get(name))
    assert info_from_json(info.to_json()) == info
    assert list(info_from_json(info.to_json()).params) == list(info.params)  # declaration order kept
    committed = cached_info(models.resolve(name))
    assert committed == info


def test_planned_requests_equal_the_derived_paths_requests():
    requests = planned_requests()
    assert {r.model for _, r in requests} >= {"laval_rotor", "euler_bernoulli_beam", "balloon_string"}
    for source, request in requests:
        model, spec = derive_with(source, request)()
        assert spec.key() == request.spec_text()
        assert request_of(model, spec, kernels=request.kernels, backend=request.backend) == request


def test_every_planned_request_is_committed_and_nothing_else():
    requests = planned_requests()
    named = set()
    for _, request in requests:
        key = request.key()
        assert read_committed(request.model, key, request.backend) is not None, request.describe()
        named |= set(committed_paths(request.model, key, request.backend))
    named |= {GENERATED / name / "info.json" for name in models.names()}
    named |= {GENERATED / rel for rel in generated_texts()}   # the Lie-group maps (codegen/lower_liegroup.py)
    present = {p for p in GENERATED.glob("*/*") if p.is_file() and p.suffix in (".c", ".json", ".py", ".h")}
    assert present == named


def test_a_structural_sweep_gets_its_own_requests():
    """beam_modes sweeps the boundary conditions (a choice): one request per choice, all committed."""
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene
    from mechgen.scene.plan import plan_scene

    scn = load_scene(str(ROOT / "scenes" / "beam_modes.toml"), lookup_model=lookup_model, model_names=models.names)
    plan = plan_scene(scn)
    sweep = [a for a in scn.analyses if a.kind == "sweep"][0]
    choices = {dict(r.values)["bc"] for r in plan.points[sweep.name]}
    assert choices == {p["bc"] for p in sweep.options["grid"]} and len(choices) > 1
    assert len(plan.requests()) == 1 + len(choices - {dict(plan.main.values)["bc"]})


def test_user_model_facts_are_cached_by_content(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "pendulum.py"
    shutil.copy(models.resolve("spring_pendulum").file, path)
    source = models.resolve(str(path))
    assert cached_info(source) is None
    info = model_info(str(path))
    assert info == info_of_model(source.load())
    assert cached_info(source) == info
    path.write_text(path.read_text() + "\n# edited\n")
    assert cached_info(models.resolve(str(path))) is None  # another content: not valid any more
