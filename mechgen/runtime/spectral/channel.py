"""The linearised channel flow of a fluid with a local stress law, by Chebyshev collocation in y.

Walls at y = -1, 1. Unknowns: the velocity disturbance u(y) (zero at the walls: the interior points) and the
m stress disturbances sigma(y) at all N + 1 points (no boundary conditions: the stress laws are local).
Linearised about a steady state with shear rate g_b(y) and stresses sigma_b(y):

    Re lambda u = epsilon u'' + (sigma_s)'                     (sigma_s: the shear stress, index ``shear``),
    lambda sigma = J_sigma(y) sigma + J_g(y) u'                (J_sigma = df/dsigma at fixed g, J_g = df/dg),

the generalised eigenproblem L x = lambda M x with M = diag(Re I, I) (Re = 0: M singular, infinite eigenvalues
dropped). The local blocks are the caller's (from a model's generated rates kernel). The stress-controlled local
Jacobian J_T = J_sigma - J_g e_s^T / epsilon (imposed total stress: g = (T - sigma_s)/epsilon) has eigenvalues
lambda_loc(y) that form the essential spectrum of the channel operator (the high-wavenumber limit, where the
viscous term slaves u' to -sigma_s/epsilon); its discretised copies lie on that band and are reported apart.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl

from mechgen.runtime.spectral.chebyshev import differentiation


@dataclass(frozen=True)
class LocalBlocks:
    """Per collocation point j (N + 1 of them): J_sigma[j] (m x m) and J_g[j] (m,); ``shear`` the index of the
    shear stress among the m stresses."""

    J_sigma: np.ndarray
    J_g: np.ndarray
    shear: int


def operator(N: int, epsilon: float, Re: float, blocks: LocalBlocks) -> tuple[np.ndarray, np.ndarray]:
    """(L, M) of size (N - 1) + m (N + 1), ordered [u interior; sigma_1 at all points; ...; sigma_m]."""
    D, _ = differentiation(N)
    m = blocks.J_g.shape[1]
    n_u, n_p = N - 1, N + 1
    size = n_u + m * n_p
    L = np.zeros((size, size))
    L[:n_u, :n_u] = epsilon * (D @ D)[1:N, 1:N]
    s0 = n_u + blocks.shear * n_p
    L[:n_u, s0:s0 + n_p] = D[1:N, :]
    Du = D[:, 1:N]  # u' at every point from the interior values (u = 0 at the walls)
    for a in range(m):
        rows = slice(n_u + a * n_p, n_u + (a + 1) * n_p)
        L[rows, :n_u] = blocks.J_g[:, a][:, None] * Du
        for b in range(m):
            cols = slice(n_u + b * n_p, n_u + (b + 1) * n_p)
            L[rows, cols] = np.diag(blocks.J_sigma[:, a, b])
    M = np.eye(size)
    M[:n_u, :n_u] *= Re
    return L, M


def eigenvalues(N: int, epsilon: float, Re: float, blocks: LocalBlocks) -> np.ndarray:
    """The finite eigenvalues lambda, rightmost first."""
    L, M = operator(N, epsilon, Re, blocks)
    lam = sl.eigvals(L, M) if Re > 0 else sl.eigvals(L, M, overwrite_a=True)
    lam = lam[np.isfinite(lam)]
    return lam[np.argsort(-lam.real, kind="stable")]


def local_eigenvalues(blocks: LocalBlocks, epsilon: float) -> np.ndarray:
    """lambda_loc at each point: eigenvalues of J_T = J_sigma - J_g e_s^T / epsilon, shape (points, m), each row
    sorted by real part descending."""
    J = blocks.J_sigma.copy()
    J[:, :, blocks.shear] -= blocks.J_g / epsilon
    lam = np.linalg.eigvals(J)
    order = np.argsort(-lam.real, axis=1, kind="stable")
    return np.take_along_axis(lam, order, axis=1)


def off_band(values: np.ndarray, band: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """(point, on_band): the eigenvalues farther than tol * max(1, |lambda|) from every sampled band value, and the
    others (the essential spectrum's discretised copies)."""
    band = band.ravel()
    far = np.array([np.min(np.abs(band - v)) > tol * max(1.0, abs(v)) for v in values], dtype=bool)
    return values[far], values[~far]
