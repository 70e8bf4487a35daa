"""``orr_sommerfeld``: the linear stability of plane Poiseuille flow (the Orr-Sommerfeld problem).

The model supplies the streamwise wavenumber ``alpha`` and the Reynolds number ``Re`` (built-in
``plane_poiseuille``); the base flow is U = 1 - y^2 between walls at y = -1, 1. The eigenproblem for the
wave speed c of psi = v(y) exp(i alpha (x - c t)),

    (U - c)(v'' - alpha^2 v) - U'' v = (v'''' - 2 alpha^2 v'' + alpha^4 v) / (i alpha Re),  v = v' = 0 at y = +-1,

is solved by Chebyshev collocation (mechgen.runtime.spectral) at ``N`` and ``N_check`` intervals (default
round(1.5 N)); an eigenvalue is kept when it reappears at the other resolution within ``tol`` * max(1, |c|),
and reported at N_check; the others are counted as unresolved (``rejected``) and not reported. A least
stable eigenvalue that is not resolved is a ConvergenceError (raise N). With ``critical = true`` (default)
Newton on Im c = 0, d Im c / d alpha = 0 (derivatives from the eigenvectors) from ``start`` = [alpha, Re]
finds the critical point, at both resolutions (they must agree within ``tol``, relative).

Outputs: ``least_stable_c`` [Re c, Im c], ``growth_rate`` alpha Im c, ``verdict`` (stable / unstable),
``eigenvalues`` (the resolved c, least stable first, at most ``count``, each [Re c, Im c]), ``resolved`` and
``rejected`` (how many), ``resolution`` [N, N_check], ``least_stable_change`` (|c(N) - c(N_check)|); with
``critical``: ``critical_Re``, ``critical_alpha``, ``critical_c`` [Re c, Im c], ``critical_Re_change``
(|Re_c(N) - Re_c(N_check)|).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.parameters import parameter_dict
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option, boolean, count, int_at_least, positive
from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.spectral.chebyshev import resolved
from mechgen.runtime.spectral.orr_sommerfeld import critical_point, operators, wave_speeds
from mechgen.scene.values import fail, type_name

#: the model parameters the analysis reads
PARAMS = ("alpha", "Re")
#: the most collocation intervals (dense eigenproblems of that size, and the round-off of D^4 grows as N^8)
MAX_N = 400


def intervals(ctx, key: str, value: object) -> int:
    """An integer from 8 to MAX_N."""
    n = int_at_least(ctx, key, value, 8)
    if n > MAX_N:
        raise fail(ctx.file, key, f"value {n} is above {MAX_N}", f"an integer from 8 to {MAX_N}")
    return n


def start_point(ctx, key: str, value: object) -> list[float]:
    """[alpha, Re], both > 0: where Newton starts."""
    if not isinstance(value, list) or len(value) != 2:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a list [alpha, Re] of two numbers > 0")
    return [positive(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]


def check(ctx, base: str, options: dict) -> None:
    """The model has parameters alpha and Re; N_check differs from N."""
    missing = [p for p in PARAMS if p not in ctx.model.params]
    if missing:
        raise fail(ctx.file, f"{base}.kind", f"model {ctx.model.name} has no parameter {', '.join(missing)}",
                   "a model with parameters alpha and Re (the built-in plane_poiseuille)")
    options.setdefault("N_check", int(round(1.5 * options["N"])))
    if options["N_check"] == options["N"]:
        raise fail(ctx.file, f"{base}.N_check", "N_check equals N", "a second resolution, e.g. round(1.5 N)")


SCHEMA = {
    "N": Option(intervals, 64, doc="Chebyshev collocation intervals (N - 1 interior points)."),
    "N_check": Option(intervals, doc="The second resolution the eigenvalues must reappear at (default round(1.5 N))."),
    "tol": Option(positive, 1e-6, doc="Agreement of an eigenvalue between the resolutions, times max(1, |c|)."),
    "count": Option(count, 6, doc="How many resolved eigenvalues to report, least stable first."),
    "critical": Option(boolean, True, doc="Find the critical point (Im c = 0 at the neutral curve's minimum Re)."),
    "start": Option(start_point, [1.0, 6000.0], doc="[alpha, Re] where the critical point's Newton starts."),
}


def frees(options: dict) -> list[str]:
    """The parameters the analysis reads, kept free so that the system carries the scene's values."""
    return list(PARAMS)


