"""``stability_boundary``: the value of a parameter at which a steady state loses its stability.

For a numeric ``parameter`` p and a ``bracket`` [p_lo, p_hi] the analysis finds the root p_c of the growth
rate g(p) = max Re s(p), the largest real part of the eigenvalues s of the linearisation about the
equilibrium at p (recomputed by Newton at every p, with the generated Jacobians: r(q, 0, 0, z) = 0 and the
internal rates g(q, 0, z) = 0, from the ``about`` steady analysis's state, else ``guess``). The eigenvalues
are those of the ``stability`` kind: with internal variables, of A = d(dx/dt)/dx at (q, 0, z); otherwise
of M q'' + (D + G) q' + K q = 0. The bracket's ends must have different verdicts, one stable (or neutral),
one unstable (divergence or flutter); else exit 1 naming both verdicts. When g(p_lo) and g(p_hi) have opposite
signs beyond the eigen-solve's accuracy and beyond AMBIGUOUS (1e-5) times the spectrum's scale (a damped
system: g is then certain of its sign and smooth at a simple crossing), Brent's method brackets the root of g
to ``rtol`` (default 1e-12) relative to it. Otherwise - a conservative system, whose growth rate is exactly 0 on the stable
side (undamped: s = +-i w; gyroscopic with M, K > 0 and C skew: s = i mu), losing stability when an eigenvalue
passes through zero (divergence) or two frequencies merge and leave the imaginary axis (flutter) - the
boundary is located by bisection on that event (the verdict changes) to ``rtol``: about 40 steps from a
bracket of the size of p_c. ``method`` says which (``growth_rate`` or ``bisection``).

Outputs: ``<parameter>_critical`` (p_c), ``frequency_critical`` (|Im s| of the eigenvalue that crosses at
p_c, rad/s; 0 for a real crossing), ``crossing`` (``complex``: an oscillation sets in, a Hopf bifurcation;
``real``: a divergence), ``eigenvalues_critical`` ([re, im]), and at the system's own value of the
parameter ``growth_rate``, ``eigenvalues`` and ``verdict``: the stability verdict (stable / neutral /
divergence / flutter), reported under the scene's word for it when ``labels`` maps it to one
(``labels = { flutter = "stick_slip", divergence = "stick_slip" }``). Also ``iterations`` (of Brent or of
the bisection) and ``method``. On the bisection path the crossing eigenvalue is taken just beyond p_c on the
unstable side (within 2 rtol p_c), where it has left the imaginary axis.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import schema, summary
from mechgen.analyses.operating_point import vector
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, REQUIRED, Option
from mechgen.analyses.steady import equilibrium_functions
from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.linear.stability import AMBIGUOUS
from mechgen.runtime.linear.stability import stability as solve_stability
from mechgen.runtime.linear.stability import stability_first_order
from mechgen.runtime.steady.newton import newton
from mechgen.scene.values import fail, is_choice, join, param_info, show, type_name

VERDICTS = ("stable", "neutral", "divergence", "flutter")


def _parameter(ctx, key: str, value: object) -> str:
    info = param_info(ctx.file, key, ctx.model, value)
    if is_choice(info) or info.integer:
        raise fail(ctx.file, key, f"parameter {show(value)} is not a real number", "a numeric model parameter")
    schema.check_not_derived(ctx, key, value)
    return value


def _bracket(ctx, key: str, value: object) -> list[float]:
    if not isinstance(value, list) or len(value) != 2:
        raise fail(ctx.file, key, f"value is {show(value)}", "two values of the parameter: [low, high]")
    low, high = (schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1))
    if not low < high:
        raise fail(ctx.file, key, f"[{low!r}, {high!r}] is not increasing", "[low, high] with low < high")
    return [low, high]


def _labels(ctx, key: str, value: object) -> dict[str, str]:
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table: verdict = \"word\"")
    for verdict, word in value.items():
        if verdict not in VERDICTS or not isinstance(word, str) or not word:
            raise fail(ctx.file, join(key, verdict), f"{show(verdict)} = {show(word)}",
                       "a verdict (" + ", ".join(VERDICTS) + ") = a word")
    return dict(value)


SCHEMA = {"parameter": Option(_parameter, REQUIRED, doc="the numeric parameter p whose critical value is "
                              "sought"),
          "bracket": Option(_bracket, REQUIRED, doc="[p_lo, p_hi]: values of the parameter (its unit) with a "
                            "stable and an unstable verdict"),
          "about": Option(schema.about, doc="an earlier steady analysis whose state starts Newton at every p"),
          "guess": Option(schema.coordinate_table, {}, doc="Newton's starting coordinates without about, "
                          "coordinate = value"),
          "rtol": Option(schema.positive, 1e-12, doc="the relative accuracy of the critical value p_c "
                         "(dimensionless)"),
          "tol": Option(schema.positive, 1e-10, doc="the residual norm of Newton's equilibrium at every p"),
          "max_iter": Option(schema.count, 100, doc="the most iterations of Brent's method or the bisection"),
          "labels": Option(_labels, ABSENT, doc="the scene's words for the verdicts, verdict = \"word\" "
                           "(flutter = \"stick_slip\")")}


def frees(options: dict) -> list[str]:
    """The parameter searched over: free in the kernels."""
    return [options["parameter"]]


def needs(options: dict, *, internal: bool) -> set[str]:
    """Newton's kernels (residual, tangent; rates with internal variables) and the linearisation's."""
    return {"residual", "tangent", "outputs", "linear"} | ({"rates", "rates_tangent"} if internal else set())


def equilibrium(system, y0: np.ndarray, tol: float) -> np.ndarray:
    """(q, z) of the equilibrium r(q, 0, 0, z) = 0, g(q, 0, z) = 0 found by Newton from ``y0``."""
    residual, jacobian = equilibrium_functions(system)
    return np.asarray(newton(residual, jacobian, y0, tol=tol, max_iter=50).x)


def spectrum(system, y: np.ndarray):
    """The stability result (mechgen.runtime.linear.stability) of the linearisation about (q, z) = y."""
    n = system.n
    if system.m:
        A = system.jacobian(0.0, np.concatenate([y[:n], np.zeros(n), y[n:]]))
        return stability_first_order(A, np.eye(A.shape[0]))
    mats = {k: (v.toarray() if hasattr(v, "toarray") else v) for k, v in system.linear(y[:n]).items()}
    return solve_stability(mats["M"], mats["D"] + mats["G"], mats["K"])


def _pairs(s) -> list[list[float]]:
    return [[float(x.real), float(x.imag)] for x in np.asarray(s)]


def own_value(system, name: str) -> float:
    """The system's own value of the parameter searched over (free in its kernels)."""
    values = system.param_values()
    if name not in values:
        raise InputError(f"parameter {name!r} was folded into the compiled kernels: the verdict at the system's "
                         "own value needs it free", key="parameter",
                         expected="a parameter kept free at compile time (mechgen.compile(..., free=[...]))")
    return values[name]


