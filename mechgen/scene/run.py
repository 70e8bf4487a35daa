"""Running a scene: load and validate, compile what the analyses need, run them, collect results.

Result dict (DESIGN.md): {"scene", "model", "backend", "analyses": [{"name", "kind", "outputs", "seconds"}]}
plus "build" (kernels built, operation counts, stage times). Entries whose name
starts with "_" are working data and never reach JSON.
"""
from __future__ import annotations

import time
from dataclasses import replace
from functools import lru_cache, partial
from pathlib import Path

import numpy as np

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
def _system_for(model_name: str, values: tuple, free: tuple, active, kernels: tuple, backend: str):
    model = models.get(model_name)
    spec = specialize(model, dict(values), free=free, active=active)
    return compile_model(model, spec, kernels=set(kernels), backend=backend)


def _laid_out(system, layout: Layout | None):
    """The system with the scene's segments and parts (a copy; the cached system stays bare)."""
    if layout is None or not (layout.segments or layout.parts):
        return system
    return replace(system, layout=layout, _cache={})


def _sweep_point(task: tuple) -> dict:
    """Run the inner analysis of a sweep at one grid point (module level: picklable)."""
    model_name, values, free, active, kernels, backend, kind, options, point, layout = task
    system, _ = _system_for(model_name, values, free, active, kernels, backend)
    model = models.get(model_name)
    sizes = {k: v for k, v in point.items() if not model.param(k).is_numeric}
    if sizes:
        system, _ = _system_for(model_name, tuple(sorted({**dict(values), **sizes}.items())), free, active,
                                kernels, backend)
    system = _laid_out(system, layout)
    system.params = np.array([float(point.get(n, dict(values).get(n, model.param(n).default)))
                              for n in system.meta.get("params", [])])
    return public(get(kind).run(system, options, {}))


def _point_task(scene: tuple, layout, kind: str, options: dict, point: dict) -> tuple:
    """The task _sweep_point takes: the scene's compile inputs, the analysis, the point and the layout."""
    return (*scene, kind, options, point, layout)


def run_scene(scene, *, overrides=(), backend: str | None = None) -> dict:
    """Run every analysis of a scene file and return the results dict."""
    scn = load_scene(str(scene), overrides=list(overrides), lookup_model=lookup_model, model_names=models.names)
    model = models.get(scn.model)
    backend = backend or scn.backend
    internal = bool(model.internals)
    kernels = sorted(set().union(*(get(a.kind).needs(a.options, internal=internal) for a in scn.analyses)))
    free = tuple(n for n in scn.free if model.param(n).is_numeric)
    fixed = tuple(sorted((k, v) for k, v in scn.params.items()))
    started = time.perf_counter()
    system, report = _system_for(scn.model, fixed, free, scn.active, tuple(kernels), backend)
    layout = Layout(scn.segments, scn.parts)
    system = _laid_out(system, layout)
    results = {"scene": Path(scn.path).name, "title": scn.title, "model": scn.model, "backend": report.backend,
               "params": dict(scn.params), "build": report.to_json(), "analyses": []}
    results["build"]["seconds_total"] = time.perf_counter() - started
    scene_inputs = (scn.model, fixed, free, scn.active, tuple(kernels), backend)
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
