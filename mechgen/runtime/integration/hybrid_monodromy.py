"""The flow map of a hybrid model over a time span, its Jacobian through the events, and its periodic orbits.

For a run from x0 at t0 = 0 to T that meets the events e_1 .. e_k (times t_i, guard g_i leaving mode m_{i-1} for
m_i), the Jacobian of the flow map x0 -> x(T) is (Leine & Nijmeijer, *Dynamics and Bifurcations of Non-Smooth
Mechanical Systems*, 2004, sec. 7.2; Bernardo et al., *Piecewise-smooth Dynamical Systems*, 2008, ch. 2)

    Phi = Phi_k S_k Phi_{k-1} ... S_1 Phi_0,

Phi_i the state-transition matrix of mode m_i from t_i to t_{i+1} (the variational equation dPhi/dt = J Phi with
the mode's exact Jacobian J, integrated along the segment from the state after event i) and S_i the event's
saltation matrix (mechgen.runtime.core.hybrid_system.HybridSystem.saltation, from the generated guard and reset
derivatives). The event times and states come from the event-driven run itself (mechgen.runtime.integration.events:
the compiled loop where it applies), so Phi is the derivative of the very map a shooting method solves with.

An event whose rate dg/dt is small against |g_x| |f| (a trajectory that touches the guard tangentially) is a
**grazing** event: the saltation matrix grows like 1/(dg/dt) there and the flow map is not differentiable; it is
reported (``grazing``) instead of silently trusted.

:func:`periodic_orbit` finds x0 with x(T) = x0 for a drive of period T (a forced model: the period is the
drive's) by Newton on r(x0) = x(T; x0) - x0 with r' = Phi - I; the orbit's Floquet multipliers are the
eigenvalues of Phi there. An event at the period's boundary (a stick-slip contact under u = U cos(omega t) reverses
at t = 0 = T) is accepted: a run that ends in another mode than it started in is continued BOUNDARY = 1e-8 of the
period past T, and the events there are taken at T, their saltation matrices in Phi (:func:`closing_run`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.integration.events import integrate_hybrid
from mechgen.runtime.integration.run_options import RunOptions

#: a forced orbit whose run ends in another mode than it started in is closed by the events within this fraction
#: of the period past its end (an event at the period's boundary: a stick-slip reversal at the drive's extremum)
BOUNDARY = 1e-8
#: an event is grazing when |dg/dt| < GRAZING |g_x| |f-| (relative to the guard's and the flow's size)
GRAZING = 1e-3


@dataclass(frozen=True)
class FlowJacobian:
    """x(T), its Jacobian ``phi`` (through the events), the events, the saltation matrices, the final mode and the
    events that graze (their positions in ``events``)."""

    x: np.ndarray
    phi: np.ndarray
    events: tuple
    saltations: tuple
    mode: int
    grazing: tuple


def guard_index(system, mode: int, name: str) -> int:
    """The position of the guard called ``name`` among those leaving ``mode``."""
    return [g.name for g in system.guards(mode)].index(name)


def transition(system, mode: int, t0: float, t1: float, x0: np.ndarray, rtol: float, atol: float) -> np.ndarray:
    """The state-transition matrix of ``mode``'s flow from (t0, x0) to t1: dPhi/dt = J(t, x) Phi, Phi(t0) = I,
    with x' = f(t, x) alongside (scipy DOP853 at rtol, atol)."""
    from scipy.integrate import solve_ivp

    flow = system.mode(mode)
    size = x0.size
    if t1 <= t0:
        return np.eye(size)

    def rhs(t, y):
        x, phi = y[:size], y[size:].reshape(size, size)
        return np.concatenate([flow.rhs(t, x), (np.asarray(flow.jacobian(t, x), float) @ phi).ravel()])

    y0 = np.concatenate([x0, np.eye(size).ravel()])
    sol = solve_ivp(rhs, (t0, t1), y0, method="DOP853", rtol=rtol, atol=atol)
    if not sol.success:
        raise ConvergenceError(f"the variational equation of mode {system.modes[mode]} from t = {t0:.10g} to "
                               f"{t1:.10g} failed: {sol.message}")
    return sol.y[size:, -1].reshape(size, size)


def flow_jacobian(system, x0, T: float, *, mode: int | None = None, rtol: float = 1e-11,
                  atol: float = 1e-13, close: bool = False) -> FlowJacobian:
    """x(T) from x0 at t = 0 in ``mode`` (default the initial one) and its Jacobian through the events (module
    doc); ``close``: a run ending in another mode is closed by the events at the period's boundary
    (:func:`closing_run`)."""
    x0 = np.asarray(x0, float)
    mode = system.initial_mode if mode is None else int(mode)
    run = closing_run(system, x0, T, mode, rtol, atol) if close else flow_run(system, x0, T, mode, rtol, atol)
    if run.terminated:
        raise ConvergenceError(f"the run from t = 0 ended at a terminal event at t = {run.t_final:.10g} before "
                               f"T = {T:.10g}: the flow map over the period is undefined there")
    phi, t, x, current = np.eye(x0.size), 0.0, x0, mode
    saltations, grazing = [], []
    for i, event in enumerate(run.events):
        phi = transition(system, current, t, event.t, x, rtol, atol) @ phi
        k = guard_index(system, current, event.guard)
        S = system.saltation(current, k, event.t, event.x_before)
        if grazes(system, current, k, event):
            grazing.append(i)
        saltations.append(S)
        phi = S @ phi
        t, x = event.t, np.asarray(event.x_after, float)
        current = event.target if event.target is not None else current
    phi = transition(system, current, t, T, x, rtol, atol) @ phi
    x_end = x if run.events and run.events[-1].t > T else np.asarray(run.x_final, float)
    return FlowJacobian(x_end, phi, tuple(run.events), tuple(saltations), run.final_mode,
                        tuple(grazing))