def unstable(result) -> bool:
    """Whether a stability result says the equilibrium loses stability (divergence or flutter)."""
    return result.verdict in ("divergence", "flutter")


def by_growth_rate(at, low: float, high: float, options: dict, name: str) -> tuple[float, int]:
    """p_c with g(p_c) = 0 by Brent's method, g = max Re s (opposite signs at the bracket's ends)."""
    from scipy.optimize import brentq  # here, not at import: every scene loads the registry (startup budget)

    critical, info = brentq(lambda v: at(v).growth_rate, low, high, xtol=1e-300, rtol=options.get("rtol", 1e-12),
                            maxiter=options.get("max_iter", 100), full_output=True, disp=False)
    if not info.converged:
        raise ConvergenceError(f"stability_boundary: Brent's method did not converge in {info.iterations} "
                               f"iterations ({name} = {critical:.12g}); raise max_iter")
    return float(critical), int(info.iterations)


def by_bisection(at, low: float, high: float, low_unstable: bool, options: dict, name: str) -> tuple[float, int]:
    """p_c where the verdict changes (stable/neutral on one side, divergence/flutter on the other), by bisection
    on that event until the bracket is within ``rtol`` of its ends: for a conservative system, whose growth rate
    is exactly 0 on the stable side (an eigenvalue through zero: divergence; two frequencies merging: flutter)."""
    rtol, most = options.get("rtol", 1e-12), options.get("max_iter", 100)
    for iteration in range(1, most + 1):
        mid = 0.5 * (low + high)
        if unstable(at(mid)) == low_unstable:
            low = mid
        else:
            high = mid
        if high - low <= rtol * max(abs(low), abs(high)):
            return 0.5 * (low + high), iteration
    raise ConvergenceError(f"stability_boundary: bisection on the stability verdict did not reach rtol = {rtol:g} in "
                           f"{most} iterations ({name} in [{low:.12g}, {high:.12g}]); raise max_iter")


