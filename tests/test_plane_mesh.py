"""Plane meshes (mechgen.runtime.plane.mesh): the generators' geometry, boundaries and orientation, determinism,
the cell checks, unknown boundaries, and gmsh files through meshio (written here by meshio itself)."""
import hashlib
import subprocess
import sys

import numpy as np
import pytest

from mechgen.errors import InputError
from mechgen.runtime.plane import mesh as M
from mechgen.runtime.plane.elements import ELEMENTS, NODES

ON_CURVE = 1e-12  # relative: boundary nodes are placed by closed-form expressions, exact to a few ulp


def generated(element):
    return {"rectangle": M.rectangle(-1.0, 3.0, 0.5, 2.0, 0.4, element), "disk": M.disk(2.0, 0.5, element),
            "annulus": M.annulus(0.5, 1.5, 0.4, element), "plate_with_hole": M.plate_with_hole(2.0, 1.0, 0.3, 0.4, element),
            "slit_plate": M.slit_plate(2.0, 1.0, 0.7, 0.3, element, grading=1.5)}


def edge_normals_point_out(mesh, edges):
    """The outward normal (t_y, -t_x) of each edge (domain on the left) points away from its cell's centre."""
    e0, e1 = mesh.points[edges[:, 0]], mesh.points[edges[:, 1]]
    t = e1 - e0
    normal = np.column_stack([t[:, 1], -t[:, 0]])
    cells = M.boundary_edges(mesh.cells, mesh.element)
    lookup = {tuple(sorted(e[:2])): c for e, c in zip(cells[0].tolist(), cells[1].tolist())}
    owner = np.array([lookup[tuple(sorted(e[:2]))] for e in edges.tolist()])
    centre = mesh.points[mesh.vertices[owner]].mean(axis=1)
    return np.all(np.sum(normal * ((e0 + e1) / 2 - centre), axis=1) > 0)


@pytest.mark.parametrize("element", ELEMENTS)
def test_generators_give_valid_meshes_with_their_boundaries(element):
    expected = {"rectangle": {"bottom", "right", "top", "left"}, "disk": {"outer"}, "annulus": {"inner", "outer"},
                "plate_with_hole": {"hole", "bottom", "right", "top", "left"},
                "slit_plate": {"crack_upper", "crack_lower", "bottom", "right", "top", "left"}}
    for name, mesh in generated(element).items():
        M.check_cells(mesh)
        assert set(mesh.boundaries) == expected[name], name
        assert mesh.cells.shape[1] == NODES[element] and mesh.cells.min() >= 0 and mesh.cells.max() < mesh.n_nodes
        assert len(np.unique(mesh.cells)) == mesh.n_nodes  # no unused node
        width = 3 if element in ("P2", "Q2") else 2
        all_edges = M.boundary_edges(mesh.cells, element)[0]
        named = np.vstack(list(mesh.boundaries.values()))
        assert named.shape == all_edges.shape and named.shape[1] == width  # every boundary edge named once
        assert edge_normals_point_out(mesh, named), name


@pytest.mark.parametrize("element", ELEMENTS)
def test_boundary_nodes_lie_on_their_curves(element):
    meshes = generated(element)
    r = lambda m, name: np.hypot(*m.points[m.boundary_nodes(name)].T)  # noqa: E731
    np.testing.assert_allclose(r(meshes["disk"], "outer"), 2.0, rtol=ON_CURVE)
    np.testing.assert_allclose(r(meshes["annulus"], "inner"), 0.5, rtol=ON_CURVE)
    np.testing.assert_allclose(r(meshes["annulus"], "outer"), 1.5, rtol=ON_CURVE)
    np.testing.assert_allclose(r(meshes["plate_with_hole"], "hole"), 0.3, rtol=ON_CURVE)
    rect = meshes["rectangle"]
    np.testing.assert_allclose(rect.points[rect.boundary_nodes("left"), 0], -1.0, atol=ON_CURVE)
    np.testing.assert_allclose(rect.points[rect.boundary_nodes("top"), 1], 2.0, atol=ON_CURVE)
    assert rect.area() == pytest.approx(4.0 * 1.5, rel=ON_CURVE)


