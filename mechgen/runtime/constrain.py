"""Essential boundary conditions C x = 0 on discretised fields: elimination or penalty.

* eliminate: x = Z q with C Z = 0. Rows that hit single dofs (nodal values of
  finite elements) drop those dofs (Z a column selection, matrices stay sparse);
  other rows (global bases) use an orthonormal null-space basis Z = null(C).
  Rows the basis already satisfies (sin(j pi s/L) at s = 0, L) are dropped.
  Reduced matrices are Z^T A Z, reduced vectors Z^T r.
* penalty: x = q and K gets alpha C^T C with alpha = PENALTY_FACTOR * max|diag K|
  (K unconstrained, at the zero state), the paper's way (seed 002); frequencies
  converge to the constrained ones as 1/PENALTY_FACTOR.
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

    @property
    def n(self) -> int:
        """Reduced unknowns."""
        return self.ndof if self.Z is None else self.Z.shape[1]

    def expand(self, q: np.ndarray) -> np.ndarray:
        """Full dof vector x = Z q."""
        return np.asarray(q, float) if self.Z is None else self.Z @ np.asarray(q, float)

    def vector(self, r: np.ndarray) -> np.ndarray:
        """Z^T r."""
        return r if self.Z is None else self.Z.T @ r

    def matrix(self, A, penalty: float = 0.0):
        """Z^T A Z, plus penalty * C^T C (the penalty method's stiffness term)."""
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


def reduction(rows: np.ndarray, scales: np.ndarray, ndof: int, method: str, sparse: bool) -> Reduction:
    """Reduction for constraint rows (one per condition) whose jets have table magnitudes ``scales``."""
    rows = np.atleast_2d(np.asarray(rows, float)).reshape(-1, ndof)
    keep = [np.abs(r).max() > 1e-10 * max(s, 1.0) for r, s in zip(rows, scales)]
    rows = rows[np.asarray(keep, bool)] if len(rows) else rows
    if not len(rows):
        return Reduction(ndof, None)
    if method == "penalty":
        return Reduction(ndof, None, rows)
    nonzero = [np.flatnonzero(np.abs(r) > 1e-12 * np.abs(r).max()) for r in rows]
    if all(len(nz) == 1 for nz in nonzero):
        fixed = {int(nz[0]) for nz in nonzero}
        free = np.array([i for i in range(ndof) if i not in fixed])
        Z = sps.csr_matrix((np.ones(len(free)), (free, np.arange(len(free)))), shape=(ndof, len(free)))
        return Reduction(ndof, Z if sparse else Z.toarray(), keep=free)
    return Reduction(ndof, sla.null_space(rows, rcond=1e-10))
