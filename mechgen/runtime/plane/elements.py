"""Plane Lagrange elements: reference shape functions, quadrature, the isoparametric map and jet tables.

Reference cells: the triangle T = {(xi, eta): xi, eta >= 0, xi + eta <= 1} (P1, P2) and the square
S = [-1, 1]^2 (Q1, Q2). Node order (the mesh's, :mod:`mechgen.runtime.plane.mesh`): vertices counter-clockwise,
then edge midpoints (edge i joins vertex i and i+1 mod nv), then (Q2) the centre.

Geometry is isoparametric: x(xi) = sum_l X_l N_l(xi) with the element's own shape functions, so a P2/Q2 cell
whose boundary midside nodes sit on a curve has curved edges; straight midsides give the affine (bilinear) map.
With J = dx/dxi (2 x 2), the physical gradients are dN/dx = J^-T dN/dxi and the weights w_q |det J|.

Quadrature (:func:`quadrature`): symmetric rules on T with positive weights, exact for polynomials of total
degree <= 1, 2, 4, 5, 6 (Strang & Fix 1973 for degree 2; Dunavant, Int. J. Numer. Meth. Eng. 21 (1985) 1129,
Table I, for 4-6; degree 3 uses the degree 4 rule, whose 6 points beat Dunavant's 4-point degree 3 rule with
its negative weight; points of 4 and 6 refined by Newton on the moment equations to round-off); above degree 6 the
conical (collapsed) Gauss-Jacobi product rule, positive but not symmetric. On S the tensor Gauss-Legendre rule
with n = ceil((degree + 1) / 2) points a direction.

Jet tables (:func:`jet_tables`): B[e, q, a, d] for a vector field of ``ncomp`` components with dofs interleaved
(d = l * ncomp + c), jets a = (component, order), order in {"", "x", "y"}. Memory: B holds
ne * nq * na * nl * ncomp doubles; for plane elasticity (4 gradient jets, 2 components) on P2 at 10^6 unknowns
(~2.5e5 cells, 6 points a cell at degree 4) that is 2.5e5 * 6 * 4 * 12 * 8 B = 0.58 GB, and dN alone 0.14 GB;
:func:`jet_element_matrices` forms the element matrices block by block without the whole B.
"""
from __future__ import annotations

from dataclasses import dataclass
from math import ceil, sqrt

import numpy as np

ELEMENTS = ("P1", "P2", "Q1", "Q2")
#: nodes a cell
NODES = {"P1": 3, "P2": 6, "Q1": 4, "Q2": 9}
#: vertices a cell
VERTICES = {"P1": 3, "P2": 3, "Q1": 4, "Q2": 4}
#: polynomial order of the shape functions
ORDER = {"P1": 1, "P2": 2, "Q1": 1, "Q2": 2}
#: default quadrature degree: the mass matrix exact on affine cells (2p), 2p + 1 on quads (tensor Gauss)
DEFAULT_DEGREE = {"P1": 2, "P2": 4, "Q1": 3, "Q2": 5}
#: orders of a jet: the value, d/dx, d/dy
JET_ORDERS = ("", "x", "y")


# -- quadrature ------------------------------------------------------------------------------------------------
def _orbit(kind: str, *coords: float) -> list[tuple[float, float, float]]:
    """Barycentric points of a symmetric orbit: 'c' the centroid, 'a' (a, b, b) x3, 'g' (a, b, c) x6."""
    if kind == "c":
        return [(1 / 3, 1 / 3, 1 / 3)]
    if kind == "a":
        a = coords[0]
        b = (1.0 - a) / 2.0
        return [(a, b, b), (b, a, b), (b, b, a)]
    a, b = coords
    c = 1.0 - a - b
    return [(a, b, c), (a, c, b), (b, a, c), (b, c, a), (c, a, b), (c, b, a)]