def flow_run(system, x0: np.ndarray, T: float, mode: int, rtol: float, atol: float):
    """The event-driven run from x0 at t = 0 to T (DOP853: the compiled loop where it applies)."""
    return integrate_hybrid(system, x0, T, mode=mode, options=RunOptions(method="DOP853", rtol=rtol, atol=atol,
                                                                         t_eval=np.array([T]), progress=False))


def closing_run(system, x0: np.ndarray, T: float, mode: int, rtol: float, atol: float):
    """The run from x0 in ``mode`` over T; when it ends in another mode, the run over T (1 + BOUNDARY) if that one
    ends in ``mode``: the events within BOUNDARY T past T are taken to be at the period's boundary (the state after
    the last of them stands for x(T), off by |dx/dt| (t_event - T) at most; a stick-slip reversal at the drive's
    extremum falls within round-off of T)."""
    run = flow_run(system, x0, T, mode, rtol, atol)
    if run.final_mode == mode:
        return run
    longer = flow_run(system, x0, T * (1.0 + BOUNDARY), mode, rtol, atol)
    return longer if longer.final_mode == mode else run


def flow_map(system, x0, T: float, *, mode: int | None = None, rtol: float = 1e-11, atol: float = 1e-13,
             close: bool = False):
    """(x(T), the mode it ends in) from x0 at t = 0 (no Jacobian; ``close`` as :func:`flow_jacobian`'s)."""
    mode = system.initial_mode if mode is None else int(mode)
    x0 = np.asarray(x0, float)
    run = closing_run(system, x0, T, mode, rtol, atol) if close else flow_run(system, x0, T, mode, rtol, atol)
    if run.events and run.events[-1].t > T:
        return np.asarray(run.events[-1].x_after, float), run.final_mode
    return np.asarray(run.x_final, float), run.final_mode


def grazes(system, mode: int, k: int, event) -> bool:
    """Whether the event's |dg/dt| is below GRAZING |g_x| |f-| (module doc)."""
    n = system.n
    x = np.asarray(event.x_before, float)
    f = system.mode(mode).rhs(event.t, x)
    state = {"q": x[:n], "v": x[n:2 * n], "z": x[2 * n:] if system.m else None, "t": event.t}
    g_x = system.bound(f"guard_jacobian__{mode}").evaluate(**state)["g_x"].reshape(-1, x.size)[k]
    _, rate = system.guard_values(mode, event.t, x, f)
    return abs(rate[k]) < GRAZING * np.linalg.norm(g_x) * np.linalg.norm(f)


@dataclass(frozen=True)
class HybridOrbit:
    """A periodic orbit of period T: the state x0 at t = 0 (and its mode), the monodromy matrix, the Floquet
    multipliers (by decreasing modulus), the events of one period, Newton's iterations and final residual, and the
    grazing events (positions in ``events``)."""

    x0: np.ndarray
    mode: int
    period: float
    monodromy: np.ndarray
    multipliers: np.ndarray
    events: tuple
    iterations: int
    residual: float
    grazing: tuple


def periodic_orbit(system, x0, T: float, *, mode: int | None = None, tol: float = 1e-10, max_iter: int = 30,
                   rtol: float = 1e-11, atol: float = 1e-13) -> HybridOrbit:
    """The orbit with x(T) = x0 (module doc), by Newton from the guess ``x0``; ConvergenceError naming the
    residual when it does not converge in ``max_iter`` steps or the orbit ends in another mode."""
    x = np.asarray(x0, float).copy()
    mode = system.initial_mode if mode is None else int(mode)
    scale = 1.0 + np.linalg.norm(x)
    for it in range(1, max_iter + 1):
        fj = flow_jacobian(system, x, T, mode=mode, rtol=rtol, atol=atol, close=True)
        r = fj.x - x
        if fj.mode != mode:
            raise ConvergenceError(f"the orbit guess ends its period in mode {system.modes[fj.mode]}, not "
                                   f"{system.modes[mode]}: a periodic orbit starts and ends in one mode "
                                   "(start the guess in the mode the orbit is in at t = 0)")
        if np.linalg.norm(r) <= tol * scale:
            multipliers = np.linalg.eigvals(fj.phi)
            order = np.argsort(-np.abs(multipliers))
            return HybridOrbit(x, mode, float(T), fj.phi, multipliers[order], fj.events, it - 1,
                               float(np.linalg.norm(r)), fj.grazing)
        try:
            x = x - np.linalg.solve(fj.phi - np.eye(x.size), r)
        except np.linalg.LinAlgError:
            raise ConvergenceError(f"the shooting Jacobian Phi - I is singular at iteration {it} (|r| = "
                                   f"{np.linalg.norm(r):.3g}): a multiplier 1 (a fold of the orbit, or an "
                                   "autonomous model, whose period is unknown)") from None
    raise ConvergenceError(f"shooting did not converge in {max_iter} Newton steps (|x(T) - x0| = "
                           f"{np.linalg.norm(r):.3g}); try a guess closer to the orbit (e.g. the end of a simulate "
                           "of a few periods)")
