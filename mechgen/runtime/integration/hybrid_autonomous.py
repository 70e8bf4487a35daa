"""Autonomous periodic orbits of a hybrid model: the return map to a Poincare section at an event, by shooting.

An autonomous hybrid model (a mass on a moving belt with dry friction: stick-slip) has orbits of unknown period. The
phase is fixed by a **section**: a guard of the model (the stick -> slip transition, say), the orbit starting just
after that guard's event, in the mode it leads to, with the state x0 after the event's reset. The return map P
takes x0 to the state just after the next event of the section's guard, at the return time tau(x0) (the period):
the run stops there (the event loop's ``stop_after``), so no event ever sits at the end of an interval of fixed
length. The orbit is the fixed point x0 = P(x0), found by Newton with the Jacobian

    P_x = S Phi + f+ (d tau / d x0),   d tau / d x0 = -g_x Phi / (dg/dt),

Phi the flow's Jacobian through the events before the return (the modes' state-transition matrices and the
events' saltation matrices: mechgen.runtime.integration.hybrid_monodromy), S the return event's saltation matrix,
g_x and dg/dt the section guard's gradient and rate just before it, f+ dx/dt just after it (the derivative of the
return state with the return time free: Leine & Nijmeijer 2004, sec. 7.2; di Bernardo et al. 2008, sec. 2.5).

The orbit's **monodromy** is M = S Phi at the return (perturbations at t = 0 carried once around at fixed time T):
M f+ = f+, so one multiplier is 1 (the trivial one, along the orbit); P_x has 0 in its place and the same others.
A phase of the orbit in which some state components are held (the stick phase, x' = v_belt) sets their
perturbations to zero (the reset's R_x), so M is rank-deficient and each such direction gives a multiplier 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.integration.events import integrate_hybrid
from mechgen.runtime.integration.hybrid_monodromy import grazes, guard_index, transition
from mechgen.runtime.integration.run_options import RunOptions


@dataclass(frozen=True)
class ReturnMap:
    """P(x0) (the state just after the return event), the return time ``period``, the monodromy S Phi, the return
    map's Jacobian ``jacobian``, the events up to and with the return, and those that graze (positions)."""

    x: np.ndarray
    period: float
    monodromy: np.ndarray
    jacobian: np.ndarray
    events: tuple
    grazing: tuple


def section_run(system, x0: np.ndarray, mode: int, section: str, horizon: float, rtol: float, atol: float):
    """The event-driven run from x0 at t = 0 in ``mode`` until just after the first event of guard ``section``
    (DOP853: the compiled loop where it applies); ConvergenceError when it does not come before ``horizon``."""
    run = integrate_hybrid(system, np.asarray(x0, float), horizon, mode=mode,
                           options=RunOptions(method="DOP853", rtol=rtol, atol=atol, t_eval=np.array([horizon]),
                                              progress=False, stop_after=lambda event: event.guard == section))
    if not run.events or run.events[-1].guard != section:
        raise ConvergenceError(f"the orbit from the guess does not return to the section (guard {section!r}) "
                               f"within t = {horizon:.6g} (3 times the period's guess): give a period guess "
                               "nearer the orbit's, or a starting state nearer it")
    return run


def return_map(system, x0, mode: int, section: str, horizon: float, *, rtol: float = 1e-11,
               atol: float = 1e-13) -> ReturnMap:
    """P(x0), its Jacobian and the monodromy (module doc)."""
    x0 = np.asarray(x0, float)
    events = tuple(section_run(system, x0, mode, section, horizon, rtol, atol).events)
    phi, t, x, current, grazing = np.eye(x0.size), 0.0, x0, int(mode), []
    for i, event in enumerate(events):
        phi = transition(system, current, t, event.t, x, rtol, atol) @ phi
        k = guard_index(system, current, event.guard)
        if grazes(system, current, k, event):
            grazing.append(i)
        S = system.saltation(current, k, event.t, event.x_before)
        if i == len(events) - 1:
            jacobian = S @ phi + np.outer(after_rate(system, event), time_gradient(system, current, k, event, phi))
        phi = S @ phi
        t, x = event.t, np.asarray(event.x_after, float)
        current = event.target if event.target is not None else current
    return ReturnMap(x, float(t), phi, jacobian, events, tuple(grazing))


def after_rate(system, event) -> np.ndarray:
    """f+, dx/dt just after the event (its target mode at the reset state)."""
    return np.asarray(system.mode(event.target).rhs(event.t, np.asarray(event.x_after, float)), float)


def time_gradient(system, mode: int, k: int, event, phi: np.ndarray) -> np.ndarray:
    """d tau / d x0 = -g_x Phi / (dg/dt): the event time's gradient, g the guard k of ``mode`` just before it."""
    n, x = system.n, np.asarray(event.x_before, float)
    f = system.mode(mode).rhs(event.t, x)
    state = {"q": x[:n], "v": x[n:2 * n], "z": x[2 * n:] if system.m else None, "t": event.t}
    g_x = system.bound(f"guard_jacobian__{mode}").evaluate(**state)["g_x"].reshape(-1, x.size)[k]
    _, rate = system.guard_values(mode, event.t, x, f)
    return -(g_x @ phi) / rate[k]


@dataclass(frozen=True)
class AutonomousOrbit:
    """The orbit through x0 (just after the section's event, in ``mode``): its period, monodromy, multipliers (by
    decreasing modulus), the events of one period, Newton's iterations and final residual, the grazing events."""

    x0: np.ndarray
    mode: int
    section: str
    period: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    events: tuple
    iterations: int
    residual: float
    grazing: tuple


