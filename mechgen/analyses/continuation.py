"""``continuation``: branches of a continuum's steady states (boundary value problems in s), and of Newton
steady states (lumped models, a continuum's discretised residual: mechgen.analyses.newton_branch).

``continuation`` follows such a steady state in one parameter by pseudo-arclength
(mechgen.runtime.steady.continuation), through turning points, with the stability verdict
of the Galerkin linearisation about every point; it reports ``branch`` (one entry
per point: the parameter, the outputs, ``verdict``), ``folds`` and, with
``minimize``, the least value of an output along the branch (``<output>_min`` and
``<parameter>_at_<output>_min``). ``aliases`` report outputs under the scene's names.

Shape outputs (mechgen.analyses.bvp_states: the balloon's ``loops``) are reported at every point
of a branch, fold, crossing and stability change.

Keys: ``about`` (an earlier steady analysis), ``parameter``, ``stop``, ``max_points``,
``stability`` (default true), ``minimize`` (an output), ``aliases``, ``max_seconds`` (the
wall-time budget of the whole analysis, default 600 s: checked before every continuation step
and between the stability verdicts and located points; reaching it ends the run with exit 1
naming the branch points done, the parameter reached and the key), ``progress`` (default true: a
bar of the branch points on stderr when it is a terminal and the branch takes over 2 s).

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
  Brent's method along the branch (mechgen.runtime.steady.branch_scan.crossing): output
  ``at_<output>``, a list of {parameter, the output, the aliased outputs, the shape
  outputs, ``verdict``, ``refinement``} sorted by the parameter (the verdict holds when
  the model discretised with 2N and 4N terms agrees, else it is 'unconverged'), and
  ``at_<output>_shapes`` (the fields at 101 points of each, for plots);
* ``eigenvalues = true``: each branch point also reports its ``eigenvalues``.

With stability, ``stability_changes`` lists where the verdict changes between
consecutive points, located by bisection along the branch to 1e-9 of the segment
(mechgen.runtime.steady.branch_scan.switch): {parameter, aliased and shape outputs,
``from``, ``to``}. ``aliases`` may also name an analysis output:
``balloons_at_tension = "at_p_e"``.

Special points (``special_points``, default true; mechgen.analyses.special_points): every branch reports its
folds as ``LP``; a Newton steady state's branch also its branch points (``BP``, the sign changes of
det [[F_y, F_p], [chord]], with the other branch's ``direction``) and, with ``stability``, its Hopf points
(``H``, sign changes of the bialternate product of the eigenvalues, with ``frequency``, the first Lyapunov
coefficient ``lyapunov`` and ``criticality``). ``switch_branches = true`` follows the other branch from every BP,
both ways (``switched_branches``).

Branches of periodic orbits (mechgen.analyses.orbit_branch): with ``about`` an earlier ``periodic_orbit`` the
orbit is continued by its own method (harmonic balance, collocation or shooting) through its folds, reporting per
point ``period``, ``frequency``, ``amplitude``, ``start``, ``multipliers`` and ``stability``, and the special points
``LPC`` (cyclic fold), ``PD`` (period doubling) and ``NS`` (torus); ``switch_branches = true`` (a forced orbit) adds
``doubled``, the period-2T orbit past every PD point, by the same method. A forced orbit's first guess may be the
linear forced response (periodic_orbit's ``start = "linear"``).

Backbone curves (mechgen.analyses.backbone): with ``about`` the free orbit of a conservative model (a
``periodic_orbit`` without ``frequency`` on a model without damping or forcing) and ``parameter = "amplitude"`` (a
model parameter of that name wins), the continuation follows the family of free orbits in the displacement
q_p(0) of the orbit's coordinate p at t = 0 (an extremum there; the amplitude of a symmetric orbit), from the
earlier orbit's to ``stop``, with the frequency an unknown (each point's level is its ``start[<coordinate p>]``;
its ``amplitude`` keeps its meaning, max |q| per coordinate). The family is regularised by the unfolding parameter
eps of Munoz-Almaraz et al. (Physica D 181, 2003): an unknown added to the equations (harmonic balance and
collocation: a viscous term eps v in the residual; shooting: eps grad E(x0) on the return map) whose energy balance
forces eps = 0 on any orbit, reported per point as ``unfolding`` (zero to the corrector's tolerance: the check that
the family is conservative). Each point also reports the orbit's ``energy``; ``backbone`` gathers frequency,
period, amplitude, energy and unfolding as columns, and the plot draws the amplitude against the frequency. With a
model parameter instead, the orbit of the earlier level is followed as that parameter moves. Special points: LPC
and PD (NS is not sought: a conservative orbit's multipliers come in pairs mu, 1/mu).

Curves of special points (mechgen.analyses.special_curves): with ``about`` an earlier continuation and
``special_point`` the position of one of its LP or H points, the continuation follows that point in two
parameters (the earlier one and ``parameter``, up to ``stop``): output ``curve``, ``type``, ``parameters``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.bvp_states import (bvp_summary, shape_declarations, shape_values, stability_about,
                                         stability_of_each)
from mechgen.analyses.newton_branch import newton_branch
from mechgen.analyses.plane_states import OPTIONS as PLANE_POINTS
from mechgen.analyses.orbit_branch import FAMILY_PARAMETER, run_orbit_branch
from mechgen.analyses.special_curves import run_curve
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import REQUIRED, Option
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.steady import branch_scan
from mechgen.runtime.steady.continuation import ContinuationOptions, minimize_along_branch
from mechgen.scene.expr import is_identifier
from mechgen.scene.values import IDENTIFIER_RULE, fail, is_choice, join, listing, param_info, show

METHODS = ("collocation", "gauss", "multiple_shooting")
DIRECTIONS = ("increasing", "decreasing", "both")


# --------------------------------------------------------------------------- schema

def _starts(ctx, key: str, value: object) -> str | list[str]:
    """One earlier steady analysis, or an array of them (one branch each); or one earlier continuation (the curve
    of one of its special points, with ``special_point``)."""
    if isinstance(value, str) and ctx.earlier.get(value) in ("continuation", "periodic_orbit"):
        return value
    if not isinstance(value, list):
        return schema.about(ctx, key, value)
    if not value:
        raise fail(ctx.file, key, "empty array", "an array of earlier steady analyses")
    names = [schema.about(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    for i, name in enumerate(names, 1):
        if name in names[:i - 1]:
            raise fail(ctx.file, f"{key}[{i}]", f"start '{name}' is listed twice", "distinct steady analyses")
    return names


def _output_values(ctx, key: str, value: object) -> dict[str, float]:
    """{output: number}: values whose crossings a branch locates (at = { p_e = 5.0 })."""
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {show(value)}", "a table: output = number, e.g. { p_e = 5.0 }")
    out = {}
    for name, number in value.items():
        if not is_identifier(name):
            raise fail(ctx.file, join(key, name), f"{show(name)} is not an output name", IDENTIFIER_RULE)
        out[name] = schema.number(ctx, join(key, name), number)
    return out


def _bounds(ctx, key: str, value: object) -> dict[str, tuple[float, float]]:
    """{output: [low, high]}: a branch ends where an output leaves its range."""
    expected = "a table: output = [low, high] with low < high, e.g. { p_e = [0, 12] }"
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {show(value)}", expected)
    out = {}
    for name, pair in value.items():
        sub = join(key, name)
        if not is_identifier(name):
            raise fail(ctx.file, sub, f"{show(name)} is not an output name", IDENTIFIER_RULE)
        if not isinstance(pair, list) or len(pair) != 2:
            raise fail(ctx.file, sub, f"value is {show(pair)}", expected)
        lo, hi = (schema.number(ctx, f"{sub}[{i}]", v) for i, v in enumerate(pair, 1))
        if not lo < hi:
            raise fail(ctx.file, sub, f"the range [{lo!r}, {hi!r}] is empty", expected)
        out[name] = (lo, hi)
    return out


class FamilyParameter(str):
    """``parameter = "amplitude"`` on a model without a parameter of that name: the level of a conservative
    family's free orbits (mechgen.analyses.backbone), not a model parameter (nothing is freed in the kernels)."""


