"""A scene's ``mesh = "file.msh"`` for a plane model: the gmsh file replaces the generated mesh; bad files are
refused with exit-2 errors naming the file and the key."""
import os

import numpy as np
import pytest

from mechgen.errors import InputError, SceneError
from mechgen.runtime.plane.mesh import disk, rectangle
from mechgen.scene.run import run_scene

meshio = pytest.importorskip("meshio")
TYPES = {"P1": ("triangle", "line"), "P2": ("triangle6", "line3"), "Q1": ("quad", "line"), "Q2": ("quad9", "line3")}


def write_msh(path, mesh):
    """The mesh as a gmsh 2.2 file with a physical line per boundary and one physical surface."""
    cell, line = TYPES[mesh.element]
    names = sorted(mesh.boundaries)
    blocks = [(line, mesh.boundaries[n]) for n in names] + [(cell, mesh.cells)]
    tags = [np.full(len(mesh.boundaries[n]), i + 1) for i, n in enumerate(names)] + [np.full(len(mesh.cells), 10)]
    field = {n: np.array([i + 1, 1]) for i, n in enumerate(names)} | {"body": np.array([10, 2])}
    pts = np.column_stack([mesh.points, np.zeros(len(mesh.points))])
    meshio.write(str(path), meshio.Mesh(pts, blocks, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                                        field_data=field), file_format="gmsh22", binary=False)
    return path


SCENE = """model = "membrane_gravity"
{mesh}
[params]
h = 0.2
[[analysis]]
name = "static"
kind = "steady"
points = {{ center = [0.0, 0.0] }}
"""


def scene(tmp_path, mesh_line):
    path = tmp_path / "membrane.toml"
    path.write_text(SCENE.format(mesh=mesh_line))
    return str(path)


def test_a_mesh_file_gives_the_numbers_of_the_same_mesh_generated(tmp_path):
    """The file written from the generated P2 disk (h = 0.2) gives the generated run's numbers to round-off."""
    write_msh(tmp_path / "disk.msh", disk(1.0, 0.2, "P2", curved=True))
    from_file = run_scene(scene(tmp_path, 'mesh = "disk.msh"'))["analyses"][0]["outputs"]
    generated = run_scene(scene(tmp_path, ""))["analyses"][0]["outputs"]
    assert np.allclose(from_file["center_displacement"], generated["center_displacement"], rtol=1e-12, atol=1e-15)
    assert from_file["strain_energy"] == pytest.approx(generated["strain_energy"], rel=1e-12)


def test_bad_mesh_files_are_refused(tmp_path):
    with pytest.raises(SceneError, match="mesh file 'nowhere.msh' cannot be read") as err:
        run_scene(scene(tmp_path, 'mesh = "nowhere.msh"'))
    assert err.value.key == "mesh"
    (tmp_path / "folder.msh").mkdir()
    with pytest.raises(SceneError, match="mesh"):
        run_scene(scene(tmp_path, 'mesh = "folder.msh"'))
    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "pipe.msh")
        with pytest.raises(SceneError, match="FIFO|fifo|pipe"):
            run_scene(scene(tmp_path, 'mesh = "pipe.msh"'))
    (tmp_path / "text.msh").write_text("this is not a mesh\n")
    with pytest.raises(InputError, match="not a readable gmsh mesh") as err:
        run_scene(scene(tmp_path, 'mesh = "text.msh"'))
    assert "text.msh" in str(err.value)
    write_msh(tmp_path / "square.msh", rectangle(0, 1, 0, 1, 0.25, "P1"))
    with pytest.raises(InputError, match="outer"):
        run_scene(scene(tmp_path, 'mesh = "square.msh"'))
    fpu = tmp_path / "fpu.toml"
    fpu.write_text('model = "duffing"\nmesh = "square.msh"\n[[analysis]]\nname = "m"\nkind = "modes"\n')
    with pytest.raises(SceneError, match="not a plane continuum"):
        run_scene(str(fpu))


GEO = """// the unit disk: its rim is the physical curve "outer"
SetFactory("OpenCASCADE");
Disk(1) = {0, 0, 0, 1.0};
Physical Curve("outer") = {1};
Physical Surface("body") = {1};
"""


def test_a_geo_file_meshed_by_gmsh_gives_the_membranes_closed_form(tmp_path):
    """gmsh meshes the disk (second order: midside nodes on the circle) and the membrane on it has u_y(0) of
    Michell's solution, -rho_g R^2 / (2 (lambda* + 3 mu)), within 1e-6 at h = 0.1 (measured 2.3e-7; 3.7e-6 at
    h = 0.2, 1.4e-8 at h = 0.05: the h^4 of curved P2 edges on gmsh's unstructured mesh too)."""
    pytest.importorskip("gmsh")
    import mechgen
    from mechgen.analyses.plane_states import plane_steady
    from mechgen.runtime.plane.gmsh_geo import mesh_from_geo

    (tmp_path / "disk.geo").write_text(GEO)
    mesh = mesh_from_geo(tmp_path / "disk.geo", 0.1, "P2")
    assert mesh.element == "P2" and "outer" in mesh.boundaries
    system = mechgen.compile("membrane_gravity", kernels=("residual", "tangent", "outputs")).with_mesh(mesh)
    out = plane_steady(system, {"points": {"c": [0.0, 0.0]}})
    mu, lam = 1 / 2.6, 0.3 / (1 - 0.09)
    assert out["c_displacement"][1] == pytest.approx(-1 / (2 * (lam + 3 * mu)), rel=1e-6)
    with pytest.raises(InputError, match="does not exist"):
        mesh_from_geo(tmp_path / "none.geo", 0.1)


def test_a_scene_cannot_name_a_geo_file(tmp_path):
    (tmp_path / "disk.geo").write_text(GEO)
    with pytest.raises(SceneError, match="is a program"):
        run_scene(scene(tmp_path, 'mesh = "disk.geo"'))
