"""Running a scene: load and validate, compile what the analyses need, run them, collect results.

Result dict (DESIGN.md): {"scene", "model", "backend", "analyses": [{"name", "kind", "outputs", "seconds"}]}
plus "build" (kernels built, operation counts, stage times). Entries whose name
starts with "_" are working data and never reach JSON.
"""
from __future__ import annotations

import time
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from mechgen import models
from mechgen.pipeline import compile_request, file_digest
from mechgen.errors import InputError
from mechgen.runtime.mesh import Layout
from mechgen.runtime.sweep import sweep
from mechgen.scene.analyses import RUNNERS
from mechgen.scene.info import lookup_model, model_info
from mechgen.scene.load import load_scene
from mechgen.scene.plan import derive_with, plan_scene, point_request, request_for


def _public(outputs: dict) -> dict:
    return {k: v for k, v in outputs.items() if not k.startswith("_")}


@lru_cache(maxsize=8)
def _system_of(source_key: str, request):
    """The compiled system of a request (mechgen.scene.plan); the model is imported only to derive."""
    return compile_request(request, derive_with(models.resolve(source_key), request))


@lru_cache(maxsize=8)
def _system_for(model_name: str, values: tuple, free: tuple, active, kernels: tuple, backend: str):
    """The compiled system of scene values (the benchmarks' entry; a scene run plans with plan_scene)."""
    source = models.resolve(model_name)
    request = request_for(model_info(source.key), file_digest(source.file), dict(values), free=free, active=active,
                          kernels=kernels, backend=backend)
    return compile_request(request, derive_with(source, request))


def _laid_out(system, layout: Layout | None):
    """The system with the scene's segments and parts (a copy; the cached system stays bare)."""
    if layout is None or not (layout.segments or layout.parts):
        return system
    return replace(system, layout=layout, _cache={})


def _sweep_point(task: tuple) -> dict:
    """Run the inner analysis of a sweep at one grid point (module level: picklable)."""
    source_key, request, values, kind, options, point, layout = task
    info = model_info(source_key)
    system, _ = _system_of(source_key, point_request(request, info, point) or request)
    system = _laid_out(system, layout)
    system.params = np.array([float(point.get(n, dict(values).get(n, info.param(n).default)))
                              for n in system.meta.get("params", [])])
    return _public(RUNNERS[kind](system, options, {}))


def _collect(grid: list[dict], results: list[dict]) -> dict:
    out: dict = {"grid": grid}
    for key in results[0] if results else []:
        out[key] = [r.get(key) for r in results]
    return out


def run_scene(scene, *, overrides=(), backend: str | None = None) -> dict:
    """Run every analysis of a scene file and return the results dict."""
    scn = load_scene(str(scene), overrides=list(overrides), lookup_model=lookup_model, model_names=models.names)
    plan = plan_scene(scn, backend=backend)
    fixed = tuple(sorted((k, v) for k, v in scn.params.items()))
    started = time.perf_counter()
    system, report = _system_of(plan.source.key, plan.main)
    layout = Layout(scn.segments, scn.parts)
    system = _laid_out(system, layout)
    results = {"scene": Path(scn.path).name, "title": scn.title, "model": scn.model, "backend": report.backend,
               "params": dict(scn.params), "build": report.to_json(), "analyses": []}
    results["build"]["seconds_total"] = time.perf_counter() - started
    context: dict = {}
    for analysis in scn.analyses:
        clock = time.perf_counter()
        if analysis.kind == "sweep":
            inner = analysis.options["analysis"]
            tasks = [(plan.source.key, plan.main, fixed, inner.kind, dict(inner.options), point, layout)
                     for point in analysis.options["grid"]]
            res = sweep(_sweep_point, tasks, workers=analysis.options.get("workers", 0),
                        progress=analysis.options.get("progress", True), desc=analysis.name)
            outputs = _collect(analysis.options["grid"], res)
        else:
            outputs = RUNNERS[analysis.kind](system, dict(analysis.options), context)
        context[analysis.name] = outputs
        results["analyses"].append({"name": analysis.name, "kind": analysis.kind, "outputs": _public(outputs),
                                    "seconds": time.perf_counter() - clock})
    return results


def check_backend(name: str | None) -> None:
    """Validate a --backend value."""
    if name is not None and name not in ("c", "numpy", "casadi"):
        raise InputError(f"unknown backend {name!r}", key="--backend", expected="c, numpy or casadi")
