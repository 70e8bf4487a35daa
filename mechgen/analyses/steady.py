"""``steady``: an equilibrium (Newton with the generated Jacobians), or a continuum's steady state as a
boundary value problem in s.

Scene keys: ``guess`` (coordinates), ``tol``, ``max_iter``; for a continuum whose boundary conditions
carry values (a string between two eyelets) ``method`` = shooting / multiple_shooting / collocation
(mechgen.runtime.steady.steady_bvp) with ``mesh`` / ``nodes``, ``bulge`` (sine amplitudes added to the
guess), ``form`` (lagrangian, or hamiltonian: the stress form), ``aliases`` (outputs under the
scene's names), ``stability`` (the Galerkin verdict about the state), ``hold = {output = value}``
with ``free = "parameter"`` (solve for the parameter that holds an end value), ``params =
{lambda0 = 0.3}`` (this analysis's own values of numeric parameters, made free in the kernels) and
``shape = {loops = 2}`` (a start with this value of a shape output, from the starting guesses the
model declares with it: each is solved by the analysis's method and form, the first whose measure
equals the value is kept, else a ConvergenceError lists what the guesses gave). Newton (a lumped model) takes
``params`` too, and ``aliases = {name = "output"}`` (the output also reported as ``name``).

``max_seconds`` bounds Newton's wall time (default 600 s; exit 1 naming the iteration reached).

Outputs: ``iterations``, ``residual_norm``; a lumped model ``coordinates``; the model's outputs
(Newton) or every output at the ends and its extremes along s, the fields' end slopes and the shape
outputs (BVP, mechgen.analyses.bvp_states); a continuum ``s`` and ``deflection``, with Newton also
``reactions``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from mechgen.analyses import figures, plane_states, schema, summary
from mechgen.analyses.bvp_states import (bvp_summary, parameter_namespace, shape_declarations, shape_values,
                                         stability_about)
from mechgen.analyses.fields import field_shapes
from mechgen.analyses.operating_point import vector
from mechgen.analyses.parameters import info_of, parameter_dict, with_free_params
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option
from mechgen.errors import ConvergenceError, SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.core.diagnose import nonfinite_kernels
from mechgen.runtime.steady.newton import newton
from mechgen.runtime.steady.steady_bvp import hamiltonian_bvp, holding, solve_steady, steady_bvp, stress_guess
from mechgen.scene.expr import is_identifier
from mechgen.scene.values import IDENTIFIER_RULE, fail, is_choice, join, listing, param_info, show, type_name

METHODS = ("newton", "shooting", "multiple_shooting", "collocation")
START_TOL = 1e-6  # the tolerance at which ``shape`` starts are tried (then refined to the analysis's tol)


# --------------------------------------------------------------------------- schema

def _form(ctx, key: str, value: object) -> str:
    forms = ("lagrangian", "hamiltonian")
    if not isinstance(value, str) or value not in forms:
        raise fail(ctx.file, key, f"unknown steady form {show(value)}", "one of: " + ", ".join(forms))
    if value == "hamiltonian" and not ctx.model.stress_form:
        raise fail(ctx.file, key, f"model {ctx.model.name} declares no complementary energy density",
                   "form = 'lagrangian' (the Hamiltonian form needs @model.complementary_density)")
    return value


def _bulge(ctx, key: str, value: object) -> dict[str, list[float]]:
    """{field: [a_1, a_2, ...]}: sine amplitudes added to a boundary-value problem's initial guess."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table: field = [amplitudes of sin(j pi s/L)]")
    out = {}
    for name, amps in value.items():
        sub = join(key, name)
        if not is_identifier(name):
            raise fail(ctx.file, sub, f"{show(name)} is not a field name", IDENTIFIER_RULE)
        if not isinstance(amps, list) or not amps:
            raise fail(ctx.file, sub, f"value is {type_name(amps)}", "an array of numbers")
        out[name] = [schema.number(ctx, f"{sub}[{i}]", a) for i, a in enumerate(amps, 1)]
    return out


def _hold(ctx, key: str, value: object) -> dict[str, float]:
    """{output_end: value}: one output at an end of a steady BVP held fixed (e.g. p_e = 17.5)."""
    if not isinstance(value, dict) or len(value) != 1:
        raise fail(ctx.file, key, f"value is {show(value)}", "a table with one entry: output = number, e.g. "
                   "{ tension_start = 17.5 } (or an alias)")
    (name, number), = value.items()
    if not is_identifier(name):
        raise fail(ctx.file, join(key, name), f"{show(name)} is not an output name", IDENTIFIER_RULE)
    return {name: schema.number(ctx, join(key, name), number)}


