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
from typing import Callable

import numpy as np

from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.spectral.chebyshev import clenshaw_curtis, differentiation
from mechgen.runtime.steady.continuation import continuation

sl = lazy_module("scipy.linalg")


@dataclass(frozen=True)
class LocalBlocks:
    """Per collocation point j (N + 1 of them): J_sigma[j] (m x m) and J_g[j] (m,); ``shear`` the index of the
    shear stress among the m stresses."""

    J_sigma: np.ndarray
    J_g: np.ndarray
    shear: int


def operator(N: int, epsilon: float, Re: float, blocks: LocalBlocks,
             diffusion: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(L, M) of size (N - 1) + m (N + 1), ordered [u interior; sigma_1 at all points; ...; sigma_m]. With stress
    diffusion D > 0 each stress law gains D sigma'' and the walls' rows become sigma' = 0 (algebraic: M's row 0)."""
    D, _ = differentiation(N)
    m = blocks.J_g.shape[1]
    n_u, n_p = N - 1, N + 1
    size = n_u + m * n_p
    L = np.zeros((size, size))
    L[:n_u, :n_u] = epsilon * (D @ D)[1:N, 1:N]
    s0 = n_u + blocks.shear * n_p
    L[:n_u, s0:s0 + n_p] = D[1:N, :]
    Du = D[:, 1:N]  # u' at every point from the interior values (u = 0 at the walls)
    M = np.eye(size)
    M[:n_u, :n_u] *= Re
    for a in range(m):
        rows = slice(n_u + a * n_p, n_u + (a + 1) * n_p)
        L[rows, :n_u] = blocks.J_g[:, a][:, None] * Du
        for b in range(m):
            cols = slice(n_u + b * n_p, n_u + (b + 1) * n_p)
            L[rows, cols] = np.diag(blocks.J_sigma[:, a, b])
        if diffusion > 0.0:
            L[rows, rows] += diffusion * (D @ D)
            for wall in (n_u + a * n_p, n_u + (a + 1) * n_p - 1):  # sigma' = 0 in place of the wall's law
                L[wall, :] = 0.0
                L[wall, rows] = D[0 if wall == n_u + a * n_p else N, :]
                M[wall, wall] = 0.0
    return L, M


def eigenvalues(N: int, epsilon: float, Re: float, blocks: LocalBlocks, diffusion: float = 0.0) -> np.ndarray:
    """The finite eigenvalues lambda, rightmost first."""
    L, M = operator(N, epsilon, Re, blocks, diffusion)
    lam = sl.eigvals(L, M)
    return rightmost_first(lam[np.isfinite(lam)])


def rightmost_first(values: np.ndarray) -> np.ndarray:
    """Sorted by real part descending (rounded to 10 decimals, so that a conjugate pair's round-off does not order
    it), then imaginary part descending (a pair's positive member first)."""
    return values[np.lexsort((-values.imag, -np.round(values.real, 10)))]


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


#: a local stress law at P points: (g (P,), sigma (P, m)) -> (f (P, m), J_sigma (P, m, m), J_g (P, m))
LocalLaw = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class SteadyChannel:
    """Steady channel flow at pressure gradient G (the continuation parameter), collocated as in ``operator``:

        epsilon u'' + (sigma_s)' + G = 0 at the interior points,   f(sigma; g = u') = 0 at every point,

    unknowns x = [u interior (N - 1); sigma_1 .. sigma_m at the N + 1 points]. F_x is the operator L of the
    linearisation (its local blocks from ``law`` at the current state), F_G = [1 (momentum rows); 0]."""

    N: int
    epsilon: float
    law: LocalLaw
    m: int
    shear: int
    name: str = "steady channel"

    def state(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(g at every point, sigma (N + 1, m)) of x."""
        D, _ = differentiation(self.N)
        u, n_p = x[:self.N - 1], self.N + 1
        sigma = x[self.N - 1:].reshape(self.m, n_p).T
        return D[:, 1:self.N] @ u, sigma

    def F(self, x: np.ndarray, G: float) -> np.ndarray:
        """The residual (see the class doc)."""
        D, _ = differentiation(self.N)
        g, sigma = self.state(x)
        u = x[:self.N - 1]
        f = self.law(g, sigma)[0]
        momentum = self.epsilon * (D @ D)[1:self.N, 1:self.N] @ u + D[1:self.N, :] @ sigma[:, self.shear] + G
        return np.concatenate([momentum, f.T.ravel()])

    def F_u(self, x: np.ndarray, G: float) -> np.ndarray:
        """dF/dx: the linearised operator at x."""
        g, sigma = self.state(x)
        _, J_sigma, J_g = self.law(g, sigma)
        return operator(self.N, self.epsilon, 1.0, LocalBlocks(J_sigma, J_g, self.shear))[0]

    def F_lam(self, x: np.ndarray, G: float) -> np.ndarray:
        """dF/dG."""
        out = np.zeros(x.size)
        out[:self.N - 1] = 1.0
        return out

    def pack(self, u_interior: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        """x from u at the interior points and sigma (N + 1, m)."""
        return np.concatenate([u_interior, sigma.T.ravel()])


@dataclass(frozen=True)
class SteadyBranch:
    """The collocated steady branch in G from its start to just past its first fold: G and the flux
    Q = int u dy (Clenshaw-Curtis) per point, the folds' G (all those passed) and why it stopped."""

    G: np.ndarray
    flow_rate: np.ndarray
    folds: tuple
    status: str


def steady_branch(channel: SteadyChannel, x0: np.ndarray, G0: float, G_max: float, *,
                  max_points: int = 400) -> SteadyBranch:
    """Pseudo-arclength continuation (mechgen.runtime.steady.continuation) of the steady channel in G from (x0, G0)
    until G has come back by 2 % of G_max after its largest value (past the first fold), or G_max."""
    top = [G0]

    def until(x, G):
        top[0] = max(top[0], G)
        return ("fold passed", "past the first fold") if G < top[0] - 0.02 * G_max else None

    branch = continuation(channel, x0, G0, lam_max=G_max, max_points=max_points, ds=0.1, ds_max=1.0, until=until)
    w = clenshaw_curtis(channel.N)[1:channel.N]
    return SteadyBranch(branch.lam.copy(), branch.u[:, :channel.N - 1] @ w, tuple(f.lam for f in branch.folds),
                        branch.status)
