"""Essential boundary conditions C x = 0 on discretised fields: elimination or penalty.

* eliminate: x = Z q with C Z = 0. Rows that hit single dofs (nodal values of
  finite elements) drop those dofs (Z a column selection, matrices stay sparse);
  other rows (global bases) use an orthonormal null-space basis Z = null(C).
  Rows the basis already satisfies (sin(j pi s/L) at s = 0, L) are dropped.
  Reduced matrices are Z^T A Z, reduced vectors Z^T r.
* penalty: x = q and K gets alpha C^T C with alpha = PENALTY_FACTOR * max|diag K|
  (K unconstrained, at the zero state), the paper's way (seed 002); frequencies
  converge to the constrained ones as 1/PENALTY_FACTOR.
* joints (substructures joined at segment interfaces): their continuity rows are
  eliminated by the null space together with eliminated boundary rows, kept beside
  penalty boundary rows (x = null(J) q, penalty on C x), or bordered with multiplier ones.
* multiplier: the unknowns are (x, lambda); K is bordered, [[K, C^T], [C, 0]], the
  residual is (r + C^T lambda, C x) and M, D, G get zero rows and columns for
  lambda (a singular mass: modes and stability solve the generalized problem and
  drop its infinite eigenvalues). lambda are the boundary reactions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps

PENALTY_FACTOR = 1e6


@dataclass(frozen=True)
class Reduction:
    """x = Z q (Z None: identity); ``penalty_rows`` C for the penalty method."""

    ndof: int
    Z: object
    penalty_rows: np.ndarray | None = None
    keep: np.ndarray | None = None
    multiplier_rows: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Reduced unknowns (dofs plus multipliers for the multiplier method)."""
        if self.multiplier_rows is not None:
            return self.ndof + len(self.multiplier_rows)
        return self.ndof if self.Z is None else self.Z.shape[1]

    def expand(self, q: np.ndarray) -> np.ndarray:
        """Full dof vector x = Z q (the first ndof unknowns with multipliers)."""
        q = np.asarray(q, float)
        if self.multiplier_rows is not None:
            return q[:self.ndof]
        return q if self.Z is None else self.Z @ q

    def vector(self, r: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """Z^T r; with multipliers (r + C^T lambda, C x) at the unknowns q = (x, lambda)."""
        if self.multiplier_rows is not None:
            C = self.multiplier_rows
            q = np.zeros(self.n) if q is None else np.asarray(q, float)
            return np.concatenate([r + C.T @ q[self.ndof:], C @ q[:self.ndof]])
        return r if self.Z is None else self.Z.T @ r

    def _bordered(self, A, border: bool):
        C = sps.csr_matrix(self.multiplier_rows)
        m = C.shape[0]
        top, bottom = (C.T, C) if border else (None, sps.csr_matrix((m, self.ndof)))
        out = sps.bmat([[sps.csr_matrix(A), top], [bottom, sps.csr_matrix((m, m))]], format="csr")
        return out if sps.issparse(A) else out.toarray()

    def matrix(self, A, penalty: float = 0.0, border: bool = False):
        """Z^T A Z, plus penalty * C^T C (the penalty method's stiffness term); bordered for multipliers."""
        if self.multiplier_rows is not None:
            return self._bordered(A, border)
        if penalty and self.penalty_rows is not None:
            C = sps.csr_matrix(self.penalty_rows)
            extra = penalty * (C.T @ C)
            A = (A + extra).tocsr() if sps.issparse(A) else A + extra.toarray()
        if self.Z is None:
            return A
        if self.keep is not None:  # a column selection: slicing, not two sparse products
            return A[self.keep][:, self.keep] if sps.issparse(A) else A[np.ix_(self.keep, self.keep)]
        out = self.Z.T @ A @ self.Z
        return sps.csr_matrix(out) if sps.issparse(out) else np.asarray(out)

    def penalty_force(self, x: np.ndarray, penalty: float) -> np.ndarray:
        """penalty * C^T C x (zero without penalty rows)."""
        if not penalty or self.penalty_rows is None:
            return np.zeros_like(x)
        return penalty * (self.penalty_rows.T @ (self.penalty_rows @ x))


def binding(row: np.ndarray, scale: float) -> bool:
    """False for a condition the basis satisfies by itself (its row vanishes at the jet's scale)."""
    return bool(np.abs(row).max() > 1e-10 * max(scale, 1.0))


def reduction(rows: np.ndarray, scales: np.ndarray, ndof: int, method: str, sparse: bool,
              joints: np.ndarray | None = None) -> Reduction:
    """Reduction for constraint rows (one per condition) whose jets have table magnitudes ``scales``.

    ``joints`` are further rows that join substructures (continuity at segment
    interfaces): eliminated exactly by their null space, x = null(J) q (the
    reduction of the constrained problem to a standard one), together with the
    boundary rows when those are eliminated too; kept as multipliers with them.
    """
    rows = np.atleast_2d(np.asarray(rows, float)).reshape(-1, ndof)
    keep = [binding(r, s) for r, s in zip(rows, scales)]
    rows = rows[np.asarray(keep, bool)] if len(rows) else rows
    joints = np.zeros((0, ndof)) if joints is None else np.atleast_2d(np.asarray(joints, float)).reshape(-1, ndof)
    if len(joints) and method != "multiplier":
        if method == "penalty":
            return Reduction(ndof, sla.null_space(joints, rcond=1e-10), rows if len(rows) else None)
        rows = np.vstack([rows, joints])
    elif len(joints):
        rows = np.vstack([rows, joints])
    if not len(rows):
        return Reduction(ndof, None)
    if method == "penalty":
        return Reduction(ndof, None, rows)
    if method == "multiplier":
        return Reduction(ndof, None, multiplier_rows=rows)
    nonzero = [np.flatnonzero(np.abs(r) > 1e-12 * np.abs(r).max()) for r in rows]
    if all(len(nz) == 1 for nz in nonzero):
        fixed = {int(nz[0]) for nz in nonzero}
        free = np.array([i for i in range(ndof) if i not in fixed])
        Z = sps.csr_matrix((np.ones(len(free)), (free, np.arange(len(free)))), shape=(ndof, len(free)))
        return Reduction(ndof, Z if sparse else Z.toarray(), keep=free)
    return Reduction(ndof, sla.null_space(rows, rcond=1e-10))
