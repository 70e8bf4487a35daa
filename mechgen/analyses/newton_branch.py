"""``continuation`` about a Newton steady state: pseudo-arclength on the generated static residual.

F(y, p) = [r(q, 0, 0, z); g(q, 0, z)] = 0 (mechgen.analyses.steady.equilibrium_functions of the system at the
parameter value p), y = (q, z), is continued in the numeric ``parameter`` by
mechgen.runtime.steady.continuation (pseudo-arclength through folds, each fold located by Brent's method), from
the steady state's point corrected at the scene's value of the parameter. F_y is the generated tangent;
F_p = (F(y, p + h) - F(y, p - h)) / (2 h), h = 1e-6 max(1, |p|): its error, of order h^2 |F_ppp|, is in the
bordered system's last column only, which slows the corrector but never moves a point (each point solves
F = 0 to 1e-10). This serves lumped models and continua alike (the discretised residual at the scene's N), and
plane models (the assembled sparse tangent; their branch points carry, instead of ``coordinates``, the
``<name>_displacement`` / ``<name>_stress`` of the ``points`` and the ``probe_displacement`` of ``probe``:
mechgen.analyses.plane_states.point_outputs).

Every point of ``branch`` reports the parameter, a lumped model's ``coordinates``, the model's outputs and their
``aliases``, and with ``stability`` (default true) the ``verdict`` and ``frequencies`` of the linearisation there
(mechgen.analyses.stability_boundary.spectrum; ``eigenvalues`` too when asked). ``folds`` lists the turning
points ({parameter, coordinates, outputs}) and ``stability_changes`` the points where the verdict changes
({parameter, coordinates, outputs, from, to}, by bisection along the branch to 1e-9 of the segment,
mechgen.runtime.steady.branch_scan.switch). The keys of boundary-value branches (``method``, ``stages``,
``bounds``, ``at``, ``minimize``, ``direction = "both"``) are refused here (exit 2 at the key).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import plane_states, special_points
from mechgen.analyses.stability_boundary import own_value, spectrum
from mechgen.analyses.steady import equilibrium_functions, newton_aliases
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import Budget
from mechgen.runtime.core.memory import require_dense
from mechgen.runtime.steady import branch_scan
from mechgen.runtime.steady.continuation import ContinuationOptions, ParametricEquations, continuation

#: keys of a continuation that only a boundary-value branch uses
BVP_KEYS = ("method", "stages", "bounds", "at", "minimize")


def refuse_bvp_keys(options: dict) -> None:
    """SceneError (exit 2) at a key that only a boundary-value branch uses."""
    for key in BVP_KEYS:
        if key in options:
            raise SceneError(f"{key} applies to the branches of boundary-value steady states; this continuation "
                             "starts from a Newton steady state", key=key,
                             expected=f"no {key} (or a steady analysis with method = \"collocation\", "
                                      "\"shooting\" or \"multiple_shooting\" as the start)")
    if options.get("direction") == "both":
        raise SceneError("direction = \"both\" follows boundary-value branches only", key="direction",
                         expected="\"increasing\" or \"decreasing\" (or two continuations)")


def equations(system, name: str) -> ParametricEquations:
    """F(y, p), F_y(y, p) and the central-difference F_p of the static residual (module doc)."""
    memo: dict = {}

    def functions(p: float):
        if p not in memo:
            if len(memo) > 8:
                memo.clear()
            memo[p] = equilibrium_functions(system.with_params(**{name: p}))
        return memo[p]

    def F_p(y, p):
        h = 1e-6 * max(1.0, abs(p))
        return (functions(p + h)[0](y) - functions(p - h)[0](y)) / (2.0 * h)

    return ParametricEquations(lambda y, p: functions(p)[0](y), lambda y, p: functions(p)[1](y), F_p,
                               name=f"the static residual in {name}")


def point(system, name: str, y: np.ndarray, p: float, options: dict) -> dict:
    """One branch point: the parameter, the coordinates (lumped), outputs, aliases, verdict and frequencies."""
    moved = system.with_params(**{name: float(p)})
    n = system.n
    out: dict = {name: float(p)}
    plane = getattr(system, "is_plane", False)
    if not system.is_field and not system.is_lattice and not plane:
        out["coordinates"] = {c: float(v) for c, v in zip(system.coordinates, y[:n])}
    out.update(moved.outputs(y[:n], None, y[n:] if system.m else None))
    if plane:
        out.update(plane_states.point_outputs(moved, y[:n], options))
    out.update(newton_aliases(out, options.get("aliases", {})))
    if options.get("stability", True):
        require_dense(2 * n, 40, "the stability verdict at every branch point", key="stability",
                      expected="stability = false for a system this large (or a smaller N)")
        res = spectrum(moved, y)
        out["verdict"], out["frequencies"] = res.verdict, [float(f) for f in res.frequencies]
        if options.get("eigenvalues"):
            out["eigenvalues"] = [[float(s.real), float(s.imag)] for s in res.eigenvalues]
    return out


def arclength_steps(options: dict, here: float, budget: Budget, *,
                    smallest_span: float = 1.0) -> ContinuationOptions:
    """The step control of a continuation from the parameter value ``here``: towards ``stop`` (or the given
    ``direction``), bounded by it; the first step ``step`` (default 0.05; at most ``max_step``) and the largest
    ``max_step`` (default max(smallest_span, |stop - here| / 20))."""
    stop = float(options["stop"])
    rising = options.get("direction", "increasing" if stop >= here else "decreasing") == "increasing"
    bound = {"lam_max": stop} if stop >= here else {"lam_min": stop}
    largest = options.get("max_step", max(smallest_span, abs(stop - here) / 20))
    return ContinuationOptions(ds=min(options.get("step", 0.05), largest), ds_max=largest,
                               direction=1 if rising else -1, max_points=options.get("max_points", 200), **bound,
                               budget=budget, progress=options.get("progress", True))


def newton_branch(system, start: dict, options: dict, budget: Budget) -> dict:
    """The branch through a Newton steady state: points, folds, stability changes and status (module doc)."""
    refuse_bvp_keys(options)
    name = options["parameter"]
    here = float(own_value(system, name))
    eqs = equations(system, name)
    y0 = np.concatenate([np.asarray(start["_q"], float), np.asarray(start["_z"], float).ravel()])
    branch = continuation(eqs, y0, here, arclength_steps(options, here, budget))
    points = [point(system, name, u, lam, options) for u, lam in zip(branch.u, branch.lam)]
    quiet = {**options, "stability": False}
    out = {"points": points, "status": branch.status,
           "folds": [point(system, name, f.u, f.lam, quiet) for f in branch.folds], "stability_changes": []}
    X = np.hstack([branch.u, branch.lam[:, None]])
    n = X.shape[1] - 1
    if options.get("special_points", True):
        out.update(special(system, eqs, X, branch, options, arclength_steps(options, here, budget)))
    if options.get("stability", True):

        def verdict(x):
            return spectrum(system.with_params(**{name: float(x[n])}), x[:n]).verdict

        for i in range(len(points) - 1):
            a, b = points[i]["verdict"], points[i + 1]["verdict"]
            if a != b:
                x = branch_scan.switch(eqs, X[i], X[i + 1], verdict, a)
                out["stability_changes"].append({**point(system, name, x[:n], x[n], quiet), "from": a, "to": b})
    return out


def special(system, eqs, X: np.ndarray, branch, options: dict, steps: ContinuationOptions) -> dict:
    """``special_points`` (LP, BP and, with ``stability``, H) and with ``switch_branches`` the ``switched_branches``
    (mechgen.analyses.special_points)."""
    name = options["parameter"]
    require_dense(X.shape[1], 8, "the branch-point test function (a dense determinant at every branch point)",
                  key="special_points", expected="special_points = false for a system this large")
    quiet = {**options, "stability": False}

    def at(y, p):
        return point(system, name, y, p, quiet)

    found = special_points.located(system, eqs, X, branch, name, hopf=options.get("stability", True))
    out = {"special_points": [special_points.record(system, name, s, at) for s in found],
           "_special_x": [s.x.copy() for s in found]}   # (y, p) of each: a curve of special points starts there
    if options.get("switch_branches"):
        full = {**options, "stability": options.get("stability", True)}
        out["switched_branches"] = special_points.switched(
            eqs, found, steps, lambda y, p: point(system, name, y, p, full))
    return out
