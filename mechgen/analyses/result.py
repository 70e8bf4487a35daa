"""The result of one analysis: what ``mechgen.modes(...)`` and friends return, and what a scene's run collects.

``Result.outputs`` holds the named outputs under the names the scene JSON uses (DESIGN.md,
"results contract"), JSON-ready; ``result[name]`` gives the same output as numpy arrays (a list of
numbers, or a rectangular nest of them, becomes an array; an object its values converted; strings
and lists of objects stay as they are). ``to_json()`` is exactly the scene JSON's entry for the
analysis ({"name", "kind", "outputs", "seconds"}); ``plot(directory)`` draws the kind's figures. A
Result prints the summary lines ``mechgen run`` prints, and renders as a table in a notebook.
"""
from __future__ import annotations

import difflib
import html
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mechgen.analyses.context import public
from mechgen.errors import ConvergenceError
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
        """The output ``key`` with numbers as numpy arrays (:func:`as_arrays`); a missing key lists those there
        are (and the closest one)."""
        if key not in self.outputs:
            raise KeyError(missing_key(key, self.outputs, f"{self.kind} result {self.name!r}"))
        return as_arrays(self.outputs[key])

    def __repr__(self) -> str:
        return "\n".join([f"Result {self.kind} {self.name!r} ({self.seconds:.3f} s)", *get(self.kind).summary(
            self.outputs)])

    def _repr_html_(self) -> str:
        """A two-column table (output, value as the summary shows it) for a notebook."""
        from mechgen.analyses.summary import fmt

        rows = "".join(f"<tr><td><code>{html.escape(str(k))}</code></td><td>{html.escape(fmt(v))}</td></tr>"
                       for k, v in self.outputs.items())
        return (f"<p><b>{html.escape(self.kind)}</b> {html.escape(repr(self.name))} ({self.seconds:.3f} s)</p>"
                f"<table><tr><th>output</th><th>value</th></tr>{rows}</table>")

    def __contains__(self, key: object) -> bool:
        return key in self.outputs

    def keys(self):
        """The output names."""
        return self.outputs.keys()

    def get(self, key: str, default=None):
        """The output ``key`` as ``result[key]`` gives it, or ``default`` when there is none."""
        return self[key] if key in self.outputs else default

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
        entry = {**self.to_json(), "units": self.working.get("units", {}),  # the parameters' units, for the axes
                 "figure": self.working.get("_figure")}  # a plane model's mesh and nodal values
        return draw(plt, entry, folder / f"{stem or self.name}.png")


def as_arrays(value):
    """A JSON-ready output as numpy: a list of numbers (or a rectangular nest of lists of numbers) becomes a
    float array (an integer array when every entry is an int), an object its values converted, a list of
    objects or strings stays a list (its objects converted); numbers and strings are returned as they are."""
    if isinstance(value, dict):
        return {k: as_arrays(v) for k, v in value.items()}
    if not isinstance(value, (list, tuple)):
        return value
    if _numeric(value):
        try:
            return np.asarray(value, dtype=int if _all_ints(value) else float)
        except (TypeError, ValueError):  # ragged: not one array
            pass
    return [as_arrays(v) for v in value]


def _numeric(value) -> bool:
    """True for a (nested) list whose leaves are all numbers (bool excluded) or None (a JSON null: nan)."""
    if isinstance(value, (list, tuple)):
        return len(value) > 0 and all(_numeric(v) for v in value)
    return value is None or (isinstance(value, (int, float, np.number)) and not isinstance(value, bool))


def _all_ints(value) -> bool:
    if isinstance(value, (list, tuple)):
        return all(_all_ints(v) for v in value)
    return isinstance(value, (int, np.integer))


def missing_key(key: object, present, where: str) -> str:
    """The message for a key that is not there: what was asked, the closest name, every name there is."""
    names = [str(k) for k in present]
    close = difflib.get_close_matches(str(key), names, n=1) if isinstance(key, str) else []
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return f"{key!r} is not an output of the {where}{hint}; its outputs: {', '.join(names) or '(none)'}"


class NumericalFailure(ConvergenceError):
    """A runner's stray numerical exception (overflow, NaN/Inf refused by a solver, a singular matrix that no
    diagnosis caught), turned into exit 1 with the analysis named (issue 33: never a traceback); a scene run
    names the parameters at the edge of the floating-point range when it has any
    (mechgen.scene.run.edge_parameters)."""


#: the stray numerical exceptions :func:`run_analysis` turns into a NumericalFailure (a ValueError only when it is
#: about NaN/Inf, as scipy's finite checks raise)
NUMERICAL = (np.linalg.LinAlgError, FloatingPointError, OverflowError, ZeroDivisionError, ValueError)


def run_analysis(name: str, kind: str, system, options: dict, context: dict) -> Result:
    """Run a validated analysis through its kind's runner and time it (a spent work budget is named by the
    analysis: ``simulate 'swing': ...``)."""
    from mechgen.runtime.core.budget import DEFAULT_SECONDS, BudgetExceeded, wall_clock
    from mechgen.runtime.core.threads import blas_threads_for

    clock = time.perf_counter()
    try:
        with blas_threads_for(_unknowns(system)), \
                wall_clock(float(options.get("max_seconds", DEFAULT_SECONDS)), "wall time"):
            outputs = get(kind).run(system, options, context)
    except BudgetExceeded as exc:
        raise exc.named(f"{kind} '{name}'") from None
    except (MemoryError, SystemError) as exc:  # an allocation no estimate foresaw (SuperLU's fill-in)
        raise NumericalFailure(f"{kind} '{name}' ran out of memory ({type(exc).__name__}: {str(exc)[:200]}); a "
                               "smaller size (N, elements, count) or a memory limit that allows it "
                               "(MECHGEN_MEMORY_LIMIT)") from None
    except NUMERICAL as exc:
        if isinstance(exc, ValueError) and not any(w in str(exc).lower() for w in ("inf", "nan", "finite")):
            raise
        raise NumericalFailure(f"{kind} '{name}' failed numerically ({type(exc).__name__}: {exc}); the numbers "
                               "left the floating-point range or a matrix was singular") from None
    shown = public(outputs)
    working = {k: v for k, v in outputs.items() if k not in shown}
    working.setdefault("units", parameter_units(system))
    return Result(name, kind, shown, time.perf_counter() - clock, working)


def parameter_units(system) -> dict[str, str]:
    """{parameter: declared unit} of the system's model (its compiled facts, else looked up by its reference;
    empty when neither is had), for the figures' axes."""
    facts = getattr(system, "facts", None)
    if facts is None:
        from mechgen.scene.info import lookup_model

        try:
            facts = lookup_model(system.metadata.reference) if system.metadata.reference else None
        except Exception:  # a system built by hand: no units, the figures label the names alone
            facts = None
    return facts.units() if facts is not None else {}


def _unknowns(system) -> int:
    """The size that decides the BLAS threads: the unknowns of a lumped model or a chain, a continuum's
    dof count (from its discretisation, which the analysis builds anyway)."""
    return int(system.n)
