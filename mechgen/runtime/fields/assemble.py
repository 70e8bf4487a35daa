"""Assembly over elements and quadrature points: local coefficients -> global vectors and matrices.

With jet tables B[e, q, a, l], weights w[e, q] and pointwise coefficients
C[e, q, a, b] (from a generated kernel), the element matrix and vector are

    K_e[l, m] = sum_q w_eq sum_ab B[e,q,a,l] C[e,q,a,b] B[e,q,b,m],
    r_e[l]    = sum_q w_eq sum_a  B[e,q,a,l] rho[e,q,a],

scattered into global dofs by the element dof map (duplicates summed). A global
basis (one element) gives a dense matrix; elements give CSR through an index
map computed once per dof map.

Speed: on a uniform mesh every element has the same table, and
:func:`~mechgen.runtime.fields.discretise.discretise` hands it over as a broadcast view
(stride 0 along the elements). Then only the (a, b) pairs whose coefficient is
not identically zero are visited and the element matrices are one product
(elements, points x pairs) @ (points x pairs, dofs x dofs) of the weighted
coefficients with the precomputed products B_qa^T B_qb; jets and element
vectors are likewise single matrix products. Any other table takes a batched
matmul per pair. Results equal the plain sums up to round-off.
"""
from __future__ import annotations

import numpy as np

from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense

sps = lazy_module("scipy.sparse")


_SHARED_PRODUCTS_MAX = 1 << 22  # entries of the (points, pairs, dofs, dofs) product table of the shared path


def shared_table(tables: np.ndarray) -> np.ndarray | None:
    """The table B[q, a, l] every element shares (a stride-0 broadcast over elements), else None."""
    if tables.shape[0] > 1 and tables.strides[0] == 0:
        return tables[0]
    return None


def jets_at_points(tables: np.ndarray, dofs: np.ndarray, x: np.ndarray) -> np.ndarray:
    """j[e, q, a] = sum_l B[e, q, a, l] x[dofs[e, l]]."""
    local = x[dofs]
    shared = shared_table(tables)
    if shared is not None and local.ndim == 2:
        ne, nq, na, nl = tables.shape
        return (local @ shared.reshape(nq * na, nl).T).reshape(ne, nq, na)
    return np.einsum("eqal,el->eqa", tables, local, optimize=True)


def nonzero_pairs(coeff: np.ndarray) -> list[tuple[int, int]]:
    """The (a, b) with C[..., a, b] not identically zero."""
    return [(int(a), int(b)) for a, b in np.argwhere(np.any(coeff != 0, axis=(0, 1)))]


def element_matrices(tables: np.ndarray, weights: np.ndarray, coeff: np.ndarray, pairs=None) -> np.ndarray:
    """K_e for every element; ``pairs`` lists the (a, b) with C[..., a, b] not identically zero (found if None)."""
    ne, nq, _, nl = tables.shape
    pairs = nonzero_pairs(coeff) if pairs is None else [(int(a), int(b)) for a, b in pairs]
    if not pairs:
        return np.zeros((ne, nl, nl))
    shared = shared_table(tables)
    if shared is not None and nq * len(pairs) * nl * nl <= _SHARED_PRODUCTS_MAX:
        a, b = np.array(pairs).T
        products = shared[:, a, :, None] * shared[:, b, None, :]  # (q, pair, l, m)
        wc = weights[:, :, None] * coeff[:, :, a, b]  # (e, q, pair)
        return (wc.reshape(ne, -1) @ products.reshape(-1, nl * nl)).reshape(ne, nl, nl)
    out = np.zeros((ne, nl, nl))
    for a, b in pairs:
        left = tables[:, :, a, :] * (weights * coeff[:, :, a, b])[:, :, None]
        out += np.matmul(left.transpose(0, 2, 1), tables[:, :, b, :])
    return out


def element_vectors(tables: np.ndarray, weights: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """r_e[l] = sum_q w sum_a B rho (:func:`element_vectors_stack` of the one set rho)."""
    return element_vectors_stack(tables, weights, np.asarray(rho)[None])[0]


def element_vectors_stack(tables: np.ndarray, weights: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """r_ke[l] = sum_q w_eq sum_a B[e, q, a, l] rho[k, e, q, a] for a stack of coefficient sets rho[k] (all k in
    one matrix product on a shared table, else one einsum)."""
    shared = shared_table(tables)
    if shared is not None:
        ne, nq, na, nl = tables.shape
        return (weights[:, :, None] * rho).reshape(len(rho), ne, nq * na) @ shared.reshape(nq * na, nl)
    return np.einsum("eqal,keqa->kel", tables * weights[:, :, None, None], rho, optimize=True)


class Assembler:
    """Scatters element vectors and matrices into global dofs (CSR pattern built once)."""

    def __init__(self, dofs: np.ndarray, ndof: int, dense: bool) -> None:
        self.dofs = dofs
        self.ndof = ndof
        self.dense = dense
        if not dense:
            # keys of the (row, col) of every element-matrix entry in (e, l, m) order; the sorted distinct keys
            # are the CSR pattern (rows ascending, columns ascending within a row) and _index maps each entry
            # to its slot. A stable sort is quick on the nearly sorted keys of a connected mesh.
            dofs = np.asarray(dofs, np.int64)
            keys = (dofs[:, :, None] * ndof + dofs[:, None, :]).ravel()
            order = np.argsort(keys, kind="stable")
            ordered = keys[order]
            first = np.empty(len(keys), bool)
            first[:1] = True
            np.not_equal(ordered[1:], ordered[:-1], out=first[1:])
            self._index = np.empty(len(keys), np.intp)
            self._index[order] = np.cumsum(first) - 1
            unique = ordered[first]
            self._rows, cols = unique // ndof, unique % ndof
            itype = np.int32 if max(ndof, len(unique)) < np.iinfo(np.int32).max else np.int64
            self._cols = cols.astype(itype)
            self._indptr = np.searchsorted(self._rows, np.arange(ndof + 1)).astype(itype)

    def vector(self, element_vectors: np.ndarray) -> np.ndarray:
        """sum of r_e scattered by the dof map."""
        return np.bincount(self.dofs.ravel(), weights=element_vectors.ravel(), minlength=self.ndof)

    def matrix(self, element_matrices: np.ndarray):
        """Global matrix: dense ndarray for a global basis, CSR for elements."""
        if self.dense:
            require_dense(self.ndof, 2, "the dense assembly of a global basis")
            out = np.zeros((self.ndof, self.ndof))
            for d, ke in zip(self.dofs, element_matrices):
                out[np.ix_(d, d)] += ke
            return out
        if element_matrices.any():
            data = np.bincount(self._index, weights=element_matrices.ravel(), minlength=len(self._rows))
        else:
            data = np.zeros(len(self._rows))
        return sps.csr_matrix((data, self._cols.copy(), self._indptr.copy()), shape=(self.ndof, self.ndof))
