"""Running a scene: load and validate, compile what the analyses need, run them, collect results.

Result dict (DESIGN.md): {"scene", "model", "backend", "analyses": [{"name", "kind", "outputs", "seconds"}]}
plus "build" (kernels built, operation counts, stage times). Entries whose name
starts with "_" are working data and never reach JSON.
"""
from __future__ import annotations

import time
from functools import lru_cache
from pathlib import Path
from typing import Mapping

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.errors import InputError
from mechgen.runtime.mesh import Layout
from mechgen.runtime.sweep import sweep
from mechgen.scene.analyses import RUNNERS, needs
from mechgen.scene.info import lookup_model
from mechgen.scene.load import load_scene
from mechgen.symbolic.specialize import specialize


def _public(outputs: dict) -> dict:
    return {k: v for k, v in outputs.items() if not k.startswith("_")}


@lru_cache(maxsize=8)
def _system_for(model_ref, values: tuple, free: tuple, active, kernels: tuple, backend: str):
    """The compiled system; ``model_ref`` a Model (cached by identity: an edited model file loads as a new
    Model) or a model reference. ``meta["source"]`` is the model's canonical reference (mechgen.models)."""
    model = models.get(model_ref) if isinstance(model_ref, str) else model_ref
    spec = specialize(model, dict(values), free=free, active=active)
    system, report = compile_model(model, spec, kernels=set(kernels), backend=backend)
    system.meta["source"] = model.source or model.name
    return system, report


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
    return _public(RUNNERS[kind](system, options, {}))


def _collect(grid: list[dict], results: list[dict]) -> dict:
    out: dict = {"grid": grid}
    for key in results[0] if results else []:
        out[key] = [r.get(key) for r in results]
    return out


def run_scene(scene, *, overrides=(), backend: str | None = None) -> dict:
    """Run every analysis of a scene (a file, or a dict of its contents) and return the results dict."""
    scn = load_scene(scene if isinstance(scene, Mapping) else str(scene), overrides=list(overrides),
                     lookup_model=lookup_model, model_names=models.known)
    model = models.get(scn.source)
    backend = backend or scn.backend
    internal = bool(model.internals)
    kernels = sorted(set().union(*(needs(a.kind, a.options, internal=internal) for a in scn.analyses)))
    free = tuple(n for n in scn.free if model.param(n).is_numeric)
    fixed = tuple(sorted((k, v) for k, v in scn.params.items()))
    started = time.perf_counter()
    system, report = _system_for(model, fixed, free, scn.active, tuple(kernels), backend)
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
            tasks = [(scn.source, fixed, free, scn.active, tuple(kernels), backend, inner.kind, dict(inner.options),
                      point, layout) for point in analysis.options["grid"]]
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