def _parameter(ctx, key: str, value: object) -> str:
    if value == FAMILY_PARAMETER and value not in ctx.model.params:
        return FamilyParameter(value)
    info = param_info(ctx.file, key, ctx.model, value)
    if is_choice(info) or info.integer:
        raise fail(ctx.file, key, f"parameter {show(value)} is not a real number", "a numeric model parameter")
    schema.check_not_derived(ctx, key, value)
    ctx.swept = (value,)
    return value


SCHEMA = {
    "about": Option(_starts, REQUIRED, doc="the earlier steady analysis the branch starts from, or a list of them "
                    "(one branch each); or an earlier periodic_orbit (a branch of orbits), or an earlier "
                    "continuation (with special_point: the curve of one of its special points)"),
    "parameter": Option(_parameter, REQUIRED, doc="the numeric parameter the branch is followed in; about the "
                        "free orbit of a conservative model (a periodic_orbit without frequency), \"amplitude\" "
                        "follows its family, the backbone curve, in the level q_p(0) (a model parameter of that name "
                        "wins)"),
    "stop": Option(schema.number, REQUIRED, doc="the parameter's value where the branch ends (its unit)"),
    "step": Option(schema.positive, 0.05, doc="the first pseudo-arclength step"),
    "max_step": Option(schema.positive, doc="the largest pseudo-arclength step"),
    "max_points": Option(schema.count, 200, doc="the most branch points (per half-branch with direction = "
                         "\"both\")"),
    "method": Option(schema.one_of("continuation method", METHODS), doc="the boundary value problem's "
                     "discretisation: collocation, gauss or multiple_shooting"),
    "stages": Option(schema.count, doc="Gauss-Legendre collocation points per interval (default 4: order 8)"),
    "mesh": Option(schema.count, 100, doc="intervals (or nodes) along s of the boundary value problem"),
    "stability": Option(schema.boolean, True, doc="give the Galerkin stability verdict at every branch point"),
    "minimize": Option(schema.name, doc="an output whose least value along the branch is reported "
                       "(<output>_min, <parameter>_at_<output>_min)"),
    "aliases": Option(schema.aliases, {}, doc="outputs also reported under the scene's names: name = "
                      "\"output\" (an analysis output too)"),
    "direction": Option(schema.one_of("direction", DIRECTIONS), doc="the parameter's direction at the start: "
                        "increasing, decreasing or both (default: towards stop)"),
    "bounds": Option(_bounds, doc="output = [low, high]: the branch ends where an output leaves its range"),
    "at": Option(_output_values, doc="output = value: the points where an output crosses the value, located "
                 "along the branch (at_<output>)"),
    "eigenvalues": Option(schema.boolean, False, doc="report every branch point's eigenvalues too"),
    "special_points": Option(schema.boolean, True, doc="locate and report the branch's special points: folds (LP), "
                             "and on a Newton steady state's branch branch points (BP) and, with stability, Hopf "
                             "points (H, with the first Lyapunov coefficient); on a branch of periodic orbits cyclic "
                             "folds (LPC), period doublings (PD) and torus points (NS; not on a conservative family)"),
    "special_point": Option(schema.count, doc="with about an earlier continuation: the position (from 1) of the "
                            "fold (LP) or Hopf point (H) in its special_points whose curve in two parameters is "
                            "followed (parameter: the second one)"),
    "switch_branches": Option(schema.boolean, False, doc="also follow the other branch through every branch point "
                              "(BP), both ways (output switched_branches; a Newton steady state's branch); about a "
                              "forced periodic_orbit, the doubled orbit (period 2T) past every period doubling (PD) "
                              "by the orbit's own method (output doubled)"),
    "max_seconds": Option(schema.positive, doc="the wall-time budget of the whole analysis (s, default 600), "
                         "checked before every continuation step"),
    "progress": Option(schema.boolean, doc="draw a bar of the branch points on stderr (default true, when it is "
                       "a terminal and the branch takes over 2 s)"),
    **PLANE_POINTS,
}


