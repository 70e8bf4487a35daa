"""Linear stability of a parallel shear flow U(y) between walls at y = -1, 1: the Orr-Sommerfeld problem.

A disturbance stream function psi = v(y) exp(i alpha (x - c t)) of the base flow U(y) (velocities in the
centreline velocity, lengths in the half-width, Re = U_c h / nu) obeys

    (U - c)(v'' - alpha^2 v) - U'' v = (v'''' - 2 alpha^2 v'' + alpha^4 v) / (i alpha Re),  v = v' = 0 at y = +-1,

discretised by Chebyshev collocation (mechgen.runtime.spectral.chebyshev) as the generalised eigenproblem
A v = c B v with B = D2 - alpha^2 I and A = U B - diag(U'') - (D4 - 2 alpha^2 D2 + alpha^4 I) / (i alpha Re).
Im c > 0 grows (growth rate alpha Im c). The derivatives of an eigenvalue in alpha and Re come from its left
and right eigenvectors, dc = w^H (dA - c dB) v / (w^H B v); the critical point (Im c = 0 at the minimum Re of
the neutral curve: Im c = 0 and d Im c / d alpha = 0) is found by Newton on those two equations.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.spectral.chebyshev import clamped_fourth, dirichlet_second, resolved

sl = lazy_module("scipy.linalg")


#: a base flow: y (interior points) -> (U, U'')
Profile = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def poiseuille(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Plane Poiseuille flow U = 1 - y^2, U'' = -2."""
    return 1.0 - y**2, np.full_like(y, -2.0)


@dataclass(frozen=True)
class Operators:
    """The alpha- and Re-independent pieces at N: D2, D4 (interior, clamped) and the profile's U, U''."""

    D2: np.ndarray
    D4: np.ndarray
    U: np.ndarray
    Upp: np.ndarray


def operators(N: int, profile: Profile = poiseuille) -> Operators:
    """The collocation matrices on the N - 1 interior points and the base flow there."""
    D2, y = dirichlet_second(N)
    U, Upp = profile(y)
    return Operators(D2, clamped_fourth(N), U, Upp)


def pencil(ops: Operators, alpha: float, Re: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of A v = c B v (see the module doc)."""
    eye = np.eye(ops.D2.shape[0])
    B = ops.D2 - alpha**2 * eye
    M = ops.D4 - 2.0 * alpha**2 * ops.D2 + alpha**4 * eye
    A = ops.U[:, None] * B - np.diag(ops.Upp) - M / (1j * alpha * Re)
    return A, B


def wave_speeds(ops: Operators, alpha: float, Re: float) -> np.ndarray:
    """The finite eigenvalues c, sorted by Im c descending (least stable first)."""
    A, B = pencil(ops, alpha, Re)
    c = sl.eigvals(A, B)
    c = c[np.isfinite(c)]
    return c[np.argsort(-c.imag, kind="stable")]


def spectrum(alpha: float, Re: float, N: int, N_check: int, tol: float,
             profile: Profile = poiseuille) -> tuple[np.ndarray, np.ndarray]:
    """(kept, rejected): the eigenvalues at N that reappear at N_check within tol * max(1, |c|) (reported at
    N_check, least stable first), and those that do not (unresolved)."""
    coarse = wave_speeds(operators(N, profile), alpha, Re)
    fine = wave_speeds(operators(N_check, profile), alpha, Re)
    kept, rejected = resolved(coarse, fine, tol)
    return kept[np.argsort(-kept.imag, kind="stable")], rejected


def least_stable(ops: Operators, alpha: float, Re: float) -> tuple[complex, complex, complex]:
    """(c, dc/dalpha, dc/dRe) of the eigenvalue with the largest Im c, derivatives by its eigenvectors."""
    A, B = pencil(ops, alpha, Re)
    c, w, v = sl.eig(A, B, left=True, right=True)
    c = np.where(np.isfinite(c), c, -np.inf * 1j)
    k = int(np.argmax(c.imag))
    eye = np.eye(B.shape[0])
    M = ops.D4 - 2.0 * alpha**2 * ops.D2 + alpha**4 * eye
    dM = -4.0 * alpha * ops.D2 + 4.0 * alpha**3 * eye
    dB = -2.0 * alpha * eye
    dA_alpha = ops.U[:, None] * dB - dM / (1j * alpha * Re) + M / (1j * alpha**2 * Re)
    dA_Re = M / (1j * alpha * Re**2)
    wk, vk = w[:, k].conj(), v[:, k]
    norm = wk @ B @ vk
    dc_alpha = wk @ (dA_alpha - c[k] * dB) @ vk / norm
    dc_Re = wk @ dA_Re @ vk / norm
    return complex(c[k]), complex(dc_alpha), complex(dc_Re)


def neutral_residual(ops: Operators, alpha: float, Re: float) -> np.ndarray:
    """[Im c, d Im c / d alpha] of the least stable mode: both zero at the critical point."""
    c, dc_alpha, _ = least_stable(ops, alpha, Re)
    return np.array([c.imag, dc_alpha.imag])


def critical_point(ops: Operators, alpha: float, Re: float, *, tol: float = 1e-7,
                   max_iter: int = 30) -> tuple[float, float, complex, int]:
    """(alpha_c, Re_c, c_c, iterations): Newton on neutral_residual = 0 in (alpha, log Re) from a start near it,
    the Jacobian by central differences (steps 1e-3) of the analytic first derivatives, until the step is below
    tol (alpha and log Re: 1e-7, a relative 1e-7 in Re, above the round-off floor of Im c, about 1e-10 at N = 96). Raises ArithmeticError when it does not converge."""
    x = np.array([alpha, np.log(Re)])
    h = 1e-3
    for it in range(1, max_iter + 1):
        F = neutral_residual(ops, x[0], np.exp(x[1]))
        J = np.empty((2, 2))
        for j in range(2):
            e = np.zeros(2)
            e[j] = h
            J[:, j] = (neutral_residual(ops, x[0] + e[0], np.exp(x[1] + e[1]))
                       - neutral_residual(ops, x[0] - e[0], np.exp(x[1] - e[1]))) / (2 * h)
        step = np.linalg.solve(J, -F)
        x = x + step
        if np.max(np.abs(step)) < tol:
            c = least_stable(ops, x[0], np.exp(x[1]))[0]
            return float(x[0]), float(np.exp(x[1])), c, it
    raise ArithmeticError(f"Newton on the neutral curve's minimum did not converge in {max_iter} iterations "
                          f"(last alpha = {x[0]:.8g}, Re = {np.exp(x[1]):.8g})")
