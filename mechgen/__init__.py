"""mechgen: energies and kinematics in, derived matrices and fast kernels out.

The public names (DESIGN.md, "the user's three jobs"), importable from ``mechgen`` itself:

* declaring a model: ``Model``, ``Param``, ``fix``;
* finding one: ``load_model(name_or_path)``;
* compiling it: ``compile(model, params=..., backend=...)`` -> an immutable compiled system
  (``with_params(**values)`` gives a new one);
* one function per analysis kind, each returning a ``Result``: ``modes``, ``stability``,
  ``steady``, ``continuation``, ``simulate``, ``sweep``, ``campbell``, ``fit``, ``impact``, ``restitution``,
  ``periodic``, ``periodic_orbit``, ``spectrum``, ``stability_boundary``, ``cross_section``, ``symplectic``, ``rod_statics``, ``rod_dynamics``,
  ``response``, ``phase_boundary``, ``phase_kinetics``, ``orr_sommerfeld``, ``shear_curve``, ``channel_flow``,
  ``channel_spectrum``; and ``analysis(kind, system, **options)`` for any registered kind by name;
* ``run(scene)``: a scene file (or a dict of its contents), built on the same functions;
* the errors: ``MechgenError`` and its kinds.

Names are loaded on first use, so ``import mechgen`` stays cheap (no sympy until a model is
declared or derived).
"""
from __future__ import annotations

import importlib

from mechgen.version import __version__

#: public name -> module that defines it
_EXPORTS = {
    "Model": "mechgen.symbolic.model",
    "Param": "mechgen.symbolic.params",
    "fix": "mechgen.symbolic.field",
    "load_model": "mechgen.models",
    "compile": "mechgen.api",
    "Result": "mechgen.analyses.result",
    "modes": "mechgen.analyses.public",
    "stability": "mechgen.analyses.public",
    "steady": "mechgen.analyses.public",
    "continuation": "mechgen.analyses.public",
    "simulate": "mechgen.analyses.public",
    "sweep": "mechgen.analyses.public",
    "campbell": "mechgen.analyses.public",
    "fit": "mechgen.analyses.public",
    "impact": "mechgen.analyses.public",
    "restitution": "mechgen.analyses.public",
    "periodic": "mechgen.analyses.public",
    "periodic_orbit": "mechgen.analyses.public",
    "spectrum": "mechgen.analyses.public",
    "response": "mechgen.analyses.public",
    "stability_boundary": "mechgen.analyses.public",
    "cross_section": "mechgen.analyses.public",
    "symplectic": "mechgen.analyses.public",
    "rod_statics": "mechgen.analyses.public",
    "rod_dynamics": "mechgen.analyses.public",
    "orr_sommerfeld": "mechgen.analyses.public",
    "shear_curve": "mechgen.analyses.public",
    "channel_flow": "mechgen.analyses.public",
    "channel_spectrum": "mechgen.analyses.public",
    "phase_boundary": "mechgen.analyses.public",
    "phase_kinetics": "mechgen.analyses.public",
    "analysis": "mechgen.analyses.public",
    "MechgenError": "mechgen.errors",
    "InputError": "mechgen.errors",
    "SceneError": "mechgen.errors",
    "ModelError": "mechgen.errors",
    "ConvergenceError": "mechgen.errors",
    "KernelError": "mechgen.errors",
}

__all__ = sorted([*_EXPORTS, "run"])


def run(scene, **kwargs):
    """Run a scene (a path to a TOML file, or a dict of its contents) and return its results dict (DESIGN.md)."""
    from mechgen.scene.run import run_scene

    return run_scene(scene, **kwargs)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'mechgen' has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
