"""A closed starting guess of an autonomous cycle from a state near it: one period re-integrated, cut where the
cycle is slowest and closed by a Poincare section there.

A simulate's samples are too coarse for a stiff cycle (a stick-slip cycle slips in a few hundredths of its period,
between samples), and the distance between its last two maxima guesses the period to a sample's width, so that the
guess curve does not close and its gap falls in the fast phase, where Newton cannot mend it. From the state x_s near
the cycle and the period's guess T_s:

1. x(t) from x_s over [0, T_s] by scipy's Radau (the exact Jacobian System.jacobian; rtol RTOL, atol ATOL relative
   to each component's range), and t_0 the time where the scaled speed max_i |f_i(x)| / range_i is least (the
   slowest point of the cycle: the cut falls in its slowest phase);
2. from x_0 = x(t_0) over [0, 2 T_s] with the section (x - x_0) . w = 0, w_i = f_i(x_0) / range_i^2, crossed upward:
   its first crossing after T_s / 2 is the period T;
3. the guess curve is that run's dense output over [0, T] (it closes to the integration's accuracy once the run has
   settled on the cycle).
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError

#: Radau's tolerances for the guess (a starting guess: Newton solves the collocation equations to rtol, atol)
RTOL = 1e-8
#: ATOL is relative to each component's range over the first run (plus 1e-300)
ATOL = 1e-10
#: samples of the first run at which the speed is compared
SAMPLES = 2001


def radau(system, x0: np.ndarray, span: float, atol: np.ndarray, events=None):
    """scipy's Radau from x0 over [0, span] with dense output (a ConvergenceError when it fails)."""
    from scipy.integrate import solve_ivp  # loaded on use (a scene's start imports no scipy.integrate)

    sol = solve_ivp(system.rhs, (0.0, span), np.asarray(x0, float), method="Radau", jac=system.jacobian,
                    rtol=RTOL, atol=atol, dense_output=True, events=events)
    if sol.status == -1:
        raise ConvergenceError(f"periodic_orbit: the starting guess's integration failed at t = {sol.t[-1]:.6g}: "
                               f"{sol.message}")
    return sol


def closed_cycle(system, x_start: np.ndarray, period: float) -> tuple[np.ndarray, float, object]:
    """(x_0, T, curve) (module doc): ``curve(times)`` the states (rows) at times in [0, T] from x_0."""
    x_start = np.asarray(x_start, float)
    first = radau(system, x_start, period, ATOL * (1.0 + np.abs(x_start)))
    times = np.linspace(0.0, period, SAMPLES)
    X = first.sol(times).T
    scale = np.ptp(X, axis=0) + 1e-300
    speed = [float(np.max(np.abs(system.rhs(0.0, x)) / scale)) for x in X]
    x0 = X[int(np.argmin(speed))]
    w = system.rhs(0.0, x0) / scale**2

    def section(t: float, x: np.ndarray) -> float:
        return float((x - x0) @ w)

    section.direction = 1.0
    run = radau(system, x0, 2 * period, ATOL * scale, events=section)
    crossings = run.t_events[0][run.t_events[0] > period / 2]
    if crossings.size == 0:
        raise ConvergenceError(f"periodic_orbit: the motion from the simulate's state did not return to its section "
                               f"within 2 x {period:.6g} (it has not settled on a cycle: a longer simulate)")
    T = float(crossings[0])
    return x0, T, lambda t: run.sol(np.asarray(t, float)).T
