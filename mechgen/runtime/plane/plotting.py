"""Plotting data of a plane mesh: linear sub-triangles over every node, and per-cell averages of pointwise values.

matplotlib's triangulations are linear; a P2 triangle is drawn as its four sub-triangles through the midside
nodes, a Q1 quad as two triangles, a Q2 quad as eight, so that the nodal values of a quadratic field are all
shown. ``cell`` maps each sub-triangle to its element (for per-element colours such as a stress average).
"""
from __future__ import annotations

import numpy as np

#: sub-triangles of each element in its local node numbering (vertices ccw, then midsides, then the Q2 centre)
SUBTRIANGLES = {
    "P1": [(0, 1, 2)],
    "P2": [(0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5)],
    "Q1": [(0, 1, 2), (0, 2, 3)],
    "Q2": [(0, 4, 8), (4, 1, 8), (1, 5, 8), (5, 2, 8), (2, 6, 8), (6, 3, 8), (3, 7, 8), (7, 0, 8)],
}


def triangulation(cells: np.ndarray, element: str) -> tuple[np.ndarray, np.ndarray]:
    """(triangles (t, 3) node indices, cell (t,) the element of each)."""
    local = np.array(SUBTRIANGLES[element])
    tris = cells[:, local].reshape(-1, 3)
    return tris, np.repeat(np.arange(len(cells)), len(local))


def cell_means(weights: np.ndarray, values: np.ndarray) -> np.ndarray:
    """sum_g w v / sum_g w per element of values (e, g, ...) at the quadrature points."""
    w = weights.reshape(weights.shape + (1,) * (values.ndim - 2))
    return (w * values).sum(axis=1) / w.sum(axis=1)


def von_mises(stress: np.ndarray) -> np.ndarray:
    """sqrt(s_xx^2 - s_xx s_yy + s_yy^2 + 3 s_xy^2) of in-plane stresses (..., 2, 2) (plane stress; Pa)."""
    sxx, syy, sxy = stress[..., 0, 0], stress[..., 1, 1], (stress[..., 0, 1] + stress[..., 1, 0]) / 2
    return np.sqrt(np.maximum(sxx**2 - sxx * syy + syy**2 + 3 * sxy**2, 0.0))
