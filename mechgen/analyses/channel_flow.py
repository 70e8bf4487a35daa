"""``channel_flow``: steady pressure-driven channel flow of a Johnson-Segalman fluid, from its local law.

The model supplies ``epsilon``, ``xi`` and the pressure gradient ``G`` (built-in ``js_channel``; walls at
y = -1, 1, stress in eta_p / lambda). In a steady state the total shear stress is G |y|, so the shear rate at
each y is a root g(G y) of T(g) = epsilon g + g / (1 + xi (2 - xi) g^2) (mechgen.runtime.fluids.johnson_segalman).
The classical (low-rate) solution exists up to the wall stress G = T_max, the curve's local maximum:
``spurt_gradient`` (exact, before any discretisation). The flux per unit width through the channel,

    Q(G) = 2 int_0^1 y g(G y) dy = (2 / G^2) int_0^G T g(T) dT,

is summed in closed form (integration by parts in g: int T g dT = [g T^2/2] - int T^2/2 dg, with
int T^2 dg elementary). Outputs: ``spurt_gradient``; the classical flow curve ``G`` (``samples`` values from 0
to spurt_gradient) and ``flow_rate``; above the threshold (``G_above``, ``samples`` values from spurt_gradient to
``G_max``, default 1.5 x spurt_gradient) the two jumping solutions: ``flow_rate_top`` (the rate jumps to the high
branch where G y = T_max) and ``flow_rate_bottom`` (where G y = T_min), with ``jump_position_top`` and
``jump_position_bottom`` (y of the jump); the quasi-static hysteresis loop of a ramp 0 -> G_max -> 0 without
inertia (each y following its local S-curve, jumping up at T_max and down at T_min): ``G_up``, ``flow_rate_up``
(classical, then top-jumping), ``G_down``, ``flow_rate_down`` and ``jump_position_down`` (the interface latched at
T_max / G_max, then bottom-jumping at T_min / G, none below G = T_min); at the model's G, ``flow_rate_at_G`` (classical, when G <=
spurt_gradient) or ``flow_rate_top_at_G`` and ``flow_rate_bottom_at_G``. For a monotone curve (epsilon >= 1/8)
there is no spurt: ``monotone`` true, a ``note``, the classical curve up to ``G_max`` (default 2) and no
threshold or jumping outputs.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.parameters import parameter_dict
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.channel_spectrum import STRESSES, kernel_law
from mechgen.analyses.orr_sommerfeld import intervals
from mechgen.analyses.schema import Option, boolean, count_within, positive
from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.fluids.johnson_segalman import extrema, flow_rate, hysteresis_loop
from mechgen.runtime.spectral.channel import SteadyChannel, steady_branch
from mechgen.runtime.spectral.chebyshev import points
from mechgen.scene.values import fail

PARAMS = ("epsilon", "xi", "G")
SAMPLED = ("G", "flow_rate", "G_above", "flow_rate_top", "flow_rate_bottom", "jump_position_top",
           "jump_position_bottom", "discrete_G", "discrete_flow_rate", "G_up", "flow_rate_up", "G_down",
           "flow_rate_down", "jump_position_down")


def check(ctx, base: str, options: dict) -> None:
    """The model has parameters epsilon, xi and G (and shear_rate for the discrete branch); N_check differs from N."""
    wanted = PARAMS + (("shear_rate",) if options["discrete"] else ())
    missing = [p for p in wanted if p not in ctx.model.params]
    if missing:
        raise fail(ctx.file, f"{base}.kind", f"model {ctx.model.name} has no parameter {', '.join(missing)}",
                   "a model with parameters epsilon, xi and G (the built-in js_channel)")
    options.setdefault("N_check", int(round(1.5 * options["N"])))
    if options["N_check"] == options["N"]:
        raise fail(ctx.file, f"{base}.N_check", "N_check equals N", "a second resolution, e.g. round(1.5 N)")


SCHEMA = {
    "samples": Option(count_within("samples"), 101, doc="Pressure gradients sampled on each part of the flow curve."),
    "discrete": Option(boolean, False, doc="Also continue the collocated steady channel in G past its first fold, "
                       "at N and N_check (the model's generated stress laws)."),
    "N": Option(intervals, 17, doc="Chebyshev intervals of the discrete steady branch (odd: the fold converges to the "
                "spurt gradient as N^-2; even: it equals it, the collocated total stress being exactly G y by symmetry)."),
    "N_check": Option(intervals, doc="Its second resolution (default round(1.5 N))."),
    "G_max": Option(positive, doc="Largest sampled pressure gradient (default 1.5 x spurt_gradient, or 2 if none)."),
}


def frees(options: dict) -> list[str]:
    """The parameters the analysis reads (and the local shear rate for the discrete branch), kept free."""
    return list(PARAMS) + (["shear_rate"] if options.get("discrete") else [])


def needs(options: dict, *, internal: bool) -> set[str]:
    """The outputs kernel (closed forms in the parameters); the local law's rates for the discrete branch."""
    return {"residual", "tangent", "rates", "rates_tangent"} if options.get("discrete") else {"outputs"}


def discrete_branch(system, N: int, epsilon: float, spurt: float):
    """The collocated steady branch at N from G = spurt / 20 (a Newtonian guess, corrected) past its first fold."""
    channel = SteadyChannel(N, epsilon, kernel_law(system), 3, STRESSES.index("txy"))
    y, G0 = points(N), 0.05 * spurt
    u = G0 * (1.0 - y**2) / (2.0 * (1.0 + epsilon))
    g = -G0 * y / (1.0 + epsilon)
    sigma = np.zeros((N + 1, 3))
    sigma[:, STRESSES.index("txy")] = g
    return steady_branch(channel, channel.pack(u[1:N], sigma), G0, 1.5 * spurt)