def _free(ctx, key: str, value: object) -> str:
    """A numeric parameter a steady BVP solves for (with ``hold``)."""
    info = param_info(ctx.file, key, ctx.model, value)
    if is_choice(info) or info.integer:
        raise fail(ctx.file, key, f"parameter {show(value)} is not a real number", "a numeric model parameter")
    if value in ctx.swept:
        raise fail(ctx.file, key, f"parameter {show(value)} is swept", "a parameter the sweep does not set")
    return value


def _params(ctx, key: str, value: object) -> dict[str, float]:
    """{parameter: number}: a steady analysis's own values of numeric parameters (made free)."""
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {show(value)}", "a table of numeric parameters, e.g. { lambda0 = 0.3 }")
    out = {}
    for name, number in value.items():
        sub = join(key, name)
        info = param_info(ctx.file, sub, ctx.model, name)
        if is_choice(info) or info.integer:
            raise fail(ctx.file, sub, f"parameter {show(name)} is not a real number", "a numeric model parameter")
        if name in ctx.swept:
            raise fail(ctx.file, sub, f"parameter {show(name)} is swept", "a parameter the sweep does not set")
        out[name] = schema.number(ctx, sub, number)
        if info.below is not None and not out[name] < info.below:
            raise fail(ctx.file, sub, f"{name} = {out[name]!r} is not below {info.below!r}",
                       f"a value below {info.below!r}")
    return out


def _shape(ctx, key: str, value: object) -> dict[str, float]:
    """{shape_output: value}: a steady start with this value of a model-declared shape output (loops = 2)."""
    known = tuple(getattr(ctx.model, "shape_outputs", ()))
    expected = "a table with one entry, a shape output of the model = number: " + listing(known)
    if not isinstance(value, dict) or len(value) != 1:
        raise fail(ctx.file, key, f"value is {show(value)}", expected)
    (name, number), = value.items()
    if name not in known:
        raise fail(ctx.file, join(key, name), f"model '{ctx.model.name}' has no shape output {show(name)}", expected)
    return {name: schema.number(ctx, join(key, name), number)}


SCHEMA = {
    "guess": Option(schema.coordinate_table, {}, doc="Newton's starting coordinates, a table coordinate = value "
                    "(left out: zero)"),
    "tol": Option(schema.positive, 1e-10, doc="the residual norm at which the solve has converged"),
    "max_iter": Option(schema.count, 50, doc="the most Newton iterations"),
    "method": Option(schema.one_of("steady method", METHODS), doc="a continuum's boundary value problem in s: "
                     "shooting, multiple_shooting or collocation (left out: Newton on the discretised system)"),
    "bulge": Option(_bulge, doc="sine amplitudes added to the boundary value problem's starting guess"),
    "mesh": Option(schema.count, doc="collocation or multiple-shooting intervals along s"),
    "nodes": Option(schema.count, doc="the boundary value problem's nodes along s (instead of mesh)"),
    "aliases": Option(schema.aliases, doc="outputs also reported under the scene's names: name = \"output\""),
    "form": Option(_form, doc="the boundary value problem's form: lagrangian, or hamiltonian (the stress form)"),
    "params": Option(_params, doc="this analysis's own values of numeric parameters, made free in the kernels "
                     "(lambda0 = 0.3)"),
    "shape": Option(_shape, doc="start from the model's declared guess with this value of a shape output "
                    "(loops = 2)"),
    "hold": Option(_hold, doc="an end value to hold, output = value, met by solving for the parameter named by free"),
    "free": Option(_free, doc="the parameter solved for so that hold is met"),
    "stability": Option(schema.boolean, doc="also give the Galerkin stability verdict about the steady state"),
    "max_seconds": Option(schema.positive, doc="the wall-time budget of Newton (s, default 600)"),
    **plane_states.OPTIONS,
}


