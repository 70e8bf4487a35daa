"""Running a scene: load and validate, compile what the analyses need, run them, collect results.

Result dict (DESIGN.md): {"scene", "model", "backend", "analyses": [{"name", "kind", "outputs", "seconds"}]}
plus "build" (kernels built, operation counts, stage times). Entries whose name
starts with "_" are working data and never reach JSON.

What a scene compiles is planned from model facts alone (mechgen.scene.plan), so a scene whose
kernels are cached or committed (mechgen/generated) runs without importing its model or sympy.
"""
from __future__ import annotations

import time
from functools import lru_cache, partial
from pathlib import Path
from typing import Mapping

from mechgen import models
from mechgen.analyses.context import NAME, POINTS, SCHEDULER, PointRunner, run_at_point
from mechgen.analyses.result import NumericalFailure, run_analysis
from mechgen.errors import InputError, MechgenError, SceneError
from mechgen.pipeline import compile_request, file_digest
from mechgen.runtime.fields.mesh import Layout
from mechgen.scene.info import lookup_model, model_info
from mechgen.scene.load import load_scene
from mechgen.scene.plan import derive_with, plan_scene, point_request, request_for
from mechgen.version import versions


@lru_cache(maxsize=8)
def system_of(source_key: str, request):
    """The compiled system of a request (mechgen.scene.plan); the model is imported only to derive.

    Memoised per process: a compiled system is immutable, so every analysis may share it.
    """
    return compile_request(request, derive_with(models.resolve(source_key), request))


def system_for(model_ref: str, values: tuple, free: tuple, active, kernels: tuple, backend: str, *,
               fresh: bool = False):
    """The compiled system (and build report) of scene-style values ``((name, value), ...)``: the
    benchmarks' entry; a scene run plans with :func:`mechgen.scene.plan.plan_scene`. ``fresh``
    bypasses the in-process memo (the on-disk compile cache is still used)."""
    source = models.resolve(model_ref)
    request = request_for(model_info(source.key), file_digest(source.file), dict(values), free=free, active=active,
                          kernels=kernels, backend=backend, source=source.key)
    build = system_of.__wrapped__ if fresh else system_of
    return build(source.key, request)


def laid_out(system, layout: Layout | None, mesh: str = ""):
    """The system with the scene's segments and parts, or a plane model's mesh file (a new system; the shared
    one stays bare)."""
    if mesh:
        from mechgen.runtime.plane.mesh import read_msh

        return system.with_mesh(read_msh(mesh))
    if layout is None or not (layout.segments or layout.parts):
        return system
    return system.with_layout(layout)


def sweep_point(task: tuple) -> dict:
    """Run the inner analysis of a sweep at one grid point (module level: picklable for worker processes)."""
    source_key, request, values, mesh, kind, options, point, layout = task
    info = model_info(source_key)  # the canonical reference: resolves in a worker process too
    system, _ = system_of(source_key, point_request(request, info, point) or request)
    system = laid_out(system, layout, mesh).with_param_vector(
        [float(point.get(n, dict(values).get(n, info.param(n).default))) for n in system.metadata.params])
    return run_at_point(kind, system, options)


def _point_task(scene: tuple, layout, kind: str, options: dict, point: dict) -> tuple:
    """The task sweep_point takes: the scene's compile inputs, the analysis, the point and the layout."""
    return (*scene, kind, options, point, layout)


def run_scene(scene, *, overrides=(), backend: str | None = None, scheduler: str | None = None) -> dict:
    """Run every analysis of a scene (a file, or a dict of its contents) and return the results dict.

    ``scheduler``: a running Dask scheduler's address (tcp://host:port) for the analyses with executor = "dask"
    (the user's choice: ``mechgen run --scheduler``; a scene cannot name one)."""
    if scheduler is not None:
        check_scheduler("scheduler", scheduler)
    scn = load_scene(scene if isinstance(scene, Mapping) else str(scene), overrides=list(overrides),
                     lookup_model=lookup_model, model_names=models.known)
    if scheduler is not None and not any(a.options.get("executor") == "dask" for a in scn.analyses):
        raise InputError(f"a scheduler is given but no analysis of {scn.path} has executor = \"dask\"",
                         key="scheduler", expected="executor = \"dask\" in the sweep or campbell analyses that "
                         "should run on the scheduler, or no scheduler")
    try:
        return _run_loaded(scn, backend, scheduler)
    except InputError as exc:
        if exc.file is not None:
            raise
        raise placed(exc, scn) from None


#: internal keys of late checks (runtime) -> the parameters that decide them
INTERNAL_KEYS = {"discretisation": ("N", "discretisation", "quadrature", "constraints", "joints"), "M": None}


def placed(exc: InputError, scn) -> SceneError:
    """A bad-input error found after loading (compiling, discretising, factorising M), which names no
    file, placed in the scene: its file, and for an internal key (``discretisation``, ``M``) the keys
    the scene wrote that decide it (``params.N = 0``), so that the user sees what to change; a parameter the user
    set on the command line is named by its flag (``--set quadrature``)."""
    note, key = "", exc.key
    name = exc.key[len("params."):] if isinstance(exc.key, str) and exc.key.startswith("params.") else None
    if name is not None and str(scn.written.get(name, "")).startswith("--set"):  # the user's flag decided it
        key = scn.written[name]
        note = f" (decided by what the scene sets: {scn.written[name]} = {scn.params[name]!r})"
    elif exc.key in INTERNAL_KEYS:
        names = INTERNAL_KEYS[exc.key]
        wanted = [n for n in scn.written if names is None or n in names]
        info = lookup_model(scn.source) if names is not None else None
        if info is not None and info.length in scn.written:
            wanted.append(info.length)
        wanted = sorted(dict.fromkeys(wanted), key=lambda n: not scn.written[n].startswith("--set"))  # flags first:
        shown = [f"{scn.written[n]} = {scn.params[n]!r}" for n in wanted][:8]  # the cap never drops the user's --set
        if scn.segments:
            shown.append("[[segments]]")
        if exc.key == "M":  # a part's values are lumped inertia: one of them can make M singular (issue 33 fuzz)
            shown += part_values(scn.parts)
        if shown:
            note = f" (decided by what the scene sets: {', '.join(shown)})"
    return SceneError(exc.message.rstrip(".") + note, file=scn.path, key=key, expected=exc.expected)