def needs(options: dict, *, internal: bool) -> set[str]:
    """Only the (empty) outputs kernel, which every model has, so that a compile request names a kernel: the
    model supplies alpha and Re, the base flow is the analysis's."""
    return {"outputs"}


def pair(c: complex) -> list[float]:
    """[Re c, Im c] as plain floats."""
    return [float(c.real) + 0.0, float(c.imag) + 0.0]


def critical_outputs(options: dict) -> dict:
    """The critical point at N and at N_check; they must agree within tol (relative in Re)."""
    alpha0, Re0 = options["start"]
    try:
        a1, R1, c1, _ = critical_point(operators(options["N"]), alpha0, Re0)
        a2, R2, _, _ = critical_point(operators(options["N_check"]), alpha0, Re0)
    except ArithmeticError as exc:
        raise ConvergenceError(f"orr_sommerfeld: {exc}; start nearer the critical point (key start)") from None
    if abs(R1 - R2) > options["tol"] * R1:
        raise ConvergenceError(f"orr_sommerfeld: the critical Re differs between N = {options['N']} and "
                               f"{options['N_check']} ({R1:.10g}, {R2:.10g}): raise N")
    return {"critical_Re": R1, "critical_alpha": a1, "critical_c": pair(c1), "critical_Re_change": abs(R1 - R2)}


def run_orr_sommerfeld(system, options: dict, context: dict) -> dict:
    """The resolved spectrum at the model's alpha, Re, and optionally the critical point."""
    values = parameter_dict(system, system.params)
    alpha, Re = values["alpha"], values["Re"]
    if not (alpha > 0 and Re > 0):
        raise InputError(f"orr_sommerfeld needs alpha > 0 and Re > 0, got alpha = {alpha:g}, Re = {Re:g}",
                         key="params", expected="alpha > 0 and Re > 0")
    N, N2, tol = options["N"], options["N_check"], options["tol"]
    coarse = wave_speeds(operators(N), alpha, Re)
    kept, rejected = resolved(coarse, wave_speeds(operators(N2), alpha, Re), tol)
    kept = kept[np.argsort(-kept.imag, kind="stable")]
    least = coarse[0]
    if kept.size == 0 or abs(kept[0] - least) > tol * max(1.0, abs(least)):
        raise ConvergenceError(f"orr_sommerfeld: the least stable eigenvalue at N = {N} ({least:.8g}) is not "
                               f"resolved at N_check = {N2}: raise N")
    out = {"least_stable_c": pair(kept[0]), "growth_rate": float(alpha * kept[0].imag),
           "verdict": "unstable" if kept[0].imag > 0 else "stable",
           "eigenvalues": [pair(c) for c in kept[:options["count"]]], "resolved": int(kept.size),
           "rejected": int(rejected.size), "resolution": [N, N2], "least_stable_change": float(abs(kept[0] - least))}
    if options["critical"]:
        out.update(critical_outputs(options))
    return out


def plot(plt, entry: dict, path) -> list:
    """The resolved wave speeds in the complex c plane, the least stable one marked."""
    out = entry["outputs"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    c = np.asarray(out["eigenvalues"], dtype=float)
    ax.plot(c[:, 0], c[:, 1], "o", mfc="none", label=f"resolved (N = {out['resolution'][0]}, {out['resolution'][1]})")
    ax.plot(*out["least_stable_c"], "r+", ms=12, label="least stable")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set(xlabel="Re c", ylabel="Im c", title=f"{entry['name']}: Orr-Sommerfeld spectrum ({out['verdict']})")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("orr_sommerfeld", SCHEMA, run_orr_sommerfeld, needs, summary.lines, check=check, frees=frees,
                      plot=plot, sweepable=True))