def _check_branch_outputs(ctx, base: str, options: dict) -> None:
    """Names in ``at`` and ``bounds``: aliases, <output>_<start|end|max|min>, <field>_s_<start|end>, shape outputs."""
    if not getattr(ctx.model, "fields", ()):
        return
    known = set(options.get("aliases", {})) | set(getattr(ctx.model, "shape_outputs", ()))
    known |= {f"{o}_{end}" for o in ctx.model.outputs for end in ("start", "end", "max", "min")}
    known |= {f"{f}_s_{end}" for f in ctx.model.fields for end in ("start", "end")}
    for key in ("at", "bounds"):
        for name in options.get(key, {}):
            if name not in known:
                raise fail(ctx.file, f"{base}.{key}.{name}", f"no output {show(name)} on a branch",
                           "an alias of this analysis or <output>_start/_end/_max/_min: " + listing(sorted(known)))


def check(ctx, base: str, options: dict) -> None:
    """minimize follows one start; ``at`` and ``bounds`` name branch outputs; ``stop`` below the parameter's bound;
    ``special_point`` with, and only with, ``about`` an earlier continuation."""
    about = options["about"]
    curve = isinstance(about, str) and ctx.earlier.get(about) == "continuation"
    if curve != ("special_point" in options):
        raise fail(ctx.file, f"{base}.special_point" if curve else f"{base}.about",
                   "a curve of special points needs both 'about' an earlier continuation and 'special_point'",
                   "special_point = <position in its special_points> with about = \"<continuation>\"" if curve
                   else "about = an earlier steady analysis (special_point goes with about = a continuation)")
    orbit = isinstance(about, str) and ctx.earlier.get(about) == "periodic_orbit"
    if isinstance(options["parameter"], FamilyParameter) and not orbit:
        raise fail(ctx.file, f"{base}.parameter", f"parameter '{FAMILY_PARAMETER}' (model {ctx.model.name} has no "
                   "parameter of that name) continues the family of a conservative model's free orbits, and 'about' "
                   "is not a periodic_orbit", "about = a periodic_orbit without frequency on a conservative model, "
                   "or one of the model's parameters: " + listing(list(ctx.model.params)))
    if curve or orbit:
        return
    if isinstance(options["about"], list) and "minimize" in options:
        raise fail(ctx.file, f"{base}.minimize", "minimize follows one branch; 'about' lists several starts",
                   "one start (about = \"name\") with minimize")
    _check_branch_outputs(ctx, base, options)
    name = options["parameter"]
    below = getattr(ctx.model.params[name], "below", None)
    if below is not None and not options["stop"] < below:
        raise fail(ctx.file, f"{base}.stop", f"stop {options['stop']!r} is not below {below!r}, the bound of "
                   f"parameter '{name}'", f"a value below {below!r}")


