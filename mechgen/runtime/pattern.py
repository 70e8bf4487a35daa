"""Sparse patterns of chain kernels, built numerically from the kernel spec.

A loop block that writes sparse entries (row offset r, col offset c) touches,
for each loop index e, the matrix entry (e + r, e + c) (wrapped when periodic,
dropped when outside [0, sites)). The union over blocks is a CSR pattern; each
block gets a slot table slot[e, j] = position of its j-th entry in the CSR data
(or -1), which the kernel uses to accumulate in place.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sps


def extent(ext: dict, sizes: dict) -> int:
    """Evaluate a spec extent {'const', 'terms'} for concrete sizes."""
    return int(ext["const"] + sum(c * sizes[n] for n, c in ext["terms"]))


@dataclass(frozen=True)
class Pattern:
    """A CSR pattern (n x n) and the slot tables of one kernel."""

    n: int
    indptr: np.ndarray
    indices: np.ndarray
    slots: dict

    @property
    def nnz(self) -> int:
        """Stored entries."""
        return int(self.indices.size)

    def matrix(self, data: np.ndarray) -> sps.csr_matrix:
        """The CSR matrix with this pattern and ``data``."""
        return sps.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))


def _block_entries(recipe: dict, sizes: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    cnt, ns = extent(recipe["count"], sizes), extent(recipe["sites"], sizes)
    e = np.arange(cnt)[:, None]
    offs = np.asarray(recipe["entries"], dtype=np.int64).reshape(-1, 2)
    rows, cols = e + offs[None, :, 0], e + offs[None, :, 1]
    if recipe["boundary"] == "periodic":
        rows, cols = rows % ns, cols % ns
        valid = np.ones(rows.shape, bool)
    else:
        valid = (rows >= 0) & (rows < ns) & (cols >= 0) & (cols < ns)
    return rows, cols, valid


def build_pattern(spec: dict, sites: int) -> Pattern:
    """The CSR pattern and slot tables of a kernel spec for ``sites`` sites."""
    sizes = {"sites": sites}
    blocks = [(r, *_block_entries(r, sizes)) for r in spec["slots"]]
    key = np.concatenate([(rows[v] * sites + cols[v]) for _, rows, cols, v in blocks] or [np.zeros(0, np.int64)])
    uniq = np.unique(key)
    rows_u, cols_u = uniq // sites, uniq % sites
    indptr = np.zeros(sites + 1, dtype=np.int64)
    np.add.at(indptr, rows_u + 1, 1)
    indptr = np.cumsum(indptr)
    slots = {}
    for recipe, rows, cols, valid in blocks:
        table = np.full(rows.shape, -1, dtype=np.int64)
        table[valid] = np.searchsorted(uniq, rows[valid] * sites + cols[valid])
        slots[recipe["port"]] = np.ascontiguousarray(table.ravel())
    return Pattern(sites, indptr, cols_u.astype(np.int32), slots)
