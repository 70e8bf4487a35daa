"""The flow map of a smooth lumped model over a time span and its sensitivity, the variational equations.

With x = (q, v) and dx/dt = f(t, x) the model's first-order form (System.rhs: v, a = -M(q)^-1 r(q, v, 0, t)),
the state transition matrix Phi(t) = dx(t)/dx(t0) solves

    dPhi/dt = J(t, x(t)) Phi,   Phi(t0) = I,   J = df/dx = [[0, I], [-M^-1 dr/dq, -M^-1 dr/dv]]

(System.jacobian: exact, from the generated ``tangent`` kernel at the current acceleration, so a mass that
depends on q is differentiated too: dr/dq holds dM/dq a). x and Phi are integrated together, (2n)(2n + 1)
equations, by scipy's DOP853 (order 8) with the error of Phi's entries controlled as the state's. Phi(t0 + T) of a
periodic orbit is its monodromy matrix. The compiled loop of mechgen.runtime.integration integrates the model's
state alone; the variational equations run in Python here (scipy's DOP853, the kernels called from Python at each
stage), exact but some hundred times slower than the compiled loop. So where the compiled loop can run the system
(:func:`compiled_flow`: the C backend), shooting's Newton iterations take x(T) from it and Phi(T) by central
differences of it (:func:`differenced_flow`, 4n + 1 compiled runs: about 1e-10 from the exact Phi, which Newton
needs only approximately), and the variational equations run once, for the converged orbit's multipliers.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError

#: the most evaluations of the augmented dx/dt in one run (about 6000 DOP853 steps): a Newton trial far from
#: any orbit (a state so large that the steps shrink without end) is abandoned as a ConvergenceError
MAX_EVALUATIONS = 72_000
#: a run whose state grows beyond ESCAPE (1 + ||x0||_inf) is abandoned (a Newton trial far from any orbit)
ESCAPE = 1e3
#: the smallest relative tolerance passed to DOP853 (100 machine epsilons: what it can honour)
MIN_RTOL = 2.3e-14


def augmented_rhs(system, bound: float = np.inf):
    """d/dt (x, vec Phi) = (f(t, x), J(t, x) Phi) (module doc), Phi row-major; a ConvergenceError beyond
    MAX_EVALUATIONS calls or when a state entry exceeds ``bound`` in magnitude."""
    calls = [0]

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        calls[0] += 1
        if calls[0] > MAX_EVALUATIONS:
            raise ConvergenceError(f"periodic_orbit: the variational equations took more than {MAX_EVALUATIONS} "
                                   f"evaluations by t = {t:.6g} (a state far from any orbit: a better starting guess)")
        d = int(round((np.sqrt(1 + 4 * y.size) - 1) / 2))
        x, Phi = y[:d], y[d:].reshape(d, d)
        if not np.all(np.abs(x) <= bound):
            raise ConvergenceError(f"periodic_orbit: the state left |x| <= {bound:.3g} at t = {t:.6g} (a state far "
                                   "from any orbit: a better starting guess)")
        J = system.jacobian(t, x)
        return np.concatenate([system.rhs(t, x), (J @ Phi).ravel()])

    return rhs


def variational_flow(system, x0: np.ndarray, t0: float, span: float, rtol: float, atol: float) -> tuple:
    """(x(t0 + span), Phi(t0 + span)) from x(t0) = x0 (module doc); a failed integration is a ConvergenceError."""
    from scipy.integrate import solve_ivp  # loaded on use (a scene's start imports no scipy.integrate)

    x0 = np.asarray(x0, float)
    d = x0.size
    y0 = np.concatenate([x0, np.eye(d).ravel()])
    bound = ESCAPE * (1.0 + float(np.max(np.abs(x0), initial=0.0)))
    sol = solve_ivp(augmented_rhs(system, bound), (t0, t0 + span), y0, method="DOP853", rtol=max(rtol, MIN_RTOL),
                    atol=atol)
    if sol.status != 0:
        raise ConvergenceError(f"periodic_orbit: the variational equations failed at t = {sol.t[-1]:.6g}: "
                               f"{sol.message} (a shorter period, or a starting guess nearer an orbit)")
    y = sol.y[:, -1]
    return y[:d], y[d:].reshape(d, d)


def states_at(system, x0: np.ndarray, t0: float, times: np.ndarray, rtol: float, atol: float) -> np.ndarray:
    """The states x(t) (rows) at ``times`` (>= t0, ascending) from x(t0) = x0, by DOP853."""
    from scipy.integrate import solve_ivp  # loaded on use (a scene's start imports no scipy.integrate)

    times = np.asarray(times, float)
    sol = solve_ivp(system.rhs, (t0, float(times[-1])), np.asarray(x0, float), method="DOP853",
                    rtol=max(rtol, MIN_RTOL), atol=atol, t_eval=times)
    if sol.status != 0:
        raise ConvergenceError(f"periodic_orbit: the integration over the orbit failed at t = {sol.t[-1]:.6g}: "
                               f"{sol.message}")
    return sol.y.T


#: the most DOP853 steps of one compiled run over a period (a normal orbit takes tens to thousands): a Newton trial
#: far from any orbit is abandoned as a ConvergenceError
MAX_STEPS = 200_000
#: central differences of the compiled flow: x0_j +- STEP (1 + |x0_j|); the error is about STEP^2 |phi'''| from the
#: truncation plus rtol / STEP from the integrations (2e-10 on a Duffing orbit at rtol 1e-12: measured)
STEP = 1e-5


def compiled_flow(system, rtol: float, atol: float):
    """``(x0, times) -> states (rows) at times`` (times ascending, from t = 0) through the compiled DOP853 loop of
    mechgen.runtime.integration.smooth_c, or None where that loop cannot run the system (no C backend, no
    compiler). A run beyond MAX_STEPS steps, or one whose kernels give NaN/Inf, is a ConvergenceError."""
    from mechgen.errors import KernelError
    from mechgen.runtime.core.budget import Budget, BudgetExceeded
    from mechgen.runtime.integration.run_options import RunOptions
    from mechgen.runtime.integration.events_c import RepeatedRuns
    from mechgen.runtime.integration.smooth_c import integrate_smooth_c, smooth_loop_problem, view_of

    rtol = max(rtol, MIN_RTOL)
    if smooth_loop_problem(system, rtol, atol) is not None:
        return None
    quick = RepeatedRuns(view_of(system), rtol, atol, MAX_STEPS)

    def run(x0: np.ndarray, times: np.ndarray) -> np.ndarray:
        times = np.asarray(times, float)
        X = quick(x0, times)  # set up once; None where the run needs the full loop's handling (its errors)
        if X is not None:
            return X
        options = RunOptions(method="DOP853", rtol=rtol, atol=atol, t_eval=times, loop="c",
                             budget=Budget("DOP853 steps", limit=MAX_STEPS, key="max_iterations", seconds=None))
        try:
            _, X, _ = integrate_smooth_c(system, np.asarray(x0, float), float(times[-1]), options)
        except (BudgetExceeded, KernelError) as err:
            raise ConvergenceError(f"periodic_orbit: the flow from x0 = {np.asarray(x0)[:6].tolist()} failed: "
                                   f"{err} (a state far from any orbit: a better starting guess)") from None
        return X

    return run


def differenced_flow(run, x0: np.ndarray, span: float) -> tuple[np.ndarray, np.ndarray]:
    """(x(span), Phi(span)) from x(0) = x0 by ``run`` (:func:`compiled_flow`): Phi's columns by central differences
    (STEP), 4n + 1 runs in all."""
    x0 = np.asarray(x0, float)
    times = np.array([0.0, span])
    xT = run(x0, times)[-1]
    Phi = np.empty((x0.size, x0.size))
    for j in range(x0.size):
        h = STEP * (1.0 + abs(x0[j]))
        e = np.zeros(x0.size)
        e[j] = h
        Phi[:, j] = (run(x0 + e, times)[-1] - run(x0 - e, times)[-1]) / (2 * h)
    return xT, Phi