def frees(options: dict) -> list[str]:
    """The continuation parameter: free in the kernels (a conservative family's level is none)."""
    return [] if isinstance(options["parameter"], FamilyParameter) else [options["parameter"]]


def needs(options: dict, *, internal: bool) -> set[str]:
    """The linear kernel for the stability along the branch (its steady start brings the BVP kernels)."""
    return {"linear"} if options.get("stability", True) else set()


# --------------------------------------------------------------------------- the branch

def _refined_verdict(system, bvp, result) -> dict:
    """The verdict at the scene's N checked on the model discretised with 2N and 4N terms (DESIGN.md: stability
    of continua under refinement): ``verdict`` is the N verdict when 2N and 4N agree, else 'unconverged'
    (balloons of three or more loops at N = 10: the in-plane sines converge slowly there, notes section 6);
    ``refinement`` lists the three ({N, verdicts}) so that the trend shows."""
    size = int(system.choices["N"])
    sizes = [size, 2 * size, 4 * size]
    verdicts = [stability_about(system if k == size else system.refined(k), bvp, result)["verdict"] for k in sizes]
    return {"verdict": verdicts[0] if len(set(verdicts)) == 1 else "unconverged",
            "refinement": {"N": sizes, "verdicts": verdicts}}



def _record(name: str, lam: float, summary: dict, shapes: dict, aliases: dict, extra=()) -> dict:
    """A located point: the parameter, the aliased outputs (and ``extra`` outputs), the shape outputs."""
    keys = list(aliases) + [k for k in extra if k not in aliases]
    return {name: float(lam), **{k: summary[k] for k in keys if k in summary}, **shapes}


def _values(system, bvp, result, aliases: dict, names=()) -> dict:
    """The summary of a steady state, with the shape outputs when ``names`` asks for one of them."""
    out = bvp_summary(bvp, result, aliases)
    if any(n not in out for n in names):
        out.update(shape_values(system, bvp, result))
    return out


def _follow(system, bvp, result, options: dict, aliases: dict, budget: Budget | None = None):
    """The branch from one start, with the options' direction, stop and bounds."""
    name = options["parameter"]
    index = bvp.params.index(name)
    here, stop = float(result.p[index]), float(options["stop"])
    towards = "increasing" if stop >= here else "decreasing"
    steps = ContinuationOptions(ds=options.get("step", 0.05),
                                ds_max=options.get("max_step", max(1.0, abs(stop - here) / 20)),
                                **({"lam_max": stop} if stop >= here else {"lam_min": stop}), budget=budget,
                                progress=options.get("progress", True))
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
                              stages=options.get("stages"), max_points=options.get("max_points", 200),
                              options=steps)


def _check_names(options: dict, known: dict) -> None:
    for key in ("at", "bounds"):
        for k in options.get(key) or {}:
            if k not in known:
                raise SceneError(f"no output {k!r} on the branch", key=f"{key}.{k}",
                                 expected="an output of the steady state or an alias: " + ", ".join(sorted(known)))


