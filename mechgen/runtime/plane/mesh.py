"""Plane meshes: the :class:`PlaneMesh` container, generators for common shapes, quality checks and gmsh files.

A mesh is points (n, 2) [m], cells (ne, k) of node indices and an element name (P1, P2, Q1, Q2). Cell node order:
vertices counter-clockwise, then edge midpoints (edge i joins vertex i and i + 1 mod nv), then (Q2) the centre.
Boundaries are named sets of boundary edges (nf, 2 or 3): the two endpoints (the domain on their left, i.e. the
outer boundary traversed counter-clockwise) then, for P2/Q2, the midside node. Groups are named sets of cells.

Generators build structured (mapped) meshes, vectorised and deterministic (the same input gives a bit-identical
mesh): ``rectangle``; ``disk`` (an O-grid: a square core and a ring mapped onto the circle); ``annulus`` and
``plate_with_hole`` (a ring between a circle and a circle or a rectangle, log-graded toward the inner circle);
``slit_plate`` (two rectangles meeting on y = 0 except along the crack, optionally graded toward the tips).
Midside nodes sit at the middle of straight chords, except on circular boundaries with ``curved=True``, where they
are moved radially onto the circle (isoparametric P2/Q2 edges; vertices are always on the circle). A Q2 centre is
the serendipity value (sum of midsides) / 2 - (sum of vertices) / 4, the bilinear centre when the edges are straight.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from math import ceil, log, pi

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.plane.elements import ELEMENTS, NODES, ORDER, VERTICES

GEOMETRY_TOL = 1e-9  # relative distance under which a point lies on a generator's boundary (coordinates are exact
# to round-off by construction, so any value well above 1e-15 and below the smallest cell works)


@dataclass(frozen=True, eq=False)
class PlaneMesh:
    """A plane mesh: points (n, 2) [m], cells (ne, k) node indices, element in {P1, P2, Q1, Q2}, boundaries
    {name: (nf, 2 | 3) edge node indices, endpoints then midside}, groups {name: cell indices}."""

    points: np.ndarray
    cells: np.ndarray
    element: str
    boundaries: dict = field(default_factory=dict)
    groups: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.element not in ELEMENTS:
            raise ValueError(f"element {self.element!r}: expected one of {', '.join(ELEMENTS)}")
        if self.cells.ndim != 2 or self.cells.shape[1] != NODES[self.element]:
            raise ValueError(f"{self.element} cells need {NODES[self.element]} nodes, got shape {self.cells.shape}")
        if self.points.ndim != 2 or self.points.shape[1] != 2:
            raise ValueError(f"points must be (n, 2), got {self.points.shape}")

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return len(self.points)

    @property
    def n_cells(self) -> int:
        """Number of cells."""
        return len(self.cells)

    @property
    def vertices(self) -> np.ndarray:
        """(ne, nv) the cells' vertex nodes."""
        return self.cells[:, :VERTICES[self.element]]

    def boundary(self, name: str, file: str | None = None, key: str | None = None) -> np.ndarray:
        """The edges (nf, 2 | 3) of boundary ``name``; an unknown name is an InputError listing the known ones."""
        if name not in self.boundaries:
            from mechgen.errors import did_you_mean

            known = ", ".join(repr(n) for n in sorted(self.boundaries)) or "none"
            raise InputError(f"the mesh has no boundary {name!r}{did_you_mean(name, self.boundaries)}", file=file,
                             key=key, expected=f"one of its boundaries: {known}")
        return self.boundaries[name]

    def boundary_nodes(self, name: str, file: str | None = None, key: str | None = None) -> np.ndarray:
        """Sorted unique node indices on boundary ``name`` (InputError naming the known ones if unknown)."""
        return np.unique(self.boundary(name, file, key))

    def area(self) -> float:
        """The domain's area [m^2] by the default quadrature (exact for straight-sided cells)."""
        from mechgen.runtime.plane.elements import tables

        return float(tables(self).w.sum())


# -- topology helpers -----------------------------------------------------------------------------------------
def cell_edges(cells: np.ndarray, element: str) -> np.ndarray:
    """(ne, nv, 2 | 3): edge i of every cell, (vertex i, vertex i + 1 mod nv[, midside i])."""
    nv = VERTICES[element]
    v = cells[:, :nv]
    parts = [v, np.roll(v, -1, axis=1)] + ([cells[:, nv:2 * nv]] if ORDER[element] == 2 else [])
    return np.stack(parts, axis=-1)


