"""Single and multiple shooting for a periodic orbit of a smooth lumped model: the unknowns, the residual and its
Jacobian.

The period [0, T] is split into S = ``segments`` equal segments [t_k, t_k + T/S], t_k = k T / S, each started from
its own unknown state x_k (S = 1: single shooting). Forced (T = 2 pi / omega fixed by the forcing's angular
frequency omega, rad/s): u = (x_0, ..., x_{S-1}) and

    R_k(u) = phi_k(x_k) - x_{k+1 mod S},      dR_k/dx_k = Phi_k,   dR_k/dx_{k+1} = -I,

phi_k the flow over segment k and Phi_k its state transition matrix (mechgen.runtime.periodic.flow: the variational
equations with the generated tangent kernel's Jacobian, or, with ``compiled``, the compiled loop's flow and its
central differences). Autonomous (T unknown): u = (x_0, ..., x_{S-1}, T), the columns dR_k/dT =
f(phi_k(x_k)) / S, and the phase condition v_p(0) = 0 (the velocity of coordinate p zero at t = 0: the orbit starts
at an extremum of q_p, which every non-constant orbit has; for a model of internal variables only, dz_p/dt = 0 at
t = 0) as the last row. The state is x = (q, v, z), internal variables after the coordinates and velocities. Multiple shooting keeps each segment's
flow short, so an unstable orbit (a multiplier mu > 1 grows a start error by mu per period) or a stiff one stays
within reach of Newton: the sensitivity is per segment, about mu^(1/S). The monodromy matrix is
Phi_{S-1} ... Phi_0. ``frequency_derivative`` gives dR/domega of a forced orbit at fixed model parameters: for single
shooting -f(T, x(T)) 2 pi / omega^2 (the period alone moves), for multiple shooting by central differences (step
1e-6 omega; the segments' start times move with omega).

The compiled loop integrates from t = 0, so it runs the segments of an autonomous orbit (whose equations do not
depend on t) and single shooting's one segment; a forced orbit's later segments use the variational equations.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.runtime.periodic.flow import differenced_flow, variational_flow


@dataclass(frozen=True)
class Shooting:
    """The shooting problem of ``system`` (module doc): ``omega`` the forcing's angular frequency (None:
    autonomous), ``phase`` the coordinate p of the phase condition, integrator tolerances ``rtol``/``atol``,
    ``segments`` S (1: single shooting)."""

    system: object
    omega: float | None
    phase: int = 0
    rtol: float = 1e-11
    atol: float = 1e-13
    #: mechgen.runtime.periodic.flow.compiled_flow's run, or None: the variational equations
    compiled: Callable | None = None
    segments: int = 1

    @property
    def autonomous(self) -> bool:
        """Whether the period is an unknown."""
        return self.omega is None

    def unknowns(self, X: np.ndarray, period: float) -> np.ndarray:
        """u from the segments' start states (rows; one row or a vector for single shooting) and the period."""
        X = np.asarray(X, float).ravel()
        return np.append(X, period) if self.autonomous else X.copy()

    def starts(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(X: the segments' start states, S x (2n + m), T) of the unknowns."""
        d = 2 * self.system.n + self.system.m
        if self.autonomous:
            return u[:-1].reshape(self.segments, d), float(u[-1])
        return u.reshape(self.segments, d), 2 * np.pi / self.omega

    def split(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(x0: the state at t = 0, T) of the unknowns (the first segment's start)."""
        X, T = self.starts(u)
        return X[0], T

    def segment_flow(self, x: np.ndarray, k: int, T: float) -> tuple[np.ndarray, np.ndarray]:
        """(x(t_k + T/S), Phi_k) from x(t_k) = x (module doc)."""
        if not (np.isfinite(T) and T > 0):
            raise FloatingPointError(f"period {T} is not positive")
        span = T / self.segments
        if self.compiled is not None and (k == 0 or self.autonomous):
            return differenced_flow(self.compiled, x, span)
        return variational_flow(self.system, x, k * span, span, self.rtol, self.atol)

    def flow(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x(T), the monodromy matrix Phi_{S-1} ... Phi_0) of the segments' flows (x(T) from the last segment)."""
        X, T = self.starts(u)
        Phi = np.eye(X.shape[1])
        for k in range(self.segments):
            end, step = self.segment_flow(X[k], k, T)
            Phi = step @ Phi
        return end, Phi

    def residual_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R(u), dR/du) (module doc)."""
        X, T = self.starts(u)
        S, d = X.shape
        R = np.empty(S * d)
        J = np.zeros((S * d + self.autonomous, S * d + self.autonomous))
        for k in range(S):
            end, Phi = self.segment_flow(X[k], k, T)
            rows = slice(k * d, (k + 1) * d)
            nxt = (k + 1) % S
            R[rows] = end - X[nxt]
            J[rows, k * d:(k + 1) * d] += Phi
            J[rows, nxt * d:(nxt + 1) * d] -= np.eye(d)
            if self.autonomous:
                J[rows, -1] = self.system.rhs((k + 1) * T / S, end) / S
        if not self.autonomous:
            return R, J
        value, row = self.phase_condition(X[0])
        J[-1, :d] = row
        return np.append(R, value), J

    def phase_condition(self, x0: np.ndarray) -> tuple[float, np.ndarray]:
        """(f_p(x0), its gradient): the p-th state component's rate zero at t = 0 - the velocity v_p of coordinate
        p (gradient e_{n+p}), or, for a model of internal variables only (n = 0), the rate of z_p."""
        n = self.system.n
        if n:
            row = np.zeros(x0.size)
            row[n + self.phase] = 1.0
            return float(x0[n + self.phase]), row
        return float(self.system.rhs(0.0, x0)[self.phase]), np.asarray(self.system.jacobian(0.0, x0), float)[self.phase]

    def frequency_derivative(self, u: np.ndarray) -> np.ndarray:
        """dR/domega of a forced orbit at fixed parameters: single shooting's f(T, x(T)) dT/domega, dT/domega =
        -2 pi / omega^2 (the period alone moves); multiple shooting's by central differences (step 1e-6 omega)."""
        if self.segments == 1:
            X, T = self.starts(u)
            end, _ = self.segment_flow(X[0], 0, T)
            return self.system.rhs(T, end) * (-2 * np.pi / self.omega**2)
        h = 1e-6 * self.omega
        shifted = [Shooting(self.system, w, self.phase, self.rtol, self.atol, self.compiled, self.segments)
                   for w in (self.omega + h, self.omega - h)]
        return (shifted[0].residual_jacobian(u)[0] - shifted[1].residual_jacobian(u)[0]) / (2 * h)
