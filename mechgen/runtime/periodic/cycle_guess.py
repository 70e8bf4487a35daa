"""A closed starting guess of an autonomous cycle from a state near it: one period re-integrated, cut where the
cycle is slowest and closed by a Poincare section there.

A simulate's samples are too coarse for a stiff cycle (a stick-slip cycle slips in a few hundredths of its period,
between samples), and the distance between its last two maxima guesses the period to a sample's width, so that the
guess curve does not close and its gap falls in the fast phase, where Newton cannot mend it. From the state x_s near
the cycle and the period's guess T_s:

1. x(t) from x_s over [0, T_s] by the Radau IIA method (the exact Jacobian System.jacobian; rtol RTOL, atol ATOL
   relative to each component's range), and t_0 the time where the scaled speed max_i |f_i(x)| / range_i is least
   (the slowest point of the cycle: the cut falls in its slowest phase);
2. from x_0 = x(t_0) over [0, 2 T_s] with the section g(x) = (x - x_0) . w = 0, w_i = f_i(x_0) / range_i^2, crossed
   upward: its first crossing after T_s / 2 is the period T (brentq on the run's dense output, from the first
   upward sign change of g among SECTION_SAMPLES samples: scipy's event location, on samples rather than steps);
3. the guess curve is that run's dense output over [0, T] (it closes to the integration's accuracy once the run has
   settled on the cycle).

The Radau runs are the compiled loop (mechgen.runtime.integration.radau_c: scipy's Radau step for step, in C)
where it takes the system, else scipy's Radau on System.rhs. The compiled loop samples the run's collocation
polynomials at given times, so the dense output at any times is the run over [0, 2 T_s] again, sampled there: the
same steps whatever the samples (a few milliseconds a run, against about a second for scipy's on a Python
right-hand side).
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError

#: the machine epsilon (brentq's tolerances, as scipy's event location)
EPS = float(np.finfo(float).eps)

#: Radau's tolerances for the guess (a starting guess: Newton solves the collocation equations to rtol, atol)
RTOL = 1e-8
#: ATOL is relative to each component's range over the first run (plus 1e-300)
ATOL = 1e-10
#: samples of the first run at which the speed is compared
SAMPLES = 2001
#: samples of the second run among which the section's first upward sign change after T_s / 2 is looked for
SECTION_SAMPLES = 4001


def radau(system, x0: np.ndarray, span: float, atol: np.ndarray):
    """scipy's Radau from x0 over [0, span] with dense output (a ConvergenceError when it fails)."""
    from scipy.integrate import solve_ivp  # loaded on use (a scene's start imports no scipy.integrate)

    sol = solve_ivp(system.rhs, (0.0, span), np.asarray(x0, float), method="Radau", jac=system.jacobian,
                    rtol=RTOL, atol=atol, dense_output=True)
    if sol.status == -1:
        raise ConvergenceError(f"periodic_orbit: the starting guess's integration failed at t = {sol.t[-1]:.6g}: "
                               f"{sol.message}")
    return sol


def dense_run(system, x0: np.ndarray, span: float, atol: np.ndarray):
    """``times -> states (rows)``: the dense output of the Radau run from x0 over [0, span] at any times in it (the
    compiled loop, run again and sampled at the times, when it takes the system; else one scipy run's)."""
    from mechgen.runtime.integration.radau_c import integrate_radau_c, radau_loop_problem
    from mechgen.runtime.integration.run_options import RunOptions

    x0 = np.asarray(x0, float)
    if radau_loop_problem(system, RTOL, atol) is not None:
        sol = radau(system, x0, span, atol).sol
        return lambda times: sol(np.asarray(times, float)).T

    def at(times) -> np.ndarray:
        times = np.asarray(times, float)
        order = np.argsort(times.reshape(-1), kind="stable")
        options = RunOptions(method="Radau", rtol=RTOL, atol=atol, t_eval=times.reshape(-1)[order])
        X = integrate_radau_c(system, x0, span, options)[1]
        out = np.empty_like(X)
        out[order] = X
        return out.reshape(times.shape + (x0.size,))
    return at


def first_crossing(g, after: float, span: float) -> float | None:
    """The first upward zero of ``g`` (a function of t, vectorised) in (after, span]: brentq from the first upward
    sign change among SECTION_SAMPLES samples of [0, span] after ``after`` (None when there is none)."""
    from scipy.optimize import brentq

    grid = np.linspace(0.0, span, SECTION_SAMPLES)
    values = g(grid)
    up = np.flatnonzero((values[:-1] < 0) & (values[1:] >= 0) & (grid[1:] > after))
    if up.size == 0:
        return None
    i = int(up[0])
    if values[i + 1] == 0.0:
        return float(grid[i + 1])
    return float(brentq(lambda t: float(g(np.array([t]))[0]), grid[i], grid[i + 1], xtol=4 * EPS, rtol=4 * EPS))


def closed_cycle(system, x_start: np.ndarray, period: float) -> tuple[np.ndarray, float, object]:
    """(x_0, T, curve) (module doc): ``curve(times)`` the states (rows) at times in [0, T] from x_0."""
    x_start = np.asarray(x_start, float)
    times = np.linspace(0.0, period, SAMPLES)
    X = dense_run(system, x_start, period, ATOL * (1.0 + np.abs(x_start)))(times)
    scale = np.ptp(X, axis=0) + 1e-300
    speed = [float(np.max(np.abs(system.rhs(0.0, x)) / scale)) for x in X]
    x0 = X[int(np.argmin(speed))]
    w = system.rhs(0.0, x0) / scale**2
    curve = dense_run(system, x0, 2 * period, ATOL * scale)
    T = first_crossing(lambda t: (curve(t) - x0) @ w, period / 2, 2 * period)
    if T is None:
        raise ConvergenceError(f"periodic_orbit: the motion from the simulate's state did not return to its section "
                               f"within 2 x {period:.6g} (it has not settled on a cycle: a longer simulate)")
    return x0, T, curve
