"""The analysis kinds: one :class:`AnalysisKind` record per kind, registered by the kind's module.

The scene loader, ``run_scene``, the text summary, the plots and the Python API find a kind here
and never name one. Adding a kind: write ``mechgen/analyses/<kind>.py`` ending in
``register(AnalysisKind(...))`` and add its module to :data:`MODULES` (the registration line).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from mechgen.errors import InputError, did_you_mean

#: the modules that register a kind, in the order kinds are listed (scene messages, ``kinds()``)
MODULES = (
    "mechgen.analyses.modes",
    "mechgen.analyses.stability",
    "mechgen.analyses.steady",
    "mechgen.analyses.simulate",
    "mechgen.analyses.sweep",
    "mechgen.analyses.campbell",
    "mechgen.analyses.continuation",
    "mechgen.analyses.response",
    "mechgen.analyses.fit",
    "mechgen.analyses.impact",
    "mechgen.analyses.restitution",
    "mechgen.analyses.stability_boundary",
    "mechgen.analyses.spectrum",
    "mechgen.analyses.periodic",
    "mechgen.analyses.periodic_orbit",
    "mechgen.analyses.cross_section",
    "mechgen.analyses.symplectic",
    "mechgen.analyses.rod_statics",
    "mechgen.analyses.rod_dynamics",
    "mechgen.analyses.phase_boundary",
    "mechgen.analyses.phase_kinetics",
    "mechgen.analyses.orr_sommerfeld",
    "mechgen.analyses.shear_curve",
    "mechgen.analyses.channel_flow",
    "mechgen.analyses.channel_spectrum",
    "mechgen.analyses.crack_integrals",
)


def no_free(options: Mapping[str, Any]) -> list[str]:
    """The parameters of a kind that keeps none free in the kernels."""
    return []


@dataclass(frozen=True)
class AnalysisKind:
    """Everything mechgen knows about one analysis kind.

    Attributes:
        name: the scene's ``kind`` and the Python function's name.
        schema: option name -> :class:`mechgen.analyses.schema.Option` (checks and defaults).
        run: ``(system, options, context) -> outputs``; ``context`` maps earlier analyses' names to
            their outputs (see :mod:`mechgen.analyses.context`). Output names starting with ``_`` are
            working data (kept for later analyses, never in JSON).
        needs: ``(options, *, internal) -> set`` of kernel names the system must have.
        check: ``(ctx, base, options)``: cross-key checks after each option's own, or None.
        frees: ``options -> [parameter]``: parameters the analysis sets, so kept free in the kernels.
        summary: ``outputs -> [line]``: the text summary's lines for these outputs.
        plot: ``(plt, entry, path) -> [written paths]`` for a scene-JSON entry, or None (nothing to plot).
        sweepable: whether a sweep may repeat this kind over a grid.
        point_defaults: options a sweep's point takes where the sweep's table leaves them out, when they
            differ from a lone analysis's defaults (a simulate's ``series``: a grid of time histories would be
            the samples times the points).
    """

    name: str
    schema: Mapping[str, Any]
    run: Callable[..., dict]
    needs: Callable[..., set]
    summary: Callable[[dict], list[str]]
    check: Callable | None = None
    frees: Callable[[Mapping[str, Any]], list[str]] = no_free
    plot: Callable | None = None
    sweepable: bool = False
    point_defaults: Mapping[str, Any] = field(default_factory=dict)


_KINDS: dict[str, AnalysisKind] = {}
_loaded = False


def register(kind: AnalysisKind) -> AnalysisKind:
    """Add a kind (called once, at the end of the kind's module)."""
    if kind.name in _KINDS and _KINDS[kind.name] is not kind:
        raise ValueError(f"analysis kind {kind.name!r} is registered twice")
    kind = with_wall_time(kind)
    _KINDS[kind.name] = kind
    return kind


def with_wall_time(kind: AnalysisKind) -> AnalysisKind:
    """The kind with a ``max_seconds`` key if its schema has none: every kind's run is bounded in wall time
    (mechgen.runtime.core.budget.wall_clock, issue 33), so every kind lets a scene raise the bound."""
    if "max_seconds" in kind.schema:
        return kind
    from dataclasses import replace

    from mechgen.analyses.schema import ABSENT, Option, positive

    option = Option(positive, ABSENT, doc="the wall-time budget of the analysis (s, default 600): past it the run "
                    "stops with exit 1 naming this key")
    return replace(kind, schema={**kind.schema, "max_seconds": option})


def unregister(name: str) -> None:
    """Remove a kind registered at run time (a plugin's or a test's); the built-in ones stay."""
    if any(m.rsplit(".", 1)[1] == name for m in MODULES):
        raise ValueError(f"analysis kind {name!r} is built in")
    _KINDS.pop(name, None)


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in MODULES:
            importlib.import_module(module)
        _loaded = True


def kinds() -> tuple[str, ...]:
    """The registered kinds' names, in the order of :data:`MODULES`."""
    _load()
    return names()


def names() -> tuple[str, ...]:
    """The kinds' names without importing their modules: the built-in ones (a kind's module is named as the kind)
    in the order of :data:`MODULES`, then those registered at run time."""
    order = [m.rsplit(".", 1)[1] for m in MODULES]
    return tuple(order) + tuple(sorted(k for k in _KINDS if k not in order))


def get(name: str) -> AnalysisKind:
    """The kind called ``name`` (importing only its own module: a scene's start loads the kinds it names, not all
    of them); an InputError listing the kinds when there is none."""
    module = f"mechgen.analyses.{name}"
    if name not in _KINDS and module in MODULES:
        importlib.import_module(module)
    if name not in _KINDS:
        _load()
    if name not in _KINDS:
        raise InputError(f"unknown analysis kind {name!r}{did_you_mean(name, kinds())}", key="kind", expected="one of: " + ", ".join(kinds()))
    return _KINDS[name]


def needs(kind: str, options: Mapping[str, Any], *, internal: bool) -> set[str]:
    """The kernels an analysis of ``kind`` with ``options`` needs (``internal``: the model has internal variables)."""
    return get(kind).needs(options, internal=internal)


def sweepable_kinds(candidate: object = None) -> list[str]:
    """The kinds a sweep or a fit may repeat, as far as checking ``candidate`` needs them: ``[candidate]`` when it
    is one (only its module is imported), else every sweepable kind (all modules: for the message)."""
    if isinstance(candidate, str) and candidate in names() and get(candidate).sweepable:
        return [candidate]
    return [k for k in kinds() if get(k).sweepable]
