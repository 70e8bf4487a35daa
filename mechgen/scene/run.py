"""Running a scene: load and validate, compile what the analyses need, run them, collect results.

Result dict (DESIGN.md): {"scene", "model", "backend", "analyses": [{"name", "kind", "outputs", "seconds"}]}
plus "build" (kernels built, operation counts, stage times). Entries whose name
starts with "_" are working data and never reach JSON.
"""
from __future__ import annotations

import time
from functools import lru_cache, partial
from pathlib import Path
from typing import Mapping

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.errors import InputError
from mechgen.analyses.context import NAME, POINTS, PointRunner, public
from mechgen.analyses.registry import get
from mechgen.analyses.result import run_analysis
from mechgen.runtime.mesh import Layout
from mechgen.scene.info import lookup_model
from mechgen.scene.load import load_scene
from mechgen.symbolic.specialize import specialize


@lru_cache(maxsize=8)
def _system_for(model_ref, values: tuple, free: tuple, active, kernels: tuple, backend: str):
    """The compiled system; ``model_ref`` a Model (cached by identity: an edited model file loads as a new
    Model) or a model reference. ``meta["source"]`` is the model's canonical reference (mechgen.models)."""
    model = models.get(model_ref) if isinstance(model_ref, str) else model_ref
    spec = specialize(model, dict(values), free=free, active=active)
    return compile_model(model, spec, kernels=set(kernels), backend=backend)


def _laid_out(system, layout: Layout | None):
    """The system with the scene's segments and parts (a copy; the cached system stays bare)."""
    if layout is None or not (layout.segments or layout.parts):
        return system
    return system.with_layout(layout)


def _sweep_point(task: tuple) -> dict:
    """Run the inner analysis of a sweep at one grid point (module level: picklable)."""
    source, values, free, active, kernels, backend, kind, options, point, layout = task
    model = models.get(source)  # the canonical reference: resolves in a worker process too
    system, _ = _system_for(model, values, free, active, kernels, backend)
    sizes = {k: v for k, v in point.items() if not model.param(k).is_numeric}
    if sizes:
        system, _ = _system_for(model, tuple(sorted({**dict(values), **sizes}.items())), free, active,
                                kernels, backend)
    system = _laid_out(system, layout).with_param_vector(
        [float(point.get(n, dict(values).get(n, model.param(n).default))) for n in system.meta.get("params", [])])
    return public(get(kind).run(system, options, {}))


def _point_task(scene: tuple, layout, kind: str, options: dict, point: dict) -> tuple:
    """The task _sweep_point takes: the scene's compile inputs, the analysis, the point and the layout."""
    return (*scene, kind, options, point, layout)


def run_scene(scene, *, overrides=(), backend: str | None = None) -> dict:
    """Run every analysis of a scene (a file, or a dict of its contents) and return the results dict."""
    scn = load_scene(scene if isinstance(scene, Mapping) else str(scene), overrides=list(overrides),
                     lookup_model=lookup_model, model_names=models.known)
    model = models.get(scn.source)
    backend = backend or scn.backend
    internal = bool(model.internals)
    kernels = sorted(set().union(*(get(a.kind).needs(a.options, internal=internal) for a in scn.analyses)))
    free = tuple(n for n in scn.free if model.param(n).is_numeric)
    fixed = tuple(sorted((k, v) for k, v in scn.params.items()))
    started = time.perf_counter()
    system, report = _system_for(model, fixed, free, scn.active, tuple(kernels), backend)
    layout = Layout(scn.segments, scn.parts)
    system = _laid_out(system, layout)
    results = {"scene": Path(scn.path).name, "title": scn.title, "model": scn.model, "backend": report.backend,
               "params": dict(scn.params), "build": report.to_json(), "analyses": []}
    results["build"]["seconds_total"] = time.perf_counter() - started
    scene_inputs = (scn.source, fixed, free, scn.active, tuple(kernels), backend)
    context: dict = {POINTS: PointRunner(_sweep_point, partial(_point_task, scene_inputs, layout))}
    for analysis in scn.analyses:
        context[NAME] = analysis.name
        result = run_analysis(analysis.name, analysis.kind, system, dict(analysis.options), context)
        context[analysis.name] = result.state
        results["analyses"].append(result.to_json())
    return results


def check_backend(name: str | None) -> None:
    """Validate a --backend value."""
    if name is not None and name not in ("c", "numpy", "casadi"):
        raise InputError(f"unknown backend {name!r}", key="--backend", expected="c, numpy or casadi")
