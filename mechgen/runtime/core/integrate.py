"""Time integration: scipy's stiff and non-stiff integrators, and a symplectic leapfrog.

* :func:`integrate_first_order` - dx/dt = f(t, x) with ``scipy.integrate.solve_ivp``
  (BDF, Radau, LSODA with the generated Jacobian; RK45, DOP853 explicit).
* :func:`leapfrog` - velocity Verlet (Stormer-Verlet) for q'' = a(q), a separable
  Hamiltonian with the mass already inverted in ``a``: second order, symplectic,
  so the energy error stays bounded over long times (no drift).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mechgen.errors import ConvergenceError, KernelError
from mechgen.runtime.core.memory import dense_bytes, require

METHODS = ("BDF", "Radau", "LSODA", "RK45", "DOP853")
IMPLICIT = ("BDF", "Radau", "LSODA")


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


def integrate_first_order(rhs, x0, t_end: float, *, jac=None, method: str = "BDF", rtol: float = 1e-8,
                          atol: float = 1e-10, t_eval=None) -> Trajectory:
    """Integrate dx/dt = rhs(t, x) from 0 to t_end; rows of ``x`` are states at ``t``."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    kwargs = {"jac": jac} if (jac is not None and method in IMPLICIT) else {}
    from scipy.integrate import solve_ivp  # loaded on use: scipy.integrate brings scipy.optimize

    sol = solve_ivp(rhs, (0.0, float(t_end)), np.asarray(x0, float), method=method, rtol=rtol, atol=atol,
                    t_eval=t_eval, **kwargs)
    if not sol.success:
        reached = sol.t[-1] if sol.t.size else 0.0
        raise ConvergenceError(f"{method} stopped at t = {reached:.6g} of {t_end:.6g}: {sol.message}")
    if not np.all(np.isfinite(sol.y)):
        raise KernelError("the state became NaN/Inf during integration")
    return Trajectory(sol.t, sol.y.T, nfev=sol.nfev, njev=sol.njev, success=True, message=sol.message)


def leapfrog(acceleration, q0, v0, dt: float, n_steps: int, *, record_every: int = 1, energy=None) -> Trajectory:
    """Velocity Verlet: v += dt/2 a(q); q += dt v; v += dt/2 a(q) (one acceleration call per step)."""
    q, v = np.array(q0, float), np.array(v0, float)
    a = np.asarray(acceleration(q), float)
    n_rec = n_steps // record_every + 1
    require(dense_bytes(n_rec, 2 * q.size + 2), f"the leapfrog record of {n_rec} states of {q.size} coordinates",
            key="params.N")
    ts, qs, vs = np.empty(n_rec), np.empty((n_rec, q.size)), np.empty((n_rec, q.size))
    energies = []
    half = 0.5 * dt

    def record(k: int, step: int) -> None:
        ts[k], qs[k], vs[k] = step * dt, q, v
        if energy is not None:
            energies.append(float(energy(q, v)))

    record(0, 0)
    k = 1
    for step in range(1, n_steps + 1):
        v += half * a
        q += dt * v
        a = np.asarray(acceleration(q), float)
        v += half * a
        if step % record_every == 0:
            record(k, step)
            k += 1
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
        raise KernelError("leapfrog state became NaN/Inf (time step too large for the stiffest mode?)")
    return Trajectory(ts[:k], q=qs[:k], v=vs[:k], energy=energies, nfev=n_steps + 1)
