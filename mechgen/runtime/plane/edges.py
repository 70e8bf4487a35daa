"""Quadrature on the named boundary edges of a plane mesh: points, outward normals, line weights, shape values.

An edge of a P1/Q1 mesh joins two nodes; of a P2/Q2 mesh it also holds its midside node, and the
edge is the isoparametric curve x(xi) = sum_i N_i(xi) x_i, xi in [-1, 1], with
N = ((1 - xi)/2, (1 + xi)/2) or (xi (xi - 1)/2, xi (xi + 1)/2, 1 - xi^2) for the nodes (end, end, mid).
At a Gauss point, ds = |dx/dxi| dxi and the unit normal is the tangent turned by -90 degrees, flipped where
it points into the cell the edge bounds (toward that cell's centroid), so that it is outward whatever the
orientation of the edge list. Edge integrals are then sum_g w_g |dx/dxi| f(x_g, n_g).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class EdgeTables:
    """Quadrature of one boundary: ``nodes`` (edges, k) node indices, ``values`` (g, k) shape values,
    ``weights`` (edges, g) = w_g |dx/dxi|, ``position`` (edges, g, 4) = (x, y, n_x, n_y)."""

    nodes: np.ndarray
    values: np.ndarray
    weights: np.ndarray
    position: np.ndarray


def _line_shapes(k: int, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (g, k) and dN/dxi (g, k) of the 2- or 3-node line element (nodes at xi = -1, 1, 0)."""
    if k == 2:
        return np.stack([(1 - xi) / 2, (1 + xi) / 2], 1), np.tile([-0.5, 0.5], (len(xi), 1))
    N = np.stack([xi * (xi - 1) / 2, xi * (xi + 1) / 2, 1 - xi**2], 1)
    return N, np.stack([xi - 0.5, xi + 0.5, -2 * xi], 1)


def _inward_centroids(points: np.ndarray, cells: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The centroid of the vertices of the cell that holds each edge (edges matched by their end nodes)."""
    nv = 4 if cells.shape[1] in (4, 8, 9) else 3
    verts = cells[:, :nv]
    a = verts.ravel()
    b = np.roll(verts, -1, axis=1).ravel()
    n = len(points)
    keys = np.minimum(a, b).astype(np.int64) * n + np.maximum(a, b)
    order = np.argsort(keys, kind="stable")
    e0, e1 = edges[:, 0].astype(np.int64), edges[:, 1].astype(np.int64)
    wanted = np.minimum(e0, e1) * n + np.maximum(e0, e1)
    slot = np.searchsorted(keys[order], wanted)
    owner = order[np.minimum(slot, len(keys) - 1)] // nv
    return points[verts[owner]].mean(axis=1)


def edge_tables(points: np.ndarray, cells: np.ndarray, edges: np.ndarray, degree: int) -> EdgeTables:
    """The Gauss rule exact to ``degree`` on every edge of one boundary."""
    xi, w = np.polynomial.legendre.leggauss(max(1, (degree + 2) // 2))
    k = edges.shape[1]
    N, dN = _line_shapes(k, xi)
    X = points[edges]  # (edges, k, 2)
    x = np.einsum("gk,ekd->egd", N, X)
    tangent = np.einsum("gk,ekd->egd", dN, X)
    length = np.linalg.norm(tangent, axis=2)
    normal = np.stack([tangent[..., 1], -tangent[..., 0]], 2) / length[..., None]
    inside = _inward_centroids(points, cells, edges)
    flip = np.einsum("egd,egd->eg", normal, inside[:, None, :] - x) > 0
    normal[flip] *= -1
    return EdgeTables(np.asarray(edges), N, w[None, :] * length, np.concatenate([x, normal], axis=2))
