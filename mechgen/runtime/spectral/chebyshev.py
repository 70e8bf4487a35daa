"""Chebyshev collocation on [-1, 1] (Trefethen, Spectral Methods in MATLAB, 2000, ch. 6, 7 and 14).

Points y_j = cos(pi j / N), j = 0..N (y_0 = 1, y_N = -1); D the first-derivative matrix of the
degree-N interpolant at those points (exact on polynomials of degree <= N). Boundary conditions are
built into the matrices by restriction to the interior points: Dirichlet v(+-1) = 0 by deleting the
end rows and columns; the clamped pair v = v' = 0 by writing v = (1 - y^2) f with f the interpolant
of v/(1 - y^2) (Trefethen's program 38/40), whose fourth derivative is

    v'''' = (1 - y^2) f'''' - 8 y f''' - 12 f''.

Eigenvalues computed at two resolutions are compared (``resolved``): one that does not reappear at the
other resolution within a tolerance is a discretisation artefact and is rejected.
"""
from __future__ import annotations

import numpy as np


def points(N: int) -> np.ndarray:
    """The N + 1 Chebyshev-Gauss-Lobatto points y_j = cos(pi j / N), from 1 down to -1."""
    if N < 2:
        raise ValueError(f"Chebyshev collocation needs N >= 2 intervals, got {N}")
    return np.cos(np.pi * np.arange(N + 1) / N)


def differentiation(N: int) -> tuple[np.ndarray, np.ndarray]:
    """(D, y): D_ij = (c_i / c_j) (-1)^(i+j) / (y_i - y_j) off the diagonal, c_0 = c_N = 2, else 1, and the
    diagonal by the negative row sums (D times a constant is zero to round-off)."""
    y = points(N)
    c = np.hstack([2.0, np.ones(N - 1), 2.0]) * (-1.0) ** np.arange(N + 1)
    dy = y[:, None] - y[None, :]
    D = np.outer(c, 1.0 / c) / (dy + np.eye(N + 1))
    return D - np.diag(D.sum(axis=1)), y


def dirichlet_second(N: int) -> tuple[np.ndarray, np.ndarray]:
    """(D2, y_interior): d^2/dy^2 on the N - 1 interior points for v(-1) = v(1) = 0."""
    D, y = differentiation(N)
    return (D @ D)[1:N, 1:N], y[1:N]


def clamped_fourth(N: int) -> np.ndarray:
    """d^4/dy^4 on the N - 1 interior points for v = v' = 0 at y = -1, 1:
    v'''' = [(1 - y^2) D^4 - 8 y D^3 - 12 D^2] diag(1 / (1 - y^2)) v (the end values of v/(1 - y^2) set to 0)."""
    D, y = differentiation(N)
    D2 = D @ D
    D3 = D2 @ D
    D4 = D3 @ D
    s = np.zeros(N + 1)
    s[1:N] = 1.0 / (1.0 - y[1:N] ** 2)
    L4 = ((1.0 - y**2)[:, None] * D4 - 8.0 * y[:, None] * D3 - 12.0 * D2) * s[None, :]
    return L4[1:N, 1:N]


def resolved(coarse: np.ndarray, fine: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Split the coarse resolution's eigenvalues into (kept, rejected): kept where the nearest fine one lies
    within tol * max(1, |lambda|) (relative for large eigenvalues, absolute for small ones). Kept values are
    the fine resolution's (the more accurate); non-finite eigenvalues (infinite ones of a singular B) are
    dropped from both."""
    coarse = coarse[np.isfinite(coarse)]
    fine = fine[np.isfinite(fine)]
    kept, rejected = [], []
    for lam in coarse:
        if fine.size == 0:
            rejected.append(lam)
            continue
        j = int(np.argmin(np.abs(fine - lam)))
        if abs(fine[j] - lam) <= tol * max(1.0, abs(lam)):
            kept.append(fine[j])
        else:
            rejected.append(lam)
    return np.asarray(kept, dtype=complex), np.asarray(rejected, dtype=complex)


def clenshaw_curtis(N: int) -> np.ndarray:
    """Weights w_j with sum_j w_j v(y_j) = int_{-1}^{1} v dy exactly for polynomials of degree <= N (Trefethen's
    clencurt): w_j = (c_j / N) (1 - sum_k b_k cos(2 k theta_j) / (4 k^2 - 1)), theta_j = pi j / N."""
    theta = np.pi * np.arange(N + 1) / N
    w = np.zeros(N + 1)
    v = np.ones(N - 1)
    inner = theta[1:N]
    if N % 2 == 0:
        w[0] = w[N] = 1.0 / (N**2 - 1)
        for k in range(1, N // 2):
            v -= 2.0 * np.cos(2 * k * inner) / (4 * k**2 - 1)
        v -= np.cos(N * inner) / (N**2 - 1)
    else:
        w[0] = w[N] = 1.0 / N**2
        for k in range(1, (N - 1) // 2 + 1):
            v -= 2.0 * np.cos(2 * k * inner) / (4 * k**2 - 1)
    w[1:N] = 2.0 * v / N
    return w