def test_straight_disk_keeps_midsides_on_chords():
    mesh = M.disk(1.0, 0.4, "P2", curved=False)
    edges = mesh.boundaries["outer"]
    p = mesh.points
    np.testing.assert_allclose(p[edges[:, 2]], (p[edges[:, 0]] + p[edges[:, 1]]) / 2, atol=1e-15)
    np.testing.assert_allclose(np.hypot(*p[edges[:, 0]].T), 1.0, rtol=ON_CURVE)  # vertices always on the circle


@pytest.mark.parametrize("element", ELEMENTS)
def test_slit_plate_duplicates_crack_faces_and_shares_the_tips(element):
    a = 0.7
    mesh = M.slit_plate(2.0, 1.0, a, 0.3, element, grading=1.5)
    upper, lower = mesh.boundary_nodes("crack_upper"), mesh.boundary_nodes("crack_lower")
    tips = np.flatnonzero((np.abs(np.abs(mesh.points[:, 0]) - a) < 1e-14) & (mesh.points[:, 1] == 0))
    assert len(tips) == 2 and set(tips) <= set(upper) & set(lower)  # each tip one node, on both faces
    assert set(upper) & set(lower) == set(tips)
    np.testing.assert_array_equal(np.sort(mesh.points[upper, 0]), np.sort(mesh.points[lower, 0]))
    on_line = mesh.points[:, 1] == 0
    ligament = on_line & (np.abs(mesh.points[:, 0]) > a + 1e-14)
    assert ligament.sum() > 0 and not (set(np.flatnonzero(ligament)) & (set(upper) | set(lower)))
    assert mesh.area() == pytest.approx(8.0, rel=ON_CURVE)


def mesh_digest(element):
    h = hashlib.sha256()
    for mesh in generated(element).values():
        for arr in (mesh.points, mesh.cells, *(mesh.boundaries[k] for k in sorted(mesh.boundaries))):
            h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def test_generators_are_deterministic_across_processes():
    code = ("import sys; sys.path.insert(0, 'tests'); from test_plane_mesh import mesh_digest; "
            "print(' '.join(mesh_digest(e) for e in ('P1', 'P2', 'Q1', 'Q2')))")
    here = " ".join(mesh_digest(e) for e in ELEMENTS)
    env = {"PYTHONHASHSEED": "123", "PATH": ""}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    assert done.stdout.split() == here.split()


# -- refusals ---------------------------------------------------------------------------------------------------
def test_unknown_boundary_names_the_known_ones():
    mesh = M.annulus(0.5, 1.0, 0.3, "P1")
    with pytest.raises(InputError) as info:
        mesh.boundary_nodes("outr", file="scene.toml", key="fix.u")
    text = str(info.value)
    assert "'outr'" in text and "'inner'" in text and "'outer'" in text and "scene.toml" in text
    assert "did you mean 'outer'" in text


@pytest.mark.parametrize("element", ELEMENTS)
def test_inverted_and_degenerate_cells_are_refused(element):
    mesh = M.rectangle(0.0, 1.0, 0.0, 1.0, 0.5, element)
    cells = mesh.cells.copy()
    cells[1] = M.reversed_cells(cells[1:2], element)[0]
    with pytest.raises(InputError, match=r"cell 1 .*inverted") as info:
        M.check_cells(M.PlaneMesh(mesh.points, cells, element), file="m.msh")
    assert info.value.key == "cells[1]" and info.value.file == "m.msh"
    points = mesh.points.copy()
    v = mesh.vertices[2]
    points[v[1]] = points[v[0]]  # two vertices of cell 2 on one point: zero area
    points[v[2]] = points[v[0]] if element in ("P1", "P2") else points[v[2]]
    if element in ("Q1", "Q2"):
        points[v[3]] = points[v[2]]
    bad = M.PlaneMesh(points, mesh.cells, element)
    with pytest.raises(InputError, match=r"cell \d+ .*(degenerate|inverted)"):
        M.check_cells(bad)