def boundary_edges(cells: np.ndarray, element: str) -> tuple[np.ndarray, np.ndarray]:
    """The edges that belong to one cell only (in cell order: the domain on their left) and their cells."""
    edges = cell_edges(cells, element)
    ne, nv = edges.shape[:2]
    flat = edges.reshape(ne * nv, -1)
    lo, hi = np.minimum(flat[:, 0], flat[:, 1]), np.maximum(flat[:, 0], flat[:, 1])
    keys = lo.astype(np.int64) * (int(cells.max()) + 1) + hi
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    once = counts[inverse] == 1
    return flat[once], np.repeat(np.arange(ne), nv)[once]


def signed_areas(points: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Shoelace area of each vertex polygon (positive counter-clockwise) [m^2]."""
    p = points[vertices]
    q = np.roll(p, -1, axis=1)
    return 0.5 * np.sum(p[..., 0] * q[..., 1] - q[..., 0] * p[..., 1], axis=1)


def reversed_cells(cells: np.ndarray, element: str) -> np.ndarray:
    """The same cells traversed the other way: vertices (0, nv-1, ..., 1), edges re-indexed to match."""
    nv = VERTICES[element]
    vorder = [0] + list(range(nv - 1, 0, -1))
    order = vorder + ([nv + (nv - 1 - i) for i in range(nv)] if ORDER[element] == 2 else [])
    order += list(range(len(order), cells.shape[1]))
    return cells[:, order]


def oriented(points: np.ndarray, cells: np.ndarray, element: str) -> np.ndarray:
    """Cells with clockwise vertex polygons reversed (counter-clockwise everywhere)."""
    flip = signed_areas(points, cells[:, :VERTICES[element]]) < 0
    if flip.any():
        cells = cells.copy()
        cells[flip] = reversed_cells(cells[flip], element)
    return cells


def straightened(points: np.ndarray, cells: np.ndarray, element: str) -> np.ndarray:
    """Points with every midside node at its chord's middle and every Q2 centre at the serendipity value."""
    if ORDER[element] == 1:
        return points
    points = points.copy()
    edges = cell_edges(cells, element).reshape(-1, 3)
    points[edges[:, 2]] = (points[edges[:, 0]] + points[edges[:, 1]]) / 2
    return centred(points, cells, element)


def centred(points: np.ndarray, cells: np.ndarray, element: str) -> np.ndarray:
    """Q2 centres x_c = (sum of midsides) / 2 - (sum of vertices) / 4 (transfinite centre; bilinear if straight)."""
    if element != "Q2":
        return points
    points = points.copy()
    p = points[cells]
    points[cells[:, 8]] = p[:, 4:8].sum(axis=1) / 2 - p[:, :4].sum(axis=1) / 4
    return points


def compacted(points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points used by the cells only (order kept), cells renumbered, and the old -> new map (-1: dropped)."""
    used = np.zeros(len(points), bool)
    used[cells.ravel()] = True
    new = np.full(len(points), -1, np.int64)
    new[used] = np.arange(int(used.sum()))
    return points[used], new[cells], new


def grid_cells(ids: np.ndarray, element: str) -> np.ndarray:
    """Cells of a logical grid of node ids (order * nu + 1, order * nv + 1), u then v right-handed: one quad a
    grid cell, or two triangles split along the (0, 0)-(1, 1) diagonal."""
    s = ORDER[element]
    nu, nv = (ids.shape[0] - 1) // s, (ids.shape[1] - 1) // s
    I, J = np.meshgrid(np.arange(nu) * s, np.arange(nv) * s, indexing="ij")
    I, J = I.ravel(), J.ravel()
    at = lambda di, dj: ids[I + di, J + dj]  # noqa: E731
    v0, v1, v2, v3 = at(0, 0), at(s, 0), at(s, s), at(0, s)
    if element == "Q1":
        return np.column_stack([v0, v1, v2, v3])
    if element == "P1":
        return np.vstack([np.column_stack([v0, v1, v2]), np.column_stack([v0, v2, v3])])
    e0, e1, e2, e3, c = at(1, 0), at(2, 1), at(1, 2), at(0, 1), at(1, 1)
    if element == "Q2":
        return np.column_stack([v0, v1, v2, v3, e0, e1, e2, e3, c])
    return np.vstack([np.column_stack([v0, v1, v2, e0, e1, c]), np.column_stack([v0, v2, v3, c, e2, e3])])


def fine(values: np.ndarray, order: int) -> np.ndarray:
    """Vertex coordinates along a line with, for order 2, the midpoints interleaved."""
    values = np.asarray(values, float)
    if order == 1:
        return values
    out = np.empty(2 * len(values) - 1)
    out[0::2] = values
    out[1::2] = (values[:-1] + values[1:]) / 2
    return out


def _check_element(element: str) -> str:
    if element not in ELEMENTS:
        raise InputError(f"unknown plane element {element!r}", key="element", expected=f"one of {', '.join(ELEMENTS)}")
    return element


def _check_positive(**values: float) -> None:
    for name, v in values.items():
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{name} = {v!r} is not a positive length", key=name, expected="a finite number > 0")


def _count(length: float, h: float, least: int = 1) -> int:
    """Cells along ``length`` at target size ``h`` (at least ``least``)."""
    return max(least, int(ceil(length / h - 1e-9)))


def _finish(points, cells, element, classify, groups=None) -> PlaneMesh:
    """Orient, name the boundary edges by ``classify(midpoints, owner) -> {name: mask}`` and build the mesh."""
    cells = oriented(points, cells, element)
    edges, owner = boundary_edges(cells, element)
    mid = (points[edges[:, 0]] + points[edges[:, 1]]) / 2
    boundaries = {name: edges[mask] for name, mask in classify(mid, owner, cells).items()}
    groups = groups or {"domain": np.arange(len(cells))}
    for a in (points, cells, *boundaries.values(), *groups.values()):
        a.setflags(write=False)
    return PlaneMesh(points=points, cells=cells, element=element, boundaries=boundaries, groups=groups)


# -- generators ----------------------------------------------------------------------------------------------
def structured(xs: np.ndarray, ys: np.ndarray, element: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tensor grid on vertex coordinates xs, ys: (points, cells, ids (fine x, fine y))."""
    s = ORDER[element]
    fx, fy = fine(xs, s), fine(ys, s)
    X, Y = np.meshgrid(fx, fy, indexing="ij")
    ids = np.arange(X.size).reshape(X.shape)
    return np.column_stack([X.ravel(), Y.ravel()]) + 0.0, grid_cells(ids, element), ids


def rectangle(x0: float, x1: float, y0: float, y1: float, h: float, element: str = "P1") -> PlaneMesh:
    """[x0, x1] x [y0, y1], ceil(length / h) cells a side; boundaries bottom, right, top, left."""
    element = _check_element(element)
    _check_positive(h=h, width=x1 - x0, height=y1 - y0)
    xs = np.linspace(x0, x1, _count(x1 - x0, h) + 1)
    ys = np.linspace(y0, y1, _count(y1 - y0, h) + 1)
    points, cells, _ = structured(xs, ys, element)
    tol = GEOMETRY_TOL * max(x1 - x0, y1 - y0)

    def classify(mid, owner, cells):
        return {"bottom": np.abs(mid[:, 1] - y0) < tol, "right": np.abs(mid[:, 0] - x1) < tol,
                "top": np.abs(mid[:, 1] - y1) < tol, "left": np.abs(mid[:, 0] - x0) < tol}

    return _finish(points, cells, element, classify)


def ring(inner_ids: np.ndarray, inner: np.ndarray, outer: np.ndarray, t: np.ndarray, start: int, element: str):
    """A periodic ring of cells between a closed chain of existing nodes ``inner_ids`` (fine, counter-clockwise,
    coordinates ``inner``) and new nodes along ``outer`` (same count): rows at x = inner + t_j (outer - inner) for
    the fine radial parameters t (t_0 = 0, t_end = 1). New ids from ``start``. Returns (new points, cells)."""
    n, rows = len(inner_ids), len(t)
    new = inner[None] + t[1:, None, None] * (outer - inner)[None]  # (rows - 1, n, 2)
    new[-1] = outer
    ids = np.empty((n + 1, rows), np.int64)
    ids[:n, 0] = inner_ids
    ids[:n, 1:] = start + np.arange((rows - 1) * n).reshape(rows - 1, n).T
    ids[n] = ids[0]
    return new.reshape(-1, 2), grid_cells(ids, element)


def _circle(radius: float, theta: np.ndarray) -> np.ndarray:
    return radius * np.column_stack([np.cos(theta), np.sin(theta)])


def _radial_fine(m: int, order: int, grading: float = 1.0) -> np.ndarray:
    """Fine radial parameters of m cells in [0, 1]: uniform (grading 1) or geometric with total ratio ``grading``
    (the last cell ``grading``^(1 - 1/m) ... times the first: t_j = (g^(j/m) - 1) / (g - 1))."""
    j = np.arange(m + 1) / m
    t = j if abs(grading - 1.0) < 1e-12 else (grading ** j - 1) / (grading - 1)
    t[-1] = 1.0
    return fine(t, order)


def _on_circle(points: np.ndarray, edges: np.ndarray, radius: float) -> np.ndarray:
    """Points with the midside nodes of ``edges`` moved radially onto the circle of ``radius`` about the origin."""
    points = points.copy()
    mids = edges[:, 2]
    points[mids] *= radius / np.hypot(points[mids, 0], points[mids, 1])[:, None]
    return points


def _curve(mesh_parts, element, classify, circles) -> PlaneMesh:
    """Straighten, put the midsides of the named circular boundaries on their circles, re-centre Q2, finish."""
    points, cells = mesh_parts
    cells = oriented(points, cells, element)
    points = straightened(points, cells, element)
    if ORDER[element] == 2 and circles:
        edges, owner = boundary_edges(cells, element)
        mid = (points[edges[:, 0]] + points[edges[:, 1]]) / 2
        named = classify(mid, owner, cells)
        for name, radius in circles.items():
            points = _on_circle(points, edges[named[name]], radius)
        points = centred(points, cells, element)
    return _finish(points, cells, element, classify)


def disk(R: float, h: float, element: str = "P1", curved: bool = True) -> PlaneMesh:
    """The disk of radius R about the origin: a square core [-R/2, R/2]^2 and a ring mapped onto the circle
    (O-grid); ceil(pi R / (2 h)) cells a quarter of the circle. Boundary "outer"."""
    element = _check_element(element)
    _check_positive(R=R, h=h)
    s, order = ORDER[element], ORDER[element]
    n = _count(pi * R / 2, h)
    m = _count(0.6 * R, h)
    xs = np.linspace(-R / 2, R / 2, n + 1)
    core, cells_core, ids = structured(xs, xs, element)
    k = s * n
    chain = np.concatenate([ids[k, :k], ids[k:0:-1, k], ids[0, k:0:-1], ids[:k, 0]])  # ccw from (R/2, -R/2)
    theta = -pi / 4 + 2 * pi * np.arange(4 * k) / (4 * k)
    new, cells_ring = ring(chain, core[chain], _circle(R, theta), _radial_fine(m, order), len(core), element)
    points = np.vstack([core, new]) + 0.0
    outer = lambda mid, owner, cells: {"outer": np.ones(len(mid), bool)}  # noqa: E731
    return _curve((points, np.vstack([cells_core, cells_ring])), element, outer, {"outer": R} if curved else {})


def annulus(a: float, b: float, h: float, element: str = "P1", curved: bool = True) -> PlaneMesh:
    """a <= r <= b: ceil(2 pi b / h) cells around, radial rows log-graded (r_j = a (b/a)^(j/m), cells about
    square). Boundaries "inner", "outer"."""
    element = _check_element(element)
    _check_positive(a=a, b=b, h=h)
    if not b > a:
        raise InputError(f"annulus radii a = {a!r}, b = {b!r}", key="b", expected="b > a > 0")
    order = ORDER[element]
    nt = _count(2 * pi * b, h, least=3) * order
    m = _count(log(b / a) * nt / order, 2 * pi)
    theta = 2 * pi * np.arange(nt) / nt
    inner = _circle(a, theta) + 0.0
    t = _radial_fine(m, order, b / a)
    new, cells = ring(np.arange(nt), inner, _circle(b, theta), t, nt, element)
    points = np.vstack([inner, new]) + 0.0
    mid_r = (a + b) / 2

    def classify(mid, owner, cells):
        r = np.hypot(mid[:, 0], mid[:, 1])
        return {"inner": r < mid_r, "outer": r >= mid_r}

    return _curve((points, cells), element, classify, {"inner": a, "outer": b} if curved else {})


def _rectangle_chain(W: float, H: float, h: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Fine points counter-clockwise around [-W, W] x [-H, H] from (W, -H), uniform on each side
    (ceil(side / h) cells), and the angles of the matching points on a circle: uniform within each corner-to-corner
    arc (corners at +-atan2(H, W), pi -+ atan2(H, W))."""
    alpha = np.arctan2(H, W)
    corners = [(W, -H), (W, H), (-W, H), (-W, -H), (W, -H)]
    arcs = [-alpha, alpha, pi - alpha, pi + alpha, 2 * pi - alpha]
    pts, ang = [], []
    for k in range(4):
        (xa, ya), (xb, yb) = corners[k], corners[k + 1]
        n = _count(np.hypot(xb - xa, yb - ya), h) * order
        f = np.arange(n) / n
        pts.append(np.column_stack([xa + f * (xb - xa), ya + f * (yb - ya)]))
        ang.append(arcs[k] + f * (arcs[k + 1] - arcs[k]))
    return np.vstack(pts), np.concatenate(ang)


def plate_with_hole(W: float, H: float, r: float, h: float, element: str = "P1", curved: bool = True) -> PlaneMesh:
    """[-W, W] x [-H, H] with a circular hole of radius r at the origin: a ring from the hole to the rectangle,
    rows graded geometrically toward the hole (ratio max(W, H) / r). Boundaries "hole", "bottom", "right", "top",
    "left"."""
    element = _check_element(element)
    _check_positive(W=W, H=H, r=r, h=h)
    if not r < min(W, H):
        raise InputError(f"hole radius r = {r!r} does not fit in the plate", key="r", expected=f"r < min(W, H) = {min(W, H)!r}")
    order = ORDER[element]
    outer, theta = _rectangle_chain(W, H, h, order)
    nt = len(outer)
    ratio = max(W, H) / r
    m = _count(log(ratio) * nt / order, 2 * pi)
    inner = _circle(r, theta) + 0.0
    new, cells = ring(np.arange(nt), inner, outer, _radial_fine(m, order, ratio), nt, element)
    points = np.vstack([inner, new]) + 0.0
    tol = GEOMETRY_TOL * max(W, H)

    def classify(mid, owner, cells):
        hole = np.hypot(mid[:, 0], mid[:, 1]) < (r + min(W, H)) / 2
        return {"hole": hole, "bottom": ~hole & (np.abs(mid[:, 1] + H) < tol),
                "right": ~hole & (np.abs(mid[:, 0] - W) < tol), "top": ~hole & (np.abs(mid[:, 1] - H) < tol),
                "left": ~hole & (np.abs(mid[:, 0] + W) < tol)}

    return _curve((points, cells), element, classify, {"hole": r} if curved else {})


def graded(x0: float, x1: float, h: float, power: float) -> np.ndarray:
    """Vertex coordinates from x0 to x1, ceil(|x1 - x0| / h) cells, x = x0 + (x1 - x0) (k / n)^power: cells shrink
    toward x0 for power > 1 (the smallest (1/n)^power of the length)."""
    n = _count(abs(x1 - x0), h)
    out = x0 + (x1 - x0) * (np.arange(n + 1) / n) ** power
    out[-1] = x1
    return out


def slit_plate(W: float, H: float, a: float, h: float, element: str = "P1", grading: float = 1.0) -> PlaneMesh:
    """[-W, W] x [-H, H] with a slit crack |x| <= a on y = 0: the upper and lower halves share their nodes on the
    ligament |x| >= a (the tips included) and not on the crack, whose faces are the boundaries "crack_upper" and
    "crack_lower" (besides "bottom", "right", "top", "left"). ``grading`` > 1 shrinks cells toward the tips and
    toward y = 0 (power grading, :func:`graded`)."""
    element = _check_element(element)
    _check_positive(W=W, H=H, a=a, h=h, grading=grading)
    if not a < W:
        raise InputError(f"crack half-length a = {a!r} reaches the plate's side", key="a", expected=f"a < W = {W!r}")
    order = ORDER[element]
    xs = np.concatenate([graded(-a, -W, h, grading)[::-1], graded(-a, 0.0, h, grading)[1:],
                         graded(a, 0.0, h, grading)[::-1][1:], graded(a, W, h, grading)[1:]])
    ys = graded(0.0, H, h, grading)
    upper, cells_up, ids_up = structured(xs, ys, element)
    lower, cells_lo, ids_lo = structured(xs, -ys[::-1] + 0.0, element)
    fx = fine(xs, order)
    ligament = np.abs(fx) >= a  # the tips are exactly +-a by construction
    remap = np.arange(len(lower)) + len(upper)
    remap[ids_lo[ligament, -1]] = ids_up[ligament, 0]
    points = np.vstack([upper, lower])
    cells = np.vstack([cells_up, remap[cells_lo]])
    points, cells, _ = compacted(points, cells)
    tol = GEOMETRY_TOL * max(W, H)

    def classify(mid, owner, cells):
        crack = (np.abs(mid[:, 1]) < tol) & (np.abs(mid[:, 0]) < a)
        centre_y = points[cells[owner, :VERTICES[element]], 1].mean(axis=1)
        return {"crack_upper": crack & (centre_y > 0), "crack_lower": crack & (centre_y < 0),
                "bottom": np.abs(mid[:, 1] + H) < tol, "right": np.abs(mid[:, 0] - W) < tol,
                "top": np.abs(mid[:, 1] - H) < tol, "left": np.abs(mid[:, 0] + W) < tol}

    return _finish(points, oriented(points, cells, element), element, classify)


# -- quality --------------------------------------------------------------------------------------------------
def check_cells(mesh: PlaneMesh, file: str | None = None) -> None:
    """Refuse (InputError naming the first bad cell) a degenerate cell (area <= 1e-12 x its longest edge squared)
    or an inverted one (det J <= 0 at a quadrature point of the default rule or at a node)."""
    from mechgen.runtime.plane.elements import DEFAULT_DEGREE, jacobians, quadrature, reference_nodes, shapes

    X = mesh.points[mesh.cells]
    ref = np.vstack([quadrature(mesh.element, DEFAULT_DEGREE[mesh.element])[0], reference_nodes(mesh.element)])
    J = jacobians(X, shapes(mesh.element, ref)[1])
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    v = X[:, :VERTICES[mesh.element]]
    longest = np.max(np.sum((v - np.roll(v, -1, axis=1)) ** 2, axis=2), axis=1)
    area = np.abs(signed_areas(mesh.points, mesh.vertices))
    bad_area = ~(area > 1e-12 * longest)
    bad_det = ~(det.min(axis=1) > 0)
    for bad, what in ((bad_area, "degenerate (zero area)"), (bad_det, "inverted (det J <= 0 inside it)")):
        if bad.any():
            e = int(np.argmax(bad))
            corners = ", ".join(f"({x:.6g}, {y:.6g})" for x, y in v[e])
            raise InputError(f"{mesh.element} cell {e} with vertices {corners} is {what}", file=file,
                             key=f"cells[{e}]", expected="cells of positive area, vertices counter-clockwise, "
                             "det J > 0 everywhere")


# -- gmsh files -----------------------------------------------------------------------------------------------
#: meshio cell type -> plane element
MESHIO_CELLS = {"triangle": "P1", "triangle6": "P2", "quad": "Q1", "quad9": "Q2"}
#: meshio line type of an element's boundary edges
MESHIO_LINES = {"P1": "line", "Q1": "line", "P2": "line3", "Q2": "line3"}


def _read_meshio(path: str):
    """meshio's Mesh of ``path``; a missing file or one meshio cannot read is an InputError."""
    import os

    try:
        import meshio
    except ImportError as exc:  # pragma: no cover - meshio is an extra
        raise InputError(f"reading {path} needs meshio ({exc})", file=path,
                         expected="pip install 'mechgen[mesh]'") from None
    if not os.path.isfile(path):
        raise InputError("the mesh file does not exist or is not a regular file", file=path,
                         expected="an existing gmsh .msh file")
    try:
        return meshio.read(path, file_format="gmsh")
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - meshio raises many kinds (and exits) on a file that is not a mesh
        raise InputError(f"not a readable gmsh mesh ({type(exc).__name__}: {str(exc)[:200]})", file=path,
                         expected="a gmsh .msh file (format 2.2 or 4.1)") from None


def _planar_points(points: np.ndarray, path: str) -> np.ndarray:
    """The (n, 2) coordinates; a z that varies is an InputError."""
    if points.shape[1] == 3:
        z = points[:, 2]
        if np.ptp(z) > 0:
            raise InputError(f"the mesh is not plane: z ranges over [{z.min():.6g}, {z.max():.6g}]", file=path,
                             key="points", expected="every z coordinate equal")
    return np.ascontiguousarray(points[:, :2], dtype=float)


def _physical_names(msh) -> dict:
    """{(dim, tag): name} from the file's physical names."""
    return {(int(dim), int(tag)): name for name, (tag, dim) in ((n, v[:2]) for n, v in msh.field_data.items())}


def _tagged(msh, kinds: set, dim: int, names: dict) -> tuple[list, dict]:
    """The blocks of the given meshio types and {name: [block-local (block, indices)]} of their physical tags."""
    phys = msh.cell_data.get("gmsh:physical", [None] * len(msh.cells))
    blocks, named = [], {}
    for block, tags in zip(msh.cells, phys):
        if block.type not in kinds:
            continue
        blocks.append(block.data)
        if tags is None:
            continue
        for tag in np.unique(tags):
            name = names.get((dim, int(tag)), str(int(tag)))
            named.setdefault(name, []).append((len(blocks) - 1, np.flatnonzero(tags == tag)))
    return blocks, named


def read_msh(path) -> PlaneMesh:
    """A plane mesh from a gmsh file through meshio: one kind of 2D cell (triangle -> P1, triangle6 -> P2,
    quad -> Q1, quad9 -> Q2); physical groups of lines (line / line3) become boundaries, of cells groups (named by
    the file's physical names, else by their tag). Unused nodes are dropped; a clockwise mesh is reversed; mixed
    orientations, degenerate or inverted cells, a z that varies are refused (InputError naming the file)."""
    path = str(path)
    msh = _read_meshio(path)
    types = sorted({b.type for b in msh.cells if b.type in MESHIO_CELLS})
    if not types:
        found = ", ".join(sorted({b.type for b in msh.cells})) or "none"
        raise InputError(f"the mesh has no 2D cells (cell types found: {found})", file=path, key="cells",
                         expected="triangle, triangle6, quad or quad9 cells")
    if len(types) > 1:
        raise InputError(f"the mesh mixes 2D cell types {', '.join(types)}", file=path, key="cells",
                         expected="one type of 2D cell")
    element = MESHIO_CELLS[types[0]]
    names = _physical_names(msh)
    blocks, cell_groups = _tagged(msh, {types[0]}, 2, names)
    offsets = np.cumsum([0] + [len(b) for b in blocks])
    cells = np.vstack(blocks).astype(np.int64)
    lines, line_groups = _tagged(msh, {MESHIO_LINES[element]}, 1, names)
    points, cells, new = compacted(_planar_points(msh.points, path), cells)
    cells = _consistently_oriented(points, cells, element, path)
    boundaries = {name: np.vstack([new[lines[b][i]] for b, i in parts]) for name, parts in line_groups.items()}
    for name, edges in boundaries.items():
        if (edges < 0).any():
            raise InputError(f"boundary {name!r} has nodes that belong to no 2D cell", file=path,
                             key=f"boundaries.{name}", expected="boundary lines on the edges of the mesh's cells")
    groups = {name: np.concatenate([offsets[b] + i for b, i in parts]) for name, parts in cell_groups.items()}
    for a in (points, cells, *boundaries.values(), *groups.values()):
        a.setflags(write=False)
    mesh = PlaneMesh(points=points, cells=cells, element=element, boundaries=boundaries, groups=groups)
    check_cells(mesh, file=path)
    return mesh


def _consistently_oriented(points: np.ndarray, cells: np.ndarray, element: str, path: str) -> np.ndarray:
    """Cells counter-clockwise: all reversed if all are clockwise; a mix is refused naming the first odd cell."""
    area = signed_areas(points, cells[:, :VERTICES[element]])
    if (area < 0).all():
        return reversed_cells(cells, element)
    if (area < 0).any() and (area > 0).any():
        odd = int(np.argmax(area < 0) if (area > 0).sum() >= (area < 0).sum() else np.argmax(area > 0))
        raise InputError(f"{element} cell {odd} is inverted: its vertices turn the other way from the mesh's",
                         file=path, key=f"cells[{odd}]", expected="cells of one orientation (no folded cells)")
    return cells
