"""``shear_curve``: the steady shear curve of a Johnson-Segalman fluid, its extrema and the local verdict.

The model supplies ``epsilon`` (solvent-to-polymer viscosity ratio) and ``xi`` (slip parameter; built-in
``js_local``). In the scales eta_p / lambda (stress) and 1 / lambda (rate), the total shear stress in steady
shear at rate g is (seed 002, Khayat & Ashrafi, eq. 4)

    T(g) = epsilon g + g / (1 + k g^2),   k = xi (2 - xi),

sampled at ``samples`` rates from 0 to ``rate_max`` (default 1.5 times the rate of the minimum, or 10 where T
is monotone). For epsilon < 1/8 (and 0 < xi < 2) T has a local maximum and minimum in closed form
(mechgen.runtime.fluids.johnson_segalman): outputs ``shear_rate_max``, ``stress_max``, ``shear_rate_min``,
``stress_min``, and ``monotone`` false. For epsilon >= 1/8 (or xi = 0, 2) T is monotone: ``monotone`` true, a
``note`` saying so, and the four extrema outputs are left out (not NaN): there is no spurt and no fold.
The stress-controlled local dynamics (imposed T, state the three polymer stresses) has at every equilibrium the
eigenvalue -1 of the off-manifold combination xi tau_xx + (2 - xi) tau_yy and a pair whose sum is
-2 - 1/(epsilon (1 + k g^2)) < 0 (from the Jacobian's trace): ``hopf`` = "none", ``pair_trace_max`` (the largest
such sum over the sampled curve) and ``off_manifold_eigenvalue`` (-1).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.parameters import parameter_dict
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option, count_within, positive
from mechgen.errors import InputError
from mechgen.runtime.fluids.johnson_segalman import MONOTONE_EPSILON, extrema, pair_trace, total_stress
from mechgen.scene.values import fail

PARAMS = ("epsilon", "xi")
#: the outputs a summary prints without their samples
SAMPLED = ("shear_rate", "stress")


def check(ctx, base: str, options: dict) -> None:
    """The model has parameters epsilon and xi."""
    missing = [p for p in PARAMS if p not in ctx.model.params]
    if missing:
        raise fail(ctx.file, f"{base}.kind", f"model {ctx.model.name} has no parameter {', '.join(missing)}",
                   "a model with parameters epsilon and xi (the built-in js_local)")


SCHEMA = {
    "samples": Option(count_within("samples"), 401, doc="Shear rates sampled from 0 to rate_max."),
    "rate_max": Option(positive, doc="Largest sampled shear rate (1/lambda; default 1.5 x the minimum's rate, or 10)."),
}


def frees(options: dict) -> list[str]:
    """The parameters the analysis reads, kept free so that the system carries the scene's values."""
    return list(PARAMS)


def needs(options: dict, *, internal: bool) -> set[str]:
    """Only the outputs kernel (closed forms in the parameters)."""
    return {"outputs"}


def verdict_outputs(epsilon: float, xi: float, top) -> dict:
    """The extrema (or the monotone note) and the no-Hopf verdict's numbers."""
    if top is None:
        return {"monotone": True, "note": f"epsilon = {epsilon:g}, xi = {xi:g}: T(shear rate) is monotone "
                f"(epsilon >= {MONOTONE_EPSILON:g} or xi(2 - xi) = 0): no extrema, no fold, no spurt"}
    (g_max, T_max), (g_min, T_min) = top
    return {"monotone": False, "shear_rate_max": g_max, "stress_max": T_max, "shear_rate_min": g_min,
            "stress_min": T_min}


def run_shear_curve(system, options: dict, context: dict) -> dict:
    """The sampled curve, the extrema and the local verdict."""
    values = parameter_dict(system, system.params)
    epsilon, xi = values["epsilon"], values["xi"]
    if not (epsilon > 0.0 and 0.0 <= xi <= 2.0):
        raise InputError(f"shear_curve needs epsilon > 0 and 0 <= xi <= 2, got epsilon = {epsilon:g}, xi = {xi:g}",
                         key="params", expected="epsilon > 0 and 0 <= xi <= 2")
    top = extrema(epsilon, xi)
    rate_max = options.get("rate_max") or (1.5 * top[1][0] if top else 10.0)
    g = np.linspace(0.0, rate_max, options["samples"])
    out = {"shear_rate": g.tolist(), "stress": total_stress(g, epsilon, xi).tolist()}
    out.update(verdict_outputs(epsilon, xi, top))
    out.update({"hopf": "none", "pair_trace_max": float(np.max(pair_trace(g, epsilon, xi))),
                "off_manifold_eigenvalue": -1.0})
    return out


def lines(outputs: dict) -> list[str]:
    """Every output but the samples."""
    return summary.output_lines(outputs, skip=SAMPLED)


def plot(plt, entry: dict, path) -> list:
    """T(g) with its extrema marked."""
    out = entry["outputs"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.plot(out["shear_rate"], out["stress"], lw=1.2, label="T(shear rate)")
    if not out["monotone"]:
        ax.plot([out["shear_rate_max"], out["shear_rate_min"]], [out["stress_max"], out["stress_min"]], "o",
                mfc="none", color="tab:red", label="extrema (closed form)")
    ax.set(xlabel="shear rate (1/lambda)", ylabel="total shear stress (eta_p/lambda)",
           title=f"{entry['name']}: steady shear curve" + (" (monotone)" if out["monotone"] else ""))
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("shear_curve", SCHEMA, run_shear_curve, needs, lines, check=check, frees=frees, plot=plot,
                      sweepable=True))