def discrete_outputs(system, options: dict, epsilon: float, xi: float, spurt: float) -> dict:
    """The first fold at N and N_check, the N_check branch's flow rate against the closed form below the fold."""
    coarse = discrete_branch(system, options["N"], epsilon, spurt)
    fine = discrete_branch(system, options["N_check"], epsilon, spurt)
    if not coarse.folds or not fine.folds:
        raise ConvergenceError(f"channel_flow: the discrete steady branch found no fold ({fine.status})")
    below = fine.G <= fine.folds[0]
    stop = int(np.argmin(below)) if not below.all() else below.size  # the points before the first fold
    G, Q = fine.G[:stop], fine.flow_rate[:stop]
    error = max(abs(q - flow_rate(float(g), epsilon, xi)[0]) for g, q in zip(G, Q) if g <= spurt)
    folds = [coarse.folds[0], fine.folds[0]]
    return {"spurt_gradient_discrete": folds, "spurt_gradient_discrete_error": [abs(f - spurt) for f in folds],
            "discrete_folds": list(fine.folds), "discrete_G": G.tolist(), "discrete_flow_rate": Q.tolist(),
            "discrete_flow_rate_error": float(error)}


def jumping(G_values: np.ndarray, epsilon: float, xi: float) -> dict:
    """The top- and bottom-jumping flow rates and jump positions at each G (all above the threshold)."""
    out = {"G_above": G_values.tolist()}
    for jump in ("top", "bottom"):
        pairs = [flow_rate(float(G), epsilon, xi, jump) for G in G_values]
        out[f"flow_rate_{jump}"] = [q for q, _ in pairs]
        out[f"jump_position_{jump}"] = [y for _, y in pairs]
    return out


def at_gradient(G: float, spurt: float | None, epsilon: float, xi: float) -> dict:
    """The flow rates at the model's own G."""
    if spurt is None or G <= spurt:
        return {"flow_rate_at_G": flow_rate(G, epsilon, xi)[0]}
    return {"flow_rate_top_at_G": flow_rate(G, epsilon, xi, "top")[0],
            "flow_rate_bottom_at_G": flow_rate(G, epsilon, xi, "bottom")[0]}


def run_channel_flow(system, options: dict, context: dict) -> dict:
    """The spurt threshold, the flow curve and the jumping solutions."""
    values = parameter_dict(system, system.params)
    epsilon, xi, G = values["epsilon"], values["xi"], values["G"]
    if not (epsilon > 0.0 and 0.0 <= xi <= 2.0 and G >= 0.0):
        raise InputError(f"channel_flow needs epsilon > 0, 0 <= xi <= 2, G >= 0; got epsilon = {epsilon:g}, "
                         f"xi = {xi:g}, G = {G:g}", key="params", expected="epsilon > 0, 0 <= xi <= 2 and G >= 0")
    top = extrema(epsilon, xi)
    spurt = top[0][1] if top else None
    n = options["samples"]
    if spurt is None:
        grid = np.linspace(0.0, options.get("G_max") or 2.0, n)
        out = {"monotone": True, "note": f"epsilon = {epsilon:g}, xi = {xi:g}: the shear curve is monotone, "
               "no spurt: one steady solution at every G"}
    else:
        G_max = options.get("G_max") or 1.5 * spurt
        if G_max <= spurt:
            raise InputError(f"channel_flow: G_max = {G_max:g} is not above the spurt gradient {spurt:.6g}",
                             key="G_max", expected="a G_max above spurt_gradient")
        grid = np.linspace(0.0, spurt, n)
        out = {"monotone": False, "spurt_gradient": spurt}
    out.update({"G": grid.tolist(), "flow_rate": [flow_rate(float(g), epsilon, xi)[0] for g in grid]})
    if spurt is not None:
        out.update(jumping(np.linspace(spurt, G_max, n), epsilon, xi))
        loop = hysteresis_loop(G_max, epsilon, xi, n)
        out.update({"G_up": loop["G_up"], "flow_rate_up": loop["flow_rate_up"], "G_down": loop["G_down"],
                    "flow_rate_down": loop["flow_rate_down"], "jump_position_down": loop["jump_down"]})
        if options["discrete"]:
            out.update(discrete_outputs(system, options, epsilon, xi, spurt))
    out.update(at_gradient(G, spurt, epsilon, xi))
    return out


def lines(outputs: dict) -> list[str]:
    """Every output but the sampled curves."""
    return summary.output_lines(outputs, skip=SAMPLED)


def plot(plt, entry: dict, path) -> list:
    """The flow curve: classical branch, top- and bottom-jumping solutions, the discrete branch, the threshold."""
    out = entry["outputs"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.plot(out["G"], out["flow_rate"], "k-", label="classical branch")
    if "G_above" in out:
        ax.plot(out["G_above"], out["flow_rate_top"], "-", color="tab:blue", label="top-jumping")
        ax.plot(out["G_above"], out["flow_rate_bottom"], "--", color="tab:orange", label="bottom-jumping")
        ax.axvline(out["spurt_gradient"], color="0.5", lw=0.8, ls=":", label="spurt gradient")
    if "G_down" in out:
        ax.plot(out["G_down"], out["flow_rate_down"], ":", color="tab:red", label="quasi-static unloading")
    if "discrete_G" in out:
        ax.plot(out["discrete_G"], out["discrete_flow_rate"], "o", mfc="none", ms=4, color="tab:green",
                label="collocated steady branch")
    ax.set(xlabel="pressure gradient G (eta_p/lambda per half-width)", ylabel="flow rate Q",
           title=f"{entry['name']}: flow curve")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("channel_flow", SCHEMA, run_channel_flow, needs, lines, check=check, frees=frees, plot=plot,
                      sweepable=True))
