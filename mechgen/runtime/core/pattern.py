"""Sparse patterns of chain kernels, built numerically from the kernel spec.

A loop block that writes sparse entries (row offset r, col offset c) touches,
for each loop index e, the matrix entry (e + r, e + c) (wrapped when periodic,
dropped when outside [0, sites)). The union over blocks is a CSR pattern; each
block gets a slot table slot[e, j] = position of its j-th entry in the CSR data
(or -1), which the kernel uses to accumulate in place.

Each such block also gets an affine summary (port ``slots{i}_affine``): the
longest run a <= e < b of its unchecked interior where slot[e, j] = base_j +
stride*e for every j, so the C interior can address the CSR data directly,
and for each output the block is first to write (the recipe's ``stored``), the
CSR positions [zlo, zhi) it then stores. The run is certified here: every
stored position is written once (carried pairs merged), else a = b = 0 and the
kernel uses the slot table alone.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


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

    def matrix(self, data: np.ndarray):
        """The CSR matrix (scipy.sparse.csr_matrix) with this pattern and ``data``."""
        import scipy.sparse as sps

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


def interior(cnt: int, ns: int, lo_off: int, hi_off: int) -> tuple[int, int]:
    """Loop indices [lo, hi) whose sites e + lo_off .. e + hi_off all lie in [0, ns) (as the C kernel computes them)."""
    lo = max(0, -lo_off) if -lo_off < cnt else cnt
    hi = min(ns - hi_off, cnt) if ns - hi_off > lo else lo
    return lo, hi


def _longest_run(table: np.ndarray, lo: int, hi: int) -> tuple[int, int, int]:
    """(a, b, stride): the longest run lo <= a <= e < b <= hi of valid rows, table[e] = table[a] + stride*(e - a).

    The first of equally long runs; (0, 0, 0) when no row in [lo, hi) is valid.
    """
    rows = table[lo:hi]
    valid = np.all(rows >= 0, axis=1)
    if rows.shape[0] < 2:
        return (lo, hi, 0) if rows.shape[0] == 1 and valid[0] else (0, 0, 0)
    step = np.diff(rows, axis=0)
    none = np.iinfo(np.int64).min
    steps = np.where(np.all(step == step[:, :1], axis=1) & valid[:-1] & valid[1:], step[:, 0], none)
    starts = np.flatnonzero(np.r_[True, steps[1:] != steps[:-1]])
    ends = np.r_[starts[1:], steps.size]
    lengths = np.where(steps[starts] == none, 0, ends - starts)
    k = int(np.argmax(lengths))
    if lengths[k] == 0:
        first = np.flatnonzero(valid)
        return (lo + int(first[0]), lo + int(first[0]) + 1, 0) if first.size else (0, 0, 0)
    return lo + int(starts[k]), lo + int(ends[k]) + 1, int(steps[starts[k]])


def _stored_positions(base: np.ndarray, stride: int, a: int, b: int, stored: dict) -> np.ndarray:
    """CSR positions the affine interior stores for one port: one per entry and index, carried pairs merged."""
    outgoing = {j_out for _, j_out in stored["carried"]}
    e = np.arange(a, b)
    parts = [base[j] + stride * e for j in stored["entries"] if j not in outgoing]
    parts += [base[[j_out for j_out in sorted(outgoing)]] + stride * (b - 1)]
    return np.concatenate(parts)


def affine_summary(recipe: dict, table: np.ndarray, sizes: dict) -> np.ndarray:
    """The affine summary ``[a, b, stride, base_j.., (zlo, zhi) per stored port]`` of one block's slot table."""
    cnt, ns = extent(recipe["count"], sizes), extent(recipe["sites"], sizes)
    width = len(recipe["entries"])
    out = np.zeros(3 + width + 2 * len(recipe["stored"]), dtype=np.int64)
    table = table.reshape(cnt, width)
    a, b, stride = _longest_run(table, *interior(cnt, ns, *recipe["offsets"]))
    if b <= a:
        return out
    base = table[a] - stride * a
    ranges = []
    for stored in recipe["stored"]:
        pos = _stored_positions(base, stride, a, b, stored)
        if np.unique(pos).size != pos.size:
            return out
        contiguous = pos.max() - pos.min() + 1 == pos.size
        ranges += [int(pos.min()), int(pos.max()) + 1] if contiguous else [0, 0]
    out[:3] = a, b, stride
    out[3:3 + width] = base
    out[3 + width:] = ranges
    return out


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
        if "affine" in recipe:
            slots[recipe["affine"]] = affine_summary(recipe, table, sizes)
    return Pattern(sites, indptr, cols_u.astype(np.int32), slots)