def _one_branch(system, start: dict, options: dict, label: str | None, budget: Budget | None = None) -> dict:
    """Points, folds, crossings and stability changes of the branch through one start (under ``budget``)."""
    bvp, result = start["_bvp"], start["_result"]
    name, aliases = options["parameter"], options.get("aliases", {})
    stability = options.get("stability", True)
    _check_names(options, {**bvp_summary(bvp, result, aliases), **shape_values(system, bvp, result)})
    branch = _follow(system, bvp, result, options, aliases, budget)
    spent = (lambda what: budget.check_time(f"{len(branch.lam)} branch points, then {what}")) if budget else \
        (lambda what: None)
    disc = branch.system
    tag = {"start": label} if label else {}
    results = [disc.to_result(u, lam) for u, lam in zip(branch.u, branch.lam)]
    summaries = [{**bvp_summary(bvp, res, aliases), **shape_values(system, bvp, res)} for res in results]
    spent("their outputs")
    stab = stability_of_each(system, bvp, results) if stability else [{}] * len(results)
    spent("their stability")
    points = []
    for lam, res, values, st in zip(branch.lam, results, summaries, stab):
        point = {**tag, name: float(lam), **{bvp.params[i]: float(res.p[i]) for i in bvp.problem.unknown},
                 **values}
        if stability:
            point["verdict"], point["frequencies"] = st["verdict"], st["frequencies"]
            if options.get("eigenvalues"):
                point["eigenvalues"] = st["eigenvalues"]
        points.append(point)

    def located(x, extra=()):
        res = disc.to_result(x[:-1], x[-1])
        return res, {**tag, **_record(name, x[-1], bvp_summary(bvp, res, aliases), shape_values(system, bvp, res),
                                      aliases, extra)}

    X = np.hstack([branch.u, branch.lam[:, None]])
    shaped = [d.name for d in shape_declarations(system)]
    out = {"points": points, "status": branch.status,
           "folds": [{**tag, name: float(f.lam), **_values(system, bvp, disc.to_result(f.u, f.lam), aliases, shaped)}
                     for f in branch.folds], "stability_changes": [], "at": {}, "branch": branch}
    if stability:
        def verdict(x):
            return stability_about(system, bvp, disc.to_result(x[:-1], x[-1]))["verdict"]

        for i in range(len(points) - 1):
            a, b = points[i]["verdict"], points[i + 1]["verdict"]
            if a != b:
                spent(f"locating the stability change after point {i + 1}")
                _, rec = located(branch_scan.switch(disc, X[i], X[i + 1], verdict, a))
                out["stability_changes"].append({**rec, "from": a, "to": b})
    for key, value in (options.get("at") or {}).items():
        found = []
        values = [s[key] - value for s in summaries]
        for i in range(len(points)):
            if values[i] == 0.0 or (i + 1 < len(points) and values[i] * values[i + 1] < 0):
                spent(f"locating {key} = {value:g} after point {i + 1}")
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


def newton_starts(starts: list[str], context: dict) -> bool:
    """True when every start is a Newton steady state (no BVP), False when every one is a BVP steady state;
    a mix is refused (SceneError at ``about``): the two kinds of branch are followed differently."""
    newton = ["_bvp" not in context[s] for s in starts]
    if any(newton) and not all(newton):
        raise SceneError("the starts mix Newton steady states (" + ", ".join(s for s, n in zip(starts, newton) if n)
                         + ") with boundary-value ones", key="about",
                         expected="starts of one kind: all Newton steady states, or all with method = "
                                  "\"collocation\", \"shooting\" or \"multiple_shooting\"")
    return all(newton)


def _newton_continuation(system, starts: list[str], options: dict, context: dict, budget: Budget) -> dict:
    """The branches through Newton steady states (mechgen.analyses.newton_branch), in the outputs' layout."""
    name, several = options["parameter"], len(starts) > 1
    branches = []
    for s in starts:
        b = newton_branch(system, context[s], options, budget)
        if several:
            for item in b["points"] + b["folds"] + b["stability_changes"] + b.get("special_points", []):
                item["start"] = s
        branches.append(b)
    out = {"parameter": name, "shape_outputs": [], "branch": [p for b in branches for p in b["points"]],
           "status": branches[0]["status"] if not several else {s: b["status"] for s, b in zip(starts, branches)},
           "points": sum(len(b["points"]) for b in branches), "folds": [f for b in branches for f in b["folds"]]}
    if options.get("special_points", True):
        out["special_points"] = [s for b in branches for s in b["special_points"]]
        out["_special_x"] = [x for b in branches for x in b["_special_x"]]
    if options.get("switch_branches"):
        out["switched_branches"] = [s for b in branches for s in b["switched_branches"]]
    if options.get("stability", True):
        out["stability_changes"] = [c for b in branches for c in b["stability_changes"]]
    return out


