"""FieldSystem.rhs and FieldSystem.outputs as precomputed sparse operators around the pointwise kernels.

FieldSystem.rhs assembles, at every call, r(q, v, 0) = Z^T (sum_e B_e^T W_e rho(B_e Z q, B_e Z v, 0) + end and
part terms + C^T diag(alpha) C Z q) and solves M a = -r. Everything in it but the pointwise kernel is linear in
the reduced state, so it is precomputed once per parameter set (:func:`field_operators`, memoised in the system):

    J_b = (jet tables of block b) Z   (CSR: rows point-major then jet, columns the reduced unknowns),
    w_b  the quadrature weight of each row (1 at an end term or placed part),
    P    = Z^T C^T diag(alpha) C Z    (CSR; the penalty stiffness, absent without penalty rows),
    L    the Cholesky factor of the constant reduced mass M (reverse Cuthill-McKee ordered, banded),

with one block per segment (its own parameters) and one per end term and placed part (kernels
``<kernel>_at_<name>``), so that

    dq/dt = v,   dv/dt = -M^-1 (sum_b J_b^T (w_b .* rho_b(J_b q, J_b v, 0, t, s_b, p_b)) + P q).

mechgen.runtime.fields.flow_c evaluates that in C for the compiled DOP853 loop. :func:`integrated_series` uses
the same blocks for any pointwise kernel's integral at many samples in one kernel call a block (the outputs, the
energy balance's powers): I_k = sum_b sum_points w out(J_b q_k, J_b v_k, 0, t_k, s, p_b).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import reverse_cuthill_mckee

from mechgen.errors import KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import dense_bytes, require

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")


@dataclass(frozen=True)
class Block:
    """A pointwise kernel over ``s.size`` points: jets J q (CSR), row weights ``w``, positions, parameters."""

    kernel: object
    J: sps.csr_matrix
    w: np.ndarray
    s: np.ndarray
    params: np.ndarray


@dataclass(frozen=True)
class Operators:
    """What FieldSystem.rhs is made of (module doc): the blocks, the penalty P (or None), the mass factor."""

    n: int
    blocks: tuple
    penalty: sps.csr_matrix | None
    chol: np.ndarray       # (band + 1, n): lower band storage of L, M[perm][:, perm] = L L^T
    perm: np.ndarray


def _csr(A) -> sps.csr_matrix:
    """A as CSR with sorted indices, explicit zeros dropped."""
    out = sps.csr_matrix(A)
    out.eliminate_zeros()
    out.sort_indices()
    return out


def jet_operator(system) -> sps.csr_matrix:
    """J_full Z: the jets j[e, q, a] at every Gauss point (row (e nq + q) na + a) from the reduced unknowns,
    j = sum_l B[e, q, a, l] x[dofs[e, l]], x = Z q."""
    disc = system.disc
    ne, nq, na, nl = disc.tables.shape
    rows = np.broadcast_to(np.arange(ne * nq * na).reshape(ne, nq, na, 1), (ne, nq, na, nl))
    cols = np.broadcast_to(disc.dofs[:, None, None, :], (ne, nq, na, nl))
    full = sps.csr_matrix((np.ascontiguousarray(disc.tables).ravel(), (rows.ravel(), cols.ravel())),
                          shape=(ne * nq * na, disc.ndof))
    return _csr(_reduce_columns(system, full))


def _reduce_columns(system, B) -> sps.csr_matrix:
    """B Z: a table on the full dofs composed with the reduction x = Z q (a column selection where it is one)."""
    red = system.reduction
    if red.Z is None:
        return sps.csr_matrix(B)
    if red.keep is not None:
        return sps.csr_matrix(B)[:, red.keep]
    return sps.csr_matrix(B @ red.Z)


def gauss_blocks(system, kernel: str = "residual") -> list[Block]:
    """The Gauss points of ``kernel``: one block per segment (each its parameter vector; one block without segment
    values)."""
    disc = system.disc
    ne, nq, na, _ = disc.tables.shape
    J = system.memo(("c_loop", "jets", *system.loop_key()), lambda: jet_operator(system))
    w = np.repeat(np.asarray(disc.weights, float).ravel(), na)
    s = np.asarray(disc.points, float).ravel()
    segment = disc.mesh.segment if disc.mesh is not None else np.zeros(ne, int)
    per_segment = system.segment_params()
    kernel = system.kernels[kernel]
    if per_segment is None:
        return [Block(kernel, J, w, s, np.asarray(system.params, float))]
    blocks = []
    for k, params in enumerate(per_segment):
        elements = np.flatnonzero(segment == k)
        points = slice(elements[0] * nq, (elements[-1] + 1) * nq)
        rows = slice(points.start * na, points.stop * na)
        blocks.append(Block(kernel, _csr(J[rows]), w[rows], s[points], np.asarray(params, float)))
    return blocks


def point_blocks(system, kernel: str = "residual") -> list[Block]:
    """One block per end term and placed part: its kernel ``<kernel>_at_<name>`` at one point, weight 1."""
    blocks = []
    for name, x, params in system.placed_points():
        J = _csr(_reduce_columns(system, system.point_table(x)))
        params = np.asarray(system.params if params is None else params, float)
        blocks.append(Block(system.kernels[f"{kernel}_at_{name}"], J, np.ones(J.shape[0]), np.array([float(x)]),
                            params))
    return blocks


def penalty_operator(system) -> sps.csr_matrix | None:
    """P = Z^T C^T diag(alpha) C Z, the penalty's stiffness on the reduced unknowns (None without penalty rows)."""
    choice = system.penalty_choice
    if choice is None:
        return None
    red = system.reduction
    zero = sps.csr_matrix((red.ndof, red.ndof))
    return _csr(red.matrix(zero, choice.alphas))


