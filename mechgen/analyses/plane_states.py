"""Steady states of plane continua (mechgen.runtime.plane.system.PlaneSystem) and their outputs at points.

``steady`` on a plane model solves r(q) = 0 by Newton with the assembled sparse tangent (one step for a
linear model), from q = 0; its ``tol`` is relative to |r(0)|, the norm of the load (a plane model's
residual carries the units of its forces, N per unit thickness, and a steel plate's are ~1e11 times a
rubber sheet's). Outputs: ``iterations``, ``residual_norm``, ``residual_history`` (|r| at every Newton iterate
from q = 0: quadratic convergence shows as e_k+1 ~ C e_k^2), the domain integrals of the model's output
densities and energies (``strain_energy``, ``potential_energy`` ...), ``reactions`` ({boundary: {field:
force}}: the force each held boundary exerts on the body, N per unit thickness), and at points:
``points = {center = [0, 0]}`` gives ``center_displacement`` (the fields' values there, [u_x, u_y]) and,
for a model with gradients, ``center_stress`` ([[s_xx, s_xy], [s_yx, s_yy]], dV/d(grad u): the first
Piola stress, Cauchy's for a linear law); ``probe = [[x, y], ...]`` gives ``probe_displacement`` (one
entry per point).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import schema
from mechgen.errors import ConvergenceError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.steady.newton import newton, symmetric_ordered_solve
from mechgen.scene.expr import is_identifier
from mechgen.scene.values import IDENTIFIER_RULE, fail, type_name


def point(ctx, key: str, value: object) -> list[float]:
    """[x, y]: two numbers or expressions of the parameters (the domain's length unit)."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a point [x, y]")
    return [schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value)]


def named_points(ctx, key: str, value: object) -> dict[str, list[float]]:
    """{name: [x, y]}: the points whose values are reported as ``<name>_displacement`` and ``<name>_stress``."""
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table name = [x, y]")
    for name in value:
        if not is_identifier(name):
            raise fail(ctx.file, f"{key}.{name}", f"point name {name!r} is not an identifier", IDENTIFIER_RULE)
    return {name: point(ctx, f"{key}.{name}", v) for name, v in value.items()}


def probe(ctx, key: str, value: object) -> list[list[float]]:
    """[[x, y], ...]: the points of ``probe_displacement``."""
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a list of points [[x, y], ...]")
    return [point(ctx, f"{key}[{i}]", v) for i, v in enumerate(value)]


OPTIONS = {
    "nodal": schema.Option(schema.boolean, doc="a plane model's fields at every node: nodes (x, y), displacement, "
                           "strain and stress per field (true or false; the JSON grows with the mesh)"),
    "points": schema.Option(named_points, doc="a plane model's named points, name = [x, y] (m): reported as "
                            "<name>_displacement and <name>_stress"),
    "probe": schema.Option(probe, doc="a plane model's points [[x, y], ...] (m): reported as probe_displacement"),
}


def _listed(a) -> list:
    """An array as nested lists of floats (JSON-ready)."""
    return np.asarray(a, float).tolist()


def point_outputs(system, q: np.ndarray, options: dict) -> dict:
    """``<name>_displacement``, ``<name>_stress`` at the named points and ``probe_displacement``."""
    out = {}
    named = options.get("points") or {}
    if named:
        xy = np.array(list(named.values()), float)
        values, _ = system.field_at(q, xy)
        has_gradient = any(k for _, k in system.info["jets"])
        stress = system.stress_at(q, xy) if has_gradient else None
        for i, name in enumerate(named):
            out[f"{name}_displacement"] = _listed(values[i])
            if stress is not None:
                out[f"{name}_stress"] = _listed(stress[i])
    if options.get("nodal"):
        out.update(nodal_outputs(system, q))
    if options.get("probe"):
        out["probe_displacement"] = _listed(system.field_at(q, np.array(options["probe"], float))[0])
    return out


def solve(system, options: dict):
    """Newton on r(q) = 0 from q = 0, tol relative to max(1, |r(0)|); a ConvergenceError names the likely cause
    of a nonlinear law (a load past a limit point under load control) and the way out."""
    q0 = np.zeros(system.n)
    scale = max(1.0, float(np.linalg.norm(system.residual(q0))))
    try:
        return newton(system.residual, lambda q: system.tangent(q)["r_q"], q0,
                      tol=options.get("tol", 1e-10) * scale, max_iter=options.get("max_iter", 50),
                      budget=Budget("steady Newton iterations",
                                    seconds=float(options.get("max_seconds", DEFAULT_SECONDS))),
                      solve=symmetric_ordered_solve)
    except ConvergenceError as exc:
        raise ConvergenceError(f"steady state of plane model {system.meta.get('model')}: {exc}. Under load control "
                               "there may be no equilibrium at this load (past a limit point of the law, or a load "
                               "too large for one Newton solve from the reference state): follow the load with "
                               "a continuation from a smaller one, which passes limit points and reports them as "
                               "folds") from None


def nodal_outputs(system, q) -> dict:
    """``nodal``: the state at every node of the mesh, {``x``, ``y`` (n,), ``displacement`` {field: (n,)},
    ``gradient`` {field: (n, 2)} (d/dx, d/dy; each cell's at its nodes, averaged), ``stress`` {field: (n, 2)}
    (dV/d(grad u) at those nodal jets) and, for a displacement (ux, uy), ``strain`` {xx, yy, xy} (the symmetric
    part of the gradient)}."""
    data = system.nodal_fields(q)
    fields = system.info["fields"]
    nodal = {"x": _listed(data["x"]), "y": _listed(data["y"]),
             "displacement": {f: _listed(data["values"][:, c]) for c, f in enumerate(fields)},
             "gradient": {f: _listed(data["gradients"][:, c]) for c, f in enumerate(fields)}}
    if np.isfinite(data["stress"]).any():
        nodal["stress"] = {f: _listed(data["stress"][:, c]) for c, f in enumerate(fields)}
    if len(fields) == 2:
        H = data["gradients"]
        nodal["strain"] = {"xx": _listed(H[:, 0, 0]), "yy": _listed(H[:, 1, 1]),
                           "xy": _listed((H[:, 0, 1] + H[:, 1, 0]) / 2)}
    return {"nodal": nodal}


def plane_steady(system, options: dict) -> dict:
    """Newton on r(q) = 0 from q = 0 with the sparse tangent; outputs as the module doc says."""
    res = solve(system, options)
    q = res.x
    out = {"iterations": int(res.iterations), "residual_norm": float(res.residual_norm),
           "residual_history": [float(h) for h in res.history]}
    out.update(system.outputs(q))
    out["reactions"] = system.reactions(q)
    out.update(point_outputs(system, q, options))
    out["_q"], out["_z"] = q, np.zeros(0)
    out["_figure"] = {**system.figure_data(q), "stress": system.cell_stress(q)}
    return out
