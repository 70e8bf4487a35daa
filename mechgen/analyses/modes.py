"""``modes``: natural frequencies and mode shapes about an operating point.

Scene keys: ``about`` (an earlier steady analysis), ``at`` (coordinates of the operating point),
``count`` (the lowest this many modes). Outputs: ``frequencies`` (ascending, rad/s or the model's
unit); a continuum with ``count`` also ``s`` and ``shapes``. A system with damping, gyroscopic terms
or a non-symmetric stiffness, and any rotor, gets its damped modes (mechgen.analyses.whirl) with
``eigenvalues``, ``log_dec`` and (rotors) ``whirl``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import figures, summary
from mechgen.analyses.fields import field_shapes
from mechgen.analyses.operating_point import linear_about, operating_point
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import LINEAR_OPTIONS
from mechgen.analyses.whirl import is_gyroscopic, run_damped_modes
from mechgen.runtime.fields.constrain import warn_penalty_errors
from mechgen.runtime.linear.modes import modes as solve_modes

def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel."""
    return {"linear"}


def run_modes(system, options: dict, context: dict) -> dict:
    """Natural frequencies (rad/s or the model's unit) about the operating point.

    Solves K x = w^2 M x (symmetric); a system with damping, gyroscopic terms or a
    non-symmetric stiffness, and any rotor (a model with a whirl pair), gets its damped
    modes instead (mechgen.analyses.whirl): ``frequencies`` are then the damped natural
    frequencies, with ``eigenvalues``, ``log_dec`` and (rotors) ``whirl``.
    """
    q = operating_point(system, options, context)
    mats = linear_about(system, q, options, context)
    if is_gyroscopic(mats) or system.metadata.whirl:
        out = run_damped_modes(system, mats, options)
        if system.is_field and options.get("count"):
            out.update(field_shapes(system, np.real(out["_shapes"]), "shapes"))
        return out
    res = solve_modes(mats["M"], mats["K"], count=options.get("count"),
                      allow_singular_mass=getattr(system, "has_multipliers", False))
    if getattr(system, "penalty_choice", None) is not None:  # penalty constraints: a-posteriori error of each mode
        warn_penalty_errors(system.penalty_errors(res.shapes, res.eigenvalues))
    out = {"frequencies": [float(f) for f in res.frequencies], "_shapes": res.shapes}
    if system.is_field and options.get("count"):
        out.update(field_shapes(system, res.shapes, "shapes"))
    return out


register(AnalysisKind("modes", dict(LINEAR_OPTIONS), run_modes, needs, summary.lines, plot=figures.linear,
                      sweepable=True))
