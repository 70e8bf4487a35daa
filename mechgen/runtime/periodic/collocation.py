"""Orthogonal collocation for a periodic orbit of a smooth lumped model: the unknowns, the residual and its Jacobian.

Time is scaled to tau = t / T in [0, 1], split into ``mesh`` equal intervals of width h. On each interval the
coordinates q and the velocities v are polynomials of degree m (m = DEGREE), held by their values at m + 1
equally spaced nodes (the interval's ends shared with its neighbours; the last node is the first: periodicity), so
the unknowns are (q, v) at mesh * m nodes. At the m Gauss-Legendre points of each interval the equations are the
model's own, in its implicit second-order form:

    dq/dtau - T v = 0,        r(q, v, (dv/dtau) / T, T tau) = 0,

with r the generated ``residual`` kernel evaluated at all mesh * m points in one batched call, and its exact
Jacobian from the ``tangent`` kernel (one batched call):

    d/dq_node: (l'(zeta) / h) I and r_q l(zeta),   d/dv_node: -T l(zeta) I and r_v l(zeta) + r_a l'(zeta) / (h T),

l the node's Lagrange polynomial. No mass matrix is inverted. Forced: T = 2 pi / omega fixed. Autonomous: T is an
unknown, the phase condition is v_p(0) = 0 (as shooting's), and dE/dT = (-v, -r_a (dv/dtau) / T^2). Gauss
collocation of degree m is of order 2m at the nodes (superconvergence); the mesh is uniform (no adaptation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the polynomial degree m on each interval (m Gauss points: order 2m = 8 at the mesh points)
DEGREE = 4


def interval_tables(m: int = DEGREE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(zeta (m,), L (m x (m+1)), D (m x (m+1))): the Gauss points on [0, 1] and the Lagrange polynomials of the m + 1
    equally spaced nodes j/m, and their derivatives, at those points."""
    xg, _ = np.polynomial.legendre.leggauss(m)
    zeta = (xg + 1) / 2
    nodes = np.arange(m + 1) / m
    L = np.ones((m, m + 1))
    D = np.zeros((m, m + 1))
    for j in range(m + 1):
        others = np.delete(nodes, j)
        denominator = np.prod(nodes[j] - others)
        L[:, j] = np.prod(zeta[:, None] - others[None, :], axis=1) / denominator
        for skip in range(m):
            rest = np.delete(others, skip)
            D[:, j] += np.prod(zeta[:, None] - rest[None, :], axis=1) / denominator
    return zeta, L, D


def lagrange_values(s: np.ndarray, m: int = DEGREE) -> np.ndarray:
    """The Lagrange polynomials of the nodes j/m at the points s in [0, 1] (rows)."""
    nodes = np.arange(m + 1) / m
    out = np.ones((len(s), m + 1))
    for j in range(m + 1):
        others = np.delete(nodes, j)
        out[:, j] = np.prod(s[:, None] - others[None, :], axis=1) / np.prod(nodes[j] - others)
    return out


