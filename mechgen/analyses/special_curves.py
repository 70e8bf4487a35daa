"""``continuation`` about an earlier continuation: the curve of one of its folds (LP) or Hopf points (H) in two
parameters.

``about`` names the earlier continuation (of a Newton steady state), ``special_point`` the point (its position in
that continuation's ``special_points``, from 1: an LP or an H), ``parameter`` the second parameter b and ``stop``
its end value (with ``parameter`` the earlier continuation's own and an H point: the branch of limit cycles born
there, mechgen.analyses.hopf_cycles); the first parameter a (the earlier continuation's) becomes an unknown. The curve is the branch of
the extended system of mechgen.runtime.steady.codim2 in b (pseudo-arclength, so a curve that turns in b is
followed round), reported as ``curve``: one entry per point with both parameters, ``coordinates`` (lumped), the
model's outputs and for an H curve ``frequency`` (omega of the pair +-i omega); with ``type`` (LP or H),
``parameters`` ([a, b]) and ``status``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.newton_branch import arclength_steps
from mechgen.analyses.parametrised import Parametrised
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.steady import codim2
from mechgen.runtime.steady.continuation import continuation

#: keys of a continuation that a curve of special points does not take
CURVE_REFUSES = ("method", "stages", "bounds", "at", "minimize", "switch_branches", "eigenvalues")


def refuse_keys(options: dict) -> None:
    for key in CURVE_REFUSES:
        if options.get(key):
            raise SceneError(f"{key} does not apply to the curve of a special point", key=key,
                             expected=f"no {key} (a continuation about a steady state takes it)")


def start_of(earlier: dict, index: int) -> tuple[str, np.ndarray, str]:
    """(type, x = (y, a), a's name) of special point ``index`` (from 1) of an earlier continuation's outputs."""
    specials = earlier.get("special_points") or []
    xs = earlier.get("_special_x") or []
    if not 1 <= index <= len(specials):
        raise SceneError(f"special_point = {index}: the continuation has {len(specials)} special points",
                         key="special_point", expected=f"a position from 1 to {len(specials)} in its special_points"
                         if specials else "a continuation that reports special points (an LP or an H)")
    kind = specials[index - 1]["type"]
    if kind not in ("LP", "H"):
        raise SceneError(f"special point {index} is a {kind}; curves follow folds (LP) and Hopf points (H)",
                         key="special_point", expected="the position of an LP or an H in special_points")
    return kind, np.asarray(xs[index - 1], float), earlier["parameter"]


def run_curve(system, options: dict, earlier: dict) -> dict:
    """The curve of a special point in two parameters (module doc)."""
    refuse_keys(options)
    if earlier.get("_backbone"):
        raise SceneError("the earlier continuation followed a conservative family (a backbone); curves of its "
                         "special points are not available", key="about",
                         expected="a continuation about a steady state or a forced or autonomous periodic orbit")
    if "_orbit" in earlier:  # a branch of periodic orbits: the curve of its cyclic fold
        from mechgen.analyses.orbit_curves import run_orbit_curve

        return run_orbit_curve(system, options, earlier)
    if "_special_x" not in earlier:
        raise SceneError("the earlier continuation followed a boundary-value branch; special-point curves follow "
                         "Newton steady states' branches", key="about",
                         expected="a continuation about a Newton steady state")
    kind, x, first = start_of(earlier, int(options["special_point"]))
    second = options["parameter"]
    if second == first and kind == "H":  # the limit cycles born at the Hopf point (mechgen.analyses.hopf_cycles)
        from mechgen.analyses.hopf_cycles import run_hopf_cycles

        return run_hopf_cycles(system, options, earlier, x, earlier["special_points"][int(options["special_point"]) - 1])
    if second == first:
        raise SceneError(f"parameter {second!r} is the earlier continuation's own", key="parameter",
                         expected=f"a second parameter, other than {first!r}")
    model = Parametrised(system, first, second)
    b0 = float(system.param_values()[second])
    y0, a0 = x[:-1], float(x[-1])
    if kind == "LP":
        G, u0 = codim2.fold_system(model.residual, model.jacobian, y0, a0, b0)
    else:
        G, u0 = codim2.hopf_system(model.residual, model.state_jacobian, y0, a0, b0)
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    steps = arclength_steps(options, b0, budget)
    branch = continuation(codim2.equations(G, f"the {kind} curve in ({first}, {second})"), u0, b0, steps)
    curve = [point(system, first, second, u, b, kind) for u, b in zip(branch.u, branch.lam)]
    return {"type": kind, "parameters": [first, second], "curve": curve, "points": len(curve),
            "status": branch.status, "parameter": second}


def point(system, first: str, second: str, u: np.ndarray, b: float, kind: str) -> dict:
    """One point of the curve: both parameters, coordinates, outputs, and omega on an H curve."""
    n_y = system.n + system.m
    y, a = u[:n_y], float(u[n_y])
    moved = system.with_params(**{first: a, second: float(b)})
    out = {first: a, second: float(b)}
    if not system.is_field and not system.is_lattice:
        out["coordinates"] = {c: float(v) for c, v in zip(system.coordinates, y[:system.n])}
    out.update(moved.outputs(y[:system.n], None, y[system.n:] if system.m else None))
    if kind == "H":
        out["frequency"] = abs(float(u[n_y + 1]))
    return out
