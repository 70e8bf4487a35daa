"""Newton's method for a periodic orbit's unknowns u: R(u) = 0 with the exact dR/du, one solve a step.

Each step solves J du = -R (LU, SuperLU for a sparse J; least squares when J is singular to working precision),
shortens it to at most ``trust`` (1 + ||u||_inf), and takes the largest
alpha in 1, 1/2, ... 1/256 that does not increase ||R||_inf (when none does, the longest trial that
could be evaluated). It stops after the step that was small,
||du||_inf <= atol + rtol ||u||_inf (Newton's convergence is quadratic, so the residual after it is far below
what that step left); it raises ConvergenceError after
``max_iterations`` steps naming the residual and what to try.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError, KernelError
from mechgen.runtime.core.lazy_import import lazy_module

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


@dataclass(frozen=True)
class OrbitSolution:
    """Unknowns ``u``, ``iterations`` used, final ``residual`` ||R(u)||_inf."""

    u: np.ndarray
    iterations: int
    residual: float


@dataclass(frozen=True)
class NewtonSettings:
    """Tolerances (the unknowns' units), the residual's absolute floor, the most steps, and the advice a
    failure gives (what to try) and its prefix (which method)."""

    rtol: float = 1e-9
    atol: float = 1e-12
    max_iterations: int = 50
    #: a step longer than trust (1 + ||u||_inf) is shortened to it (a trust region: a full Newton step from a
    #: poor guess of a shooting problem leaves for states whose flow is far from periodic)
    trust: float = np.inf
    what: str = "periodic_orbit"
    advice: str = "a better starting guess (q0, v0)"


def step(J, R: np.ndarray) -> np.ndarray:
    """du = -J^-1 R (least squares when J is singular); J dense, or sparse (SuperLU)."""
    if sps.issparse(J):
        try:
            with np.errstate(all="ignore"):
                du = spla.splu(J.tocsc()).solve(-R)
            if np.all(np.isfinite(du)):
                return du
        except RuntimeError:  # exactly singular
            pass
        J = J.toarray()
    try:
        with np.errstate(all="ignore"):
            du = sla.solve(J, -R, check_finite=True)
        if np.all(np.isfinite(du)):
            return du
    except (sla.LinAlgError, ValueError):
        pass
    return sla.lstsq(J, -R, check_finite=False)[0]


def norm(x: np.ndarray) -> float:
    """||x||_inf (0 for an empty x)."""
    return float(np.max(np.abs(x), initial=0.0))


def line_search(system_of: Callable, u: np.ndarray, du: np.ndarray, before: float) -> tuple:
    """(u + alpha du, R, J) for the largest alpha in 1, 1/2, ... 1/256 with ||R||_inf <= ``before``; when none
    is, the longest trial that could be evaluated (a Newton step through a bump of ||R|| is still the best
    information); a ConvergenceError when no trial could be evaluated."""
    best = None
    for alpha in 0.5 ** np.arange(9):
        trial = u + alpha * du
        try:
            R, J = system_of(trial)
        except (ConvergenceError, FloatingPointError, KernelError):  # a trial the flow or the kernels cannot take
            continue
        if not np.all(np.isfinite(R)):
            continue
        if norm(R) <= before:
            return trial, R, J
        if best is None:  # the longest step that could be evaluated
            best = (trial, R, J)
    if best is None:
        raise ConvergenceError("no step along the Newton direction could be evaluated (the integration or the "
                               "kernels failed at each trial)")
    return best


def newton(system_of: Callable[[np.ndarray], tuple], u0: np.ndarray, settings: NewtonSettings) -> OrbitSolution:
    """Solve R(u) = 0 from u0 (module doc); ``system_of(u)`` -> (R, dR/du)."""
    u = np.asarray(u0, float).copy()
    R, J = system_of(u)
    history = [norm(R)]
    for it in range(1, settings.max_iterations + 1):
        if not (np.all(np.isfinite(R)) and np.all(np.isfinite(J.data if sps.issparse(J) else J))):
            break
        du = step(J, R)
        limit = settings.trust * (1.0 + norm(u))
        if norm(du) > limit:
            du = du * (limit / norm(du))
        small = norm(du) <= settings.atol + settings.rtol * norm(u)
        u, R, J = line_search(system_of, u, du, history[-1])
        history.append(norm(R))
        if small:
            return OrbitSolution(u, it, history[-1])
    shown = ", ".join(f"{r:.3g}" for r in history[-4:])
    raise ConvergenceError(f"{settings.what}: Newton did not converge in {settings.max_iterations} iterations: "
                           f"the residual ||R||_inf went ... {shown} (the last {min(4, len(history))}); try "
                           f"{settings.advice}, or more iterations (key max_iterations)")