def run_stability_boundary(system, options: dict, context: dict) -> dict:
    """p_c where the equilibrium loses stability between the bracket's ends, and the verdict at the system's own
    parameter value (module doc: Brent on the growth rate, or bisection on the verdict)."""
    name, (low, high) = options["parameter"], options["bracket"]
    here = float(own_value(system, name))
    if options.get("about"):
        start = np.concatenate([context[options["about"]]["_q"], np.asarray(context[options["about"]]["_z"])])
    else:
        start = np.concatenate([vector(system, options.get("guess")), np.zeros(system.m)])
    tol = options.get("tol", 1e-10)
    point = {"y": start}

    def at(value: float):
        moved = system.with_params(**{name: value})
        try:
            point["y"] = equilibrium(moved, point["y"], tol)
        except ConvergenceError as exc:
            raise ConvergenceError(f"stability_boundary: no equilibrium at {name} = {value:.12g} ({exc})") from exc
        return spectrum(moved, point["y"])

    ends = at(low), at(high)
    g_low, g_high = ends[0].growth_rate, ends[1].growth_rate
    if unstable(ends[0]) == unstable(ends[1]):
        same = ", the same sign at both ends" if np.sign(g_low) == np.sign(g_high) != 0 else ""
        raise ConvergenceError(f"stability_boundary: the bracket does not straddle a stability boundary: the verdict "
                               f"is {ends[0].verdict} at {name} = {low:.6g} and {ends[1].verdict} at {name} = "
                               f"{high:.6g} (growth rate max Re s {g_low:.6g}/s and {g_high:.6g}/s{same}); give a "
                               "bracket with a stable and an unstable end")
    if g_low * g_high < 0 and all(abs(r.growth_rate) > max(r.threshold, AMBIGUOUS * r.scale) for r in ends):
        critical, iterations = by_growth_rate(at, low, high, options, name)
        method = "growth_rate"
    else:
        critical, iterations = by_bisection(at, low, high, unstable(ends[0]), options, name)
        method = "bisection"
    return _outputs(at, critical, here, options, method, iterations, name)


def _outputs(at, critical: float, here: float, options: dict, method: str, iterations: int, name: str) -> dict:
    """The outputs at p_c (the crossing eigenvalue: the one whose real part is the growth rate there, or just
    beyond p_c on the unstable side when p_c was found by bisection) and at the system's own value."""
    res = at(critical)
    s = np.asarray(res.eigenvalues)
    past = res
    if method == "bisection" and not unstable(res):  # the event's eigenvalue just beyond p_c (within rtol)
        step = 2.0 * options.get("rtol", 1e-12) * max(abs(critical), 1e-300)
        past = next((r for r in (at(critical + step), at(critical - step)) if unstable(r)), res)
    t = np.asarray(past.eigenvalues)
    crossing = t[np.argmax(t.real)]  # the eigenvalue whose real part is the growth rate
    own = at(here)
    labels = options.get("labels", {})
    return {f"{name}_critical": float(critical), "frequency_critical": float(abs(crossing.imag)),
            "crossing": "complex" if abs(crossing.imag) > past.threshold else "real",
            "eigenvalues_critical": _pairs(s), "verdict": labels.get(own.verdict, own.verdict),
            "growth_rate": float(own.growth_rate) + 0.0, "eigenvalues": _pairs(own.eigenvalues),
            "iterations": int(iterations), "method": method}


register(AnalysisKind("stability_boundary", SCHEMA, run_stability_boundary, needs, summary.lines, frees=frees))
