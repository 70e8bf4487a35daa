"""Single shooting for a periodic orbit of a smooth lumped model: the unknowns, the residual and its Jacobian.

Forced (the period T = 2 pi / omega fixed by the forcing's angular frequency omega, rad/s): the unknowns are
u = x0 = (q(0), v(0)) and

    R(u) = phi_T(x0) - x0,                 dR/du = Phi(T) - I,

phi_T the flow over [0, T] and Phi(T) its monodromy matrix (mechgen.runtime.periodic.flow: the variational
equations with the generated tangent kernel's Jacobian, or, with ``compiled``, the compiled loop's flow and its
central differences). Autonomous (T unknown): u = (x0, T) and

    R(u) = (phi_T(x0) - x0,  v_p(0)),      dR/du = [[Phi(T) - I, f(phi_T(x0))], [e_{n+p}^T, 0]],

the phase condition v_p(0) = 0 (the velocity of coordinate p zero at t = 0: the orbit starts at an extremum of
q_p, which every non-constant orbit has) making the solution isolated. ``frequency_derivative`` gives dR/domega of a
forced orbit at fixed model parameters, -f(T, x(T)) 2 pi / omega^2 (the period alone moves).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.runtime.periodic.flow import differenced_flow, variational_flow


@dataclass(frozen=True)
class Shooting:
    """The shooting problem of ``system`` (module doc): ``omega`` the forcing's angular frequency (None:
    autonomous), ``phase`` the coordinate p of the phase condition, integrator tolerances ``rtol``/``atol``."""

    system: object
    omega: float | None
    phase: int = 0
    rtol: float = 1e-11
    atol: float = 1e-13
    #: mechgen.runtime.periodic.flow.compiled_flow's run, or None: the variational equations
    compiled: Callable | None = None

    @property
    def autonomous(self) -> bool:
        """Whether the period is an unknown."""
        return self.omega is None

    def unknowns(self, x0: np.ndarray, period: float) -> np.ndarray:
        """u from a starting state and period."""
        return np.append(x0, period) if self.autonomous else np.asarray(x0, float).copy()

    def split(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(x0, T) of the unknowns."""
        if self.autonomous:
            return u[:-1], float(u[-1])
        return u, 2 * np.pi / self.omega

    def flow(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x(T), Phi(T)) from x0: the compiled flow and its central differences when ``compiled`` is given, else the
        variational equations (mechgen.runtime.periodic.flow)."""
        x0, T = self.split(u)
        if not (np.isfinite(T) and T > 0):
            raise FloatingPointError(f"period {T} is not positive")
        if self.compiled is not None:
            return differenced_flow(self.compiled, x0, T)
        return variational_flow(self.system, x0, 0.0, T, self.rtol, self.atol)

    def residual_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R(u), dR/du) (module doc)."""
        x0, T = self.split(u)
        xT, Phi = self.flow(u)
        R = xT - x0
        J = Phi - np.eye(x0.size)
        if not self.autonomous:
            return R, J
        n = self.system.n
        fT = self.system.rhs(T, xT)
        row = np.zeros(u.size)
        row[n + self.phase] = 1.0
        return np.append(R, x0[n + self.phase]), np.vstack([np.hstack([J, fT[:, None]]), row])

    def frequency_derivative(self, u: np.ndarray) -> np.ndarray:
        """dR/domega of a forced orbit at fixed parameters: f(T, x(T)) dT/domega, dT/domega = -2 pi / omega^2."""
        x0, T = self.split(u)
        xT, _ = self.flow(u)
        return self.system.rhs(T, xT) * (-2 * np.pi / self.omega**2)
