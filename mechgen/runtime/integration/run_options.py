"""The options of a time integration, one object for every loop: the Python event loop
(mechgen.runtime.integration.events), the compiled one (events_c) and the smooth model's compiled loop (smooth_c).

:class:`RunOptions` holds how a run integrates (method, tolerances), what it samples, what bounds it
(budget, event rules), what it shows (progress), how a failure is explained, when it stops early and which
loop runs it; :class:`EventRules` the bounds of the events. The loops read these and nothing else, so the
same options give the same run in either loop (their rules: mechgen.runtime.integration.events' module doc).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from mechgen.runtime.core.options import Options


@dataclass(frozen=True)
class EventRules:
    """Bounds of the event loop: at most ``max_events`` events, and no more than ``zeno_events`` of them within
    ``zeno_span`` (None: 1e-9 t_end)."""

    max_events: int = 10_000
    zeno_events: int = 100
    zeno_span: float | None = None


@dataclass(frozen=True)
class RunOptions(Options):
    """How one time integration runs.

    Attributes:
        method: scipy's integrator (BDF, Radau, LSODA, RK45, DOP853); the compiled loops step DOP853, and a smooth
            lumped model's Radau (mechgen.runtime.integration.radau_c).
        rtol, atol: the integrator's tolerances (atol: a scalar, or one per state where the loop takes that).
        t_eval: the sample times (sorted, in [0, t_end]); None: every step end (and both sides of each event).
        budget: counts accepted steps and wall time (mechgen.runtime.core.budget.Budget), or None.
        rules: the bounds of the events (:class:`EventRules`).
        progress, desc: a progress bar in t and its label.
        explain: ``(t, x) -> str`` says what went wrong at a failing state (called on that path only).
        stop_after: ``event -> bool``, true ends the run after that event (an impact up to its release).
        loop: "auto" (the compiled loop where it can run), "python" or "c".
    """

    method: str = "Radau"
    rtol: float = 1e-8
    atol: float = 1e-10
    t_eval: Any = None
    budget: Any = None
    rules: EventRules = EventRules()
    progress: bool = False
    desc: str = "simulate"
    explain: Callable | None = None
    stop_after: Callable | None = None
    loop: str = "auto"

    def samples(self) -> np.ndarray | None:
        """``t_eval`` as a float array (None when every step is kept)."""
        return None if self.t_eval is None else np.asarray(self.t_eval, float)
