"""Points of a plane mesh: the cell that holds a point and its reference coordinates there.

A point x is found in two steps: the cells whose straight-sided vertex polygon holds x (barycentric
coordinates >= -tol on a triangle, or on either half of a quad), then Newton on the isoparametric map
x(xi) = sum_l N_l(xi) X_l of each candidate (curved P2/Q2 cells included), keeping the first whose
reference coordinates lie in the reference cell. Field values at x are then sum_l N_l(xi) u_l, gradients
J^-T dN/dxi. A point outside the mesh is an InputError naming it.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError

TOL = 1e-9


def _barycentric(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (cells, 3) of P in triangles ABC (cells, 2 each)."""
    v0, v1, v2 = B - A, C - A, P - A
    det = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        b = (v2[:, 0] * v1[:, 1] - v2[:, 1] * v1[:, 0]) / det
        c = (v0[:, 0] * v2[:, 1] - v0[:, 1] * v2[:, 0]) / det
    return np.stack([1 - b - c, b, c], 1)


def _candidates(mesh, p: np.ndarray, slack: float) -> np.ndarray:
    """Cells whose vertex polygon (grown by ``slack`` in barycentric terms) holds p."""
    nv = 3 if mesh.element in ("P1", "P2") else 4
    V = mesh.points[mesh.cells[:, :nv]]
    halves = [(0, 1, 2)] if nv == 3 else [(0, 1, 2), (0, 2, 3)]
    hit = np.zeros(len(V), bool)
    for i, j, k in halves:
        lam = _barycentric(p[None, :], V[:, i], V[:, j], V[:, k])
        hit |= np.all(lam >= -slack, axis=1)
    return np.flatnonzero(hit)


def _inside_reference(element: str, xi: np.ndarray) -> bool:
    if element in ("P1", "P2"):
        return xi[0] >= -TOL and xi[1] >= -TOL and xi[0] + xi[1] <= 1 + TOL
    return bool(np.all(np.abs(xi) <= 1 + TOL))


def _newton(element: str, X: np.ndarray, p: np.ndarray) -> np.ndarray | None:
    """Reference coordinates of p in the cell with nodes X (l, 2), None if Newton does not converge."""
    from mechgen.runtime.plane.elements import shapes

    xi = np.array([1 / 3, 1 / 3]) if element in ("P1", "P2") else np.zeros(2)
    scale = np.ptp(X, axis=0).max()
    for _ in range(30):
        N, dN = shapes(element, xi[None, :])
        residual = N[0] @ X - p
        if np.linalg.norm(residual) <= 1e-13 * scale:
            return xi
        J = X.T @ dN[0]  # dx_i / dxi_j
        xi = xi - np.linalg.solve(J, residual)
    return None


def locate(mesh, points) -> tuple[np.ndarray, np.ndarray]:
    """(cells (p,), reference coordinates (p, 2)) of each point (an InputError for a point outside the mesh)."""
    points = np.atleast_2d(np.asarray(points, float))
    cells, refs = [], []
    size = np.ptp(mesh.points, axis=0).max()
    for p in points:
        found = None
        for slack in (1e-9, 0.05, 0.3):  # a curved edge bulges past the straight polygon of its vertices
            for e in _candidates(mesh, p, slack):
                xi = _newton(mesh.element, mesh.points[mesh.cells[e]], p)
                if xi is not None and _inside_reference(mesh.element, xi):
                    found = (e, xi)
                    break
            if found:
                break
        if found is None:
            raise InputError(f"the point ({p[0]:.6g}, {p[1]:.6g}) is not in the mesh (size {size:.3g})",
                             key="points", expected="points inside the domain")
        cells.append(found[0])
        refs.append(found[1])
    return np.array(cells, int), np.array(refs)


def point_shapes(mesh, cells: np.ndarray, refs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape values N (p, l) and physical gradients dN/dx (p, l, 2) at located points."""
    from mechgen.runtime.plane.elements import shapes

    N = np.empty((len(cells), mesh.cells.shape[1]))
    dN = np.empty(N.shape + (2,))
    for i, (e, xi) in enumerate(zip(cells, refs)):
        n, dn = shapes(mesh.element, xi[None, :])
        X = mesh.points[mesh.cells[e]]
        J = X.T @ dn[0]
        N[i] = n[0]
        dN[i] = dn[0] @ np.linalg.inv(J)
    return N, dN
