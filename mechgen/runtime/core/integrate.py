"""Time integration: scipy's stiff and non-stiff integrators, and a symplectic leapfrog.

* :func:`integrate_first_order` - dx/dt = f(t, x) with scipy's ``OdeSolver`` classes (BDF, Radau,
  LSODA with the generated Jacobian; RK45, DOP853 explicit), stepped here as ``solve_ivp`` steps
  them (the same steps, samples at ``t_eval`` from each step's dense output) so that every step is
  counted against a work :class:`~mechgen.runtime.core.budget.Budget` and drawn on a progress bar.
* :func:`leapfrog` - velocity Verlet (Stormer-Verlet) for q'' = a(q), a separable
  Hamiltonian with the mass already inverted in ``a``: second order, symplectic,
  so the energy error stays bounded over long times (no drift). Its n_steps are known before it
  starts, so a budget refuses too long a run up front.

A failure (a step size below the spacing of the numbers, a singular mass matrix, a kernel giving
NaN/Inf) raises ConvergenceError or KernelError saying where (t reached of t_end); ``explain(t, x)``,
given by the caller, adds what went wrong at that state (which kernel, output and input) and is
called only on that path.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mechgen.errors import ConvergenceError, KernelError
from mechgen.runtime.core.budget import Budget, BudgetExceeded, Progress
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.integration.run_options import RunOptions

METHODS = ("BDF", "Radau", "LSODA", "RK45", "DOP853")
IMPLICIT = ("BDF", "Radau", "LSODA")
#: the smallest relative tolerance scipy's integrators honour (they raise a smaller one to it)
MIN_RTOL = 100 * float(np.finfo(float).eps)
#: the leapfrog checks its wall-time budget and moves its bar every this many steps
CHECK_EVERY = 1024
#: an adaptive run is refused early when its projected steps exceed this many times max_steps
PROJECT_MARGIN = 10.0


@dataclass(frozen=True)
class Trajectory:
    """Sampled solution: times t and states (x rows, or q and v for leapfrog)."""

    t: np.ndarray
    x: np.ndarray | None = None
    q: np.ndarray | None = None
    v: np.ndarray | None = None
    energy: list = field(default_factory=list)
    nfev: int = 0
    njev: int = 0
    success: bool = True
    message: str = ""
    steps: int = 0


def _solver_class(method: str):
    import scipy.integrate as si  # loaded on use: scipy.integrate brings scipy.optimize

    return {"BDF": si.BDF, "Radau": si.Radau, "LSODA": si.LSODA, "RK45": si.RK45, "DOP853": si.DOP853}[method]


def reached_at(t: float, t_end: float, steps: int) -> str:
    """How far a run got: t, t_end and the accepted steps (the budget's and failures' ``reached``)."""
    return f"t = {t:.6g} of t_end = {t_end:.6g} after {steps:,} steps"


def integrate_first_order(rhs, x0, t_end: float, *, jac=None, options: RunOptions | None = None,
                          **changes) -> Trajectory:
    """Integrate dx/dt = rhs(t, x) from 0 to t_end; rows of ``x`` are states at ``t`` (``t_eval``, or every step).

    ``options``: mechgen.runtime.integration.run_options.RunOptions (default method BDF here; its fields may be given
    as keywords, which change it; ``rules``, ``stop_after`` and ``loop`` are not read). Each accepted step is
    one unit of ``budget`` (BudgetExceeded names t reached); ``progress`` draws a bar in t (see
    :class:`~mechgen.runtime.core.budget.Progress`).
    """
    options = RunOptions.of(options or RunOptions(method="BDF"), **changes)
    method = options.method
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    t_end = float(t_end)
    watch = _Watched(rhs, jac, x0, method, options.explain)
    from numpy.linalg import LinAlgError

    samples = _Samples(options.t_eval)
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # its first step's size, checked below
            solver = _solver_class(method)(watch.fun, 0.0, np.asarray(x0, float), t_end, rtol=options.rtol,
                                           atol=options.atol, **watch.solver_options())
        with Progress(t_end, desc=options.desc, unit="t", enabled=options.progress) as bar:
            steps, t = _march(solver, watch, samples, options, t_end, bar)
    except (LinAlgError, ZeroDivisionError, ValueError) as exc:  # a singular M; a NaN met by a check_finite solve
        raise ConvergenceError(watch.failed(f"failed at t = {watch.last[0]:.6g} of t_end = {t_end:.6g} ({exc})")) \
            from exc
    except KernelError as exc:
        why = watch.note()
        if not why:
            raise
        raise KernelError(f"{method} at t = {watch.last[0]:.6g} of t_end = {t_end:.6g}: {why}") from exc
    t_out, x_out = samples.arrays(np.size(x0))
    if not np.all(np.isfinite(x_out)):
        raise KernelError(watch.failed(f"state became NaN/Inf by t = {t:.6g} of t_end = {t_end:.6g}"))
    return Trajectory(t_out, x_out, nfev=solver.nfev, njev=solver.njev, success=True,
                      message="The solver successfully reached the end of the integration interval.", steps=steps)


class _Watched:
    """dx/dt = rhs(t, x) and its Jacobian for scipy's stepper, remembering the latest evaluated and the last
    accepted state, so that a failure says where (``explain(t, x)``, or None, adds what went wrong there)."""

    def __init__(self, rhs, jac, x0, method: str, explain) -> None:
        self.rhs, self.jac, self.method, self.explain = rhs, jac, method, explain
        self.last: list = [0.0, np.asarray(x0, float)]
        self.accepted: list = [0.0, np.asarray(x0, float)]

    def fun(self, t, x):  # remembers the state of the latest evaluation, for the failure message
        self.last[0], self.last[1] = t, x
        return self.rhs(t, x)

    def jacobian(self, t, x):
        self.last[0], self.last[1] = t, x
        return self.jac(t, x)

    def solver_options(self) -> dict:
        return {"jac": self.jacobian} if (self.jac is not None and self.method in IMPLICIT) else {}

    def note(self) -> str:
        """explain() at the latest evaluated state, or at the last accepted one when that one is not finite."""
        if self.explain is None:
            return ""
        t_x, x = self.last[0], np.asarray(self.last[1], float)
        if not np.all(np.isfinite(x)):
            t_x, x = self.accepted[0], np.asarray(self.accepted[1], float)
        return self.explain(t_x, x)

    def failed(self, what: str) -> str:
        why = self.note()
        return f"{self.method} {what}" + (f"; {why}" if why else "")


class _Samples:
    """The samples of a run: at ``t_eval`` (from each step's dense output), or at every step end (None)."""

    def __init__(self, t_eval) -> None:
        self.t_eval = None if t_eval is None else np.asarray(t_eval, float)
        self.ts: list = []
        self.ys: list = []
        self.i_eval = 0

    def take(self, solver) -> None:
        """The samples of the step the solver has just taken."""
        t, t_eval = solver.t, self.t_eval
        if t_eval is None:
            self.ts.append(t)
            self.ys.append(solver.y.copy())
            return
        i_new = int(np.searchsorted(t_eval, t, side="right"))
        if i_new > self.i_eval:
            self.ts.append(t_eval[self.i_eval:i_new])
            self.ys.append(solver.dense_output()(t_eval[self.i_eval:i_new]).T)
            self.i_eval = i_new

    def arrays(self, size: int) -> tuple[np.ndarray, np.ndarray]:
        """(t, x rows) of the samples; ``size`` the state's."""
        ts, ys = self.ts, self.ys
        if self.t_eval is None:
            return np.array(ts), np.array(ys).reshape(len(ts), -1)
        return (np.hstack(ts) if ts else np.empty(0)), (np.vstack(ys) if ys else np.empty((0, size)))


def _march(solver, watch: _Watched, samples: _Samples, options: RunOptions, t_end: float, bar) -> tuple[int, float]:
    """Step the solver to t_end, sampling each step and spending one unit of the budget per step (with the
    projection of :func:`project_steps` every CHECK_EVERY steps): (accepted steps, t reached)."""
    budget, method = options.budget, options.method
    steps, t = 0, 0.0
    while solver.status == "running":
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # finiteness is checked here
            message = solver.step()
        if solver.status == "failed":
            raise ConvergenceError(watch.failed(f"stopped at {reached_at(solver.t, t_end, steps)}: "
                                                f"{str(message).rstrip('.')}"))
        steps += 1
        t = solver.t
        watch.accepted[0], watch.accepted[1] = t, solver.y
        samples.take(solver)
        if budget is not None:
            budget.spend(1, lambda: reached_at(t, t_end, steps))
            if steps % CHECK_EVERY == 0:
                project_steps(budget, method, steps, t, t - solver.t_old, t_end)
        bar.to(t)
    return steps, t


def project_steps(budget: Budget, method: str, steps: int, t: float, h: float, t_end: float) -> None:
    """Once a tenth of the step budget is spent: refuse when the steps so far plus (t_end - t) / h at the
    latest step size h exceed PROJECT_MARGIN times the budget (a step size that stopped growing: a fast
    mode resolved over the whole interval); a margin that an early transient's short steps cannot reach."""
    if budget.limit is None or steps < budget.limit / 10 or h <= 0:
        return
    estimate = steps + (t_end - t) / h
    if estimate > PROJECT_MARGIN * budget.limit:
        raise BudgetExceeded(f"{method} steps: at the step size of the latest step (h = {h:.3g}) t_end = {t_end:.6g} "
                             f"needs about {estimate:.3g} steps, more than {PROJECT_MARGIN:g} x max_steps = "
                             f"{budget.limit:,} (a fast mode resolved over the whole interval: shorten t_end, or "
                             "raise max_steps)", key=budget.key, reached=reached_at(t, t_end, steps))


def leapfrog(acceleration, q0, v0, dt: float, n_steps: int, *, record_every: int = 1, energy=None,
             budget: Budget | None = None, progress: bool = False, desc: str = "leapfrog") -> Trajectory:
    """Velocity Verlet: v += dt/2 a(q); q += dt v; v += dt/2 a(q) (one acceleration call per step).

    ``budget`` refuses n_steps above its limit before the first step and checks its wall time every
    CHECK_EVERY steps; a NaN/Inf state stops the run at the check that sees it.
    """
    if budget is not None:
        budget.refuse(n_steps, f"nothing (refused before starting: t_end / dt = {n_steps:,} steps)")
    q, v = np.array(q0, float), np.array(v0, float)
    a = np.asarray(acceleration(q), float)
    rec = _LeapfrogRecord(q.size, dt, n_steps, record_every, energy)
    rec.record(0, q, v)
    with Progress(n_steps, desc=desc, unit="step", enabled=progress) as bar:
        q, v = _verlet(acceleration, (q, v, a), rec, budget, bar)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
        raise rec.unstable(n_steps)
    return Trajectory(rec.ts[:rec.k], q=rec.qs[:rec.k], v=rec.vs[:rec.k], energy=rec.energies, nfev=n_steps + 1,
                      steps=n_steps)


class _LeapfrogRecord:
    """The leapfrog's samples: (t, q, v) every ``every`` steps (and the start), with energy(q, v) when given."""

    def __init__(self, size: int, dt: float, n_steps: int, every: int, energy) -> None:
        self.dt, self.n_steps, self.every, self.energy = dt, n_steps, every, energy
        self.t_end = n_steps * dt
        n_rec = n_steps // every + 1
        require(dense_bytes(n_rec, 2 * size + 2), f"the leapfrog record of {n_rec} states of {size} coordinates",
                key="params.N")
        self.ts, self.qs, self.vs = np.empty(n_rec), np.empty((n_rec, size)), np.empty((n_rec, size))
        self.energies: list = []
        self.k = 0

    def record(self, step: int, q, v) -> None:
        k = self.k
        self.ts[k], self.qs[k], self.vs[k] = step * self.dt, q, v
        if self.energy is not None:
            self.energies.append(float(self.energy(q, v)))
        self.k = k + 1

    def unstable(self, step: int) -> KernelError:
        return KernelError(f"leapfrog state became NaN/Inf by t = {step * self.dt:.6g} of t_end = {self.t_end:.6g} "
                           f"(step {step:,} of {self.n_steps:,}; time step dt = {self.dt:g} too large for the "
                           "stiffest mode?)")


def _verlet(acceleration, start: tuple, rec: _LeapfrogRecord, budget: Budget | None, bar) -> tuple:
    """The velocity Verlet steps from ``start`` = (q, v, a(q)) (updated in place), recorded in ``rec``; the
    finiteness, the budget's wall time and the bar checked every CHECK_EVERY steps. Returns (q, v)."""
    q, v, a = start
    dt, n_steps, every, t_end = rec.dt, rec.n_steps, rec.every, rec.t_end
    half = 0.5 * dt
    for step in range(1, n_steps + 1):
        v += half * a
        q += dt * v
        a = np.asarray(acceleration(q), float)
        v += half * a
        if step % every == 0:
            rec.record(step, q, v)
        if step % CHECK_EVERY == 0:
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                raise rec.unstable(step)
            if budget is not None:
                budget.check_time(lambda: reached_at(step * dt, t_end, step))
            bar.to(step)
    return q, v


__all__ = ["Budget", "BudgetExceeded", "IMPLICIT", "METHODS", "MIN_RTOL", "Trajectory", "integrate_first_order",
           "leapfrog"]
