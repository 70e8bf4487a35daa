"""Two-parameter continuation of a fold (LP) or a Hopf point (H) of equilibria F(y, a, b) = 0.

Each curve is the branch, in the second parameter b, of an extended system G(u, b) = 0 continued by
mechgen.runtime.steady.continuation (pseudo-arclength through turns of b):

* **fold curve** (minimally augmented, Govaerts, *Numerical Methods for Bifurcations of Dynamical Equilibria*,
  2000, ch. 4): u = (y, a) and

      G = [F(y, a, b); g(y, a, b)],   [[F_y, w], [v^T, 0]] [phi; g] = [0; 1],

  with v and w the right and left null vectors of F_y at the starting fold (fixed along the curve: the bordered
  matrix stays regular near it); g = 0 exactly where F_y is singular.
* **Hopf curve** (the standard extended system, Kuznetsov, *Elements of Applied Bifurcation Theory*, sec. 10.2):
  u = (y, a, omega, q_r, q_i) and, with A = d(dx/dt)/dx the first-order Jacobian at the equilibrium's state,

      G = [F(y, a, b); A q_r + omega q_i; A q_i - omega q_r; c^T q_r - 1; c^T q_i],

  the eigenvector q = q_r + i q_i of A for i omega normalised against a fixed real c (the start's q_r / |q_r|^2
  after rotating q so that q_r . q_i = 0).

G is evaluated exactly (the generated F, F_y and A); its Jacobian G_u and G_b are forward differences with
step 1e-7 (1 + |u_k|) (1e-5 for periodic orbits, whose R_u may itself come from differences of a flow): their
error only slows Newton's convergence, it does not move a point, which solves G = 0 to the corrector's
tolerance.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from mechgen.runtime.steady.continuation import ParametricEquations

#: the forward-difference step of G's Jacobian, relative to 1 + |u_k|
DIFF_STEP = 1e-7


def jacobian_by_differences(G: Callable, u: np.ndarray, lam: float,
                            step: float = DIFF_STEP) -> tuple[np.ndarray, np.ndarray]:
    """(G_u, G_lam) by forward differences of relative step ``step`` (module doc)."""
    g0 = G(u, lam)
    cols = []
    for k in range(u.size):
        h = step * (1.0 + abs(u[k]))
        du = u.copy()
        du[k] += h
        cols.append((G(du, lam) - g0) / h)
    h = step * (1.0 + abs(lam))
    return np.column_stack(cols), (G(u, lam + h) - g0) / h


def equations(G: Callable, name: str, step: float = DIFF_STEP) -> ParametricEquations:
    """G(u, lam) as the continuation's ParametricEquations, its Jacobian by differences of relative step ``step``
    (larger where G's own Jacobian inputs carry difference noise, as a shooting monodromy by differences does)."""
    memo: dict = {}

    def both(u, lam):
        key = (np.asarray(u, float).tobytes(), float(lam))
        if key not in memo:
            memo.clear()
            memo[key] = jacobian_by_differences(G, np.asarray(u, float), float(lam), step)
        return memo[key]

    return ParametricEquations(G, lambda u, lam: both(u, lam)[0], lambda u, lam: both(u, lam)[1], name=name)


def fold_system(residual: Callable, jacobian: Callable, y0: np.ndarray, a0: float, b0: float):
    """(G, u0) of the fold curve through the fold y0 at (a0, b0); ``residual(y, a, b)`` and
    ``jacobian(y, a, b)`` give F and F_y (dense)."""
    Fy = np.asarray(jacobian(y0, a0, b0), float)
    u_, _, vt = np.linalg.svd(Fy)
    v, w = vt[-1], u_[:, -1]
    n = y0.size

    def G(u, b):
        y, a = u[:n], float(u[n])
        bordered = np.block([[np.asarray(jacobian(y, a, b), float), w[:, None]], [v[None, :], np.zeros((1, 1))]])
        rhs = np.zeros(n + 1)
        rhs[-1] = 1.0
        g = np.linalg.solve(bordered, rhs)[-1]
        return np.append(residual(y, a, b), g)

    return G, np.append(y0, a0)


def hopf_system(residual: Callable, state_jacobian: Callable, y0: np.ndarray, a0: float, b0: float):
    """(G, u0) of the Hopf curve through the Hopf point y0 at (a0, b0); ``state_jacobian(y, a, b)``: A, the
    first-order Jacobian at the equilibrium's state (N x N)."""
    A = np.asarray(state_jacobian(y0, a0, b0), float)
    lam, vecs = np.linalg.eig(A)
    k = int(np.argmin(np.where(lam.imag > 0, np.abs(lam.real), np.inf)))
    omega, q = float(lam[k].imag), vecs[:, k]
    # rotate q so that q_r . q_i = 0 (the largest real part), then c = q_r / |q_r|^2
    theta = 0.5 * np.angle(np.sum(q * q))
    q = q * np.exp(-1j * theta)
    c = q.real / (q.real @ q.real)
    n, N = y0.size, A.shape[0]

    def G(u, b):
        y, a, w = u[:n], float(u[n]), float(u[n + 1])
        qr, qi = u[n + 2:n + 2 + N], u[n + 2 + N:]
        J = np.asarray(state_jacobian(y, a, b), float)
        return np.concatenate([residual(y, a, b), J @ qr + w * qi, J @ qi - w * qr, [c @ qr - 1.0, c @ qi]])

    return G, np.concatenate([y0, [a0, omega], q.real, q.imag])
