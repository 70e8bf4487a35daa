"""``periodic_orbit``'s ``start = "linear"``: a forced orbit's first guess from the linear forced response.

The model is linearised at the rest state q = 0, v = 0, a = 0, t = 0 (the generated ``tangent`` kernel: K = dr/dq,
C = dr/dv, M = dr/da), and the forcing f(t) = -r(0, 0, 0, t) is sampled at the N = 8 (H + 1) phases of one
period 2 pi / omega and projected onto its harmonics, f = f_0 + sum_k Re(F_k e^{i k omega t}),
F_k = a_k - i b_k (mechgen.runtime.periodic.fourier). The guess is the linear response to each harmonic,

    X_k = (K - (k omega)^2 M + i k omega C)^-1 F_k,   X_0 = K^-1 f_0,
    q(t) = X_0 + sum_k Re(X_k e^{i k omega t}),

the receptance at the starting frequency (for one harmonic forcing F cos(omega t): (K - omega^2 M + i omega C)^-1 F).
Harmonics whose forcing is zero (below 1e-12 of the largest) are left out; where a forced harmonic's dynamic
stiffness is singular (an undamped resonance: mechgen.runtime.linear.harmonic.harmonic_solve's pivot test) the
linear response does not exist and the start is refused (SceneError at ``start``), as is a singular K under a
mean force.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError, SceneError
from mechgen.runtime.linear.harmonic import harmonic_solve
from mechgen.runtime.periodic import fourier
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance

#: forcing harmonics below this share of the largest are left out
NEGLIGIBLE = 1e-12


def forcing_and_matrices(system, omega: float, harmonics: int) -> tuple[np.ndarray, tuple]:
    """(F: the forcing's coefficients ((2H + 1) x n) of f = -r(0, 0, 0, t), (K, C, M) at the rest state, t = 0)."""
    n = system.n
    problem = HarmonicBalance(system, fourier.basis(harmonics), omega)
    at = problem.samples(np.zeros((problem.basis.size, n)), omega)
    r = np.asarray(problem.evaluate("residual", at)["r"], float).reshape(-1, n)
    F = -(problem.basis.projector @ r)
    tan = problem.evaluate("tangent", at)
    K, C, M = (np.asarray(tan[k], float).reshape(-1, n, n)[0] for k in ("r_q", "r_v", "r_a"))
    return F, (K, C, M)


def singular(what: str, omega: float, k: int) -> SceneError:
    """The refusal of a linear response that does not exist."""
    return SceneError(f"periodic_orbit: start = \"linear\": the linear response does not exist at harmonic {k} of "
                      f"the frequency {omega:.6g}: {what} is singular (an undamped resonance of the linearisation "
                      "at q = 0)", key="start",
                      expected="start = \"guess\" with q0 / v0 near the orbit, or a frequency away from the linear "
                      "resonance (or damping in the model)")


def solve_dense(M, C, K, w: float, rhs: np.ndarray, what: str, omega: float, k: int) -> np.ndarray:
    """(K - w^2 M + i w C)^-1 rhs by the forced response's own solve (mechgen.runtime.linear.harmonic), refused
    (:func:`singular`) where it finds the dynamic stiffness singular."""
    try:
        return harmonic_solve(M, C, K, w, np.asarray(rhs, complex))
    except ConvergenceError:
        raise singular(what, omega, k) from None


def linear_coefficients(system, omega: float, harmonics: int) -> np.ndarray:
    """U ((2H + 1) x n): the coefficients of the linear response q(t) (module doc)."""
    F, (K, C, M) = forcing_and_matrices(system, omega, harmonics)
    H = harmonics
    U = np.zeros_like(F)
    largest = float(np.max(np.abs(F), initial=0.0))
    if np.max(np.abs(F[0]), initial=0.0) > NEGLIGIBLE * largest:
        U[0] = solve_dense(M, C, K, 0.0, F[0], "K", omega, 0).real
    for k in range(1, H + 1):
        Fk = F[k] - 1j * F[H + k]
        if np.max(np.abs(Fk), initial=0.0) <= NEGLIGIBLE * largest:
            continue
        w = k * omega
        X = solve_dense(M, C, K, w, Fk, f"K - ({k} omega)^2 M + i {k} omega C", omega, k)
        U[k], U[H + k] = X.real, -X.imag
    return U
