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
collocation of degree m is of order 2m at the nodes (superconvergence). The mesh starts uniform; ``adapted``
redistributes its intervals so that each holds an equal share of the monitor |x^(m+1)|^(1/(m+1)) (AUTO's rule), for
orbits with fast and slow phases.
"""
from __future__ import annotations

from dataclasses import dataclass

from math import factorial as math_factorial

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
    #: the mesh's edges in tau (mesh + 1 values from 0 to 1, increasing); None: uniform
    edges: tuple | None = None

    @property
    def widths(self) -> np.ndarray:
        """h_i, the intervals' widths in tau."""
        return np.diff(self.edge_array)

    @property
    def edge_array(self) -> np.ndarray:
        """The mesh's edges (uniform when ``edges`` is None)."""
        return np.linspace(0.0, 1.0, self.mesh + 1) if self.edges is None else np.asarray(self.edges, float)

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
        n, h = self.system.n, self.widths
        local = X[self.node_index()]  # mesh x (m + 1) x 2n
        values = np.einsum("kj,ijd->ikd", L, local).reshape(-1, 2 * n)
        slopes = (np.einsum("kj,ijd->ikd", D, local) / h[:, None, None]).reshape(-1, 2 * n)
        tau = (self.edge_array[:-1, None] + zeta[None, :] * h[:, None]).ravel()
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
        n, widths, m = self.system.n, self.widths, DEGREE
        _, L, D = interval_tables()
        tan = self.kernel("tangent", at, T)
        rq, rv, ra = (np.asarray(tan[k], float).reshape(-1, n, n) for k in ("r_q", "r_v", "r_a"))
        size = self.nodes * 2 * n
        J = np.zeros((self.mesh * m * 2 * n + self.autonomous, size + self.autonomous))
        eye = np.eye(n)
        index = self.node_index()
        for i in range(self.mesh):
            h = widths[i]
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
        up = Collocation(self.system, self.mesh, self.omega + h, self.phase, self.edges).residual(u)
        down = Collocation(self.system, self.mesh, self.omega - h, self.phase, self.edges).residual(u)
        return (up - down) / (2 * h)

    def states_at(self, u: np.ndarray, times: np.ndarray) -> np.ndarray:
        """The collocation polynomials' states at ``times`` (0 <= t <= T; rows)."""
        X, T = self.split(u)
        tau = np.clip(np.asarray(times, float) / T, 0.0, 1.0)
        edges = self.edge_array
        i = np.clip(np.searchsorted(edges, tau, side="right") - 1, 0, self.mesh - 1)
        values = lagrange_values((tau - edges[i]) / self.widths[i])
        return np.einsum("sj,sjd->sd", values, X[self.node_index()[i]])

    def adapted(self, u: np.ndarray) -> tuple["Collocation", np.ndarray]:
        """(the problem on a new mesh of as many intervals, u interpolated onto it): the mesh that equidistributes
        the monitor |x^(m+1)|^(1/(m+1)) (as AUTO's), x^(m+1) estimated on each interval from the jumps of the
        polynomials' m-th derivatives (constant on an interval) between its neighbours, the largest component of
        the state scaled by its range."""
        X, T = self.split(u)
        local = X[self.node_index()]  # mesh x (m + 1) x d
        m, h = DEGREE, self.widths
        nodes = np.arange(m + 1) / m
        # the m-th derivative of the interpolant in tau: m! times the leading coefficient (divided differences)
        weights = np.array([1.0 / np.prod(nodes[j] - np.delete(nodes, j)) for j in range(m + 1)])
        top = math_factorial(m) * np.einsum("j,ijd->id", weights, local) / h[:, None] ** m
        scale = np.ptp(X, axis=0) + 1e-300
        jump = (np.abs(np.roll(top, -1, axis=0) - top) / (0.5 * (h + np.roll(h, -1)))[:, None]
                + np.abs(top - np.roll(top, 1, axis=0)) / (0.5 * (h + np.roll(h, 1)))[:, None]) / 2
        monitor = np.max(jump / scale, axis=1) ** (1.0 / (m + 1)) + 1e-12
        mass = np.concatenate([[0.0], np.cumsum(monitor * h)])
        edges = np.interp(np.linspace(0.0, mass[-1], self.mesh + 1), mass, self.edge_array)
        edges[0], edges[-1] = 0.0, 1.0
        new = Collocation(self.system, self.mesh, self.omega, self.phase, tuple(edges))
        node_tau = (edges[:-1, None] + nodes[None, :-1] * np.diff(edges)[:, None]).ravel()
        return new, new.unknowns(self.states_at(u, node_tau * T), T)