def mass_factor(M) -> tuple[np.ndarray, np.ndarray]:
    """(L in lower band storage, perm): M[perm][:, perm] = L L^T, perm the reverse Cuthill-McKee ordering of M's
    pattern (a narrow band for element meshes). LinAlgError when M is not symmetric positive definite."""
    A = sps.csr_matrix(M)
    n = A.shape[0]
    if abs(A - A.T).max() > 1e-13 * max(abs(A).max(), 1e-300):
        raise np.linalg.LinAlgError("the mass matrix is not symmetric")
    perm = np.asarray(reverse_cuthill_mckee(A, symmetric_mode=True), int) if n > 1 else np.arange(n)
    P = A[perm][:, perm].tocoo()
    band = int(np.max(np.abs(P.row - P.col), initial=0))
    require(dense_bytes(band + 1, n), f"the banded factor of the {n} x {n} mass matrix (bandwidth {band})",
            key="params.N")
    ab = np.zeros((band + 1, n))
    lower = P.row >= P.col
    ab[(P.row - P.col)[lower], P.col[lower]] = P.data[lower]
    return np.ascontiguousarray(sla.cholesky_banded(ab, lower=True)), perm


def field_operators(system) -> Operators:
    """The operators of FieldSystem.rhs (module doc), memoised in the system per parameter set."""
    def make() -> Operators:
        M = system.tangent(np.zeros(system.n))["r_a"]
        chol, perm = mass_factor(M)
        blocks = blocks_of(system, "residual")
        return Operators(system.n, blocks, penalty_operator(system), chol, perm)

    return system.memo(("c_loop", "operators", *system.loop_key()), make)


def blocks_of(system, kernel: str) -> tuple:
    """The Gauss-point blocks and the end and part blocks of ``kernel`` (memoised per parameter set)."""
    return system.memo(("c_loop", "blocks", kernel, *system.loop_key()),
                       lambda: tuple(gauss_blocks(system, kernel) + point_blocks(system, kernel)))


def integrated_series(system, kernel: str, t: np.ndarray, X: np.ndarray) -> dict[str, np.ndarray]:
    """Each output of the pointwise ``kernel`` (and of its ``<kernel>_at_<name>`` end and part terms) integrated
    over the domain at every sample (row k of X: (q, v) at t[k]): rows (samples, entries),
    I_k = sum_b sum_i w_i out(J_b q_k, J_b v_k, 0, t_k, s_i, p_b), each block's points of all samples in one call."""
    n, ns = system.n, len(t)
    Q, V = np.asarray(X[:, :n], float).T, np.asarray(X[:, n:2 * n], float).T
    values: dict[str, np.ndarray] = {}
    for block in blocks_of(system, kernel):
        npts = block.s.size
        na = block.J.shape[0] // npts
        jets = [np.ascontiguousarray((block.J @ Y).reshape(npts, na, ns).transpose(2, 0, 1).reshape(-1, na))
                for Y in (Q, V)]
        inputs = {"q": jets[0], "v": jets[1], "a": np.zeros_like(jets[0]), "z": np.zeros((ns * npts, 0)),
                  "t": np.repeat(np.asarray(t, float), npts)[:, None], "s": np.tile(block.s, ns)[:, None],
                  "p": block.params}
        out = block.kernel.evaluate(inputs, check=False)
        weights = block.w[::na]
        for name, arr in out.items():
            summed = np.einsum("kij,i->kj", arr.reshape(ns, npts, -1), weights)
            values[name] = values[name] + summed if name in values else summed
    bad = [k for k, v in values.items() if not np.all(np.isfinite(v))]
    if bad:
        raise KernelError(f"{kernel} of {system.metadata.model} is NaN/Inf: {', '.join(bad)}")
    return values


def outputs_series(system, t: np.ndarray, X: np.ndarray) -> dict[str, np.ndarray]:
    """Each output of the ``outputs`` kernels at every sample (row k of X: (q, v) at t[k]): the integral over the
    Gauss points plus the end and part terms (:func:`integrated_series`; FieldSystem.outputs per row, to
    rounding)."""
    return {name: values[:, 0] for name, values in integrated_series(system, "outputs", t, X).items()}