def part_values(parts) -> list[str]:
    """``'parts[i]' (kind at s): name = value, ...`` of each [[parts]] table (at most 8), for messages."""
    shown = [f"'parts[{i}]' ({p.kind} at {p.at:g}): " + ", ".join(f"{k} = {v!r}" for k, v in p.values.items())
             for i, p in enumerate(parts[:8], 1)]
    return shown + ([f"{len(parts) - 8} more [[parts]]"] if len(parts) > 8 else [])


def _run_loaded(scn, backend: str | None, scheduler: str | None = None) -> dict:
    """Compile and run a loaded scene."""
    plan = plan_scene(scn, backend=backend)
    fixed = tuple(sorted((k, v) for k, v in scn.params.items()))
    started = time.perf_counter()
    system, report = system_of(plan.source.key, plan.main)
    layout = Layout(scn.segments, scn.parts)
    system = laid_out(system, layout, scn.mesh)
    results = {"scene": Path(scn.path).name, "title": scn.title, "model": scn.model, "backend": report.backend,
               "params": dict(scn.params), "units": model_info(scn.source).units() if scn.source else {},
               "build": report.to_json(), "versions": versions(), "analyses": []}
    results["build"]["seconds_total"] = time.perf_counter() - started
    scene_inputs = (plan.source.key, plan.main, fixed, scn.mesh)
    context: dict = {POINTS: PointRunner(sweep_point, partial(_point_task, scene_inputs, layout))}
    if scheduler is not None:
        context[SCHEDULER] = scheduler
    for analysis in scn.analyses:
        context[NAME] = analysis.name
        try:
            result = run_analysis(analysis.name, analysis.kind, system, dict(analysis.options), context)
        except NumericalFailure as exc:
            raise with_partial(edge_parameters(exc, scn), results, analysis, scn) from None
        except MechgenError as exc:
            raise with_partial(exc, results, analysis, scn) from None
        context[analysis.name] = result.state
        results["analyses"].append(result.to_json())
        if result.working.get("_figure") is not None:  # a plane model's mesh and nodal values, for --plot only
            results.setdefault(FIGURES, {})[analysis.name] = result.working["_figure"]
    return results


#: the results' key of the figures' working data (never written to the JSON: mechgen.cli drops it)
FIGURES = "_figures"


#: a parameter beyond this magnitude (or nonzero below its inverse) is at the edge of the floating-point range:
#: its square, or its product with another such value, leaves it
EDGE = 1e150


def edge_parameters(exc: MechgenError, scn) -> MechgenError:
    """A numerical failure of a scene whose parameters hold values at the edge of the floating-point range
    (|x| > EDGE or 0 < |x| < 1/EDGE) is that value's fault: a SceneError (exit 2) at the key that wrote it
    (``params.k_r``, ``--set k_r``); otherwise the failure itself."""
    edge = [n for n, v in scn.params.items() if isinstance(v, (int, float)) and not isinstance(v, bool)
            and (abs(v) > EDGE or 0 < abs(v) < 1 / EDGE)]
    if not edge:
        return exc
    name = edge[0]
    return SceneError(f"{name} = {scn.params[name]!r} is at the edge of the floating-point range and the "
                      f"computation overflowed: {exc}", file=scn.path, key=scn.written.get(name, f"params.{name}"),
                      expected=f"a value of magnitude between {1 / EDGE:.0e} and {EDGE:.0e} (or 0); change the "
                               "model's units if the physics needs more")


def with_partial(exc: MechgenError, results: dict, analysis, scn) -> MechgenError:
    """The error of a failed analysis carrying the results so far as ``exc.partial_results``: the analyses
    before it, then an entry ``{"name", "kind", "outputs": {}, "error"}`` for it (the CLI prints them and
    writes them to --json before the error; the exit code stays the error's). A bad input found while
    running is placed in the scene first (:func:`placed`)."""
    if isinstance(exc, InputError) and exc.file is None:
        exc = placed(exc, scn)
    message = exc.paragraph() if isinstance(exc, InputError) else str(exc)
    results["analyses"].append({"name": analysis.name, "kind": analysis.kind, "outputs": {}, "seconds": 0.0,
                                "error": f"{type(exc).__name__}: {message}"})
    exc.partial_results = results
    return exc


def check_scheduler(key: str, address: str) -> str:
    """Validate a Dask scheduler address the user gave (``--scheduler``, ``scheduler=``) before anything connects."""
    from mechgen.runtime.core.sweep import SCHEDULER_FORM, scheduler_address

    try:
        return scheduler_address(address)
    except ValueError as exc:
        raise InputError(f"{address[:80]!r} is not a scheduler address: {exc}", key=key,
                         expected=SCHEDULER_FORM) from None


def check_backend(name: str | None) -> None:
    """Validate a --backend value."""
    if name is not None and name not in ("c", "numpy", "casadi"):
        raise InputError(f"unknown backend {name!r}", key="--backend", expected="c, numpy or casadi")
