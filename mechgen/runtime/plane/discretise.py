"""A plane continuum's discretisation: the mesh of its domain, element and edge tables, dof maps, held dofs.

:func:`generate_mesh` makes the mesh of a declared domain at the target edge length h (memory estimated
first); :func:`discretise` turns a mesh and the model's plane facts (fields, jets, edge terms, boundary
conditions: mechgen.codegen.lower_plane.plane_meta) into :class:`PlaneDisc`: one :class:`Piece` for the
domain and one per edge term, each with its factored tables (mechgen.runtime.plane.assemble), weights,
kernel positions, dof map and CSR pattern, and the free dofs left by the boundary conditions.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.memory import require
from mechgen.runtime.fields.assemble import Assembler
from mechgen.runtime.plane import assemble
from mechgen.runtime.plane.edges import edge_tables
from mechgen.runtime.plane.elements import node_dofs

#: the pseudo-boundary of rigid-motion pins (mechgen.symbolic.plane.RIGID; runtime never imports symbolic)
RIGID = "rigid"

#: nodes per vertex of each element family on a large mesh (P2: vertices + edge midpoints = 4 x vertices)
NODES_PER_VERTEX = {"P1": 1, "P2": 4, "Q1": 1, "Q2": 4}
#: local nodes per element and polynomial order
LOCAL_NODES = {"P1": 3, "P2": 6, "Q1": 4, "Q2": 9}
ORDER = {"P1": 1, "P2": 2, "Q1": 1, "Q2": 2}


@dataclass(frozen=True)
class Piece:
    """The domain (``edge`` None) or one edge term: tables T_k (e, g, l), jet index [(field, order)], weights
    (e, g), kernel positions (e, g, 2 or 4), dof map (e, l * fields) and its assembler."""

    edge: str | None
    T: tuple
    index: list
    weights: np.ndarray
    position: np.ndarray
    dofs: np.ndarray
    assembler: Assembler


@dataclass(frozen=True)
class PlaneDisc:
    """Pieces, number of dofs, free dofs and the held dofs {boundary: {field: dofs}}."""

    mesh: object
    pieces: tuple
    ndof: int
    free: np.ndarray
    held: dict


def _area(shape: str, sizes: dict) -> float:
    """The area of a generated domain (m^2 in the model's length unit)."""
    if shape == "disk":
        return math.pi * sizes["R"] ** 2
    if shape == "annulus":
        return math.pi * (sizes["b"] ** 2 - sizes["a"] ** 2)
    if shape == "rectangle":
        return sizes["width"] * sizes["height"]
    return 4 * sizes["W"] * sizes["H"]


def estimate_bytes(shape: str, sizes: dict, h: float, element: str, nfields: int) -> float:
    """Bytes of a mesh at edge length h: ~2.3 area/h^2 triangles (half as many quads), their tables, element
    matrices and CSR pattern (the largest allocations of an assembly)."""
    cells = 2.3 * _area(shape, sizes) / h**2 / (2 if element.startswith("Q") else 1)
    k = LOCAL_NODES[element] * nfields
    points = (ORDER[element] + 1) ** 2
    return cells * (8 * 3 * points * LOCAL_NODES[element] + 8 * 4 * k * k)


def check_domain(shape: str, sizes: dict) -> None:
    """InputError for sizes that make no domain (an annulus with a >= b, a crack longer than its plate)."""
    bad = None
    if any(not (v > 0 and math.isfinite(v)) for v in sizes.values()):
        bad = "every size must be a positive finite number"
    elif shape == "annulus" and not sizes["a"] < sizes["b"]:
        bad = "the inner radius a must be below the outer radius b"
    elif shape == "slit_plate" and not sizes["a"] < sizes["W"]:
        bad = "the crack's half-length a must be below the half-width W"
    elif shape == "plate_with_hole" and not sizes["r"] < min(sizes["W"], sizes["H"]):
        bad = "the hole's radius r must be below the half-width W and half-height H"
    if bad:
        raise InputError(f"the {shape} domain with {sizes} is not a domain: {bad}", key="params",
                         expected=bad)


def generate_mesh(shape: str, sizes: dict, h: float, element: str, curved: bool, grading: float = 1.0):
    """The mesh of a generated domain (mechgen.runtime.plane.mesh), refused before allocation when too large."""
    from mechgen.runtime.plane import mesh as meshes

    check_domain(shape, sizes)
    require(estimate_bytes(shape, sizes, h, element, 2), f"a {element} mesh of the {shape} at h = {h:g}",
            key="params.h", expected="a larger h")
    if shape == "disk":
        return meshes.disk(sizes["R"], h, element, curved=curved)
    if shape == "annulus":
        return meshes.annulus(sizes["a"], sizes["b"], h, element, curved=curved)
    if shape == "rectangle":
        return meshes.rectangle(0.0, sizes["width"], 0.0, sizes["height"], h, element)
    if shape == "slit_plate":
        return meshes.slit_plate(sizes["W"], sizes["H"], sizes["a"], h, element, grading=grading)
    return meshes.plate_with_hole(sizes["W"], sizes["H"], sizes["r"], h, element, curved=curved)


def _domain_piece(mesh, info: dict, degree: int) -> Piece:
    from mechgen.runtime.plane.elements import tables

    tab = tables(mesh, degree or 2 * ORDER[mesh.element])
    nf = len(info["fields"])
    dofs = node_dofs(mesh.cells, nf)
    T = assemble.order_tables(tab.N, tab.dN)
    index = assemble.jet_index(info["jets"], info["fields"])
    return Piece(None, T, index, tab.w, tab.x, dofs, Assembler(dofs, len(mesh.points) * nf, dense=False))


def _edge_piece(mesh, info: dict, name: str, degree: int) -> Piece:
    nf = len(info["fields"])
    tab = edge_tables(mesh.points, mesh.cells, mesh.boundaries[name], degree or 2 * ORDER[mesh.element])
    ne, ng = tab.weights.shape
    N = np.broadcast_to(tab.values, (ne, ng, tab.values.shape[1]))
    dofs = node_dofs(tab.nodes, nf)
    index = assemble.jet_index(info["edges"][name], info["fields"])
    return Piece(name, (N, None, None), index, tab.weights, tab.position, dofs,
                 Assembler(dofs, len(mesh.points) * nf, dense=False))


def rigid_pins(mesh, fields) -> dict[str, np.ndarray]:
    """The nodes that hold the rigid motions (``fix(..., "rigid")``): every field at the node nearest the mesh's
    lower-left corner and, with two fields, the second (u_y) also at the node nearest the lower-right corner
    (no translation, no rotation). With self-equilibrated loads the pins carry no force and the solution is
    the exact one up to a rigid motion."""
    p = mesh.points
    low = np.array([p[:, 0].min(), p[:, 1].min()])
    high = np.array([p[:, 0].max(), p[:, 1].min()])
    first = int(np.argmin(np.sum((p - low) ** 2, axis=1)))
    second = int(np.argmin(np.sum((p - high) ** 2, axis=1)))
    pins = {f: np.array([first]) for f in fields}
    if len(fields) == 2:
        pins[fields[1]] = np.array([first, second])
    return pins


def _point_piece(mesh, info: dict, name: str, xy) -> Piece:
    """A point term as a piece of one 'element' (the cell that holds the point) with one point of weight 1."""
    from mechgen.runtime.plane.points import locate, point_shapes

    nf = len(info["fields"])
    cells, refs = locate(mesh, [xy])
    N, _ = point_shapes(mesh, cells, refs)
    dofs = node_dofs(mesh.cells[cells], nf)
    position = np.array([[[xy[0], xy[1], 0.0, 0.0]]])
    index = assemble.jet_index(info["edges"][name], info["fields"])
    return Piece(name, (N[None, :, :], None, None), index, np.ones((1, 1)), position, dofs,
                 Assembler(dofs, len(mesh.points) * nf, dense=False))


def discretise(mesh, info: dict, quadrature: int = 0, points: dict | None = None) -> PlaneDisc:
    """Tables, dof maps and held dofs of a mesh for a plane model's facts ``info``."""
    nf = len(info["fields"])
    points = points or {}
    for name in sorted({c[1] for c in info["constraints"] if c[1] != RIGID} | set(info["edges"]) - set(points)):
        if name not in mesh.boundaries:
            raise InputError(f"the mesh has no boundary {name!r}", key="mesh",
                             expected=f"a mesh with the boundaries the model names; it has {', '.join(mesh.boundaries)}")
    from mechgen.runtime.plane.elements import require_assembly_memory

    require_assembly_memory(mesh, nf, len(info["jets"]), key="params.h", degree=quadrature or 2 * ORDER[mesh.element])
    pieces = [_domain_piece(mesh, info, quadrature)]
    pieces += [_point_piece(mesh, info, name, points[name]) if name in points else
               _edge_piece(mesh, info, name, quadrature) for name in sorted(info["edges"])]
    ndof = len(mesh.points) * nf
    held: dict = {}
    pins = rigid_pins(mesh, info["fields"])
    for f, boundary in info["constraints"]:
        if boundary == RIGID:
            if f in pins:
                held.setdefault(boundary, {})[f] = pins[f] * nf + info["fields"].index(f)
            continue
        nodes = np.unique(mesh.boundaries[boundary])
        held.setdefault(boundary, {})[f] = nodes * nf + info["fields"].index(f)
    mask = np.ones(ndof, bool)
    for per_field in held.values():
        for dofs in per_field.values():
            mask[dofs] = False
    return PlaneDisc(mesh, tuple(pieces), ndof, np.flatnonzero(mask), held)