def check(ctx, base: str, options: dict) -> None:
    """hold goes with free; shape excludes bulge; params, shape, hold, stability and form need a BVP method."""
    newton_method = options.get("method", "newton") == "newton"
    if ("hold" in options) != ("free" in options):
        missing = "free" if "hold" in options else "hold"
        raise fail(ctx.file, f"{base}.{missing}", f"'hold' and 'free' go together; '{missing}' is missing",
                   "hold = { output = value } with free = \"parameter\"")
    if "shape" in options and "bulge" in options:
        raise fail(ctx.file, f"{base}.bulge", "'shape' takes its starting guesses from the model; 'bulge' would be "
                   "ignored", "either shape or bulge")
    if "shape" in options and newton_method:
        raise fail(ctx.file, f"{base}.method", "shape is for a boundary-value steady state",
                   "method = shooting, multiple_shooting or collocation")
    if ("hold" in options or options.get("stability") or "form" in options) and newton_method:
        raise fail(ctx.file, f"{base}.method", "hold, stability and form need a boundary-value steady state",
                   "method = shooting, multiple_shooting or collocation")


def frees(options: dict) -> list[str]:
    """The parameter ``free`` solves for and those ``params`` sets: free in the kernels."""
    names = [options["free"]] if options.get("free") else []
    return names + [n for n in options.get("params", {}) if n not in names]


def needs(options: dict, *, internal: bool) -> set[str]:
    """Residual, tangent and outputs (Newton), or the steady BVP's kernels (and linear, with stability)."""
    if options.get("method", "newton") != "newton":
        linear = {"linear"} if options.get("stability") else set()
        if options.get("form", "lagrangian") == "hamiltonian":
            return {"hbvp_rates", "hbvp_rates_tangent", "hbvp_outputs"} | linear
        return {"bvp_residual", "bvp_tangent", "bvp_outputs"} | linear
    return {"residual", "tangent", "outputs"} | ({"rates", "rates_tangent"} if internal else set())


# --------------------------------------------------------------------------- Newton

def equilibrium_functions(system):
    """F(y) = [r(q, 0, 0, z); g(q, 0, z)] and dF/dy for y = (q, z)."""
    n = system.n

    def residual(y):
        q, z = y[:n], y[n:]
        r = system.residual(q, None, None, z if system.m else None)
        return np.concatenate([r, system.call("rates", q=q, z=z)["g"].ravel()]) if system.m else r

    def jacobian(y):
        q, z = y[:n], y[n:]
        tan = system.tangent(q, z=z if system.m else None)
        if not system.m:
            return tan["r_q"]
        g = system.call("rates_tangent", q=q, z=z)
        return np.block([[tan["r_q"], tan["r_z"]], [g["g_q"], g["g_z"]]])

    return residual, jacobian


def newton_aliases(out: dict, aliases: dict) -> dict:
    """{alias: out[output]} for ``aliases = {alias = "output"}`` (an unknown output: SceneError at the key)."""
    for alias, target in aliases.items():
        if target not in out:
            raise SceneError(f"aliases.{alias}: the steady state has no output {target!r}", key=f"aliases.{alias}",
                             expected="one of: " + ", ".join(k for k in out if not k.startswith("_")))
    return {alias: out[target] for alias, target in aliases.items()}


def run_steady(system, options: dict, context: dict) -> dict:
    """Equilibrium r(q, 0, 0, z) = 0, g(q, 0, z) = 0 by Newton with the generated Jacobians.

    ``method`` shooting / multiple_shooting / collocation: a continuum's steady state as a
    boundary value problem in s (:func:`run_steady_bvp`); a plane continuum: mechgen.analyses.plane_states."""
    if getattr(system, "is_plane", False) and options.get("method", "newton") == "newton":
        return plane_states.plane_steady(system, options)
    if options.get("method", "newton") != "newton":
        if not system.is_field:
            raise SceneError(f"steady method {options['method']!r} is for continua", key="method",
                             expected="'newton' for a lumped or chain model")
        return run_steady_bvp(system, options, context)
    if system.is_field and system.field_meta.boundary_values:
        raise SceneError(f"model {system.metadata.model} fixes its ends at nonzero values: its steady state is "
                         "a boundary value problem in s", key="method",
                         expected="method = 'collocation', 'shooting' or 'multiple_shooting'")
    if options.get("params"):
        system = with_free_params(system, options["params"])
    y0 = np.concatenate([vector(system, options.get("guess")), np.zeros(system.m)])
    residual, jacobian = equilibrium_functions(system)
    res = newton(residual, jacobian, y0, tol=options.get("tol", 1e-10), max_iter=options.get("max_iter", 50),
                 budget=Budget("steady Newton iterations", seconds=float(options.get("max_seconds", DEFAULT_SECONDS))),
                 explain=lambda y: nonfinite_kernels(system, {"q": y[:system.n], "z": y[system.n:] if system.m else None}))
    q, z = res.x[:system.n], res.x[system.n:]
    out = {"iterations": int(res.iterations), "residual_norm": float(res.residual_norm)}
    if not system.is_lattice and not system.is_field:
        out["coordinates"] = {n: float(x) for n, x in zip(system.coordinates, q)}
    out.update(system.outputs(q, None, z if system.m else None))
    out.update(newton_aliases(out, options.get("aliases", {})))
    if system.is_field:
        out["reactions"] = system.reactions(q)
        out.update(field_shapes(system, q[:, None], "deflection"))
    out["_q"], out["_z"] = q, z
    return out


