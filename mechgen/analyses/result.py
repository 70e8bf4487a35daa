"""The result of one analysis: what ``mechgen.modes(...)`` and friends return, and what a scene's run collects.

``Result.outputs`` holds the named outputs under the names the scene JSON uses (DESIGN.md,
"results contract"); ``to_json()`` is exactly the scene JSON's entry for the analysis
({"name", "kind", "outputs", "seconds"}); ``plot(directory)`` draws the kind's figures.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from mechgen.analyses.context import public
from mechgen.analyses.registry import get


@dataclass(frozen=True)
class Result:
    """One analysis's outputs.

    Attributes:
        name: the analysis's name (the scene's ``name``; in Python the kind unless given).
        kind: the analysis kind (``modes``, ``stability`` ...).
        outputs: output name -> number, list or table (JSON-ready).
        seconds: the wall time the analysis took.
        working: working data that later analyses use (a steady state's q, a BVP solution);
            never part of the JSON.
    """

    name: str
    kind: str
    outputs: dict
    seconds: float = 0.0
    working: dict = field(default_factory=dict, repr=False, compare=False)

    def __getitem__(self, key: str):
        return self.outputs[key]

    def __contains__(self, key: object) -> bool:
        return key in self.outputs

    def keys(self):
        """The output names."""
        return self.outputs.keys()

    @property
    def state(self) -> dict:
        """Outputs and working data together: what an analysis that builds on this one reads."""
        return {**self.outputs, **self.working}

    def to_json(self) -> dict:
        """{"name", "kind", "outputs", "seconds"}: the scene JSON's entry for this analysis."""
        return {"name": self.name, "kind": self.kind, "outputs": self.outputs, "seconds": self.seconds}

    def plot(self, directory, *, stem: str | None = None) -> list[Path]:
        """Write the kind's figures into ``directory`` as ``<stem>.png`` (default stem: the name) and
        companions (``<stem>_shapes.png`` ...); returns the paths (none for a kind with nothing to draw).
        Needs matplotlib (the ``plot`` extra)."""
        from mechgen.analyses.figures import pyplot

        draw = get(self.kind).plot
        if draw is None:
            return []
        plt = pyplot()
        folder = Path(directory)
        folder.mkdir(parents=True, exist_ok=True)
        return draw(plt, self.to_json(), folder / f"{stem or self.name}.png")


def run_analysis(name: str, kind: str, system, options: dict, context: dict) -> Result:
    """Run a validated analysis through its kind's runner and time it (a spent work budget is named by the
    analysis: ``simulate 'swing': ...``)."""
    from mechgen.runtime.core.budget import BudgetExceeded
    from mechgen.runtime.core.threads import blas_threads_for

    clock = time.perf_counter()
    try:
        with blas_threads_for(_unknowns(system)):
            outputs = get(kind).run(system, options, context)
    except BudgetExceeded as exc:
        raise exc.named(f"{kind} '{name}'") from None
    shown = public(outputs)
    working = {k: v for k, v in outputs.items() if k not in shown}
    return Result(name, kind, shown, time.perf_counter() - clock, working)


def _unknowns(system) -> int:
    """The size that decides the BLAS threads: the unknowns of a lumped model or a chain, a continuum's
    dof count (from its discretisation, which the analysis builds anyway)."""
    return int(system.n)
