"""mechgen: energies and kinematics in, derived matrices and fast kernels out."""
from __future__ import annotations

__version__ = "0.1.0"


def run(scene, **kwargs):
    """Run a scene (path or dict) and return its results dict (see DESIGN.md)."""
    from mechgen.scene.run import run_scene

    return run_scene(scene, **kwargs)
