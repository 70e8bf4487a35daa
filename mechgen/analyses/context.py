"""The context an analysis runs in (the runner's third argument).

A mapping from the names of the analyses run before it to their outputs (working entries ``_q``,
``_bvp`` ... included), so that ``about = "name"`` finds its steady state. A scene's run also
stores, under :data:`POINTS`, a :class:`PointRunner`: how an analysis is run at another parameter
point of the scene (a sweep's grid point, compiled again when the point sets a size). Analysis
names are identifiers that do not start with ``__``, so these keys cannot clash with one.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

#: context key of the scene's PointRunner
POINTS = "__points__"
#: context key of the running analysis's name (progress bars)
NAME = "__name__"
#: context key of the Dask scheduler address the user gave (mechgen run --scheduler, mechgen.run(scheduler=)):
#: the analyses with executor = "dask" connect to it; a scene itself cannot name one
SCHEDULER = "__scheduler__"


def scheduler_of(options: dict, context: dict) -> str | None:
    """The Dask scheduler an analysis's points go to: its own ``scheduler`` (a Python call's argument), else the
    one the user gave for the whole run, else None (Dask's scheduler-address setting, else a LocalCluster)."""
    return options.get("scheduler", context.get(SCHEDULER))


@dataclass(frozen=True)
class PointRunner:
    """``evaluate(task(kind, options, point))`` -> the public outputs of ``kind`` at ``point``.

    ``evaluate`` is a module-level function and tasks are plain data, so that points can run in
    other processes.
    """

    evaluate: Callable[[Any], dict]
    task: Callable[[str, dict, dict], Any]


def public(outputs: dict) -> dict:
    """The outputs without working entries (names starting with ``_``)."""
    return {k: v for k, v in outputs.items() if not k.startswith("_")}


def run_at_point(kind: str, system, options: dict) -> dict:
    """The public outputs of analysis ``kind`` on ``system`` (already set to the point's parameters) under the inner
    analysis's own wall-time budget: ``max_seconds`` of ``options`` (default 600 s) enforced by the SIGALRM backstop
    (mechgen.runtime.core.budget.wall_clock) also where the point runs in a worker process, whose main thread runs
    it. A point past its budget raises BudgetExceeded (key ``max_seconds``), which the sweep names with the point and
    the key under ``analysis`` (mechgen.runtime.core.sweep.inner_budget)."""
    from mechgen.analyses.registry import get
    from mechgen.runtime.core.budget import DEFAULT_SECONDS, wall_clock

    with wall_clock(float(options.get("max_seconds", DEFAULT_SECONDS)), f"{kind} at a sweep point"):
        return public(get(kind).run(system, options, {}))