def test_curved_cell_folded_inside_is_refused():
    mesh = M.disk(1.0, 0.5, "P2")
    points = mesh.points.copy()
    edge = mesh.boundaries["outer"][0]
    points[edge[2]] *= 0.2  # the midside node pulled far inside: det J < 0 near the edge
    with pytest.raises(InputError, match="inverted"):
        M.check_cells(M.PlaneMesh(points, mesh.cells, "P2"))


def test_bad_generator_arguments_are_refused():
    with pytest.raises(InputError, match="element"):
        M.rectangle(0, 1, 0, 1, 0.1, "P3")
    with pytest.raises(InputError, match="positive"):
        M.disk(1.0, -0.1)
    with pytest.raises(InputError, match="b > a"):
        M.annulus(1.0, 0.5, 0.1)
    with pytest.raises(InputError, match="a < W"):
        M.slit_plate(1.0, 1.0, 1.0, 0.1)
    with pytest.raises(InputError, match="does not fit"):
        M.plate_with_hole(1.0, 0.5, 0.5, 0.1)


# -- gmsh files through meshio ------------------------------------------------------------------------------------
meshio = pytest.importorskip("meshio")
TYPES = {"P1": ("triangle", "line"), "P2": ("triangle6", "line3"), "Q1": ("quad", "line"), "Q2": ("quad9", "line3")}


def write_msh(path, mesh, fmt="gmsh22", z=None):
    """The mesh as a gmsh file with physical lines per boundary (tags 1..) and one physical surface 'plate'."""
    cell, line = TYPES[mesh.element]
    names = sorted(mesh.boundaries)
    blocks = [(line, mesh.boundaries[n]) for n in names] + [(cell, mesh.cells)]
    tags = [np.full(len(mesh.boundaries[n]), i + 1) for i, n in enumerate(names)] + [np.full(len(mesh.cells), 10)]
    field = {n: np.array([i + 1, 1]) for i, n in enumerate(names)} | {"plate": np.array([10, 2])}
    pts = np.column_stack([mesh.points, np.zeros(len(mesh.points)) if z is None else z])
    out = meshio.Mesh(pts, blocks, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags}, field_data=field)
    meshio.write(str(path), out, file_format=fmt, binary=False)
    return path


@pytest.mark.parametrize("fmt", ["gmsh22"])  # meshio writes 4.1 with several cell types only given entity tags
@pytest.mark.parametrize("element", ELEMENTS)
def test_msh_round_trip(tmp_path, element, fmt):
    mesh = M.plate_with_hole(2.0, 1.0, 0.4, 0.6, element)
    back = M.read_msh(write_msh(tmp_path / "plate.msh", mesh, fmt))
    assert back.element == element
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.cells, mesh.cells)
    assert set(back.boundaries) == set(mesh.boundaries)
    for name in mesh.boundaries:
        np.testing.assert_array_equal(back.boundaries[name], mesh.boundaries[name])
    np.testing.assert_array_equal(back.groups["plate"], np.arange(mesh.n_cells))


def test_msh_clockwise_mesh_is_reoriented(tmp_path):
    mesh = M.rectangle(0.0, 2.0, 0.0, 1.0, 0.5, "P2")
    flipped = M.PlaneMesh(mesh.points, M.reversed_cells(mesh.cells, "P2"), "P2", mesh.boundaries)
    back = M.read_msh(write_msh(tmp_path / "cw.msh", flipped))
    np.testing.assert_array_equal(back.cells, mesh.cells)
    assert back.area() == pytest.approx(2.0, rel=ON_CURVE)


