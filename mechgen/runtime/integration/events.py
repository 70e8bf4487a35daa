"""Event-driven integration of a hybrid system: integrate a mode, find its guards' zeros, reset, go on.

Between events the state x = (q, v, z) of mode i obeys dx/dt = f_i(t, x) (the mode's first-order
form, mechgen.runtime.core.system), integrated by scipy's ``OdeSolver`` classes step by step (the
implicit BDF/Radau/LSODA with the mode's generated Jacobian, or the explicit RK45/DOP853). After
every accepted step [t0, t1] the guards g_k of the mode are checked on the step, an event is
located on the step's dense output and the state there is recomputed to the integrator's own
accuracy; the reset then gives the state the next mode starts from.

Rules (the documented behaviour of each hard case; tests/test_hybrid_events.py checks each against a
closed form):

* **Crossing.** A guard fires when its sign changes the way of its direction (rising: - to +,
  falling: + to -, both: either) between two points of a step where it is evaluated. The sign
  tracked is the last nonzero one, so a guard that touches zero and turns back (**grazing**,
  g = (x - 1)^2 or -v^2 at an apex) never fires, and one that crosses at a tangency with a sign change
  (g = (x - 1)^3) fires once.
* **Missed events.** Every accepted step is checked at its ends with the values g and the rates
  dg/dt (the generated ``g_t`` kernel, with the integrator's own dx/dt at the step's end where it keeps
  one: RK45, DOP853, Radau; BDF and LSODA pay one extra dx/dt). An interval is halved (dense output,
  up to :data:`MAX_DEPTH` times: 2^-12 of the step), the earlier half checked first, while a guard of
  unchanged sign could hide two zeros in it: a zero is within reach of either end at that end's
  rate towards zero (s g_a <= h max(0, -s g_t,a), or the same backwards from b), the cubic Hermite
  interpolant through both ends dips through zero inside, or the end rates depart from the chord
  (|h g_t - (g_b - g_a)| at either end) by as much as g's larger distance from zero (g varies faster
  than the interval resolves: a fast t-dependent guard). An interval whose guard changed sign is
  halved while its cubic turns inside (the zero may not be the first). A guard on its surface moving
  away (just after a reset) costs nothing. So a pair of zeros is found when g stays past zero for
  longer than 2^-12 of the step and its zeros are more than that apart: for g = x - A sin(w t) with
  |x| ~ A/2 (past zero a third of each period) steps of up to 2^12/3 ~ 1365 periods; a pair closer than
  that, or hidden between two samples where g sits at its extremes with zero slopes (aliasing), can be
  missed, and at the depth limit the zero found in an interval holding several may not be the first.
  At the depth limit, an interval whose guard's cubic still dips through zero between two ends of its
  tracked sign is split at the cubic's extremum (kept within [1/16, 15/16] of the interval), up to
  :data:`DIP_DEPTH` more times: at 2^-12 of the step the cubic resolves g, and a narrow excursion past zero
  is sampled where it is deepest (a stick 1e6 times longer than the slip: a slip of 1e-6 rad in steps of
  0.1 rad, its guard past zero by 5e-13 of its scale, is found although it is 25 times narrower than
  2^-12 of the step).
  A guard varying faster than the steps costs up to 2^13 evaluations per step; an ordinary one one.
* **Location.** The zero is found by Brent's method on g along the dense output (to a few
  machine epsilons in t); the state there is integrated afresh from the step's start to that
  time (the dense output of the implicit methods is less accurate than their steps), and one
  Newton correction t* = t - g/g_t, x* = x + (t* - t) f(x) puts g to zero at that accuracy. The
  event time then carries the integrator's own error (Kelvin-Voigt restitution: error ~ rtol).
* **Simultaneous events.** The earliest zero wins; zeros within the location tolerance
  (:func:`time_tolerance`) of it, a guard crossing just after the interval included, are a tie, won
  by a terminal guard, then by the guard declared first (the order of HybridSystem.guards).
* **Start of a mode** (t = 0 or just after a reset). A guard within the location tolerance of
  zero at its rate (|g| <= |g_t| dt_tol, or g = 0) takes the sign it is moving to; it fires at once
  when that motion is its direction (an impact starting at contact, t = 0: the event is logged at
  t = 0), and not when it moves away. When g = 0 and g_t = 0 its sign is unknown: the first step's
  first 2^-12 is sampled for the first point where g is nonzero, and it fires only on a later crossing.
* **Unnoticed crossings.** A one-directional guard whose sign is unknown at the start of a mode (g = g_t = 0)
  and is first seen past zero the way of its direction (a ball at rest on the floor, or left there by a Zeno
  sequence whose resets no longer lift it) has been crossed without an event that can be located: the run ends
  with ConvergenceError (exit 1) naming the guard, the mode and the time, never goes on past the guard.
* **Zeno / chattering.** More than ``zeno_events`` events within ``zeno_span`` (default 1e-9
  t_end), or more than ``max_events`` in all, end the run with BudgetExceeded (exit 1) naming the
  time, the mode and the key; never a hang (each step's checks are bounded, and so is Brent).
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError, InputError, KernelError
from mechgen.runtime.core.budget import BudgetExceeded, Progress
from mechgen.runtime.core.integrate import IMPLICIT, METHODS
from mechgen.runtime.integration.event_records import (ZENO_HINT, Event, HybridTrajectory,
                                                        ZenoApproach, diagnosis, unnoticed)
from mechgen.runtime.integration.run_options import EventRules, RunOptions

#: the event loops: this module's ("python"), the compiled one ("c"), or the compiled one where it applies
LOOPS = ("auto", "python", "c")
#: a suspicious interval of a step is halved at most this many times (2^-12 of the step)
MAX_DEPTH = 12
#: levels of splitting at a guard's cubic dip beyond MAX_DEPTH (module doc, "Missed events")
DIP_DEPTH = 4
EPS = float(np.finfo(float).eps)


def time_tolerance(t: float, t_end: float) -> float:
    """The location tolerance in time: a guard within |g_t| times this of zero is on its surface."""
    return max(1e-12 * abs(t_end), 64 * EPS * abs(t))


def _solver_class(method: str):
    import scipy.integrate as si

    return {"BDF": si.BDF, "Radau": si.Radau, "LSODA": si.LSODA, "RK45": si.RK45, "DOP853": si.DOP853}[method]


class _Segment:
    """The flow of one mode with its guards: rhs, Jacobian, and the guard evaluations counted in ``counts``
    (``guards``: calls of the guard kernel; ``rates``: the extra dx/dt evaluations their rates needed)."""

    def __init__(self, system, mode: int, t_end: float, counts: dict) -> None:
        self.system = system
        self.index = mode
        self.view = system.mode(mode)
        self.guards = system.guards(mode)
        self.directions = np.array([g.direction for g in self.guards], dtype=float)
        self.t_end = t_end
        self.counts = counts

    def rhs(self, t, x):
        try:
            return self.view.rhs(t, x)
        except KernelError as exc:
            why = diagnosis(self.system, self.index, t, x)
            raise KernelError(f"{exc} in mode {self.system.modes[self.index]}" + (f"; {why}" if why else "")) from exc

    def jac(self, t, x):
        return self.view.jacobian(t, x)

    def values(self, t: float, x: np.ndarray, with_rates: bool = True, dxdt: np.ndarray | None = None):
        """(g, g_t) at (t, x); g_t from the mode's dx/dt there (``dxdt`` when the integrator has it; zeros
        without ``with_rates``)."""
        self.counts["guards"] += 1
        if with_rates and dxdt is None:
            self.counts["rates"] += 1
            dxdt = self.rhs(t, x)
        g, g_t = self.system.guard_values(self.index, t, x, dxdt if with_rates else None)
        return g, (g_t if with_rates else np.zeros_like(g))


def _interior_extrema(ga: float, da: float, gb: float, db: float, h: float) -> list[tuple[float, float]]:
    """(u, p(u)) at the extrema in (0, 1), in order, of the cubic Hermite p(u) = ga + c1 u + c2 u^2 + c3 u^3
    through (ga, h da) and (gb, h db): the roots of p'(u) = c1 + 2 c2 u + 3 c3 u^2 (the stable quadratic
    formula)."""
    c1, c2, c3 = h * da, 3 * (gb - ga) - h * (2 * da + db), 2 * (ga - gb) + h * (da + db)
    crit: list[float] = []
    if c3 != 0.0:
        disc = c2 * c2 - 3 * c1 * c3
        if disc >= 0.0:
            q = -(c2 + math.copysign(math.sqrt(disc), c2))
            crit = [q / (3 * c3)] + ([c1 / q] if q != 0.0 else [])
    elif c2 != 0.0:
        crit = [-c1 / (2 * c2)]
    return [(u, ga + u * (c1 + u * (c2 + u * c3))) for u in sorted(u for u in crit if 0.0 < u < 1.0)]


def _hermite(s: float, ga: float, da: float, gb: float, db: float, h: float) -> tuple[int, bool]:
    """The cubic Hermite p(u), u in [0, 1], through (ga, h da) and (gb, h db): its sign changes counted along
    its value at 0 (taken as the tracked sign ``s``), at its interior extrema and at 1; whether it has an
    interior extremum."""
    inside = _interior_extrema(ga, da, gb, db, h)
    changes, last = 0, s
    for value in [value for _, value in inside] + [gb]:
        if value != 0.0 and math.copysign(1.0, value) != last:
            changes, last = changes + 1, -last
    return changes, bool(inside)


def _suspicious(sign: np.ndarray, ga, da, gb, db, h: float, at_start: bool) -> bool:
    """Whether the interval of length h with ends (ga, da), (gb, db) must be halved (module doc, "Missed
    events"): for a guard whose tracked sign ``sign`` holds at both ends, a zero is within reach of either
    end at its rate or the cubic Hermite dips through zero inside; for one whose sign flipped, the cubic
    turns inside (the zero may not be the only one); for one of unknown sign (g = g_t = 0 at the start of
    the mode), the interval starts the mode."""
    for k in range(len(sign)):
        s = float(sign[k])
        if s == 0.0:
            if at_start:
                return True
            continue
        a, ra, b, rb = float(ga[k]), float(da[k]), float(gb[k]), float(db[k])
        if b != 0.0 and math.copysign(1.0, b) != s:  # flipped
            if _hermite(s, a, ra, b, rb, h)[1]:
                return True
            continue
        toward_a, toward_b = -s * ra, s * rb  # rates towards zero: forwards from a, backwards from b
        if (toward_a > 0 and s * a <= h * toward_a) or (toward_b > 0 and s * b <= h * toward_b):
            return True
        chord = b - a  # unresolved: the rates depart from the chord by as much as g's distance from zero
        if max(abs(h * ra - chord), abs(h * rb - chord)) >= max(s * a, s * b):
            return True
        if _hermite(s, a, ra, b, rb, h)[0] > 0:
            return True
    return False


def _dip(s: float, ga: float, da: float, gb: float, db: float, h: float) -> float | None:
    """u in (0, 1) of the first interior extremum at which the cubic Hermite through (ga, h da), (gb, h db)
    is past zero (sign -s) while both ends keep the sign s; None when it has none."""
    if ga == 0.0 or gb == 0.0 or math.copysign(1.0, ga) != s or math.copysign(1.0, gb) != s:
        return None
    for u, value in _interior_extrema(ga, da, gb, db, h):
        if value != 0.0 and math.copysign(1.0, value) != s:
            return u
    return None


def split_point(sign: np.ndarray, ga, da, gb, db, ta: float, tb: float, depth: int) -> float | None:
    """Where a suspicious interval [ta, tb] at ``depth`` is split (module doc, "Missed events"): the midpoint
    above :data:`MAX_DEPTH`; below it, for up to :data:`DIP_DEPTH` more levels, the extremum of the first
    guard whose cubic Hermite dips through zero between two ends of its tracked sign, kept within
    [1/16, 15/16] of the interval; else None (not split)."""
    if depth < MAX_DEPTH:
        return 0.5 * (ta + tb)
    if depth >= MAX_DEPTH + DIP_DEPTH:
        return None
    h = tb - ta
    for k in range(len(sign)):
        if sign[k] != 0.0:
            u = _dip(float(sign[k]), float(ga[k]), float(da[k]), float(gb[k]), float(db[k]), h)
            if u is not None:
                return ta + min(max(u, 1.0 / 16), 15.0 / 16) * h
    return None


def _crossed(sign: np.ndarray, g: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Guards whose tracked sign ``sign`` flips to the sign of g the way of their direction."""
    new = np.sign(g)
    flip = (sign != 0) & (new != 0) & (new == -sign)
    return flip & ((directions == 0) | (directions == new))


def integrate_hybrid(system, x0, t_end: float, *, mode: int | None = None, options: RunOptions | None = None,
                     **changes) -> HybridTrajectory:
    """Integrate a :class:`~mechgen.runtime.core.hybrid_system.HybridSystem` from x0 at t = 0 in ``mode``
    (default its initial mode) to t_end or a terminal event, by the rules of the module doc.

    ``options`` (mechgen.runtime.integration.run_options.RunOptions; its fields may also be given as keywords, which
    change it): samples are taken at ``t_eval`` (sorted, in [0, t_end]), else at every step end and on both
    sides of every event. ``budget`` counts accepted steps; ``rules`` bound the events;
    ``stop_after(event)`` true ends the run after that event (an impact measured up to its release).
    ``loop``: "python" (this loop), "c" (the compiled loop of mechgen.runtime.integration.events_c: DOP853 on
    the C backend) or "auto" (the compiled one where it can run, else this one).
    """
    options = RunOptions.of(options, **changes)
    compiled = _compiled_loop(system, x0, t_end, mode, options)
    if compiled is not None:
        return compiled
    if options.method not in METHODS:
        raise ValueError(f"unknown method {options.method!r}; expected one of {METHODS}")
    run = _EventRun(system, float(t_end), options, np.size(x0))
    mode = system.initial_mode if mode is None else int(mode)
    t, x = 0.0, np.array(x0, float)
    run.record(t, x, mode)
    try:
        with Progress(run.t_end, desc=options.desc, unit="t", enabled=options.progress) as bar:
            mode, t, x = _run_modes(run, mode, (t, x), options, bar)
    except ZenoApproach as exc:  # the run so far, up to the event that made it Zeno (on_zeno = "stop")
        last = run.events[-1]
        run.stats["zeno"] = exc
        mode = last.source if last.target is None else last.target
        t, x, run.terminated = last.t, last.x_after, True
    trajectory = run.trajectory(mode, t, x)
    if "zeno" in run.stats:
        raise run.stats["zeno"].with_trajectory(trajectory)
    return trajectory


def _compiled_loop(system, x0, t_end: float, mode, options: RunOptions) -> HybridTrajectory | None:
    """The run by the compiled DOP853 loop (mechgen.runtime.integration.events_c) where ``loop`` allows it and it
    can run; None for this loop (InputError when ``loop`` is 'c' and it cannot run)."""
    method, rtol, atol = options.method, options.rtol, options.atol
    if options.loop not in LOOPS:
        raise ValueError(f"unknown loop {options.loop!r}; expected one of {LOOPS}")
    if options.loop != "python" and method in METHODS:
        from mechgen.runtime.integration.events_c import c_loop_problem, integrate_hybrid_c

        why = c_loop_problem(system, method, rtol, atol)
        if why is None:
            return integrate_hybrid_c(system, x0, t_end, mode=mode, options=options)
        if options.loop == "c":
            raise InputError(f"loop 'c' cannot run here: {why}", key="loop",
                             expected="method DOP853 on the C backend with a C compiler, or loop 'auto'/'python'")
    return None


def _run_modes(run: "_EventRun", mode: int, state: tuple, options: RunOptions, bar) -> tuple:
    """Mode after mode from ``state`` = (t, x) until t_end, a terminal event or ``stop_after``: the last
    (mode, t, x)."""
    t, x = state
    while True:
        t, x, target, ended = _next_event(run, mode, (t, x), options, bar)
        if ended:
            return mode, t, x
        if target is None or (options.stop_after is not None and options.stop_after(run.events[-1])):
            run.terminated = True
            return (mode if target is None else target), t, x
        mode = target


def _next_event(run: "_EventRun", mode: int, state: tuple, options: RunOptions, bar) -> tuple:
    """From ``state`` = (t, x) at the start of ``mode``: (t, x, the mode entered (None: terminal), False) after
    the next event (a guard active at once, or one that fires during the mode), or (t, x, None, True) at t_end."""
    t, x = state
    seg = run.segment(mode)
    g0, d0 = _start_values(seg, t, x, options.method, run.where)
    sign, at_once = start_signs(g0, d0, seg.directions, time_tolerance(t, run.t_end))
    if at_once:  # the guards are in priority order: terminal first, then declared order
        target, x = run.fire(seg, at_once[0], t, x)
        run.record(t, x, mode if target is None else target)
        return t, x, target, False
    if t >= run.t_end:
        return t, x, None, True
    hit = _integrate_segment(seg, (t, x), (g0, d0), sign, options, run.stats,
                             _Hooks(run.sample_until, run.record, bar, run.where))
    if hit is None:
        return run.t_end, run.stats["y_end"], None, True
    k, t, x_before = hit
    run.sample_until(t, run.stats["dense"], mode, inclusive=True)
    target, x = run.fire(seg, k, t, x_before)
    run.record(t, x_before, mode)
    run.record(t, x, mode if target is None else target)
    return t, x, target, False


class _EventRun:
    """What the Python event loop has recorded so far: the samples (at t_eval, or at every step end and both
    sides of every event), the events, the recent event times the Zeno rule reads, the counters; and the
    event itself (:meth:`fire`: the reset, the log entry, the bounds of the events)."""

    def __init__(self, system, t_end: float, options: RunOptions, size: int) -> None:
        self.system, self.t_end, self.options, self.size = system, t_end, options, size
        rules = options.rules
        self.rules = rules
        self.zeno_span = rules.zeno_span if rules.zeno_span is not None else 1e-9 * t_end
        self.t_eval = options.samples()
        self.ts: list = []
        self.xs: list = []
        self.ms: list = []
        self.events: list[Event] = []
        self.recent: deque = deque(maxlen=max(2, rules.zeno_events + 1))
        self.stats = {"steps": 0, "nfev": 0, "njev": 0}
        self.counts = {"guards": 0, "rates": 0}
        self.segments: dict[int, _Segment] = {}
        self.i_eval = 0
        self.terminated = False

    def segment(self, mode: int) -> "_Segment":
        if mode not in self.segments:
            self.segments[mode] = _Segment(self.system, mode, self.t_end, self.counts)
        return self.segments[mode]

    def sample_until(self, t_hi: float, dense, seg: int, inclusive: bool) -> None:
        """The samples at t_eval up to t_hi (inclusive or not) from the last step's dense output."""
        if self.t_eval is None:
            return
        i_new = int(np.searchsorted(self.t_eval, t_hi, side="right" if inclusive else "left"))
        if i_new > self.i_eval:
            chunk = self.t_eval[self.i_eval:i_new]
            self.ts.append(chunk)
            self.xs.append(np.atleast_2d(dense(chunk).T))
            self.ms.append(np.full(len(chunk), seg))
            self.i_eval = i_new

    def record(self, tk: float, xk: np.ndarray, seg: int) -> None:
        """A sample at (tk, xk) in mode seg, when samples are every step end (no t_eval)."""
        if self.t_eval is None:
            self.ts.append(np.array([tk]))
            self.xs.append(np.array(xk, float)[None, :])
            self.ms.append(np.array([seg]))

    def where(self, tk: float, seg: int) -> str:
        return f"t = {tk:.9g} of t_end = {self.t_end:.6g} in mode {self.system.modes[seg]}"

    def fire(self, seg: "_Segment", k: int, tk: float, xk: np.ndarray) -> tuple[int | None, np.ndarray]:
        """Guard k of seg fires at (tk, xk): (the mode entered, None for a terminal event; the state after it);
        BudgetExceeded past max_events, ZenoApproach past zeno_events within zeno_span."""
        info, rules, recent = seg.guards[k], self.rules, self.recent
        x_after = xk if info.reset is None else self.system.reset(info.reset, tk, xk)
        if not np.all(np.isfinite(x_after)):
            raise KernelError(f"reset of guard {info.name} gave NaN/Inf at {self.where(tk, seg.index)}")
        target = None if info.terminal else info.to
        self.events.append(Event(tk, seg.index, target, info.name, np.array(xk), np.array(x_after)))
        recent.append(tk)
        if len(self.events) > rules.max_events:
            raise BudgetExceeded(f"events: more than max_events = {rules.max_events:,} events", key="max_events",
                                 reached=self.where(tk, seg.index))
        if len(recent) == recent.maxlen and recent[-1] - recent[0] <= self.zeno_span:
            raise ZenoApproach(f"events: {len(recent)} events within {recent[-1] - recent[0]:.3g} (more than "
                               f"zeno_events = {rules.zeno_events} within zeno_span = {self.zeno_span:.3g}): a Zeno "
                               f"or chattering approach (guard {info.name} of mode {self.system.modes[seg.index]}); "
                               f"{ZENO_HINT}", key="zeno_events", reached=self.where(tk, seg.index))
        return target, x_after

    def trajectory(self, mode: int, t: float, x: np.ndarray) -> HybridTrajectory:
        """The HybridTrajectory of the run, ended in ``mode`` at (t, x)."""
        t_out = np.hstack(self.ts) if self.ts else np.empty(0)
        x_out = np.vstack(self.xs) if self.xs else np.empty((0, self.size))
        m_out = np.hstack(self.ms).astype(int) if self.ms else np.empty(0, int)
        return HybridTrajectory(t_out, x_out, m_out, tuple(self.events), mode, float(t), np.array(x),
                                self.terminated, self.stats["steps"], self.stats["nfev"], self.stats["njev"],
                                self.counts["guards"], {"rate_evaluations": self.counts["rates"]})


def start_signs(g0: np.ndarray, d0: np.ndarray, directions: np.ndarray, tol: float):
    """The tracked signs of the guards at the start of a mode, and the guards that fire there at once (module
    doc, "Start of a mode"): a guard on its surface (g = 0, or |g| <= |g_t| tol) takes the sign it moves to
    (0 when g_t = 0 too: unknown until a point where g is nonzero) and fires when that is its direction."""
    surface = (g0 == 0) | (np.abs(g0) <= np.abs(d0) * tol)
    sign = np.where(surface, np.sign(d0), np.sign(g0))
    at_once = [int(k) for k in np.flatnonzero(surface & (sign != 0)) if directions[k] in (0, sign[k])]
    return sign, at_once


def _end_rate(solver, seg, t: float, y: np.ndarray) -> np.ndarray:
    """dx/dt at the step's end: the integrator's own (RK45, DOP853, Radau keep it), else evaluated."""
    f = getattr(solver, "f", None)
    if f is not None and getattr(solver, "t", None) == t:
        return np.asarray(f)
    seg.counts["rates"] += 1
    return seg.rhs(t, y)


@dataclass(frozen=True)
class _Hooks:
    """What one mode's integration reports to the loop around it: samples up to a time, step records, the
    progress bar, and where a time is (for messages)."""

    sample_until: Callable
    record: Callable
    bar: Progress
    where: Callable


def _start_values(seg, t: float, x: np.ndarray, method: str, where) -> tuple:
    """The guards' (g, g_t) where a mode starts; a singular mass there (a zero mass in that mode) is a
    ConvergenceError with its diagnosis, as inside a step, never a bare LinAlgError."""
    from numpy.linalg import LinAlgError

    try:
        return seg.values(t, x)
    except (LinAlgError, ZeroDivisionError) as exc:
        why = diagnosis(seg.system, seg.index, t, np.array(x))
        raise ConvergenceError(f"{method} failed near {where(t, seg.index)} ({exc})" + (f"; {why}" if why else "")) \
            from None


def _integrate_segment(seg, state: tuple, start, sign, options: RunOptions, stats: dict, hooks: _Hooks):
    """Integrate one mode from ``state`` = (t, x) until a guard fires (-> (guard, t*, x*)) or t_end (-> None).
    ``start``: the guards' (g, g_t) at (t, x); ``sign``: their tracked signs there."""
    from numpy.linalg import LinAlgError

    t, x = state
    y_old, t_old = np.array(x), t
    try:
        solver = _start_solver(seg, t, x, options)
        g_old, d_old = start
        t_start = t
        while solver.status == "running":
            t_new, y_new, dense = _take_step(solver, seg, options.method, stats, hooks.where)
            g_new, d_new = seg.values(t_new, y_new, dxdt=_end_rate(solver, seg, t_new, y_new))
            found = _scan_step(seg, dense, sign, (t_old, g_old, d_old), (t_new, g_new, d_new), t_start, hooks.where)
            if found is not None:
                k, t_root, t_lo, t_hi = found
                t_star, x_star = _locate(seg, dense, k, (t_root, t_lo, t_hi), (t_old, y_old), options)
                _count_evaluations(stats, solver)
                return k, t_star, x_star
            _accepted(seg, (t_new, y_new, dense), options.budget, hooks)
            t_old, y_old, g_old, d_old = t_new, y_new, g_new, d_new
    except (LinAlgError, ZeroDivisionError, ValueError) as exc:
        explain = options.explain
        why = diagnosis(seg.system, seg.index, t_old, y_old) or (explain(t_old, y_old) if explain is not None else "")
        raise ConvergenceError(f"{options.method} failed near {hooks.where(t_old, seg.index)} ({exc})"
                               + (f"; {why}" if why else "")) from exc
    _count_evaluations(stats, solver)
    stats["y_end"] = np.array(solver.y)
    return None


def _start_solver(seg, t: float, x, options: RunOptions):
    """scipy's stepper of ``options.method`` on the mode's dx/dt from (t, x) towards t_end."""
    kwargs = {"jac": seg.jac} if options.method in IMPLICIT else {}
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _solver_class(options.method)(seg.rhs, t, x, seg.t_end, rtol=options.rtol, atol=options.atol,
                                             **kwargs)


def _take_step(solver, seg, method: str, stats: dict, where) -> tuple:
    """One accepted step: (t, y, the step's dense output, also kept as stats['dense']); ConvergenceError when
    the stepper fails, KernelError when the state is not finite."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        message = solver.step()
    if solver.status == "failed":
        raise ConvergenceError(f"{method} stopped at {where(solver.t, seg.index)}: "
                               f"{str(message).rstrip('.')}")
    stats["steps"] += 1
    t_new, y_new = solver.t, np.array(solver.y)
    if not np.all(np.isfinite(y_new)):
        raise KernelError(f"{method}: state became NaN/Inf by {where(t_new, seg.index)}")
    dense = solver.dense_output()
    stats["dense"] = dense
    return t_new, y_new, dense


def _scan_step(seg, dense, sign, a, b, t_start, where):
    """:func:`_scan` of the step [a, b], a guard that left its surface unnoticed raised as its error."""
    try:
        return _scan(seg, dense, sign, a, b, t_start)
    except LeftSurface as left:
        info = seg.guards[left.k]
        raise unnoticed(info.name, info.direction, seg.system.modes[seg.index], left.ta, left.tb,
                        where(left.tb, seg.index)) from None


def _accepted(seg, step: tuple, budget, hooks: _Hooks) -> None:
    """A step (t, y, dense output) without an event: its samples and record, one unit of the budget, the bar."""
    t_new, y_new, dense = step
    hooks.sample_until(t_new, dense, seg.index, inclusive=True)
    hooks.record(t_new, y_new, seg.index)
    if budget is not None:
        budget.spend(1, lambda: hooks.where(t_new, seg.index))
    hooks.bar.to(t_new)


def _count_evaluations(stats: dict, solver) -> None:
    stats["nfev"] += solver.nfev
    stats["njev"] += getattr(solver, "njev", 0)


def _scan(seg, dense, sign, a, b, t_start):
    """The earliest crossing of the step [a, b]: (guard, its zero, t_lo, t_hi bracketing it), or None.

    ``a`` and ``b`` are (t, g, g_t) at the step's ends; ``sign`` (updated in place along the way) the
    tracked signs at the start; ``t_start`` the time the mode started. Suspicious intervals are halved
    (module doc, "Missed events"), the earlier half first."""
    directions = seg.directions
    stack = [(a, b, 0)]
    while stack:
        (ta, ga, da), (tb, gb, db), depth = stack.pop()
        tm = None
        if depth < MAX_DEPTH + DIP_DEPTH and _suspicious(sign, ga, da, gb, db, tb - ta, ta == t_start):
            tm = split_point(sign, ga, da, gb, db, ta, tb, depth)
        if tm is not None:
            gm, dm = seg.values(tm, dense(tm))
            stack.append(((tm, gm, dm), (tb, gb, db), depth + 1))
            stack.append(((ta, ga, da), (tm, gm, dm), depth + 1))
            continue
        crossed = _crossed(sign, gb, directions)
        if crossed.any():
            return _first(seg, dense, sign, crossed, ta, tb)
        nonzero = np.sign(gb) != 0
        left = np.flatnonzero((sign == 0) & nonzero & (directions != 0) & (np.sign(gb) == directions))
        if left.size:
            raise LeftSurface(int(left[0]), ta, tb)
        sign[...] = np.where(nonzero, np.sign(gb), sign)
    return None


class LeftSurface(Exception):
    """A one-directional guard of unknown sign (g = g_t = 0 where its mode started) first seen past zero in its
    own direction: the state crossed it without an event (module doc, "Unnoticed crossings")."""

    def __init__(self, k: int, ta: float, tb: float) -> None:
        super().__init__(k, ta, tb)
        self.k, self.ta, self.tb = k, ta, tb


def _first(seg, dense, sign, crossed, ta: float, tb: float):
    """(guard, zero, t_lo, t_hi) of the winner among the guards crossing in [ta, tb] and those crossing
    within the location tolerance after the earliest zero (module doc, "Simultaneous events")."""
    roots = {int(k): _root(seg, dense, int(k), ta, tb) for k in np.flatnonzero(crossed)}
    t_first = min(roots.values())
    t_tie = t_first + time_tolerance(t_first, seg.t_end)
    t_hi = {k: tb for k in roots}
    others = ~crossed & (sign != 0)
    if t_tie > tb and others.any():
        g_tie, _ = seg.values(t_tie, dense(t_tie), with_rates=False)
        for k in np.flatnonzero(_crossed(sign, g_tie, seg.directions) & others):
            roots[int(k)], t_hi[int(k)] = _root(seg, dense, int(k), ta, t_tie), t_tie
    k = min(k for k, r in roots.items() if r <= t_tie)  # the guards are in priority order
    return k, roots[k], ta, t_hi[k]


def _root(seg, dense, k: int, ta: float, tb: float) -> float:
    """The zero of guard k on [ta, tb] along the dense output (Brent's method, a few epsilons in t)."""
    from scipy.optimize import brentq

    def g(tt):
        return seg.values(tt, dense(tt), with_rates=False)[0][k]

    ga, gb = g(ta), g(tb)
    if ga == 0:
        return ta
    if gb == 0 or np.sign(ga) == np.sign(gb):
        return tb
    return brentq(g, ta, tb, xtol=4 * EPS * max(abs(ta), abs(tb), 1e-300), rtol=4 * EPS, maxiter=200)


def _locate(seg, dense, k: int, bracket: tuple, start: tuple, options: RunOptions):
    """(t*, x*) of guard k's zero on the dense output (``bracket`` = (t_d, t_lo, t_hi): the zero and the interval
    holding it): the state integrated afresh from the step's start ``start`` = (t_old, y_old) to t_d by the run's
    method and tolerances, and one Newton correction on g."""
    t_d, t_lo, t_hi = bracket
    t_old, y_old = start
    if t_d > t_old:
        jac = {"jac": seg.jac} if options.method in IMPLICIT else {}
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            fresh = _solver_class(options.method)(seg.rhs, t_old, y_old, t_d, rtol=options.rtol, atol=options.atol,
                                                  first_step=t_d - t_old, **jac)
            while fresh.status == "running":
                fresh.step()
        x_d = np.array(fresh.y) if fresh.status == "finished" else dense(t_d)
    else:
        x_d = np.array(y_old)
    f = seg.rhs(t_d, x_d)
    g, g_t = seg.values(t_d, x_d, dxdt=f)
    if g_t[k] != 0 and abs(g[k] / g_t[k]) <= max(t_hi - t_lo, time_tolerance(t_d, seg.t_end)):
        dt = -g[k] / g_t[k]
        return t_d + dt, x_d + dt * f
    return t_d, x_d


__all__ = ["DIP_DEPTH", "EPS", "Event", "EventRules", "HybridTrajectory", "LOOPS", "LeftSurface", "MAX_DEPTH",
           "RunOptions", "ZENO_HINT", "ZenoApproach", "diagnosis", "integrate_hybrid", "split_point", "start_signs",
           "time_tolerance", "unnoticed"]
