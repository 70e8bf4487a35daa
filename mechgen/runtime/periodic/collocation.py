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

A model with internal variables z (m_z of them; the state x = (q, v, z), possibly without coordinates) adds at each
Gauss point the first-order rows

    dz/dtau - T g(q, v, z, T tau) = 0,

g the generated ``rates`` kernel (its Jacobian from ``rates_tangent``: d/dz_node (l'(zeta)/h) I - T g_z l(zeta),
d/dq_node -T g_q l(zeta), d/dv_node -T g_v l(zeta), d/dT -g), and r takes z too (r_z from the tangent). Its
Jacobian is sparse (scipy CSR, built in one vectorised pass: a stiff orbit needs hundreds of intervals), and each of
its point's rows is weighted by the interval's width h_i (h_i dx/dtau - h_i T f: the state's change over the
interval, so that the small intervals of a fast phase do not dominate ||R|| and R's round-off is the state's). Its
autonomous phase condition is AUTO's integral one against a ``reference`` orbit x_ref (the starting guess, then the
previous solution on each adapted mesh),

    int_0^1 x(tau) . x_ref'(tau) dtau = 0,

by Gauss quadrature on the mesh: it keeps the orbit's phase nearest the reference's (it needs no coordinate and no
extremum, so it serves a model of internal variables only, whose orbit may turn fast).