# --------------------------------------------------------------------------- boundary value problems

def _start_with_shape(system, bvp, options: dict, method: str):
    """A steady state whose shape output equals the requested value, from the model's starting guesses."""
    (name, value), = options["shape"].items()
    declared = {d.name: d for d in shape_declarations(system)}
    if name not in declared or declared[name].start is None:
        with_start = [n for n, d in declared.items() if d.start is not None]
        raise SceneError(f"model {system.metadata.model} declares no starting guesses for {name!r}",
                         key=f"shape.{name}", expected="one of: " + (", ".join(with_start) or "(none)"))
    mesh = options.get("mesh", 200)
    sigma = np.linspace(0.0, 1.0, mesh + 1)
    L = bvp.start[bvp.length_index] if bvp.length_index is not None else bvp.length
    p = parameter_namespace(system, bvp.start)
    tol = options.get("tol", 1e-10)
    gave = []
    from mechgen.symbolic.declared import call_declared

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
        got = shape_values(system, bvp, result)[name]
        if abs(got - float(value)) <= 1e-9 * max(1.0, abs(float(value))):
            if tol < START_TOL:
                result = solve_steady(bvp, method=method, guess=result, mesh=mesh, nodes=options.get("nodes", 20),
                                      tol=tol)
            return result
        gave.append(f"{name} = {got:g}")
    where = ", ".join(f"{k} = {v:g}" for k, v in parameter_dict(system, bvp.start).items())
    raise ConvergenceError(f"steady: no state with {name} = {float(value):g} from the {len(gave)} starting guesses "
                           f"of model {system.metadata.model} by {method} ({bvp.form} form, {where}): they gave "
                           f"{'; '.join(gave)}. Try another start (params), method = 'collocation' with "
                           "form = 'hamiltonian', or another value")


def run_steady_bvp(system, options: dict, context: dict) -> dict:
    """A steady state of a continuum with boundary values, by the BVP method the scene names."""
    if options.get("params"):
        system = with_free_params(system, options["params"])
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
        below = info_of(system).param(free).below
        if below is not None and not solved < below:
            raise ConvergenceError(f"steady state with {next(iter(options['hold']))} held: the solved {free} = "
                                   f"{solved:.6g} is not below {below:g} (no such state near the start; try "
                                   f"another start value of {free} or another bulge)")
        out[free] = solved
    out.update(bvp_summary(bvp, result, aliases))
    out.update(shape_values(system, bvp, result))
    if options.get("stability"):
        out.update(stability_about(system, bvp, result))
    s = np.linspace(0.0, bvp.length_of(result), 101)
    y = bvp.values(result, s)
    out["s"] = [float(v) for v in s]
    out["deflection"] = {f: [float(v) for v in y[i]] for i, f in enumerate(bvp.fields)}
    out["_bvp"], out["_result"] = bvp, result
    return out


# --------------------------------------------------------------------------- plot

def plot(plt, a: dict, path: Path) -> list[Path]:
    """A continuum's deflection against s and, with two or more fields, its curve (first field against last)."""
    if a.get("figure"):
        from mechgen.analyses import plane_figures

        return plane_figures.steady(plt, a, path)
    if not figures.shapes(plt, a, path):
        return []
    written = []
    deflection = a["outputs"].get("deflection")
    curve = path.with_name(path.stem + "_curve.png")
    if isinstance(deflection, dict) and len(deflection) >= 2 and isinstance(
            next(iter(deflection.values()))[0], float) and figures.curves(plt, a["name"], [("", deflection)], curve):
        written.append(curve)
    return written + [path]


register(AnalysisKind("steady", SCHEMA, run_steady, needs, summary.lines, check=check, frees=frees, plot=plot,
                      sweepable=True))