def test_msh_bad_files_are_refused(tmp_path):
    with pytest.raises(InputError, match="does not exist") as info:
        M.read_msh(tmp_path / "nope.msh")
    assert info.value.file.endswith("nope.msh")
    junk = tmp_path / "junk.msh"
    junk.write_text("this is not a mesh\n")
    with pytest.raises(InputError, match="not a readable gmsh mesh"):
        M.read_msh(junk)
    with pytest.raises(InputError, match="does not exist"):
        M.read_msh(tmp_path)  # a folder
    mesh = M.rectangle(0.0, 1.0, 0.0, 1.0, 0.5, "P1")
    lines_only = tmp_path / "lines.msh"
    meshio.write(str(lines_only), meshio.Mesh(np.column_stack([mesh.points, 0 * mesh.points[:, 0]]),
                                              [("line", mesh.boundaries["top"])]), file_format="gmsh22", binary=False)
    with pytest.raises(InputError, match="no 2D cells"):
        M.read_msh(lines_only)
    with pytest.raises(InputError, match="not plane") as info:
        M.read_msh(write_msh(tmp_path / "warped.msh", mesh, z=0.1 * mesh.points[:, 0]))
    assert info.value.key == "points"


def test_msh_inverted_and_degenerate_cells_are_refused(tmp_path):
    mesh = M.rectangle(0.0, 2.0, 0.0, 1.0, 0.5, "Q1")
    cells = mesh.cells.copy()
    cells[3] = M.reversed_cells(cells[3:4], "Q1")[0]
    with pytest.raises(InputError, match="cell 3 is inverted") as info:
        M.read_msh(write_msh(tmp_path / "inv.msh", M.PlaneMesh(mesh.points, cells, "Q1", mesh.boundaries)))
    assert info.value.key == "cells[3]"
    points = mesh.points.copy()
    points[mesh.cells[5, 2]] = points[mesh.cells[5, 0]]  # a diagonal collapsed: cell 5 folds onto a triangle's half
    points[mesh.cells[5, 1]] = points[mesh.cells[5, 0]]
    with pytest.raises(InputError, match=r"cell \d+ .*(degenerate|inverted)"):
        M.read_msh(write_msh(tmp_path / "flat.msh", M.PlaneMesh(points, mesh.cells, "Q1", mesh.boundaries)))


def test_msh_unused_nodes_are_dropped_and_unnamed_groups_keep_their_tag(tmp_path):
    mesh = M.rectangle(0.0, 1.0, 0.0, 1.0, 0.5, "Q1")
    extra = np.vstack([mesh.points, [[5.0, 5.0]]])  # a geometry point outside every cell, as gmsh writes them
    pts = np.column_stack([extra, np.zeros(len(extra))])
    blocks = [("vertex", np.array([[len(extra) - 1]])), ("line", mesh.boundaries["left"]), ("quad", mesh.cells)]
    tags = [np.array([7]), np.full(len(mesh.boundaries["left"]), 3), np.full(mesh.n_cells, 4)]
    meshio.write(str(tmp_path / "x.msh"), meshio.Mesh(pts, blocks, cell_data={"gmsh:physical": tags,
                 "gmsh:geometrical": tags}), file_format="gmsh22", binary=False)
    back = M.read_msh(tmp_path / "x.msh")
    np.testing.assert_array_equal(back.points, mesh.points)
    np.testing.assert_array_equal(back.boundaries["3"], mesh.boundaries["left"])
    np.testing.assert_array_equal(back.groups["4"], np.arange(mesh.n_cells))


@pytest.mark.parametrize("element", ["P2", "Q1"])
def test_msh_format_41_is_read(tmp_path, element):
    mesh = M.disk(1.0, 0.5, element)
    pts = np.column_stack([mesh.points, np.zeros(mesh.n_nodes)])
    cell = TYPES[element][0]
    meshio.write(str(tmp_path / "d.msh"), meshio.Mesh(pts, [(cell, mesh.cells)]), file_format="gmsh", binary=False)
    assert (tmp_path / "d.msh").read_text().splitlines()[1].startswith("4.1")
    back = M.read_msh(tmp_path / "d.msh")
    np.testing.assert_array_equal(back.cells, mesh.cells)
    assert back.boundaries == {} and back.area() == pytest.approx(mesh.area(), rel=ON_CURVE)