@dataclass(frozen=True)
class Collocation:
    """The collocation problem of ``system`` on ``mesh`` intervals (module doc): ``omega`` the forcing's angular
    frequency (None: autonomous), ``phase`` the coordinate p of the phase condition."""

    system: object
    mesh: int
    omega: float | None
    phase: int = 0

    @property
    def autonomous(self) -> bool:
        """Whether the period is an unknown."""
        return self.omega is None

    @property
    def nodes(self) -> int:
        """mesh * m distinct nodes."""
        return self.mesh * DEGREE

    def unknowns(self, X: np.ndarray, period: float) -> np.ndarray:
        """u from the states at the nodes (rows, (q, v)) and the period."""
        return np.append(X.ravel(), period) if self.autonomous else np.asarray(X, float).ravel().copy()

    def split(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(X: states at the nodes (nodes x 2n), T) of the unknowns."""
        d = 2 * self.system.n
        if self.autonomous:
            return u[:-1].reshape(self.nodes, d), float(u[-1])
        return u.reshape(self.nodes, d), 2 * np.pi / self.omega

    def node_index(self) -> np.ndarray:
        """(mesh x (m + 1)): the global node of each interval's local node (the last one wraps to 0)."""
        i = np.arange(self.mesh)[:, None] * DEGREE + np.arange(DEGREE + 1)[None, :]
        return i % self.nodes

    def points(self, X: np.ndarray, T: float) -> dict:
        """q, v, dq/dtau, dv/dtau at the Gauss points (mesh * m rows) and tau there."""
        zeta, L, D = interval_tables()
        n, h = self.system.n, 1.0 / self.mesh
        local = X[self.node_index()]  # mesh x (m + 1) x 2n
        values = np.einsum("kj,ijd->ikd", L, local).reshape(-1, 2 * n)
        slopes = np.einsum("kj,ijd->ikd", D, local).reshape(-1, 2 * n) / h
        tau = ((np.arange(self.mesh)[:, None] + zeta[None, :]) * h).ravel()
        return {"q": values[:, :n], "v": values[:, n:], "dq": slopes[:, :n], "dv": slopes[:, n:], "tau": tau}

    def kernel(self, name: str, at: dict, T: float) -> dict:
        """One batched call of ``name`` at the Gauss points (a = (dv/dtau) / T, t = T tau)."""
        k = self.system.kernels[name]
        inputs = {"q": at["q"], "v": at["v"], "a": at["dv"] / T, "t": (T * at["tau"])[:, None],
                  "p": self.system.params}
        wanted = {port["name"] for port in k.spec["inputs"]}
        return k.evaluate({key: value for key, value in inputs.items() if key in wanted})

    def residual(self, u: np.ndarray) -> np.ndarray:
        """The collocation equations (module doc), point by point ((dq - T v, r) per point), the phase condition
        appended when autonomous."""
        X, T = self.split(u)
        at = self.points(X, T)
        n = self.system.n
        r = np.asarray(self.kernel("residual", at, T)["r"], float).reshape(-1, n)
        E = np.hstack([at["dq"] - T * at["v"], r]).ravel()
        return np.append(E, X[0, n + self.phase]) if self.autonomous else E

    def residual_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R(u), dR/du) (module doc), dense."""
        X, T = self.split(u)
        at = self.points(X, T)
        n, h, m = self.system.n, 1.0 / self.mesh, DEGREE
        _, L, D = interval_tables()
        tan = self.kernel("tangent", at, T)
        rq, rv, ra = (np.asarray(tan[k], float).reshape(-1, n, n) for k in ("r_q", "r_v", "r_a"))
        size = self.nodes * 2 * n
        J = np.zeros((self.mesh * m * 2 * n + self.autonomous, size + self.autonomous))
        eye = np.eye(n)
        index = self.node_index()
        for i in range(self.mesh):
            for k in range(m):
                c = i * m + k
                rows = slice(c * 2 * n, c * 2 * n + n), slice(c * 2 * n + n, (c + 1) * 2 * n)
                for j in range(m + 1):
                    g = index[i, j] * 2 * n
                    J[rows[0], g:g + n] += D[k, j] / h * eye
                    J[rows[0], g + n:g + 2 * n] += -T * L[k, j] * eye
                    J[rows[1], g:g + n] += rq[c] * L[k, j]
                    J[rows[1], g + n:g + 2 * n] += rv[c] * L[k, j] + ra[c] * D[k, j] / (h * T)
        R = self.residual(u)
        if self.autonomous:
            column = np.hstack([-at["v"], -np.einsum("cij,cj->ci", ra, at["dv"]) / T**2]).ravel()
            J[:-1, -1] = column
            J[-1, n + self.phase] = 1.0
        return R, J

    def frequency_derivative(self, u: np.ndarray) -> np.ndarray:
        """dR/domega of a forced orbit at fixed parameters (central differences, step 1e-6 omega)."""
        h = 1e-6 * self.omega
        up = Collocation(self.system, self.mesh, self.omega + h, self.phase).residual(u)
        down = Collocation(self.system, self.mesh, self.omega - h, self.phase).residual(u)
        return (up - down) / (2 * h)

    def states_at(self, u: np.ndarray, times: np.ndarray) -> np.ndarray:
        """The collocation polynomials' states at ``times`` (0 <= t <= T; rows)."""
        X, T = self.split(u)
        tau = np.clip(np.asarray(times, float) / T, 0.0, 1.0) * self.mesh
        i = np.minimum(tau.astype(int), self.mesh - 1)
        values = lagrange_values(tau - i)
        return np.einsum("sj,sjd->sd", values, X[self.node_index()[i]])
