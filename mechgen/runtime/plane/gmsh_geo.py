"""Meshes generated from a gmsh geometry (``.geo``) by the gmsh Python package (the ``gmsh`` extra).

A ``.geo`` file is a gmsh *program*: besides points, curves and physical groups it may run shell commands
(``SystemCall``), include other files and write files (``Save``, ``Print``). It is therefore read only through
the Python API (``mesh_from_geo``), where the caller's own code runs anyway, and never from a scene, which is
data (a scene names a ``.msh`` file, read by :func:`mechgen.runtime.plane.mesh.read_msh`).

The mesh is generated in a private temporary folder at the target edge length ``h`` (gmsh's
``Mesh.CharacteristicLengthMax``), of order 1 or 2 (P1/Q1 or P2/Q2, curved edges following the geometry), with
quadrilaterals when ``element`` is Q1/Q2 (``Mesh.RecombineAll``), written as gmsh 2.2 and read back by
``read_msh``: its physical lines are the boundaries a model's ``fix`` and edge terms name.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from mechgen.errors import InputError

ELEMENT_ORDER = {"P1": 1, "P2": 2, "Q1": 1, "Q2": 2}


def _gmsh():
    try:
        import gmsh
    except ImportError as exc:
        raise InputError(f"meshing a .geo file needs the gmsh package ({exc})", key="mesh",
                         expected="pip install 'mechgen[gmsh]'") from None
    return gmsh


def mesh_from_geo(path, h: float, element: str = "P2"):
    """The :class:`~mechgen.runtime.plane.mesh.PlaneMesh` gmsh generates from the geometry ``path`` at edge length
    ``h`` (the geometry's length unit) with ``element`` cells; InputError naming the file for a missing file, a
    bad element or h, or a geometry gmsh cannot mesh."""
    from mechgen.runtime.plane.mesh import read_msh

    path = Path(path)
    if element not in ELEMENT_ORDER:
        raise InputError(f"element {element!r} is not a plane element", key="element", expected="P1, P2, Q1 or Q2")
    if not (isinstance(h, (int, float)) and h > 0):
        raise InputError(f"h = {h!r} is not a positive edge length", key="h", expected="a number > 0")
    if not path.is_file():
        raise InputError("the geometry file does not exist or is not a regular file", file=str(path),
                         expected="a gmsh .geo file")
    gmsh = _gmsh()
    with tempfile.TemporaryDirectory(prefix="mechgen-gmsh-") as folder:
        out = os.path.join(folder, "mesh.msh")
        gmsh.initialize(readConfigFiles=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.open(str(path))
            gmsh.option.setNumber("Mesh.CharacteristicLengthMax", float(h))
            gmsh.option.setNumber("Mesh.ElementOrder", ELEMENT_ORDER[element])
            gmsh.option.setNumber("Mesh.RecombineAll", 1 if element.startswith("Q") else 0)
            gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
            gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
            gmsh.model.mesh.generate(2)
            gmsh.write(out)
        except Exception as exc:  # noqa: BLE001 - gmsh raises a bare Exception with its log's last line
            raise InputError(f"gmsh could not mesh the geometry ({str(exc)[:200]})", file=str(path),
                             expected="a 2D gmsh geometry with physical curves for the boundaries") from None
        finally:
            gmsh.finalize()
        return read_msh(out)
