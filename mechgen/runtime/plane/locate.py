"""Points in a plane mesh: the cell that holds each point, its reference coordinates, and a nodal field there.

:func:`locate` inverts the isoparametric map x(xi) = sum_l X_l N_l(xi) by Newton's method,
xi <- xi - J(xi)^-1 (x(xi) - p), on the cells whose vertex centroids are nearest to p (a k-d tree; all cells if
none of those holds it), and accepts the first cell whose reference cell holds xi within ``tol``. A point on an
edge or a vertex belongs to the first such cell found; on a slit crack's face that is the nearer face's cell.
:func:`interpolate` evaluates u(p) = sum_l u_l N_l(xi) and grad u(p) = sum_l u_l J^-T dN_l/dxi;
:func:`node_gradients` averages each cell's gradient at its nodes (nodal strains and stresses).
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.plane.elements import VERTICES, shapes

#: candidate cells a point tries before all cells
CANDIDATES = 16
NEWTON_STEPS = 30
INSIDE_TOL = 1e-9  # in reference coordinates: a point this far outside a cell (relative to its size) still belongs


def _inverse_map(X: np.ndarray, p: np.ndarray, element: str) -> np.ndarray:
    """xi with x(xi) = p for each cell X (m, l, 2) and point p (m, 2) by Newton; NaN where it does not settle."""
    xi = np.tile([1 / 3, 1 / 3] if element in ("P1", "P2") else [0.0, 0.0], (len(p), 1))
    scale = np.ptp(X, axis=1).max(axis=1)
    with np.errstate(all="ignore"):
        for _ in range(NEWTON_STEPS):
            N, dN = shapes(element, xi)
            r = np.einsum("ml,mli->mi", N, X) - p
            J = np.einsum("mli,mlj->mij", X, dN)
            det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
            step = np.stack([J[:, 1, 1] * r[:, 0] - J[:, 0, 1] * r[:, 1],
                             -J[:, 1, 0] * r[:, 0] + J[:, 0, 0] * r[:, 1]], axis=1) / det[:, None]
            xi = np.clip(xi - step, -3.0, 3.0)  # a far candidate cannot run off to overflow
            if np.all(np.abs(r).max(axis=1) <= 1e-14 * scale):
                break
        N, _ = shapes(element, xi)
        r = np.einsum("ml,mli->mi", N, X) - p
    xi[~(np.abs(r).max(axis=1) <= 1e-10 * scale)] = np.nan
    return xi


def _inside(xi: np.ndarray, element: str, tol: float) -> np.ndarray:
    """Whether reference points lie in the reference cell (within tol); NaN is outside."""
    with np.errstate(invalid="ignore"):
        if element in ("P1", "P2"):
            return (xi[:, 0] >= -tol) & (xi[:, 1] >= -tol) & (xi.sum(axis=1) <= 1 + tol)
        return np.all(np.abs(xi) <= 1 + tol, axis=1)


def _search(mesh, points: np.ndarray, candidates: np.ndarray, tol: float):
    """(cell, xi) per point among its candidate cells (m, k) in order; cell -1 where none holds it."""
    m, k = candidates.shape
    X = mesh.points[mesh.cells[candidates.ravel()]]
    xi = _inverse_map(X, np.repeat(points, k, axis=0), mesh.element).reshape(m, k, 2)
    ok = _inside(xi.reshape(-1, 2), mesh.element, tol).reshape(m, k)
    first = np.argmax(ok, axis=1)
    found = ok[np.arange(m), first]
    cells = np.where(found, candidates[np.arange(m), first], -1)
    return cells, xi[np.arange(m), first]


def locate(mesh, points, *, tol: float = INSIDE_TOL, file: str | None = None, key: str | None = None):
    """(cells (m,), reference coordinates (m, 2)) of points (m, 2); a point in no cell is an InputError at ``key``."""
    from scipy.spatial import cKDTree

    points = np.atleast_2d(np.asarray(points, float))
    centroids = mesh.points[mesh.cells[:, :VERTICES[mesh.element]]].mean(axis=1)
    k = min(CANDIDATES, mesh.n_cells)
    _, near = cKDTree(centroids).query(points, k=k)
    cells, xi = _search(mesh, points, np.asarray(near).reshape(len(points), k), tol)
    for i in np.flatnonzero(cells < 0):  # rare: a point beside long thin cells; try every cell
        c, x = _search(mesh, points[i:i + 1], np.arange(mesh.n_cells)[None], tol)
        cells[i], xi[i] = c[0], x[0]
    if (cells < 0).any():
        i = int(np.argmax(cells < 0))
        raise InputError(f"point ({points[i, 0]:.6g}, {points[i, 1]:.6g}) lies outside the mesh", file=file,
                         key=f"{key}[{i}]" if key else None, expected="points inside the meshed domain")
    return cells, xi


def interpolate(mesh, u: np.ndarray, cells: np.ndarray, xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(values (m, c), gradients (m, c, 2)) of the nodal field u (n, c) at the located points."""
    u = np.asarray(u, float).reshape(mesh.n_nodes, -1)
    N, dNref = shapes(mesh.element, xi)
    X = mesh.points[mesh.cells[cells]]
    U = u[mesh.cells[cells]]  # (m, l, c)
    J = np.einsum("mli,mlj->mij", X, dNref)
    dN = np.linalg.solve(np.transpose(J, (0, 2, 1)), np.transpose(dNref, (0, 2, 1)))  # J^T g = dN/dxi
    return np.einsum("ml,mlc->mc", N, U), np.einsum("mlc,mil->mci", U, dN)


def node_gradients(mesh, u: np.ndarray) -> np.ndarray:
    """grad u at the nodes (n, c, 2): each cell's gradient at its own nodes (reference node coordinates, J^-T dN),
    averaged over the cells that share the node (the plain mean; exact wherever the field is in the element space,
    e.g. stresses of a linear field, or of a quadratic one on straight P2/Q2 cells)."""
    from mechgen.runtime.plane.elements import jacobians, reference_nodes

    u = np.asarray(u, float).reshape(mesh.n_nodes, -1)
    _, dNref = shapes(mesh.element, reference_nodes(mesh.element))  # (k, l, 2) at the cell's own nodes
    X = mesh.points[mesh.cells]
    J = jacobians(X, dNref)  # (e, k, 2, 2)
    rhs = np.broadcast_to(np.transpose(dNref, (0, 2, 1)), J.shape[:2] + (2, dNref.shape[1]))
    g = np.linalg.solve(np.transpose(J, (0, 1, 3, 2)), rhs)  # J^T g = dN/dxi: g[e, k, i, l] = dN_l/dx_i
    grads = np.einsum("elc,ekil->ekci", u[mesh.cells], g)  # (e, k, c, 2)
    count = np.bincount(mesh.cells.ravel(), minlength=mesh.n_nodes)
    flat = grads.reshape(-1, grads.shape[2] * 2)
    total = np.stack([np.bincount(mesh.cells.ravel(), weights=flat[:, j], minlength=mesh.n_nodes)
                      for j in range(flat.shape[1])], axis=1)
    return (total / count[:, None]).reshape(mesh.n_nodes, -1, 2)
