"""Newton's method with a backtracking line search: solve r(x) = 0 with the Jacobian J = dr/dx.

Each step solves J dx = -r (dense LU or sparse LU) and accepts the largest
alpha in 1, 1/2, 1/4, ... that decreases ||r||; it stops when ||r|| <= tol (or
the step is below tol relative to ||x||), and raises ConvergenceError after
``max_iter`` iterations with the residual history. A ``budget``
(mechgen.runtime.core.budget.Budget) bounds the wall time, checked every iteration; a
non-finite residual or Jacobian raises KernelError with ``explain(x)`` (called only then: which
kernel, output and input).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mechgen.errors import ConvergenceError, KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


@dataclass(frozen=True)
class NewtonResult:
    """Solution, iterations used, final residual norm, converged flag, the residual norms of every iterate."""

    x: np.ndarray
    iterations: int
    residual_norm: float
    converged: bool
    history: tuple[float, ...] = ()


def _why(explain, x) -> str:
    note = explain(x) if explain is not None else ""
    return f": {note}" if note else ""


def _finite_residual(residual, x, explain=None):
    r = np.asarray(residual(x), float)
    if not np.all(np.isfinite(r)):
        raise KernelError(f"residual is not finite at x = {x[:6]}{_why(explain, x)}")
    return r


def symmetric_ordered_solve(J, rhs) -> np.ndarray:
    """x with J x = rhs by SuperLU ordered on the pattern of J + J^T (minimum degree) and preferring diagonal
    pivots (threshold 0.1): for the near-symmetric sparse tangents of 2D finite elements far less fill than the
    default column ordering (measured at 1e5 unknowns, P2: 2.5x fewer factor entries, 5x faster); any J is
    solved correctly (threshold partial pivoting)."""
    lu = spla.splu(sps.csc_matrix(J), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1,
                   options={"SymmetricMode": True})
    return lu.solve(rhs)


def _step(J, r, explain=None, x=None, solve=None) -> np.ndarray:
    if sps.issparse(J):
        if not np.all(np.isfinite(J.data)):
            raise KernelError(f"Jacobian is not finite{_why(explain, x)}")
        try:
            dx = (solve or (lambda A, b: spla.splu(A.tocsc()).solve(b)))(J, -r)
        except RuntimeError as exc:
            raise ConvergenceError(f"singular Jacobian: {exc}") from exc
    else:
        require_dense(np.size(r), 3, "the dense Newton step")
        J = np.atleast_2d(np.asarray(J, float))
        if not np.all(np.isfinite(J)):
            raise KernelError(f"Jacobian is not finite{_why(explain, x)}")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", sla.LinAlgWarning)
                lu = sla.lu_factor(J, check_finite=False)
        except (np.linalg.LinAlgError, ValueError, sla.LinAlgWarning) as exc:
            raise ConvergenceError(f"singular Jacobian: {exc}") from exc
        if np.min(np.abs(np.diag(lu[0]))) <= 1e-14 * max(np.abs(J).max(), 1e-300):
            raise ConvergenceError("singular Jacobian (a zero pivot): the equilibrium is not isolated or the "
                                   "guess is at a degenerate point")
        dx = sla.lu_solve(lu, -r, check_finite=False)
    return dx


def newton(residual, jacobian, x0, *, tol: float = 1e-10, max_iter: int = 50, damping: bool = True,
           budget=None, explain=None, solve=None) -> NewtonResult:
    """Solve residual(x) = 0 from x0 (``budget``, ``explain``: see the module doc; ``solve(J, b)``: the sparse
    linear solver, default SuperLU with its column ordering)."""
    x = np.array(x0, dtype=float)
    r = _finite_residual(residual, x, explain)
    history = [float(np.linalg.norm(r))]
    for it in range(1, max_iter + 1):
        if history[-1] <= tol:
            return NewtonResult(x, it - 1, history[-1], True, tuple(history))
        if budget is not None:
            budget.check_time(lambda: f"Newton iteration {it} of max_iter = {max_iter}, residual norm {history[-1]:.3g}")
        dx = _step(jacobian(x), r, explain, x, solve)
        alpha = 1.0
        while True:
            trial = x + alpha * dx
            r_trial = residual(trial)
            norm = float(np.linalg.norm(r_trial)) if np.all(np.isfinite(r_trial)) else np.inf
            if not damping or norm < history[-1] or alpha < 1e-6:
                break
            alpha /= 2
        if not np.isfinite(norm):
            raise KernelError(f"residual is not finite after a Newton step at x = {trial[:6]}{_why(explain, trial)}")
        x, r = trial, np.asarray(r_trial, float)
        history.append(norm)
        if norm <= tol or np.linalg.norm(alpha * dx) <= tol * max(1.0, np.linalg.norm(x)) and norm <= 1e3 * tol:
            return NewtonResult(x, it, norm, True, tuple(history))
    tail = ", ".join(f"{h:.3g}" for h in history[-5:])
    raise ConvergenceError(f"Newton did not converge in {max_iter} iterations; last residual norms: {tail}")
