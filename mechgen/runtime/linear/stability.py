"""Stability of M q'' + C q' + K q = 0 (C = D + G, K possibly non-symmetric), and of E x' = A x.

First-order form with x = (q, q'): A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]],
eigenvalues s of A x = s B x (``scipy.linalg.eig``). The verdict uses a tolerance
relative to the spectrum's scale, ``tol = tolerance * scale`` with scale the
largest finite |s| (at least sqrt(||K|| / ||M||)), so round-off never turns a
conservative gyroscopic system into "flutter":

* ``stable``      - every Re s <= tol,
* ``divergence``  - the most unstable s has Re s > tol and |Im s| <= tol,
* ``flutter``     - the most unstable s has Re s > tol and |Im s| > tol.

Conservative gyroscopic systems with a positive definite energy (M and K symmetric
positive definite, C skew-symmetric; all to rounding) are stable whatever G (the energy
q'^T M q' + q^T K q is conserved), and their spectrum is found from a Hermitian problem
at about a third of the cost: with M = L_M L_M^T, K = L_K L_K^T and z = (L_M^T q', L_K^T q),
z' = S z with the real skew-symmetric

    S = [[-L_M^-1 C L_M^-T, -L_M^-1 L_K], [L_K^T L_M^-T, 0]],   s = i mu,  mu = eigvalsh(-i S).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from mechgen.runtime.core.memory import require_dense


@dataclass(frozen=True)
class StabilityResult:
    """Eigenvalues (sorted by imaginary, then real part), verdict, growth rate, frequencies, scale."""

    eigenvalues: np.ndarray
    verdict: str
    growth_rate: float
    frequencies: np.ndarray
    scale: float


def _verdict(s: np.ndarray, tolerance: float, floor: float = 0.0) -> StabilityResult:
    s = s[np.isfinite(s)]
    scale = max(float(np.max(np.abs(s))) if s.size else 0.0, floor, 1e-300)
    tol = tolerance * scale
    order = np.lexsort((s.real, s.imag))
    s = s[order]
    growth = float(np.max(s.real)) if s.size else 0.0
    if growth <= tol:
        verdict = "stable"
    else:
        worst = s[np.argmax(s.real)]
        verdict = "divergence" if abs(worst.imag) <= tol else "flutter"
    pos = np.sort(s.imag[s.imag > tol])
    freqs = pos[np.concatenate([[True], np.diff(pos) > tol])] if pos.size else pos
    return StabilityResult(s, verdict, growth, freqs, scale)


def _symmetric(A: np.ndarray, sign: float, rel: float = 1e-10) -> bool:
    """A = sign A^T to ``rel`` of its largest entry."""
    scale = float(np.max(np.abs(A))) if A.size else 0.0
    return float(np.max(np.abs(A - sign * A.T))) <= rel * scale if scale > 0 else True


def conservative_gyroscopic(M, C, K) -> np.ndarray | None:
    """The eigenvalues s = i mu of M q'' + C q' + K q = 0 when M, K are symmetric positive definite and C is
    skew-symmetric (to rounding: see the module doc), else None."""
    if not (_symmetric(M, 1.0) and _symmetric(K, 1.0) and _symmetric(C, -1.0)):
        return None
    try:
        LM = np.linalg.cholesky(0.5 * (M + M.T))
        LK = np.linalg.cholesky(0.5 * (K + K.T))
    except np.linalg.LinAlgError:
        return None
    n = M.shape[0]
    G = sla.solve_triangular(LM, sla.solve_triangular(LM, 0.5 * (C - C.T), lower=True).T, lower=True).T
    B = sla.solve_triangular(LM, LK, lower=True)
    S = np.block([[-G, -B], [B.T, np.zeros((n, n))]])
    mu = np.linalg.eigvalsh(-1j * S)
    return 1j * mu


def stability(M, C, K, *, tolerance: float = 1e-8) -> StabilityResult:
    """Eigenvalues and verdict of M q'' + C q' + K q = 0 (dense)."""
    M, C, K = (np.atleast_2d(np.asarray(x, float)) for x in (M, C, K))
    n = M.shape[0]
    require_dense(n, 40, "the dense stability eigenproblem")
    s = conservative_gyroscopic(M, C, K)
    if s is not None:  # K > 0: every |s| >= sqrt(lambda_min(K) / lambda_max(M)) > 0 sets the scale
        return _verdict(s, tolerance)
    eye, zero = np.eye(n), np.zeros((n, n))
    try:
        # M symmetric positive definite: the standard problem for M^-1 [K, C] (3-4x faster than QZ)
        factor = sla.cho_factor(M)
        A = np.block([[zero, eye], [-sla.cho_solve(factor, K), -sla.cho_solve(factor, C)]])
        s = sla.eig(A, right=False)
    except np.linalg.LinAlgError:
        A = np.block([[zero, eye], [-K, -C]])
        B = np.block([[eye, zero], [zero, M]])
        s = sla.eig(A, B, right=False)
    norm_m = np.linalg.norm(M, 2)
    floor = np.sqrt(np.linalg.norm(K, 2) / norm_m) if norm_m > 0 else 0.0
    return _verdict(np.asarray(s), tolerance, floor)


def stability_first_order(A, E, *, tolerance: float = 1e-8) -> StabilityResult:
    """Eigenvalues and verdict of E x' = A x (E may be singular: infinite eigenvalues are dropped)."""
    s = sla.eig(np.asarray(A, float), np.asarray(E, float), right=False)
    return _verdict(np.asarray(s), tolerance)


def stability_sparse(M, C, K, count: int, *, tolerance: float = 1e-8) -> StabilityResult:
    """The 2 ``count`` eigenvalues nearest 0 of M q'' + C q' + K q = 0 (sparse shift-invert, ARPACK).

    A x = s B x with A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]], shifted by a small
    negative sigma so that a singular K (rigid modes) does not make A - sigma B
    singular. The verdict is about the computed part of the spectrum: the lowest
    modes, where a discretised continuum is accurate.
    """
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    M, C, K = (sps.csc_matrix(x) for x in (M, C, K))
    n = M.shape[0]
    eye = sps.identity(n, format="csc")
    A = sps.bmat([[None, eye], [-K, -C]], format="csc")
    B = sps.bmat([[eye, None], [None, M]], format="csc")
    scale = np.sqrt(max(abs(K.diagonal()).max(), 1e-300) / max(abs(M.diagonal()).max(), 1e-300))
    sigma = -1e-6 * scale
    k = min(2 * count, 2 * n - 2)
    try:
        s = spla.eigs(A, k=k, M=B, sigma=sigma, which="LM", return_eigenvectors=False)
    except (RuntimeError, spla.ArpackError) as exc:
        from mechgen.errors import ConvergenceError

        raise ConvergenceError(f"sparse eigensolver (ARPACK shift-invert) failed: {exc}") from exc
    return _verdict(np.asarray(s), tolerance, floor=float(np.max(np.abs(s))) if len(s) else 0.0)
