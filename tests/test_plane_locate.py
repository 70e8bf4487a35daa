"""Points in plane meshes (mechgen.runtime.plane.locate): the cell and reference coordinates of a point, a nodal
field there, and points outside refused."""
import numpy as np
import pytest

from mechgen.errors import InputError
from mechgen.runtime.plane import mesh as M
from mechgen.runtime.plane.elements import ELEMENTS, shapes
from mechgen.runtime.plane.locate import interpolate, locate

G = np.array([[0.3, -1.2], [0.7, 0.25]])
ROUND_OFF = 1e-11  # Newton stops at 1e-14 of a cell's size; gradients carry 1/h


@pytest.mark.parametrize("element", ELEMENTS)
def test_located_points_map_back_and_linear_fields_interpolate_exactly(element):
    mesh = M.plate_with_hole(2.0, 1.0, 0.4, 0.3, element)
    rng = np.random.default_rng(0)
    p = rng.uniform([-2, -1], [2, 1], (200, 2))
    p = p[np.hypot(*p.T) > 0.45]
    cells, xi = locate(mesh, p)
    N, _ = shapes(element, xi)
    back = np.einsum("ml,mli->mi", N, mesh.points[mesh.cells[cells]])
    np.testing.assert_allclose(back, p, atol=ROUND_OFF)
    u = np.array([0.1, -0.2]) + mesh.points @ G.T
    val, grad = interpolate(mesh, u, cells, xi)
    np.testing.assert_allclose(val, np.array([0.1, -0.2]) + p @ G.T, atol=ROUND_OFF)
    np.testing.assert_allclose(grad, np.broadcast_to(G, grad.shape), atol=ROUND_OFF)


def test_a_point_between_chord_and_arc_is_in_the_curved_cell_only():
    R, h = 1.0, 0.5
    angle = np.pi / 2 - np.pi / 16  # the middle of a boundary edge: 16 edges, a vertex at pi / 2
    p = 0.999 * np.array([[np.cos(angle), np.sin(angle)]])  # between the chord (apothem cos(pi / 16) = 0.981) and arc
    cells, xi = locate(M.disk(R, h, "P2", curved=True), p)
    assert cells[0] >= 0
    with pytest.raises(InputError, match="outside the mesh"):
        locate(M.disk(R, h, "P2", curved=False), p)


def test_centre_of_a_disk_and_vertices_are_found():
    mesh = M.disk(1.0, 0.2, "Q2")
    cells, xi = locate(mesh, np.vstack([[0.0, 0.0], mesh.points[:5]]))
    u = mesh.points ** 2
    val, _ = interpolate(mesh, u, cells, xi)
    np.testing.assert_allclose(val[1:], u[:5], atol=ROUND_OFF)


def test_points_outside_are_refused_with_their_key():
    mesh = M.annulus(0.5, 1.0, 0.2, "P1")
    with pytest.raises(InputError, match=r"point \(0, 0\) lies outside") as info:
        locate(mesh, [[0.8, 0.0], [0.0, 0.0]], file="s.toml", key="analysis[0].probe")
    assert info.value.key == "analysis[0].probe[1]" and info.value.file == "s.toml"


@pytest.mark.parametrize("element", ELEMENTS)
def test_node_gradients_of_fields_in_the_space_are_exact(element):
    from mechgen.runtime.plane.locate import node_gradients

    curved = M.disk(1.0, 0.3, element, curved=True)
    g = node_gradients(curved, np.array([0.1, -0.2]) + curved.points @ G.T)
    np.testing.assert_allclose(g, np.broadcast_to(G, g.shape), atol=ROUND_OFF)
    if element in ("P2", "Q2"):
        mesh = M.plate_with_hole(2.0, 1.0, 0.4, 0.4, element, curved=False)
        x, y = mesh.points.T
        g = node_gradients(mesh, np.column_stack([x * x - 2 * x * y, 3 * y * y + x * y]))
        exact = np.stack([np.column_stack([2 * x - 2 * y, -2 * x]), np.column_stack([y, 6 * y + x])], axis=1)
        np.testing.assert_allclose(g, exact, atol=ROUND_OFF)