def autonomous_orbit(system, x0, mode: int, section: str, period: float, *, tol: float = 1e-10,
                     max_iter: int = 30, rtol: float = 1e-11, atol: float = 1e-13) -> AutonomousOrbit:
    """The fixed point x0 = P(x0) of the return map to ``section`` by Newton (module doc), from the guess x0 in
    ``mode`` (just after the section's event) with the period's guess ``period`` (the run looks 3 periods ahead)."""
    x = np.asarray(x0, float).copy()
    horizon = 3.0 * float(period)
    scale = 1.0 + np.linalg.norm(x)
    for it in range(1, max_iter + 1):
        rm = return_map(system, x, mode, section, horizon, rtol=rtol, atol=atol)
        r = rm.x - x
        if np.linalg.norm(r) <= tol * scale:
            mu = np.linalg.eigvals(rm.monodromy)
            return AutonomousOrbit(x, int(mode), section, rm.period, rm.monodromy, mu[np.argsort(-np.abs(mu))],
                                   rm.events, it - 1, float(np.linalg.norm(r)), rm.grazing)
        try:
            x = x - np.linalg.solve(rm.jacobian - np.eye(x.size), r)
        except np.linalg.LinAlgError:
            raise ConvergenceError(f"the return map's Jacobian P_x - I is singular at iteration {it} (|r| = "
                                   f"{np.linalg.norm(r):.3g}): a multiplier 1 besides the trivial one (a fold of "
                                   "the orbit)") from None
        horizon = 3.0 * rm.period
    raise ConvergenceError(f"shooting on the return map to {section!r} did not converge in {max_iter} Newton steps "
                           f"(|P(x0) - x0| = {np.linalg.norm(r):.3g}); try a guess nearer the orbit")


def settle_on_section(system, x0, mode: int, section: str | None, period: float, *, rtol: float = 1e-11,
                      atol: float = 1e-13, passes: int = 3):
    """(state, mode, section, period) just after the last of ``passes`` events of ``section`` (None: the guard of
    the first event of the run) from the guess x0 in ``mode``: a start on the section near an attracting orbit, and
    the time between its last two events there (the guess ``period`` when there is one event only)."""
    horizon = 3.0 * float(period) * passes
    run = integrate_hybrid(system, np.asarray(x0, float), horizon, mode=mode,
                           options=RunOptions(method="DOP853", rtol=rtol, atol=atol, t_eval=np.array([horizon]),
                                              progress=False))
    events = list(run.events)
    if not events:
        raise ConvergenceError(f"the run from the guess meets no event within t = {horizon:.6g} (3 x passes x the "
                               "period's guess): an autonomous hybrid orbit starts at an event (section)")
    section = events[0].guard if section is None else section
    hits = [e for e in events if e.guard == section and e.target is not None]
    if not hits:
        raise ConvergenceError(f"the run from the guess meets no event of guard {section!r} within t = "
                               f"{horizon:.6g}; its events: {sorted({e.guard for e in events})}")
    used = hits[:passes]
    between = used[-1].t - used[-2].t if len(used) > 1 else float(period)
    return np.asarray(used[-1].x_after, float), int(used[-1].target), section, float(between)


#: the central-difference step of R_p, relative to 1 + |p| (as mechgen.runtime.integration.hybrid_orbit_branch's)
PARAM_STEP = 1e-6


class SectionFamily:
    """Autonomous orbits of ``system`` in its parameter ``name``, each through the event of ``section`` (starting in
    ``mode``): R(x0, p) = P(x0; p) - x0, R_x0 = P_x - I (module doc), R_p by central differences; the return time
    found with each orbit (each run looks 3 times the last return time ahead)."""

    def __init__(self, system, name: str, mode: int, section: str, period: float, *, rtol: float = 1e-11,
                 atol: float = 1e-13) -> None:
        self.system, self.name, self.mode, self.section = system, name, int(mode), section
        self.last_period, self.rtol, self.atol = float(period), rtol, atol
        self.memo: dict = {}

    def moved(self, p: float):
        """The system at p."""
        return self.system.with_params(**{self.name: float(p)})

    def map(self, x0, p: float) -> ReturnMap:
        """P(x0; p), its Jacobian and the monodromy (the last few kept)."""
        key = (tuple(np.asarray(x0, float)), float(p))
        if key not in self.memo:
            if len(self.memo) > 32:
                self.memo.clear()
            self.memo[key] = return_map(self.moved(p), x0, self.mode, self.section, 3.0 * self.last_period,
                                        rtol=self.rtol, atol=self.atol)
            self.last_period = self.memo[key].period
        return self.memo[key]

    def equations(self):
        """R, R_x0 and R_p for mechgen.runtime.steady.continuation."""
        from mechgen.runtime.steady.continuation import ParametricEquations

        def R(x0, p):
            return self.map(x0, p).x - np.asarray(x0, float)

        def R_p(x0, p):
            h = PARAM_STEP * (1.0 + abs(p))
            return (R(x0, p + h) - R(x0, p - h)) / (2 * h)

        return ParametricEquations(R, lambda x0, p: self.map(x0, p).jacobian - np.eye(np.size(x0)), R_p,
                                   name=f"the autonomous orbits in {self.name}")

    def multipliers(self, x: np.ndarray) -> np.ndarray:
        """The multipliers of the return map at the branch point x = (x0, p): the monodromy's, with 0 in place of
        the trivial 1 (so that the PD and NS test functions see the others only)."""
        return np.linalg.eigvals(self.map(x[:-1], x[-1]).jacobian)
