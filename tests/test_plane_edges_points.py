"""Edges and points of plane meshes (mechgen.runtime.plane.edges, .points) on the generated meshes: the divergence
theorem on every boundary, the curved disk's perimeter rate, a traction's force and moment, located points mapped
back, fields there and at nodes, points between chord and arc, points outside refused."""
import numpy as np
import pytest

from mechgen.errors import InputError
from mechgen.runtime.plane import elements as E
from mechgen.runtime.plane import mesh as M
from mechgen.runtime.plane.edges import edge_tables
from mechgen.runtime.plane.points import locate, point_shapes

G = np.array([[0.3, -1.2], [0.7, 0.25]])
ROUND_OFF = 1e-11  # relative sums of O(100) unit terms; Newton stops at 1e-13 of a cell's size; gradients carry 1/h


def edges_of(mesh, name, degree):
    et = edge_tables(mesh.points, mesh.cells, mesh.boundaries[name], degree)
    return et.weights, et.position[..., :2], et.position[..., 2:]


# -- edges ------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("element", E.ELEMENTS)
def test_divergence_theorem_on_every_generated_boundary(element):
    """oint x.n ds = int div x dA = 2 |Omega| and oint n ds = 0: the edge tables (curved edges included) against
    the cell tables of the same isoparametric geometry; both integrands are polynomials of the reference
    coordinate on these maps, so the equality holds to round-off."""
    for mesh in (M.disk(1.0, 0.3, element), M.plate_with_hole(2.0, 1.0, 0.4, 0.35, element),
                 M.slit_plate(1.0, 1.0, 0.4, 0.25, element)):
        flux, net = 0.0, np.zeros(2)
        for name in mesh.boundaries:
            w, x, n = edges_of(mesh, name, 6)
            flux += np.sum(w * np.sum(x * n, axis=-1))
            net += np.einsum("fq,fqi->i", w, n)
        assert flux == pytest.approx(2 * E.tables(mesh, 8).w.sum(), rel=ROUND_OFF)
        np.testing.assert_allclose(net, 0.0, atol=ROUND_OFF)


@pytest.mark.parametrize("element", ["P2", "Q2"])
def test_disk_perimeter_converges_at_four_when_curved(element):
    """Parabolic arcs through three points of each circular arc: perimeter error O(n^-4) (measured 4.0)."""
    err = []
    for quarters in (8, 16, 32):
        mesh = M.disk(1.0, np.pi / 2 / (quarters - 0.5), element, curved=True)
        err.append(abs(edges_of(mesh, "outer", 8)[0].sum() - 2 * np.pi))
    rates = np.log2(np.array(err[:-1]) / err[1:])
    assert np.all(rates > 3.9), rates


@pytest.mark.parametrize("element", E.ELEMENTS)
def test_edge_load_of_a_linear_traction(element):
    """t = (0, 1 + x) on the top of [0, 2] x [0, 1]: total force int t dx = (0, 4) and moment int x t_y dx = 14/3
    (closed forms), scattered to the edge nodes with the edge's shape values."""
    mesh = M.rectangle(0.0, 2.0, 0.0, 1.0, 0.3, element)
    et = edge_tables(mesh.points, mesh.cells, mesh.boundaries["top"], 4)
    ty = 1 + et.position[..., 0]
    load = np.einsum("fq,qk->fk", et.weights * ty, et.values)
    f = np.bincount(et.nodes.ravel(), weights=load.ravel(), minlength=mesh.n_nodes)
    assert f.sum() == pytest.approx(4.0, rel=ROUND_OFF)
    assert np.sum(mesh.points[:, 0] * f) == pytest.approx(14 / 3, rel=ROUND_OFF)


# -- points -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("element", E.ELEMENTS)
def test_located_points_map_back_and_linear_fields_interpolate_exactly(element):
    mesh = M.plate_with_hole(2.0, 1.0, 0.4, 0.5, element)
    rng = np.random.default_rng(0)
    p = rng.uniform([-2, -1], [2, 1], (40, 2))
    p = p[np.hypot(*p.T) > 0.45]
    cells, xi = locate(mesh, p)
    N, dN = point_shapes(mesh, cells, xi)
    np.testing.assert_allclose(np.einsum("ml,mli->mi", N, mesh.points[mesh.cells[cells]]), p, atol=ROUND_OFF)
    u = (np.array([0.1, -0.2]) + mesh.points @ G.T)[mesh.cells[cells]]  # (m, l, 2)
    np.testing.assert_allclose(np.einsum("ml,mlc->mc", N, u), np.array([0.1, -0.2]) + p @ G.T, atol=ROUND_OFF)
    np.testing.assert_allclose(np.einsum("mlc,mli->mci", u, dN), np.broadcast_to(G, (len(p), 2, 2)), atol=ROUND_OFF)


def test_a_point_between_chord_and_arc_is_in_the_curved_cell_only():
    angle = np.pi / 2 - np.pi / 16  # the middle of a boundary edge: 16 edges, a vertex at pi / 2
    p = 0.999 * np.array([[np.cos(angle), np.sin(angle)]])  # between the chord (apothem cos(pi / 16) = 0.981) and arc
    cells, _ = locate(M.disk(1.0, 0.5, "P2", curved=True), p)
    assert cells[0] >= 0
    with pytest.raises(InputError, match="not in the mesh"):
        locate(M.disk(1.0, 0.5, "P2", curved=False), p)


def test_points_outside_are_refused():
    with pytest.raises(InputError, match=r"point \(0, 0\) is not in the mesh"):
        locate(M.annulus(0.5, 1.0, 0.2, "P1"), [[0.8, 0.0], [0.0, 0.0]])


# -- gradients at nodes -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("element", E.ELEMENTS)
def test_node_gradients_of_fields_in_the_space_are_exact(element):
    curved = M.disk(1.0, 0.3, element, curved=True)
    g = E.node_gradients(curved, np.array([0.1, -0.2]) + curved.points @ G.T)
    np.testing.assert_allclose(g, np.broadcast_to(G, g.shape), atol=ROUND_OFF)
    if element in ("P2", "Q2"):
        mesh = M.plate_with_hole(2.0, 1.0, 0.4, 0.4, element, curved=False)
        x, y = mesh.points.T
        g = E.node_gradients(mesh, np.column_stack([x * x - 2 * x * y, 3 * y * y + x * y]))
        exact = np.stack([np.column_stack([2 * x - 2 * y, -2 * x]), np.column_stack([y, 6 * y + x])], axis=1)
        np.testing.assert_allclose(g, exact, atol=ROUND_OFF)
