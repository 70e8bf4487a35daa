"""Steady states of continua as boundary value problems, and branches of them (the scene's face).

``steady`` of a continuum whose boundary conditions carry values (a string
between two eyelets) solves the steady equations in s (mechgen.runtime.steady_bvp)
by shooting, multiple shooting or collocation and reports every model output
at the ends and its extremes along s (``tension_start``, ``radius_max`` ...), the
fields' slopes at the ends (``x_s_start`` ...),
the shape (``s``, ``deflection``) and ``iterations`` / ``residual_norm``.
``continuation`` follows such a steady state in one parameter by pseudo-arclength
(mechgen.runtime.continuation), through turning points, with the stability verdict
of the Galerkin linearisation about every point; it reports ``branch`` (one entry
per point: the parameter, the outputs, ``verdict``), ``folds`` and, with
``minimize``, the least value of an output along the branch (``<output>_min`` and
``<parameter>_at_<output>_min``). ``aliases`` report outputs under the scene's names.
"""
from __future__ import annotations

import numpy as np

from mechgen import models
from mechgen.errors import ConvergenceError

from mechgen.runtime.continuation import continue_bvp, minimize_along_branch
from mechgen.runtime.stability import stability as solve_stability
from mechgen.runtime.steady_bvp import hamiltonian_bvp, holding, solve_steady, steady_bvp

SAMPLES = 201


def _summary(bvp, result, aliases: dict) -> dict:
    """Outputs at the ends and their extremes along s (sampled at SAMPLES points), aliased."""
    s = np.linspace(0.0, bvp.length_of(result), SAMPLES)
    out = {}
    for name, values in bvp.outputs(result, s).items():
        if name in ("potential_density", "hamiltonian"):
            continue
        out.update({f"{name}_start": float(values[0]), f"{name}_end": float(values[-1]),
                    f"{name}_max": float(values.max()), f"{name}_min": float(values.min())})
    ends = bvp.values(result, np.array([s[0], s[-1]]))
    for i, f in enumerate(bvp.fields):
        out[f"{f}_s_start"], out[f"{f}_s_end"] = float(ends[bvp.n + i, 0]), float(ends[bvp.n + i, 1])
    for alias, target in aliases.items():
        if target in out:
            out[alias] = out[target]
    return out


def linear_about_steady(system, steady: dict) -> dict:
    """M, D, G, K of the model's discretisation about a boundary-value steady state (its jets at the points)."""
    bvp, result = steady["_bvp"], steady["_result"]
    disc = system.disc
    return system.linear(jets=bvp.jets(result, disc.points, disc.jets))


def _stability_about(system, bvp, result) -> dict:
    """Verdict, lowest ten frequencies and the eigenvalues of the Galerkin linearisation about a steady state."""
    saved = np.array(system.params, float)
    try:
        system.params[...] = result.p
        mats = linear_about_steady(system, {"_bvp": bvp, "_result": result})
    finally:
        system.params[...] = saved
    dense = {k: v.toarray() if hasattr(v, "toarray") else np.asarray(v) for k, v in mats.items()}
    verdict = solve_stability(dense["M"], dense["D"] + dense["G"], dense["K"])
    return {"verdict": verdict.verdict, "frequencies": [float(f) for f in verdict.frequencies[:10]],
            "eigenvalues": [[float(e.real), float(e.imag)] for e in verdict.eigenvalues]}


def run_steady_bvp(system, options: dict, context: dict) -> dict:
    """A steady state of a continuum with boundary values, by the BVP method the scene names."""
    bvp = hamiltonian_bvp(system) if options.get("form") == "hamiltonian" else steady_bvp(system)
    aliases = options.get("aliases", {})
    if options.get("hold"):
        (name, value), = options["hold"].items()
        output, at = aliases.get(name, name).rsplit("_", 1)
        bvp = holding(bvp, output, at, float(value), options["free"])
    method = "collocation" if options.get("method", "newton") == "newton" else options["method"]
    result = solve_steady(bvp, method=method, modes=options.get("bulge"), mesh=options.get("mesh", 200),
                          nodes=options.get("nodes", 20), tol=options.get("tol", 1e-10))
    out = {"method": method, "iterations": int(result.iterations), "residual_norm": float(result.residual_norm)}
    if options.get("hold"):
        free = options["free"]
        solved = float(result.p[bvp.params.index(free)])
        below = models.get(system.meta["model"]).param(free).below
        if below is not None and not solved < below:
            raise ConvergenceError(f"steady state with {next(iter(options['hold']))} held: the solved {free} = "
                                   f"{solved:.6g} is not below {below:g} (no such state near the start; try "
                                   f"another start value of {free} or another bulge)")
        out[free] = solved
    out.update(_summary(bvp, result, aliases))
    if options.get("stability"):
        out.update(_stability_about(system, bvp, result))
    s = np.linspace(0.0, bvp.length_of(result), 101)
    y = bvp.values(result, s)
    out["s"] = [float(v) for v in s]
    out["deflection"] = {f: [float(v) for v in y[i]] for i, f in enumerate(bvp.fields)}
    out["_bvp"], out["_result"] = bvp, result
    return out


def run_continuation(system, options: dict, context: dict) -> dict:
    """The branch of steady states through the ``about`` one as ``parameter`` goes to ``stop``."""
    start = context[options["about"]]
    bvp, result = start["_bvp"], start["_result"]
    name = options["parameter"]
    index = bvp.params.index(name)
    here, stop = float(result.p[index]), float(options["stop"])
    direction = 1 if stop >= here else -1
    bound = {"lam_max": stop} if direction > 0 else {"lam_min": stop}
    branch = continue_bvp(bvp.problem, result, index, mesh=options.get("mesh", 100), ds=options.get("step", 0.05),
                          ds_max=max(1.0, abs(stop - here) / 20),
                          max_points=options.get("max_points", 200), direction=direction, **bound)
    aliases = options.get("aliases", {})
    saved = np.array(system.params, float)
    points = []
    try:
        for u, lam in zip(branch.u, branch.lam):
            res = branch.system.to_result(u, lam)
            point = {name: float(lam), **{bvp.params[i]: float(res.p[i]) for i in bvp.problem.unknown},
                     **_summary(bvp, res, aliases)}
            if options.get("stability", True):
                system.params[...] = res.p
                mats = linear_about_steady(system, {"_bvp": bvp, "_result": res})
                dense = {k: v.toarray() if hasattr(v, "toarray") else np.asarray(v) for k, v in mats.items()}
                verdict = solve_stability(dense["M"], dense["D"] + dense["G"], dense["K"])
                point["verdict"] = verdict.verdict
                point["frequencies"] = [float(f) for f in verdict.frequencies[:10]]
            points.append(point)
    finally:
        system.params[...] = saved
    out = {"branch": points, "status": branch.status, "points": len(points),
           "folds": [{name: float(f.lam), **_summary(bvp, branch.system.to_result(f.u, f.lam), aliases)}
                     for f in branch.folds]}
    target = options.get("minimize")
    if target:
        def value(u, lam):
            return _summary(bvp, branch.system.to_result(u, lam), aliases)[target]

        best = minimize_along_branch(branch, value, kind="min")
        out[f"{target}_min"] = float(best.value)
        out[f"{name}_at_{target}_min"] = float(best.lam)
    return out