def run_continuation(system, options: dict, context: dict) -> dict:
    """The branch of steady states through the ``about`` one (or one branch per start) as ``parameter`` goes to
    ``stop``; see the module doc for the keys and outputs."""
    about = options["about"]
    starts = about if isinstance(about, list) else [about]
    name, aliases = options["parameter"], options.get("aliases", {})
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    if "special_point" in options:
        return run_curve(system, options, context[about])
    if isinstance(about, str) and "_orbit" in context[about]:
        return run_orbit_branch(system, options, context[about])
    if newton_starts(starts, context):
        return _newton_continuation(system, starts, options, context, budget)
    if options.get("switch_branches"):
        raise SceneError("switch_branches follows the branches of Newton steady states only; this continuation "
                         "starts from a boundary-value steady state (its branch reports folds, LP)",
                         key="switch_branches", expected="switch_branches = false (or a Newton steady state as the "
                         "start)")
    branches = [_one_branch(system, context[s], options, s if isinstance(about, list) else None, budget)
                for s in starts]
    out = {"parameter": name, "shape_outputs": [d.name for d in shape_declarations(system)],
           "branch": [p for b in branches for p in b["points"]],
           "special_points": [{"type": "LP", **f} for b in branches for f in b["folds"]]
           if options.get("special_points", True) else [],
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
            return bvp_summary(bvp, branch.system.to_result(u, lam), aliases)[target]

        best = minimize_along_branch(branch, value, kind="min")
        out[f"{target}_min"] = float(best.value)
        out[f"{name}_at_{target}_min"] = float(best.lam)
    for alias, target in aliases.items():
        if target in out and alias not in out:
            out[alias] = out[target]
    return out


# --------------------------------------------------------------------------- plots

_POINT_KEYS = ("start", "verdict", "frequencies", "eigenvalues")


def _branch_axes(out: dict) -> tuple[str, str, list[str]]:
    """(parameter, the output drawn against it, the shape outputs written on the diagram) of a continuation:
    the output of ``at``, else the minimized one, else the first number reported per point that varies along
    the branch (else the first number)."""
    points = out["branch"]
    name = out.get("parameter") or next(iter(points[0]))
    at = [k[3:] for k in out if k.startswith("at_") and not k.endswith("_shapes")]
    minimized = [k[:-4] for k in out if k.endswith("_min") and f"{name}_at_{k[:-4]}_min" in out]
    numeric = [k for k, v in points[0].items() if k not in _POINT_KEYS and k != name and isinstance(v, float)]
    varying = [k for k in numeric if len({p.get(k) for p in points}) > 1]
    return name, (at or minimized or varying or numeric)[0], list(out.get("shape_outputs", []))


def _families(points: list) -> list[list[dict]]:
    """The branch's points split by start (one list per branch, in order)."""
    groups: dict = {}
    for p in points:
        groups.setdefault(p.get("start"), []).append(p)
    return list(groups.values())


#: the legend's name for branch points without a verdict (``stability = false``)
UNJUDGED = "no verdict (stability = false)"
#: the markers of the special points besides folds (BP: square, H: star)
_SPECIAL_MARKS = {"BP": "s", "H": "*"}


def _branch(plt, a: dict, path: Path) -> bool:
    """p_e (or another output) against the parameter: verdict colours, loop counts, folds, changes, crossings,
    branch and Hopf points (labelled) and the branches switched onto (dashed)."""
    out = a["outputs"]
    if not out.get("branch"):
        return False
    colours = {**figures.VERDICT_COLOURS, UNJUDGED: "0.55"}  # stability = false: no verdict, not "stable"
    name, output, shapes = _branch_axes(out)
    fig, ax = plt.subplots(figsize=(7, 5))
    for family in _families(out["branch"]):
        lam = [p[name] for p in family]
        val = [p.get(output, float("nan")) for p in family]
        ax.plot(lam, val, "-", color="0.75", lw=0.8, zorder=1)
        for verdict in colours:
            sel = [i for i, p in enumerate(family) if p.get("verdict", UNJUDGED) == verdict]
            if sel:
                ax.plot([lam[i] for i in sel], [val[i] for i in sel], ".", ms=3, color=colours[verdict], zorder=2)
        for key in shapes:
            last = None
            for i, p in enumerate(family):
                if p.get(key) != last:
                    last = p.get(key)
                    ax.annotate(f"{key} {last:g}", (lam[i], val[i]), fontsize=7, xytext=(4, 4),
                                textcoords="offset points", color="tab:green")
    for fold in out.get("folds", []):
        ax.plot(fold[name], fold.get(output, float("nan")), "x", color="tab:purple", ms=7)
    for change in out.get("stability_changes", []):
        ax.plot(change[name], change.get(output, float("nan")), "d", color="tab:orange", ms=6, mfc="none")
    for key in [k[3:] for k in out if k.startswith("at_") and not k.endswith("_shapes")]:
        for p in out[f"at_{key}"]:
            ax.plot(p[name], p[key], "o", ms=8, mfc="none", color="tab:green")
    for half in out.get("switched_branches", []):
        ax.plot([p[name] for p in half["branch"]], [p.get(output, float("nan")) for p in half["branch"]], "--",
                color="0.45", lw=0.8, zorder=1)
    for special in out.get("special_points", []):
        if special["type"] in _SPECIAL_MARKS:
            ax.plot(special[name], special.get(output, float("nan")), _SPECIAL_MARKS[special["type"]], ms=8,
                    mfc="none", color="k")
            ax.annotate(special["type"], (special[name], special.get(output, float("nan"))), fontsize=7,
                        xytext=(5, -9), textcoords="offset points")
    seen = {p.get("verdict", UNJUDGED) for p in out["branch"]}
    handles = [plt.Line2D([], [], ls="", marker=".", color=c, label=v) for v, c in colours.items() if v in seen]
    marks = [("x", "tab:purple", "fold", bool(out.get("folds"))),
             ("d", "tab:orange", "stability change", bool(out.get("stability_changes"))),
             ("o", "tab:green", "at", any(k.startswith("at_") for k in out))]
    handles += [plt.Line2D([], [], ls="", marker=m, mfc="tab:purple" if m == "x" else "none", color=c, label=label)
                for m, c, label, shown in marks if shown]
    ax.legend(handles=handles, fontsize=7, loc="best")
    ax.set_xlabel(figures.labelled(a, name))
    ax.set_ylabel(output)
    ax.set_title(f"{a['name']}: {output} against {name}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _orbit_branch(plt, a: dict, path: Path) -> bool:
    """A branch of periodic orbits: each coordinate's amplitude against the parameter (stable solid, unstable
    dashed), its cyclic folds, period doublings and torus points marked."""
    out = a["outputs"]
    points = out.get("branch") or []
    key = "orbit_amplitude" if points and "orbit_amplitude" in points[0] else "amplitude"  # a parameter "amplitude"
    if not points or not isinstance(points[0].get(key), dict):
        return False
    name = out["parameter"]
    fig, ax = plt.subplots(figsize=(7, 5))
    for coordinate in points[0][key]:
        lam = np.array([p[name] for p in points])
        amp = np.array([p[key][coordinate] for p in points])
        for style, label in (("-", "stable"), ("--", "unstable")):
            mask = np.array([p["stability"] == label for p in points])
            if not mask.any():
                continue
            mask[:-1] |= mask[1:]  # each run of points joined to its neighbours: no gap where stability changes
            shown = np.where(mask, amp, np.nan)
            ax.plot(lam, shown, style, lw=1.2, label=f"{coordinate}, {label}")
        doubled = [d for d in out.get("doubled", []) if coordinate in d.get(key, {})]
        if doubled:
            ax.plot([d[name] for d in doubled], [d[key][coordinate] for d in doubled], "o", mfc="none",
                    color="tab:purple", label=f"{coordinate}, doubled orbit (period 2T)")
        for special in out.get("special_points", []):
            ax.plot(special[name], special[key][coordinate], _ORBIT_MARKS.get(special["type"], "o"), ms=7,
                    mfc="none", color="k")
            ax.annotate(special["type"], (special[name], special[key][coordinate]), fontsize=7,
                        xytext=(5, 4), textcoords="offset points")
    ax.set_xlabel(figures.labelled(a, name))
    ax.set_ylabel("amplitude max |q| over the period")
    ax.legend(fontsize=7, loc="best")
    ax.set_title(f"{a['name']}: periodic orbits against {name} ({out.get('method', '')})", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _backbone(plt, a: dict, path: Path) -> bool:
    """A conservative family's backbone: each coordinate's amplitude against the orbit's frequency (stable solid,
    unstable dashed), its special points marked (mechgen.analyses.backbone)."""
    out = a["outputs"]
    table = out.get("backbone")
    if not table or not out.get("branch"):
        return False
    points = out["branch"]
    w = np.array(table["frequency"])
    fig, ax = plt.subplots(figsize=(7, 5))
    for coordinate, values in table["amplitude"].items():
        amp = np.array(values)
        for style, label in (("-", "stable"), ("--", "unstable")):
            mask = np.array([p["stability"] == label for p in points])
            if mask.any():
                mask[:-1] |= mask[1:]
                ax.plot(w, np.where(mask, amp, np.nan), style, lw=1.2, label=f"{coordinate}, {label}")
        for special in out.get("special_points", []):
            ax.plot(special["frequency"], special["amplitude"][coordinate], _ORBIT_MARKS.get(special["type"], "o"),
                    ms=7, mfc="none", color="k")
            ax.annotate(special["type"], (special["frequency"], special["amplitude"][coordinate]), fontsize=7,
                        xytext=(5, 4), textcoords="offset points")
    ax.set_xlabel("frequency of the free orbit, 2 pi / T (rad per unit time)")
    ax.set_ylabel("amplitude max |q| over the period")
    ax.legend(fontsize=7, loc="best")
    ax.set_title(f"{a['name']}: backbone curve, the free orbits' family ({out.get('method', '')})", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


#: markers of the special points of a branch of orbits
_ORBIT_MARKS = {"LPC": "x", "PD": "s", "NS": "D"}


def _curve(plt, a: dict, path: Path) -> bool:
    """A special point's curve: the first parameter against the second (LP: fold curve; H: Hopf curve, the
    frequency on a second axis)."""
    out = a["outputs"]
    if not out.get("curve"):
        return False
    first, second = out["parameters"]
    b, p = [c[second] for c in out["curve"]], [c[first] for c in out["curve"]]
    fig, ax = plt.subplots(figsize=(7, 5))
    ax.plot(b, p, "k.-", ms=3, lw=1.0, label=f"{out['type']} curve")
    if out["type"] == "H":
        twin = ax.twinx()
        freq = [c["frequency"] for c in out["curve"]]
        twin.plot(b, freq, "--", color="tab:blue", lw=0.8)
        twin.set_ylabel("frequency at the Hopf point (rad per unit time)", color="tab:blue")
        middle, half = (max(freq) + min(freq)) / 2, max((max(freq) - min(freq)) / 2 * 1.1, 0.01 * max(freq))
        twin.set_ylim(middle - half, middle + half)   # a frequency constant along the curve: +-1 %, not round-off
    ax.set_xlabel(figures.labelled(a, second))
    ax.set_ylabel(figures.labelled(a, first))
    ax.legend(fontsize=7, loc="best")
    ax.set_title(f"{a['name']}: the {out['type']} point in ({first}, {second})", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _eigenvalues_along(plt, a: dict, path: Path, count: int = 4) -> bool:
    """Real and imaginary parts of the eigenvalues with the smallest |Im| (Im >= 0) at every branch point."""
    points = a["outputs"].get("branch")
    if not points or "eigenvalues" not in points[0]:
        return False
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for i, p in enumerate(points):
        ev = sorted((e for e in p["eigenvalues"] if e[1] >= 0), key=lambda e: (abs(e[1]), -e[0]))[:count]
        colour = figures.VERDICT_COLOURS.get(p.get("verdict"), "k")
        top.plot([i] * len(ev), [e[0] for e in ev], ".", ms=3, color=colour)
        bottom.plot([i] * len(ev), [e[1] for e in ev], ".", ms=3, color=colour)
    for i in range(len(points) - 1):
        if points[i].get("verdict") != points[i + 1].get("verdict"):
            for ax in (top, bottom):
                ax.axvline(i + 0.5, color="0.6", lw=0.6, ls="--")
    name = a["outputs"].get("parameter", "parameter")
    ticks = list(range(0, len(points), max(1, len(points) // 8)))
    bottom.set_xticks(ticks, [f"{points[i][name]:.3g}" for i in ticks])
    top.axhline(0.0, color="0.6", lw=0.5)
    top.set_ylabel("Re mu")
    bottom.set_ylabel("Im mu")
    bottom.set_xlabel(f"branch points in order ({name} marked)")
    top.set_title(f"{a['name']}: the {count} eigenvalues with the smallest Im >= 0 (colour: verdict)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _frequencies_along(plt, a: dict, path: Path) -> bool:
    """The lowest frequencies of every branch point against the parameter (log axis over decades)."""
    out = a["outputs"]
    points = [p for p in out.get("branch", []) if p.get("frequencies")]
    if not points:
        return False
    name = out.get("parameter") or next(iter(points[0]))
    lam = [p[name] for p in points]
    fig, ax = plt.subplots(figsize=(7, 5))
    for k in range(max(len(p["frequencies"]) for p in points)):
        ax.plot(lam, [p["frequencies"][k] if k < len(p["frequencies"]) else float("nan") for p in points], "-",
                lw=1.0)
    if min(lam) > 0 and max(lam) / min(lam) > 100:
        ax.set_xscale("log")
    ax.set_xlabel(figures.labelled(a, name))
    ax.set_ylabel("frequency (rad/s)")
    ax.set_title(f"{a['name']}: the lowest frequencies along the branch", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def plot(plt, a: dict, path: Path) -> list[Path]:
    """The branch diagram (an output against the parameter, points coloured by the stability verdict, shape
    outputs such as the loop count written where they change, folds, stability changes and the ``at``
    crossings marked), the shapes of the ``at`` points (first field against the last), with ``eigenvalues``
    their real and imaginary parts along the branch, and the lowest frequencies against the parameter."""
    written = [path] if (_backbone(plt, a, path) or _orbit_branch(plt, a, path) or _branch(plt, a, path)
                         or _curve(plt, a, path)) else []
    out = a["outputs"]
    name = out.get("parameter", "parameter")
    for key in [k[3:] for k in out if k.startswith("at_") and not k.endswith("_shapes")]:
        labels = [f"{name} = {p[name]:.4g}" + (f", loops {p['loops']:g}" if "loops" in p else "")
                  + (f", {p['verdict']}" if "verdict" in p else "") for p in out[f"at_{key}"]]
        shapes = path.with_name(f"{path.stem}_at_{key}.png")
        if figures.curves(plt, f"{a['name']}: steady states at {key} = {out[f'at_{key}'][0][key]:.4g}"
                          if labels else "", list(zip(labels, out.get(f"at_{key}_shapes", []))), shapes):
            written.append(shapes)
    eig = path.with_name(path.stem + "_eigenvalues.png")
    if _eigenvalues_along(plt, a, eig):
        written.append(eig)
    freq = path.with_name(path.stem + "_frequencies.png")
    if _frequencies_along(plt, a, freq):
        written.append(freq)
    return written


register(AnalysisKind("continuation", SCHEMA, run_continuation, needs, summary.lines, check=check, frees=frees,
                      plot=plot))
