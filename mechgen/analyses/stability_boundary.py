"""``stability_boundary``: the value of a parameter at which a steady state loses its stability.

For a numeric ``parameter`` p and a ``bracket`` [p_lo, p_hi] the analysis finds the root p_c of the growth
rate g(p) = max Re s(p), the largest real part of the eigenvalues s of the linearisation about the
equilibrium at p (recomputed by Newton at every p, with the generated Jacobians: r(q, 0, 0, z) = 0 and the
internal rates g(q, 0, z) = 0, from the ``about`` steady analysis's state, else ``guess``). The eigenvalues
are those of the ``stability`` kind: with internal variables, of A = d(dx/dt)/dx at (q, 0, z); otherwise
of M q'' + (D + G) q' + K q = 0. g(p_lo) and g(p_hi) must have opposite signs (else exit 1 naming both);
Brent's method then brackets p_c to ``rtol`` (default 1e-12) relative to it.

Outputs: ``<parameter>_critical`` (p_c), ``frequency_critical`` (|Im s| of the eigenvalue that crosses at
p_c, rad/s; 0 for a real crossing), ``crossing`` (``complex``: an oscillation sets in, a Hopf bifurcation;
``real``: a divergence), ``eigenvalues_critical`` ([re, im]), and at the system's own value of the
parameter ``growth_rate``, ``eigenvalues`` and ``verdict``: the stability verdict (stable / neutral /
divergence / flutter), reported under the scene's word for it when ``labels`` maps it to one
(``labels = { flutter = "stick_slip", divergence = "stick_slip" }``). Also ``iterations`` (of Brent).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import schema, summary
from mechgen.analyses.operating_point import vector
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, REQUIRED, Option
from mechgen.analyses.steady import equilibrium_functions
from mechgen.errors import ConvergenceError, InputError
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


SCHEMA = {"parameter": Option(_parameter, REQUIRED), "bracket": Option(_bracket, REQUIRED),
          "about": Option(schema.about), "guess": Option(schema.coordinate_table, {}),
          "rtol": Option(schema.positive, 1e-12), "tol": Option(schema.positive, 1e-10),
          "max_iter": Option(schema.count, 100), "labels": Option(_labels, ABSENT)}


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


def run_stability_boundary(system, options: dict, context: dict) -> dict:
    """p_c with g(p_c) = 0 between the bracket's ends, and the verdict at the system's own parameter value."""
    from scipy.optimize import brentq  # here, not at import: every scene loads the registry (startup budget)

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

    g_low, g_high = at(low).growth_rate, at(high).growth_rate
    if not np.sign(g_low) * np.sign(g_high) < 0:
        raise ConvergenceError(f"stability_boundary: the growth rate max Re s has the same sign at both ends of "
                               f"the bracket ({name} = {low:.6g}: {g_low:.6g}/s, {name} = {high:.6g}: {g_high:.6g}/s); "
                               "give a bracket across the stability boundary")
    critical, info = brentq(lambda v: at(v).growth_rate, low, high, xtol=1e-300, rtol=options.get("rtol", 1e-12),
                            maxiter=options.get("max_iter", 100), full_output=True, disp=False)
    if not info.converged:
        raise ConvergenceError(f"stability_boundary: Brent's method did not converge in {info.iterations} "
                               f"iterations ({name} = {critical:.12g}); raise max_iter")
    res = at(critical)
    s = np.asarray(res.eigenvalues)
    crossing = s[np.argmax(s.real)]  # the eigenvalue whose real part is the growth rate
    own = at(here)
    labels = options.get("labels", {})
    return {f"{name}_critical": float(critical), "frequency_critical": float(abs(crossing.imag)),
            "crossing": "complex" if abs(crossing.imag) > res.threshold else "real",
            "eigenvalues_critical": _pairs(s), "verdict": labels.get(own.verdict, own.verdict),
            "growth_rate": float(own.growth_rate), "eigenvalues": _pairs(own.eigenvalues),
            "iterations": int(info.iterations)}


register(AnalysisKind("stability_boundary", SCHEMA, run_stability_boundary, needs, summary.lines, frees=frees))
