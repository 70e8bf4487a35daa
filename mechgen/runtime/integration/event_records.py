"""What an event run reports, shared by the Python event loop (mechgen.runtime.integration.events) and the compiled
one (mechgen.runtime.integration.events_c): the records (:class:`Event`, :class:`HybridTrajectory`), the Zeno stop
(:class:`ZenoApproach`) and the messages of a failure (:func:`diagnosis`, :func:`unnoticed`)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.core.budget import BudgetExceeded
from mechgen.runtime.core.diagnose import explain_state

#: what a Zeno error says a run that should end there can do
ZENO_HINT = "simulate's on_zeno = \"stop\" ends the run there, keeping the events so far"


class ZenoApproach(BudgetExceeded):
    """More than ``zeno_events`` events within ``zeno_span``: a Zeno accumulation or chattering (exit 1).

    ``trajectory`` is the run up to and including the event that tipped it (a HybridTrajectory whose
    ``t_final``, ``x_final`` and ``final_mode`` are those just after that event), so that an analysis that
    asks to stop there (``on_zeno = "stop"``) keeps the events so far."""

    trajectory = None

    def with_trajectory(self, trajectory) -> "ZenoApproach":
        """The same error carrying the run so far."""
        self.trajectory = trajectory
        return self


@dataclass(frozen=True)
class Event:
    """One event: time, the mode left and the mode entered (None: the run ended), the guard, the states."""

    t: float
    source: int
    target: int | None
    guard: str
    x_before: np.ndarray
    x_after: np.ndarray


@dataclass(frozen=True)
class HybridTrajectory:
    """Samples (t, x, mode index per sample), the events, and where the run ended."""

    t: np.ndarray
    x: np.ndarray
    mode: np.ndarray
    events: tuple
    final_mode: int
    t_final: float
    x_final: np.ndarray
    terminated: bool
    steps: int = 0
    nfev: int = 0
    njev: int = 0
    guard_evaluations: int = 0
    extra: dict = field(default_factory=dict)


def diagnosis(system, mode: int, t: float, x: np.ndarray) -> str:
    """Why the flow of ``mode`` fails at (t, x): the non-finite kernel output, a singular mass matrix or the
    largest rate, found on the mode's own kernels (diagnose.explain_state); "" when nothing is found."""
    try:
        flow = system.mode(mode)  # its own state (q, v, z): integrals a loop carries after it are left out
        return explain_state(flow, t, np.asarray(x, float)[:2 * flow.n + flow.m])
    except Exception:  # the diagnosis never hides the error it explains
        return ""


def unnoticed(guard: str, direction: int, mode: str, ta: float, tb: float, where: str) -> ConvergenceError:
    """The error of :class:`LeftSurface`: names the guard, the mode and the time (exit 1)."""
    way = "falling" if direction < 0 else "rising"
    return ConvergenceError(
        f"guard {guard} of mode {mode} ({way}) was crossed without an event between t = {ta:.17g} and "
        f"{tb:.17g} ({where}): the mode started on the guard's surface with zero rate (g = dg/dt = 0: a contact at "
        "rest, or the accumulation point of a Zeno sequence of events) and the state left it past zero the way "
        "of the guard, so no crossing can be located; the run is stopped rather than go on past the guard. "
        "Start the mode off the surface, model the contact as a mode of its own, or keep zeno_events low enough "
        f"(default 100) that the Zeno approach is caught first ({ZENO_HINT})")
