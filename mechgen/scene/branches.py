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

Shape outputs. A model may declare numbers measured on a sampled steady state
(``Model.shape_output``: the balloon's ``loops``); ``steady`` reports them, and so
does every point of a branch, fold, crossing and stability change.

More keys of ``steady``:

* ``params = { lambda0 = 0.3 }``: this analysis's own values of numeric parameters
  (made free in the kernels), e.g. a start where a multi-loop balloon exists;
* ``shape = { loops = 2 }``: a start with this value of a shape output, from the
  starting guesses the model declares with it (each is solved by the analysis's
  method and form; the first whose measure equals the value is kept, else a
  ConvergenceError lists what the guesses gave).

More keys of ``continuation``:

* ``method = "collocation" | "gauss" | "multiple_shooting"`` (with ``mesh`` intervals or nodes;
  ``stages`` for Gauss-Legendre collocation, default 4: order 8), ``step`` and ``max_step`` (the
  first and largest arclength steps);

* ``about = ["double", "triple"]``: several starts (earlier steady analyses), one
  branch each (the disconnected loop families of a balloon); every point, fold,
  crossing and change then carries ``start``, and ``status`` is per start;
* ``direction = "increasing" | "decreasing" | "both"``: the parameter's direction at
  the start (default: towards ``stop``); "both" follows both half-branches
  (``max_points`` each) and joins them in branch order; ``stop`` bounds the side it
  lies on;
* ``bounds = { p_e = [0, 12] }``: the branch ends where an output leaves its range
  (the continuation then runs in chunks of 20 points);
* ``at = { p_e = 5.0 }``: the points where an output crosses the value, located by
  Brent's method along the branch (mechgen.runtime.branch_scan.crossing): output
  ``at_<output>``, a list of {parameter, the output, the aliased outputs, the shape
  outputs, ``verdict``, ``refinement``} sorted by the parameter (the verdict holds when
  the model discretised with 2N and 4N terms agrees, else it is 'unconverged'), and
  ``at_<output>_shapes`` (the fields at 101 points of each, for plots);
* ``eigenvalues = true``: each branch point also reports its ``eigenvalues``.

With stability, ``stability_changes`` lists where the verdict changes between
consecutive points, located by bisection along the branch to 1e-9 of the segment
(mechgen.runtime.branch_scan.switch): {parameter, aliased and shape outputs,
``from``, ``to``}. ``aliases`` may also name an analysis output:
``balloons_at_tension = "at_p_e"``.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from mechgen import models
from mechgen.errors import ConvergenceError, SceneError
from mechgen.runtime import branch_scan
from mechgen.runtime.branch_stability import stability_along
from mechgen.runtime.constrained import linear_about_bvp
from mechgen.runtime.continuation import minimize_along_branch
from mechgen.runtime.steady_bvp import hamiltonian_bvp, holding, solve_steady, steady_bvp, stress_guess
from mechgen.scene.info import model_info

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
    return linear_about_bvp(system, steady["_bvp"], steady["_result"])


def _reported(verdict) -> dict:
    """Verdict, lowest ten frequencies and eigenvalues of a StabilityResult, as the scene reports them."""
    return {"verdict": verdict.verdict, "frequencies": [float(f) for f in verdict.frequencies[:10]],
            "eigenvalues": [[float(e.real), float(e.imag)] for e in verdict.eigenvalues]}


def _stability_about(system, bvp, result) -> dict:
    """The Galerkin linearisation's stability about one steady state (mechgen.runtime.branch_stability)."""
    return _reported(stability_along(system, bvp, None, [result])[0])


# ----------------------------------------------------------------------------- shape outputs, starts
SHAPE_SAMPLES = 1001
START_TOL = 1e-6  # the tolerance at which ``shape`` starts are tried (then refined to the analysis's tol)


def _shape_declarations(system) -> tuple:
    """The model's shape outputs (Model.shape_output); the model is imported only when it declares some."""
    if not model_info(system.meta["model"]).shape_outputs:
        return ()
    return tuple(getattr(models.get(system.meta["model"]), "shape_outputs", ()))


def _parameter_dict(system, p) -> dict:
    """Numeric parameter values: the model's defaults, the scene's fixed ones, the free ones from p."""
    info = model_info(system.meta["model"])
    values = {name: float(prm.default) for name, prm in info.params.items() if prm.numeric}
    values.update({k: float(v) for k, v in getattr(system, "fixed", {}).items()})
    values.update(zip(system.meta.get("params", []), (float(v) for v in p)))
    return values


def _parameter_values(system, p):
    from mechgen.symbolic.params import Namespace  # declared model code needs the model's own types

    return Namespace(_parameter_dict(system, p))


def _shapes(system, bvp, result) -> dict:
    """Every shape output of the model on a steady state (sampled at SHAPE_SAMPLES points)."""
    declared = _shape_declarations(system)
    if not declared:
        return {}
    from mechgen.symbolic.model import call_declared
    from mechgen.symbolic.params import Namespace

    s = np.linspace(0.0, bvp.length_of(result), SHAPE_SAMPLES)
    y = bvp.values(result, s)
    u = Namespace({**{f: y[i] for i, f in enumerate(bvp.fields)},
                   **{f"{f}_s": y[bvp.n + i] for i, f in enumerate(bvp.fields)}})
    out = Namespace(bvp.outputs(result, s))
    p = _parameter_values(system, result.p)
    return {d.name: float(call_declared(d.fn, s=s, u=u, out=out, p=p)) for d in declared}


def _with_params(system, values: dict):
    """A copy of the system with some free parameters set (``steady``'s ``params``)."""
    names = list(system.meta.get("params", []))
    params = np.array(system.params, float)
    for name, value in values.items():
        if name not in names:
            raise SceneError(f"parameter {name!r} is not free in the compiled kernels", key=f"params.{name}",
                             expected="a parameter the scene leaves free: " + ", ".join(names))
        params[names.index(name)] = float(value)
    return replace(system, params=params, _cache={})


def _start_with_shape(system, bvp, options: dict, method: str):
    """A steady state whose shape output equals the requested value, from the model's starting guesses."""
    from mechgen.symbolic.model import call_declared

    (name, value), = options["shape"].items()
    declared = {d.name: d for d in _shape_declarations(system)}
    if name not in declared or declared[name].start is None:
        with_start = [n for n, d in declared.items() if d.start is not None]
        raise SceneError(f"model {system.meta['model']} declares no starting guesses for {name!r}",
                         key=f"shape.{name}", expected="one of: " + (", ".join(with_start) or "(none)"))
    mesh = options.get("mesh", 200)
    sigma = np.linspace(0.0, 1.0, mesh + 1)
    L = bvp.start[bvp.length_index] if bvp.length_index is not None else bvp.length
    p = _parameter_values(system, bvp.start)
    tol = options.get("tol", 1e-10)
    gave = []
    for guess in call_declared(declared[name].start, value=float(value), s=L * sigma, p=p):
        u = np.array([np.broadcast_to(np.asarray(guess["u"][f], float), sigma.shape) for f in bvp.fields])
        du = np.array([np.broadcast_to(np.asarray(guess["u_s"][f], float), sigma.shape) for f in bvp.fields])
        if bvp.form == "hamiltonian":
            Y = np.vstack([u, [guess["n"][f] for f in bvp.fields]]) if "n" in guess else \
                stress_guess(bvp, sigma, np.vstack([u, du]))
        else:
            Y = np.vstack([u, du])

        def interpolate(at, Y=Y):
            return np.array([np.interp(np.asarray(at, float), sigma, row) for row in Y])

        try:  # a loose tolerance first: failures are cheap, and the measure is decided by then
            result = solve_steady(bvp, method=method, guess=interpolate, mesh=mesh, nodes=options.get("nodes", 20),
                                  tol=max(tol, START_TOL))
        except ConvergenceError as exc:
            gave.append(f"no convergence ({str(exc).split(':')[0]})")
            continue
        got = _shapes(system, bvp, result)[name]
        if abs(got - float(value)) <= 1e-9 * max(1.0, abs(float(value))):
            if tol < START_TOL:
                result = solve_steady(bvp, method=method, guess=result, mesh=mesh, nodes=options.get("nodes", 20),
                                      tol=tol)
            return result
        gave.append(f"{name} = {got:g}")
    where = ", ".join(f"{k} = {v:g}" for k, v in _parameter_dict(system, bvp.start).items())
    raise ConvergenceError(f"steady: no state with {name} = {float(value):g} from the {len(gave)} starting guesses "
                           f"of model {system.meta['model']} by {method} ({bvp.form} form, {where}): they gave "
                           f"{'; '.join(gave)}. Try another start (params), method = 'collocation' with "
                           "form = 'hamiltonian', or another value")


def _refined_verdict(system, bvp, result) -> dict:
    """The verdict at the scene's N checked on the model discretised with 2N and 4N terms (DESIGN.md: stability
    of continua under refinement): ``verdict`` is the N verdict when 2N and 4N agree, else 'unconverged'
    (balloons of three or more loops at N = 10: the in-plane sines converge slowly there, notes section 6);
    ``refinement`` lists the three ({N, verdicts}) so that the trend shows."""
    size = int(system.choices["N"])
    sizes = [size, 2 * size, 4 * size]
    verdicts = [_stability_about(system if k == size else system.refined(k), bvp, result)["verdict"] for k in sizes]
    return {"verdict": verdicts[0] if len(set(verdicts)) == 1 else "unconverged",
            "refinement": {"N": sizes, "verdicts": verdicts}}


def run_steady_bvp(system, options: dict, context: dict) -> dict:
    """A steady state of a continuum with boundary values, by the BVP method the scene names."""
    if options.get("params"):
        system = _with_params(system, options["params"])
    bvp = hamiltonian_bvp(system) if options.get("form") == "hamiltonian" else steady_bvp(system)
    aliases = options.get("aliases", {})
    if options.get("hold"):
        (name, value), = options["hold"].items()
        output, at = aliases.get(name, name).rsplit("_", 1)
        bvp = holding(bvp, output, at, float(value), options["free"])
    method = "collocation" if options.get("method", "newton") == "newton" else options["method"]
    if options.get("shape"):
        result = _start_with_shape(system, bvp, options, method)
    else:
        result = solve_steady(bvp, method=method, modes=options.get("bulge"), mesh=options.get("mesh", 200),
                              nodes=options.get("nodes", 20), tol=options.get("tol", 1e-10))
    out = {"method": method, "iterations": int(result.iterations), "residual_norm": float(result.residual_norm)}
    if options.get("hold"):
        free = options["free"]
        solved = float(result.p[bvp.params.index(free)])
        below = model_info(system.meta["model"]).param(free).below
        if below is not None and not solved < below:
            raise ConvergenceError(f"steady state with {next(iter(options['hold']))} held: the solved {free} = "
                                   f"{solved:.6g} is not below {below:g} (no such state near the start; try "
                                   f"another start value of {free} or another bulge)")
        out[free] = solved
    out.update(_summary(bvp, result, aliases))
    out.update(_shapes(system, bvp, result))
    if options.get("stability"):
        out.update(_stability_about(system, bvp, result))
    s = np.linspace(0.0, bvp.length_of(result), 101)
    y = bvp.values(result, s)
    out["s"] = [float(v) for v in s]
    out["deflection"] = {f: [float(v) for v in y[i]] for i, f in enumerate(bvp.fields)}
    out["_bvp"], out["_result"] = bvp, result
    return out


def _stability_along(system, bvp, results) -> list[dict]:
    """The stability of every steady state in ``results`` (one Galerkin eigenproblem each); the one place to
    swap for a batched runtime call."""
    return [_reported(v) for v in stability_along(system, bvp, None, results)]


def _record(name: str, lam: float, summary: dict, shapes: dict, aliases: dict, extra=()) -> dict:
    """A located point: the parameter, the aliased outputs (and ``extra`` outputs), the shape outputs."""
    keys = list(aliases) + [k for k in extra if k not in aliases]
    return {name: float(lam), **{k: summary[k] for k in keys if k in summary}, **shapes}


def _values(system, bvp, result, aliases: dict, names=()) -> dict:
    """The summary of a steady state, with the shape outputs when ``names`` asks for one of them."""
    out = _summary(bvp, result, aliases)
    if any(n not in out for n in names):
        out.update(_shapes(system, bvp, result))
    return out


def _follow(system, bvp, result, options: dict, aliases: dict):
    """The branch from one start, with the options' direction, stop and bounds."""
    name = options["parameter"]
    index = bvp.params.index(name)
    here, stop = float(result.p[index]), float(options["stop"])
    towards = "increasing" if stop >= here else "decreasing"
    bound = {"lam_max": stop} if stop >= here else {"lam_min": stop}
    bounds = options.get("bounds") or {}

    def inside(u, lam, disc):
        values = _values(system, bvp, disc.to_result(u, lam), aliases, bounds)
        return all(lo <= values[k] <= hi for k, (lo, hi) in bounds.items())

    first = _values(system, bvp, result, aliases, bounds)
    for k, (lo, hi) in bounds.items():
        if not lo <= first[k] <= hi:
            raise SceneError(f"the start's {k} = {first[k]:.6g} lies outside the bounds [{lo:g}, {hi:g}]",
                             key=f"bounds.{k}", expected="bounds that hold the start")
    return branch_scan.follow(bvp.problem, result, index, direction=options.get("direction", towards),
                              inside=inside if bounds else None,
                              mesh=options.get("mesh", 100), method=options.get("method", "collocation"),
                              stages=options.get("stages"), ds=options.get("step", 0.05),
                              ds_max=options.get("max_step", max(1.0, abs(stop - here) / 20)),
                              max_points=options.get("max_points", 200),
                              **bound)


def _check_names(options: dict, known: dict) -> None:
    for key in ("at", "bounds"):
        for k in options.get(key) or {}:
            if k not in known:
                raise SceneError(f"no output {k!r} on the branch", key=f"{key}.{k}",
                                 expected="an output of the steady state or an alias: " + ", ".join(sorted(known)))


def _one_branch(system, start: dict, options: dict, label: str | None) -> dict:
    """Points, folds, crossings and stability changes of the branch through one start."""
    bvp, result = start["_bvp"], start["_result"]
    name, aliases = options["parameter"], options.get("aliases", {})
    stability = options.get("stability", True)
    _check_names(options, {**_summary(bvp, result, aliases), **_shapes(system, bvp, result)})
    branch = _follow(system, bvp, result, options, aliases)
    disc = branch.system
    tag = {"start": label} if label else {}
    results = [disc.to_result(u, lam) for u, lam in zip(branch.u, branch.lam)]
    summaries = [{**_summary(bvp, res, aliases), **_shapes(system, bvp, res)} for res in results]
    stab = _stability_along(system, bvp, results) if stability else [{}] * len(results)
    points = []
    for lam, res, summary, st in zip(branch.lam, results, summaries, stab):
        point = {**tag, name: float(lam), **{bvp.params[i]: float(res.p[i]) for i in bvp.problem.unknown},
                 **summary}
        if stability:
            point["verdict"], point["frequencies"] = st["verdict"], st["frequencies"]
            if options.get("eigenvalues"):
                point["eigenvalues"] = st["eigenvalues"]
        points.append(point)

    def located(x, extra=()):
        res = disc.to_result(x[:-1], x[-1])
        return res, {**tag, **_record(name, x[-1], _summary(bvp, res, aliases), _shapes(system, bvp, res), aliases,
                                      extra)}

    X = np.hstack([branch.u, branch.lam[:, None]])
    shaped = [d.name for d in _shape_declarations(system)]
    out = {"points": points, "status": branch.status,
           "folds": [{**tag, name: float(f.lam), **_values(system, bvp, disc.to_result(f.u, f.lam), aliases, shaped)}
                     for f in branch.folds], "stability_changes": [], "at": {}, "branch": branch}
    if stability:
        def verdict(x):
            return _stability_about(system, bvp, disc.to_result(x[:-1], x[-1]))["verdict"]

        for i in range(len(points) - 1):
            a, b = points[i]["verdict"], points[i + 1]["verdict"]
            if a != b:
                _, rec = located(branch_scan.switch(disc, X[i], X[i + 1], verdict, a))
                out["stability_changes"].append({**rec, "from": a, "to": b})
    for key, value in (options.get("at") or {}).items():
        found = []
        values = [s[key] - value for s in summaries]
        for i in range(len(points)):
            if values[i] == 0.0 or (i + 1 < len(points) and values[i] * values[i + 1] < 0):
                x = X[i] if values[i] == 0.0 else branch_scan.crossing(
                    disc, X[i], X[i + 1],
                    lambda x: _values(system, bvp, disc.to_result(x[:-1], x[-1]), aliases, (key,))[key] - value)
                res, rec = located(x, (key,))
                if stability:
                    rec.update(_refined_verdict(system, bvp, res))
                s = np.linspace(0.0, bvp.length_of(res), 101)
                y = bvp.values(res, s)
                found.append((rec, {f: [float(v) for v in y[j]] for j, f in enumerate(bvp.fields)}))
        out["at"][key] = found
    return out


def run_continuation(system, options: dict, context: dict) -> dict:
    """The branch of steady states through the ``about`` one (or one branch per start) as ``parameter`` goes to
    ``stop``; see the module doc for the keys and outputs."""
    about = options["about"]
    starts = about if isinstance(about, list) else [about]
    name, aliases = options["parameter"], options.get("aliases", {})
    saved = np.array(system.params, float)
    try:
        branches = [_one_branch(system, context[s], options, s if isinstance(about, list) else None) for s in starts]
    finally:
        system.params[...] = saved
    out = {"parameter": name, "shape_outputs": [d.name for d in _shape_declarations(system)],
           "branch": [p for b in branches for p in b["points"]],
           "status": branches[0]["status"] if len(branches) == 1 else
           {s: b["status"] for s, b in zip(starts, branches)},
           "points": sum(len(b["points"]) for b in branches),
           "folds": [f for b in branches for f in b["folds"]]}
    if options.get("stability", True):
        out["stability_changes"] = [c for b in branches for c in b["stability_changes"]]
    for key in options.get("at") or {}:
        found = sorted((item for b in branches for item in b["at"][key]), key=lambda item: item[0][name])
        out[f"at_{key}"] = [rec for rec, _ in found]
        out[f"at_{key}_shapes"] = [shape for _, shape in found]
    target = options.get("minimize")
    if target:
        bvp, branch = context[starts[0]]["_bvp"], branches[0]["branch"]

        def value(u, lam):
            return _summary(bvp, branch.system.to_result(u, lam), aliases)[target]

        best = minimize_along_branch(branch, value, kind="min")
        out[f"{target}_min"] = float(best.value)
        out[f"{name}_at_{target}_min"] = float(best.lam)
    for alias, target in aliases.items():
        if target in out and alias not in out:
            out[alias] = out[target]
    return out