:meth:`Collocation.monodromy` is the monodromy matrix of the discretisation itself (AUTO's Floquet multipliers): the
linearised collocation equations of interval i, at fixed T, give its end state from its start state, y_{i+1} =
P_i y_i (the interval's interior nodes condensed), and Phi(T) = P_{N-1} ... P_0, the collocation solution of the
variational equations dy/dtau = T J y (of the same order 2m), with no integration (a stiff orbit's monodromy
without an explicit integrator's step limits).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace

from math import factorial as math_factorial

import numpy as np

from mechgen.runtime.core.lazy_import import lazy_module

sps = lazy_module("scipy.sparse")


#: the polynomial degree m on each interval (m Gauss points: order 2m = 8 at the mesh points)
DEGREE = 4
#: the most bytes of dense interval blocks the monodromy gathers at a time (Collocation.interval_blocks)
BLOCK_BYTES = 32 << 20


@functools.lru_cache(maxsize=8)
def interval_tables(m: int = DEGREE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(zeta (m,), L (m x (m+1)), D (m x (m+1))): the Gauss points on [0, 1] and the Lagrange polynomials of the m + 1
    equally spaced nodes j/m, and their derivatives, at those points. Computed once per m (each residual and
    Jacobian of a continuation reads them), read-only."""
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
    for table in (zeta, L, D):
        table.flags.writeable = False
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
    frequency (None: autonomous), ``phase`` the coordinate p of the phase condition v_p(0) = 0, or, with
    ``reference`` (the node states of a reference orbit on this mesh, nodes x (2n + m_z)), the integral phase
    condition against it."""

    system: object
    mesh: int
    omega: float | None
    phase: int = 0
    #: the mesh's edges in tau (mesh + 1 values from 0 to 1, increasing); None: uniform
    edges: tuple | None = None
    #: the reference orbit of the integral phase condition (node states); None: v_p(0) = 0
    reference: np.ndarray | None = field(default=None, compare=False)

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

    @property
    def state_size(self) -> int:
        """d = 2n + m_z, the state x = (q, v, z) at a node."""
        return 2 * self.system.n + self.system.m

    @property
    def first_order(self) -> bool:
        """Whether the equations hold first-order rows (internal variables) or the integral phase condition: the
        sparse Jacobian (module doc)."""
        return bool(self.system.m) or self.reference is not None

    def unknowns(self, X: np.ndarray, period: float) -> np.ndarray:
        """u from the states at the nodes (rows, (q, v, z)) and the period."""
        return np.append(X.ravel(), period) if self.autonomous else np.asarray(X, float).ravel().copy()

    def split(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(X: states at the nodes (nodes x d), T) of the unknowns."""
        d = self.state_size
        if self.autonomous:
            return u[:-1].reshape(self.nodes, d), float(u[-1])
        return u.reshape(self.nodes, d), 2 * np.pi / self.omega

    def node_tau(self) -> np.ndarray:
        """tau at the nodes (in the order of the unknowns)."""
        nodes = np.arange(DEGREE) / DEGREE
        return (self.edge_array[:-1, None] + nodes[None, :] * self.widths[:, None]).ravel()

    def node_index(self) -> np.ndarray:
        """(mesh x (m + 1)): the global node of each interval's local node (the last one wraps to 0)."""
        i = np.arange(self.mesh)[:, None] * DEGREE + np.arange(DEGREE + 1)[None, :]
        return i % self.nodes

    def points(self, X: np.ndarray, T: float) -> dict:
        """q, v, z and dq/dtau, dv/dtau, dz/dtau at the Gauss points (mesh * m rows) and tau there."""
        zeta, L, D = interval_tables()
        n, h, d = self.system.n, self.widths, self.state_size
        local = X[self.node_index()]  # mesh x (m + 1) x d
        values = np.einsum("kj,ijd->ikd", L, local).reshape(-1, d)
        slopes = (np.einsum("kj,ijd->ikd", D, local) / h[:, None, None]).reshape(-1, d)
        tau = (self.edge_array[:-1, None] + zeta[None, :] * h[:, None]).ravel()
        return {"q": values[:, :n], "v": values[:, n:2 * n], "z": values[:, 2 * n:], "dq": slopes[:, :n],
                "dv": slopes[:, n:2 * n], "dz": slopes[:, 2 * n:], "tau": tau}

    def kernel(self, name: str, at: dict, T: float) -> dict:
        """One batched call of ``name`` at the Gauss points (a = (dv/dtau) / T, t = T tau)."""
        k = self.system.kernels[name]
        inputs = {"q": at["q"], "v": at["v"], "a": at["dv"] / T, "z": at["z"], "t": (T * at["tau"])[:, None],
                  "p": self.system.params}
        wanted = {port["name"] for port in k.spec["inputs"]}
        return k.evaluate({key: value for key, value in inputs.items() if key in wanted})

    def residual(self, u: np.ndarray) -> np.ndarray:
        """The collocation equations (module doc), point by point ((dq - T v, r, dz - T g) per point), the phase
        condition appended when autonomous."""
        X, T = self.split(u)
        at = self.points(X, T)
        n, m = self.system.n, self.system.m
        parts = []
        if n:
            r = np.asarray(self.kernel("residual", at, T)["r"], float).reshape(-1, n)
            parts += [at["dq"] - T * at["v"], r]
        if m:
            parts.append(at["dz"] - T * np.asarray(self.kernel("rates", at, T)["g"], float).reshape(-1, m))
        E = np.hstack(parts)
        if self.first_order:  # weighted by the interval's width (module doc)
            E = E * np.repeat(self.widths, DEGREE)[:, None]
        E = E.ravel()
        return np.append(E, self.phase_row() @ X.ravel()) if self.autonomous else E

    def phase_row(self) -> np.ndarray:
        """The phase condition's gradient in the node states (it is linear in them): e_{n+p} at node 0, or the
        integral condition's Gauss quadrature sum_i h_i sum_k w_k l_j(zeta_k) x_ref'(tau_ik) gathered per node.
        Computed once per problem (it depends on the mesh and the reference only), read-only."""
        return self._phase_row

    @functools.cached_property
    def _phase_row(self) -> np.ndarray:
        """:meth:`phase_row`'s vector, built on first use."""
        d = self.state_size
        row = np.zeros(self.nodes * d)
        if self.reference is None:
            row[self.system.n + self.phase] = 1.0
        else:
            _, L, D = interval_tables()
            weights = np.polynomial.legendre.leggauss(DEGREE)[1] / 2
            index = self.node_index()
            ref = np.asarray(self.reference, float).reshape(self.nodes, d)[index]  # mesh x (m + 1) x d
            slopes = np.einsum("kj,ijd->ikd", D, ref) / self.widths[:, None, None]  # dx_ref/dtau at the points
            share = np.einsum("k,kj,ikd->ijd", weights, L, slopes) * self.widths[:, None, None]
            np.add.at(row.reshape(self.nodes, d), index, share)
        row.flags.writeable = False
        return row

    def residual_jacobian(self, u: np.ndarray) -> tuple:
        """(R(u), dR/du) (module doc): dense for a model of coordinates only with v_p(0) = 0, else sparse (CSR)."""
        if self.first_order:
            return self.residual(u), self.sparse_jacobian(u)
        X, T = self.split(u)
        at = self.points(X, T)
        n, widths, m = self.system.n, self.widths, DEGREE
        _, L, D = interval_tables()
        tan = self.kernel("tangent", at, T)
        rq, rv, ra = (np.asarray(tan[k], float).reshape(-1, n, n) for k in ("r_q", "r_v", "r_a"))
        size = self.nodes * 2 * n
        J = np.zeros((self.mesh * m * 2 * n + self.autonomous, size + self.autonomous))
        # point c = i m + k and its interval's local node j: the 2n x 2n block
        # [[D_kj / h_i I, -T L_kj I], [r_q L_kj, r_v L_kj + r_a D_kj / (h_i T)]], all blocks at once
        P = self.mesh * m
        k, h = np.tile(np.arange(m), self.mesh), np.repeat(widths, m)
        Lp, Dp = L[k][:, :, None, None], D[k][:, :, None, None]  # P x (m + 1) x 1 x 1
        hp = h[:, None, None, None]
        eye = np.eye(n)
        blocks = np.empty((P, m + 1, 2 * n, 2 * n))
        blocks[:, :, :n, :n] = Dp / hp * eye
        blocks[:, :, :n, n:] = -T * Lp * eye
        blocks[:, :, n:, :n] = rq[:, None] * Lp
        blocks[:, :, n:, n:] = rv[:, None] * Lp + ra[:, None] * Dp / (hp * T)
        nodes = np.repeat(self.node_index(), m, axis=0)  # P x (m + 1)
        rows = np.arange(P)[:, None, None, None] * 2 * n + np.arange(2 * n)[None, None, :, None]
        cols = nodes[:, :, None, None] * 2 * n + np.arange(2 * n)[None, None, None, :]
        np.add.at(J, (np.broadcast_to(rows, blocks.shape), np.broadcast_to(cols, blocks.shape)), blocks)
        R = self.residual(u)
        if self.autonomous:
            column = np.hstack([-at["v"], -np.einsum("cij,cj->ci", ra, at["dv"]) / T**2]).ravel()
            J[:-1, -1] = column
            J[-1, n + self.phase] = 1.0
        return R, J

    def point_blocks(self, X: np.ndarray, T: float, at: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, c) per Gauss point (d x d, d x d, d): each point's equations E linearised as
        dE = A dx + B d(dx/dtau) + c dT (module doc), rows (q, r, z), columns (q, v, z)."""
        n, m, d = self.system.n, self.system.m, self.state_size
        P = at["tau"].size
        A, B, c = np.zeros((P, d, d)), np.zeros((P, d, d)), np.zeros((P, d))
        if n:
            tan = self.kernel("tangent", at, T)
            A[:, :n, n:2 * n] = -T * np.eye(n)
            B[:, :n, :n] = np.eye(n)
            A[:, n:2 * n, :n] = np.asarray(tan["r_q"], float).reshape(P, n, n)
            A[:, n:2 * n, n:2 * n] = np.asarray(tan["r_v"], float).reshape(P, n, n)
            if m:
                A[:, n:2 * n, 2 * n:] = np.asarray(tan["r_z"], float).reshape(P, n, m)
            ra = np.asarray(tan["r_a"], float).reshape(P, n, n)
            B[:, n:2 * n, n:2 * n] = ra / T
            c[:, :n] = -at["v"]
            c[:, n:2 * n] = -np.einsum("cij,cj->ci", ra, at["dv"]) / T**2
        if m:
            g = self.kernel("rates_tangent", at, T)
            for k, name in ((slice(0, n), "g_q"), (slice(n, 2 * n), "g_v"), (slice(2 * n, d), "g_z")):
                A[:, 2 * n:, k] = -T * np.asarray(g[name], float).reshape(P, m, -1)
            B[:, 2 * n:, 2 * n:] = np.eye(m)
            c[:, 2 * n:] = -np.asarray(self.kernel("rates", at, T)["g"], float).reshape(P, m)
        return A, B, c

    def sparse_jacobian(self, u: np.ndarray):
        """dR/du as scipy CSR, in one vectorised pass: the block of point (i, k) and local node j is
        h_i (A l_j(zeta_k) + B l_j'(zeta_k) / h_i) (the rows weighted by h_i), the period's column h_i c, the phase
        condition's row."""
        X, T = self.split(u)
        at = self.points(X, T)
        A, B, c = self.point_blocks(X, T, at)
        _, L, D = interval_tables()
        m, d, P = DEGREE, self.state_size, at["tau"].size
        h = np.repeat(self.widths, m)  # per point
        k = np.tile(np.arange(m), self.mesh)
        blocks = (A[:, None] * (L[k] * h[:, None])[:, :, None, None]
                  + B[:, None] * D[k][:, :, None, None])  # P x (m + 1) x d x d, the rows weighted by h_i
        nodes = np.repeat(self.node_index(), m, axis=0)  # P x (m + 1)
        rows = np.broadcast_to((np.arange(P)[:, None, None, None] * d + np.arange(d)[None, None, :, None]),
                               blocks.shape)
        cols = np.broadcast_to(nodes[:, :, None, None] * d + np.arange(d)[None, None, None, :], blocks.shape)
        size = self.nodes * d
        data, I, J = [blocks.ravel()], [rows.ravel()], [cols.ravel()]
        if self.autonomous:
            phase = self.phase_row()
            nz = np.flatnonzero(phase)
            data += [(c * h[:, None]).ravel(), phase[nz]]
            I += [np.arange(P * d), np.full(nz.size, P * d)]
            J += [np.full(P * d, size), nz]
        shape = (P * d + self.autonomous, size + self.autonomous)
        return sps.csr_matrix((np.concatenate(data), (np.concatenate(I), np.concatenate(J))), shape=shape)

    def monodromy(self, u: np.ndarray) -> np.ndarray:
        """Phi(T) of the orbit u from the collocation equations (module doc): P_i = -(B_rest^-1 B_start) at the end
        node, B the rows of interval i's points in the columns of its start node and of its other m nodes."""
        _, J = self.residual_jacobian(u)
        d = self.state_size
        Phi = np.eye(d)
        for block in self.interval_blocks(J):
            step = -np.linalg.solve(block[:, d:], block[:, :d])[-d:]
            Phi = step @ Phi
        return Phi

    def interval_blocks(self, J):
        """Each interval's rows of the collocation Jacobian J in the columns of its m + 1 nodes (node_index's
        order), dense m d x (m + 1) d, in interval order: gathered from J's nonzeros in one pass (a node j of
        interval i is global node (i m + j) mod nodes), BLOCK_BYTES of blocks at a time."""
        d, m, mesh, nodes = self.state_size, DEGREE, self.mesh, self.nodes
        coo = J.tocoo() if sps.issparse(J) else sps.coo_matrix(np.asarray(J))
        keep = (coo.row < mesh * m * d) & (coo.col < nodes * d)  # not the phase row, nor T's or a parameter's column
        r, c, v = coo.row[keep], coo.col[keep], coo.data[keep]
        order = np.argsort(r, kind="stable")
        r, c, v = r[order], c[order], v[order]
        i = r // (m * d)
        j = (c // d - i * m) % nodes
        per = max(1, BLOCK_BYTES // (8 * m * d * (m + 1) * d))  # intervals per chunk
        for first in range(0, mesh, per):
            count = min(per, mesh - first)
            lo, hi = np.searchsorted(i, [first, first + count])
            blocks = np.zeros((count, m * d, (m + 1) * d))
            ii, rr, jj, cc, vv = i[lo:hi] - first, r[lo:hi], j[lo:hi], c[lo:hi], v[lo:hi]
            for wrap in (0, nodes) if nodes <= m else (0,):  # one interval: its last node is its first
                ok = jj + wrap <= m
                np.add.at(blocks, (ii[ok], rr[ok] - (ii[ok] + first) * m * d, (jj[ok] + wrap) * d + cc[ok] % d),
                          vv[ok])
            yield from blocks

    def frequency_derivative(self, u: np.ndarray) -> np.ndarray:
        """dR/domega of a forced orbit at fixed parameters (central differences, step 1e-6 omega)."""
        h = 1e-6 * self.omega
        return (replace(self, omega=self.omega + h).residual(u) - replace(self, omega=self.omega - h).residual(u)) \
            / (2 * h)

    def states_at(self, u: np.ndarray, times: np.ndarray) -> np.ndarray:
        """The collocation polynomials' states at ``times`` (0 <= t <= T; rows)."""
        X, T = self.split(u)
        tau = np.clip(np.asarray(times, float) / T, 0.0, 1.0)
        edges = self.edge_array
        i = np.clip(np.searchsorted(edges, tau, side="right") - 1, 0, self.mesh - 1)
        values = lagrange_values((tau - edges[i]) / self.widths[i])
        return np.einsum("sj,sjd->sd", values, X[self.node_index()[i]])

    def adapted(self, u: np.ndarray, mesh: int | None = None) -> tuple["Collocation", np.ndarray]:
        """(the problem on a new mesh of ``mesh`` intervals (left out: as many), u interpolated onto it, and the
        reference of an integral phase condition the interpolated u): the mesh that equidistributes
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
        count = self.mesh if mesh is None else int(mesh)
        edges = np.interp(np.linspace(0.0, mass[-1], count + 1), mass, self.edge_array)
        edges[0], edges[-1] = 0.0, 1.0
        node_tau = (edges[:-1, None] + nodes[None, :-1] * np.diff(edges)[:, None]).ravel()
        states = self.states_at(u, node_tau * T)
        new = replace(self, mesh=count, edges=tuple(edges),
                      reference=None if self.reference is None else states)
        return new, new.unknowns(states, T)
