"""Assembly over elements and quadrature points: local coefficients -> global vectors and matrices.

With jet tables B[e, q, a, l], weights w[e, q] and pointwise coefficients
C[e, q, a, b] (from a generated kernel), the element matrix and vector are

    K_e[l, m] = sum_q w_eq sum_ab B[e,q,a,l] C[e,q,a,b] B[e,q,b,m],
    r_e[l]    = sum_q w_eq sum_a  B[e,q,a,l] rho[e,q,a],

scattered into global dofs by the element dof map (duplicates summed). A global
basis (one element) gives a dense matrix; elements give CSR through an index
map computed once per dof map.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sps


def jets_at_points(tables: np.ndarray, dofs: np.ndarray, x: np.ndarray) -> np.ndarray:
    """j[e, q, a] = sum_l B[e, q, a, l] x[dofs[e, l]]."""
    return np.einsum("eqal,el->eqa", tables, x[dofs], optimize=True)


def element_matrices(tables: np.ndarray, weights: np.ndarray, coeff: np.ndarray, pairs=None) -> np.ndarray:
    """K_e for every element; ``pairs`` lists the (a, b) with C[..., a, b] not identically zero."""
    if pairs is not None and len(pairs) <= coeff.shape[-1] ** 2 // 2:
        weighted = tables * weights[:, :, None, None]
        out = np.zeros(tables.shape[:1] + (tables.shape[-1],) * 2)
        for a, b in pairs:
            out += np.einsum("eql,eq,eqm->elm", weighted[:, :, a, :], coeff[:, :, a, b], tables[:, :, b, :],
                             optimize=True)
        return out
    left = np.einsum("eqal,eqab->eqlb", tables * weights[:, :, None, None], coeff, optimize=True)
    return np.einsum("eqlb,eqbm->elm", left, tables, optimize=True)


def element_vectors(tables: np.ndarray, weights: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """r_e[l] = sum_q w sum_a B rho."""
    return np.einsum("eqal,eqa->el", tables * weights[:, :, None, None], rho, optimize=True)


class Assembler:
    """Scatters element vectors and matrices into global dofs (CSR pattern built once)."""

    def __init__(self, dofs: np.ndarray, ndof: int, dense: bool) -> None:
        self.dofs = dofs
        self.ndof = ndof
        self.dense = dense
        if not dense:
            rows = np.repeat(dofs[:, :, None], dofs.shape[1], axis=2).ravel()
            cols = np.repeat(dofs[:, None, :], dofs.shape[1], axis=1).ravel()
            keys, self._index = np.unique(rows * ndof + cols, return_inverse=True)
            self._rows, self._cols = keys // ndof, keys % ndof
            self._indptr = np.searchsorted(self._rows, np.arange(ndof + 1)).astype(np.int64)

    def vector(self, element_vectors: np.ndarray) -> np.ndarray:
        """sum of r_e scattered by the dof map."""
        return np.bincount(self.dofs.ravel(), weights=element_vectors.ravel(), minlength=self.ndof)

    def matrix(self, element_matrices: np.ndarray):
        """Global matrix: dense ndarray for a global basis, CSR for elements."""
        if self.dense:
            out = np.zeros((self.ndof, self.ndof))
            for d, ke in zip(self.dofs, element_matrices):
                out[np.ix_(d, d)] += ke
            return out
        data = np.bincount(self._index.ravel(), weights=element_matrices.ravel(), minlength=len(self._rows))
        return sps.csr_matrix((data, self._cols.astype(np.int32), self._indptr), shape=(self.ndof, self.ndof))