_S15 = sqrt(15.0)
#: degree -> [(kind, weight (summing to 1 over the triangle), coordinates)]
_TRIANGLE_RULES = {
    1: [("c", 1.0)],
    2: [("a", 1 / 3, 2 / 3)],
    4: [("a", 0.22338158967801144, 0.10810301816807014), ("a", 0.10995174365532187, 0.8168475729804584)],
    5: [("c", 9 / 40), ("a", (155 + _S15) / 1200, (9 - 2 * _S15) / 21), ("a", (155 - _S15) / 1200, (9 + 2 * _S15) / 21)],
    6: [("a", 0.1167862757263447, 0.501426509658138), ("a", 0.050844906370200206, 0.8738219710170051),
        ("g", 0.08285107561839422, 0.05314504984483155, 0.3103524510337681)],
}


def _symmetric_triangle(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (q, 2) and weights (q,) of the symmetric rule for ``degree`` (1, 2, 4, 5, 6) on T (area 1/2)."""
    pts, wts = [], []
    for kind, weight, *coords in _TRIANGLE_RULES[degree]:
        orbit = _orbit(kind, *coords)
        pts += orbit
        wts += [weight] * len(orbit)
    bary = np.array(pts)
    return bary[:, 1:].copy(), np.array(wts) / 2.0


def _conical_triangle(degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Collapsed Gauss-Jacobi product rule on T, exact to ``degree``: xi = s, eta = t (1 - s) with s Gauss-Jacobi
    (alpha = 1) and t Gauss-Legendre on [0, 1]."""
    from scipy.special import roots_jacobi

    n = ceil((degree + 2) / 2)
    s, ws = roots_jacobi(n, 1.0, 0.0)  # weight (1 - s)^1 on [-1, 1]
    t, wt = np.polynomial.legendre.leggauss(n)
    s, ws = (s + 1) / 2, ws / 4  # (1 - s') = 2 (1 - s): weight (1 - s) ds on [0, 1]
    t, wt = (t + 1) / 2, wt / 2
    S, T = np.meshgrid(s, t, indexing="ij")
    pts = np.column_stack([S.ravel(), (T * (1 - S)).ravel()])
    return pts, np.outer(ws, wt).ravel()


def quadrature(element: str, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Reference points (q, 2) and weights (q,) exact for polynomials of total degree ``degree`` (triangles) or
    of degree ``degree`` in each variable (quads). sum of the weights = |reference cell| (1/2 or 4)."""
    degree = max(int(degree), 1)
    if element in ("P1", "P2"):
        if degree <= 6:
            return _symmetric_triangle(min(d for d in _TRIANGLE_RULES if d >= degree))
        return _conical_triangle(degree)
    n = ceil((degree + 1) / 2)
    g, wg = np.polynomial.legendre.leggauss(n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    return np.column_stack([X.ravel(), Y.ravel()]), np.outer(wg, wg).ravel()


# -- shape functions -------------------------------------------------------------------------------------------
def _lagrange_1d(t: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    """1D Lagrange values and derivatives on [-1, 1] at nodes (-1, 1) or (-1, 1, 0): (len(t), order + 1) each."""
    if order == 1:
        return np.column_stack([(1 - t) / 2, (1 + t) / 2]), np.column_stack([-0.5 + 0 * t, 0.5 + 0 * t])
    val = np.column_stack([t * (t - 1) / 2, t * (t + 1) / 2, 1 - t * t])
    der = np.column_stack([t - 0.5, t + 0.5, -2 * t])
    return val, der


#: Q1/Q2 node l -> (i, j) indices into the 1D node lists (-1, 1, 0)
_QUAD_INDEX = {"Q1": [(0, 0), (1, 0), (1, 1), (0, 1)],
               "Q2": [(0, 0), (1, 0), (1, 1), (0, 1), (2, 0), (1, 2), (2, 1), (0, 2), (2, 2)]}


def _triangle_shapes(element: str, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """P1: N = (L0, L1, L2); P2: L_i (2 L_i - 1), then 4 L0 L1, 4 L1 L2, 4 L2 L0; L0 = 1 - xi - eta, L1 = xi,
    L2 = eta. Values (q, l), gradients (q, l, 2)."""
    L = np.column_stack([1 - p[:, 0] - p[:, 1], p[:, 0], p[:, 1]])
    dL = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])  # dL_i / d(xi, eta)
    if element == "P1":
        return L, np.broadcast_to(dL, (len(p), 3, 2)).copy()
    pairs = [(0, 1), (1, 2), (2, 0)]
    N = np.column_stack([L * (2 * L - 1)] + [4 * L[:, i] * L[:, j] for i, j in pairs])
    dN = np.empty((len(p), 6, 2))
    dN[:, :3] = (4 * L - 1)[:, :, None] * dL[None]
    for k, (i, j) in enumerate(pairs):
        dN[:, 3 + k] = 4 * (L[:, j, None] * dL[i] + L[:, i, None] * dL[j])
    return N, dN


def _quad_shapes(element: str, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tensor Lagrange N_l(xi, eta) = n_i(xi) n_j(eta) on [-1, 1]^2 (1D nodes -1, 1 and, for Q2, 0)."""
    order = ORDER[element]
    vx, dx = _lagrange_1d(p[:, 0], order)
    vy, dy = _lagrange_1d(p[:, 1], order)
    idx = _QUAD_INDEX[element]
    N = np.column_stack([vx[:, i] * vy[:, j] for i, j in idx])
    dN = np.stack([np.column_stack([dx[:, i] * vy[:, j] for i, j in idx]),
                   np.column_stack([vx[:, i] * dy[:, j] for i, j in idx])], axis=-1)
    return N, dN


def shapes(element: str, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reference shape functions N (q, l) and their gradients dN/dxi (q, l, 2) at reference points p (q, 2)."""
    p = np.atleast_2d(np.asarray(p, float))
    if element in ("P1", "P2"):
        return _triangle_shapes(element, p)
    return _quad_shapes(element, p)


def reference_nodes(element: str) -> np.ndarray:
    """The reference coordinates (l, 2) of the element's nodes, in the mesh's node order."""
    if element in ("P1", "P2"):
        v = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    else:
        v = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    if ORDER[element] == 1:
        return v
    mids = (v + np.roll(v, -1, axis=0)) / 2
    return np.vstack([v, mids] + ([v.mean(axis=0, keepdims=True)] if element == "Q2" else []))


# -- geometry and tables ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlaneTables:
    """Quadrature data of a plane mesh.

    x (e, q, 2): physical points [m]; w (e, q): reference weights times |det J| [m^2]; N (q, l): reference shape
    values (the same on every cell: Lagrange values do not depend on the map); dN (e, q, l, 2): physical
    gradients dN_l/dx [1/m]; detJ (e, q): det(dx/dxi) [m^2 per reference area]; ref (q, 2) the reference points;
    element, degree.
    """

    x: np.ndarray
    w: np.ndarray
    N: np.ndarray
    dN: np.ndarray
    detJ: np.ndarray
    ref: np.ndarray
    element: str
    degree: int


def jacobians(X: np.ndarray, dNref: np.ndarray) -> np.ndarray:
    """J[e, q, i, j] = dx_i/dxi_j = sum_l X[e, l, i] dN_l/dxi_j."""
    nq, nl = dNref.shape[:2]
    G = np.ascontiguousarray(dNref.transpose(0, 2, 1).reshape(nq * 2, nl))  # rows (q, j)
    return np.matmul(G, X).reshape(len(X), nq, 2, 2).transpose(0, 1, 3, 2)


def tables(mesh, degree: int | None = None) -> PlaneTables:
    """Quadrature tables of ``mesh`` (a :class:`~mechgen.runtime.plane.mesh.PlaneMesh`) at ``degree`` (default
    :data:`DEFAULT_DEGREE`): dN/dx = J^-T dN/dxi, w = w_ref |det J|."""
    element = mesh.element
    degree = DEFAULT_DEGREE[element] if degree is None else int(degree)
    ref, wref = quadrature(element, degree)
    N, dNref = shapes(element, ref)
    X = mesh.points[mesh.cells]  # (e, l, 2)
    J = jacobians(X, dNref)
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
    # J^-T = [[J11, -J10], [-J01, J00]] / det, applied to the reference gradient (g0, g1)
    g0, g1 = dNref[None, :, :, 0], dNref[None, :, :, 1]
    dN = np.empty(det.shape + (N.shape[1], 2))
    dN[..., 0] = (J[..., 1, 1, None] * g0 - J[..., 1, 0, None] * g1) * inv[..., None]
    dN[..., 1] = (-J[..., 0, 1, None] * g0 + J[..., 0, 0, None] * g1) * inv[..., None]
    x = np.matmul(N, X)
    return PlaneTables(x=x, w=wref[None, :] * np.abs(det), N=N, dN=dN, detJ=det, ref=ref, element=element,
                       degree=degree)


def node_dofs(nodes: np.ndarray, ncomp: int) -> np.ndarray:
    """(m, k * ncomp) global dofs of rows of k nodes (cells, edges), interleaved: dof = node * ncomp + component,
    local l * ncomp + c."""
    nodes = np.asarray(nodes, np.int64)
    return (nodes[:, :, None] * ncomp + np.arange(ncomp)[None, None, :]).reshape(len(nodes), -1)


def element_dofs(mesh, ncomp: int) -> np.ndarray:
    """(ne, k * ncomp) global dofs of each cell (:func:`node_dofs` of the cells)."""
    return node_dofs(mesh.cells, ncomp)


def _check_jets(ncomp: int, jets) -> list[tuple[int, str]]:
    """The jets as (component, order) with component < ncomp and order in JET_ORDERS (ValueError otherwise)."""
    out = []
    for c, o in jets:
        if not 0 <= int(c) < ncomp or o not in JET_ORDERS:
            raise ValueError(f"jet {(c, o)!r}: expected a component in 0..{ncomp - 1} and an order in {JET_ORDERS}")
        out.append((int(c), o))
    return out


def basis_values(tab: PlaneTables, order: str) -> np.ndarray:
    """phi[e, q, l] of a jet order: N (broadcast over cells), dN/dx or dN/dy."""
    if order == "":
        return np.broadcast_to(tab.N[None], tab.dN.shape[:3])
    return tab.dN[..., "xy".index(order)]


def jet_tables(tab: PlaneTables, ncomp: int, jets) -> np.ndarray:
    """B[e, q, a, l * ncomp + c]: jet a = (c_a, order_a) of the basis function of node l, component c: phi_order
    if c == c_a else 0."""
    jets = _check_jets(ncomp, jets)
    ne, nq, nl = tab.dN.shape[:3]
    B = np.zeros((ne, nq, len(jets), nl, ncomp))
    for a, (c, o) in enumerate(jets):
        B[:, :, a, :, c] = basis_values(tab, o)
    return B.reshape(ne, nq, len(jets), nl * ncomp)


#: cells a block in :func:`jet_element_matrices` (the block's B: CHUNK x q x a x l ncomp doubles, a few MB)
CHUNK = 4096


def blocked_element_matrices(tables, comps, weights: np.ndarray, coeff: np.ndarray, ncomp: int,
                             chunk: int = CHUNK) -> np.ndarray:
    """K_e[(l, c), (m, d)] = sum_q w sum_{a, b} phi_a[e, q, l] C[e, q, a, b] phi_b[e, q, m] with c = comps[a],
    d = comps[b], phi_a = tables[a] (e, q, l) (a broadcast view is fine): B[e, q, a, l ncomp + c] built ``chunk``
    cells at a time for the jets that meet a non-zero coefficient only, each block one batched product
    (e, l, q a) @ ((e, q, a, b) @ (e, q, b, m))."""
    ne, nq, nl = tables[0].shape
    n = nl * ncomp
    out = np.zeros((ne, n, n))
    nonzero = np.any(coeff != 0, axis=(0, 1))
    live = np.flatnonzero(nonzero.any(axis=0) | nonzero.any(axis=1))
    if not len(live):
        return out
    every = len(live) == coeff.shape[2]
    for lo in range(0, ne, chunk):
        hi = min(ne, lo + chunk)
        C = coeff[lo:hi] if every else coeff[lo:hi][:, :, live[:, None], live]
        B = np.zeros((hi - lo, nq, len(live), nl, ncomp))
        for j, a in enumerate(live):
            B[:, :, j, :, comps[a]] = tables[a][lo:hi]
        B = B.reshape(hi - lo, nq, len(live), n)
        right = np.matmul(weights[lo:hi, :, None, None] * C, B)
        np.matmul(B.reshape(hi - lo, nq * len(live), n).transpose(0, 2, 1), right.reshape(hi - lo, -1, n),
                  out=out[lo:hi])
    return out


def jet_element_matrices(tab: PlaneTables, ncomp: int, jets, coeff: np.ndarray, chunk: int = CHUNK) -> np.ndarray:
    """K_e = sum_q w_q B_q^T C_q B_q for every cell, B the jet table of :func:`jet_tables`: the same as
    :func:`mechgen.runtime.fields.assemble.element_matrices` on the whole B, but through
    :func:`blocked_element_matrices` (B a block of cells at a time: at 10^6 unknowns the whole would take 0.6 GB)."""
    jets = _check_jets(ncomp, jets)
    tables = [basis_values(tab, o) for _, o in jets]
    return blocked_element_matrices(tables, [c for c, _ in jets], tab.w, coeff, ncomp, chunk)


def assembly_bytes(mesh, ncomp: int, njets: int, degree: int | None = None) -> int:
    """Peak bytes of tables + coefficients + element matrices + CSR pattern + one matrix of ``mesh`` for a field of
    ``ncomp`` components and ``njets`` jets: 8 ne (7 n^2 + 16 q l + 2 q a^2), n = l ncomp the element's dofs, q the
    points a cell, l its nodes, a the jets. Measured with tracemalloc (tests/test_plane_elements.py): the
    coefficients 6 n^2 + 14 q l (+ q a^2 for C) on P1, P2, Q1, Q2; the constants rounded up."""
    degree = DEFAULT_DEGREE[mesh.element] if degree is None else int(degree)
    q = len(quadrature(mesh.element, degree)[1])
    nl = NODES[mesh.element]
    n = nl * ncomp
    return 8 * int(mesh.n_cells) * (7 * n * n + 16 * q * nl + 2 * q * njets * njets)


def require_assembly_memory(mesh, ncomp: int, njets: int, *, key: str, degree: int | None = None) -> None:
    """Refuse (InputError at ``key``, nothing allocated) an assembly whose :func:`assembly_bytes` exceed the memory
    limit of :func:`mechgen.runtime.core.memory.require`."""
    from mechgen.runtime.core.memory import require

    unknowns = mesh.n_nodes * ncomp
    require(assembly_bytes(mesh, ncomp, njets, degree), f"the assembly of {unknowns} unknowns on "
            f"{mesh.n_cells} {mesh.element} cells", key=key, expected="a coarser mesh")


def node_gradients(mesh, u: np.ndarray) -> np.ndarray:
    """grad u at the nodes (n, c, 2): each cell's gradient at its own nodes (reference node coordinates, J^-T dN),
    averaged over the cells that share the node (the plain mean; exact wherever the field is in the element space,
    e.g. stresses of a linear field, or of a quadratic one on straight P2/Q2 cells)."""
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
