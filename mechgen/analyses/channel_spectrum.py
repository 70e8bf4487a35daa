"""``channel_spectrum``: eigenvalues of a Johnson-Segalman channel flow linearised about its classical steady state.

The model (built-in ``js_channel``) supplies ``epsilon``, ``xi``, ``Re``, ``G`` and declares the local stress laws at
an imposed shear rate ``shear_rate`` (internal variables tau_xx, tau_yy, tau_xy). The base state is the classical
one, shear rate g_b(y) = -sign(y) g(G |y|) with g the low-rate root of the local shear curve
(mechgen.runtime.fluids.johnson_segalman; G <= the spurt gradient, else refused) and the steady stresses; the
generated kernels' residual there is checked to vanish (the model is the law the base state is for). At each
Chebyshev point the rates kernel's Jacobian J_sigma and its derivative in the shear rate J_g (the law is affine in
g, checked: both from the kernels at shear_rate = 0 and 1) are the local blocks of the linearised channel
(mechgen.runtime.spectral.channel):

    Re lambda u = epsilon u'' + (tau_xy)',   lambda sigma = J_sigma(y) sigma + J_g(y) u',   u = 0 at y = +-1,

solved at ``N`` and ``N_check`` intervals (default round(1.5 N)); an eigenvalue is kept when it reappears at the
other resolution within ``tol`` * max(1, |lambda|). The local stress-controlled eigenvalues lambda_loc(T = G y)
form the essential spectrum: sampled over 0 <= y <= 1 at ``band_samples`` points, kept eigenvalues on that band
are reported apart (``band_eigenvalues``), not as point eigenvalues.

Outputs: ``eigenvalues`` (the resolved point spectrum, rightmost first, at most ``count``, each [Re, Im]),
``rightmost`` ([Re, Im] of the first, absent when none), ``verdict`` (stable / unstable by the rightmost point and
band eigenvalues), ``essential_spectrum`` (the band's ends: the local eigenvalues at the centre y = 0 and at the
wall y = 1, each a list of [Re, Im]), ``essential_rightmost`` (the largest Re lambda_loc over y),
``band_eigenvalues`` and ``rejected`` (how many), ``resolution`` [N, N_check], ``base_residual``, and the band's
samples ``band_y`` (0 to 1) and ``band`` (per y, the local eigenvalues [Re, Im], rightmost first). With
``stress_diffusion`` D > 0 (D tau'' in each stress law, tau' = 0 at the walls) the band is no longer an essential
spectrum (diffusion sends the high wavenumbers to -infinity): every resolved eigenvalue is then reported as a point
eigenvalue, and the band's outputs describe the local law only.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.orr_sommerfeld import intervals, pair
from mechgen.analyses.parameters import parameter_dict
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option, count, count_within, number, positive
from mechgen.errors import InputError, KernelError
from mechgen.runtime.fluids.johnson_segalman import classical_rate, extrema, polymer_stresses
from mechgen.runtime.spectral.channel import LocalBlocks, eigenvalues, local_eigenvalues, off_band, rightmost_first
from mechgen.runtime.spectral.chebyshev import points, resolved
from mechgen.scene.values import fail

PARAMS = ("epsilon", "xi", "Re", "G", "shear_rate")
STRESSES = ("txx", "tyy", "txy")
#: a base state's rates residual above this (relative to the stresses' size) means the model is another law
BASE_TOL = 1e-10


def non_negative(ctx, key: str, value: object) -> float:
    """A number >= 0."""
    x = number(ctx, key, value)
    if x < 0:
        raise fail(ctx.file, key, f"value {x!r} is negative", "a number >= 0")
    return x


def check(ctx, base: str, options: dict) -> None:
    """The model has the parameters and stresses of js_channel; N_check differs from N."""
    missing = [p for p in PARAMS if p not in ctx.model.params]
    if missing:
        raise fail(ctx.file, f"{base}.kind", f"model {ctx.model.name} has no parameter {', '.join(missing)}",
                   "a model with parameters epsilon, xi, Re, G, shear_rate (the built-in js_channel)")
    options.setdefault("N_check", int(round(1.5 * options["N"])))
    if options["N_check"] == options["N"]:
        raise fail(ctx.file, f"{base}.N_check", "N_check equals N", "a second resolution, e.g. round(1.5 N)")


SCHEMA = {
    "N": Option(intervals, 48, doc="Chebyshev collocation intervals across the channel."),
    "N_check": Option(intervals, doc="The second resolution the eigenvalues must reappear at (default round(1.5 N))."),
    "tol": Option(positive, 1e-6, doc="Agreement of an eigenvalue between the resolutions, times max(1, |lambda|)."),
    "count": Option(count, 8, doc="How many point eigenvalues to report, rightmost first."),
    "band_samples": Option(count_within("samples"), 201, doc="Points 0 <= y <= 1 at which the band is sampled."),
    "stress_diffusion": Option(non_negative, 0.0, doc="D of a stress diffusion D tau'' added to each stress law, with "
                               "tau' = 0 at the walls (lambda h^2 units; 0: none, the band is then essential)."),
}


def frees(options: dict) -> list[str]:
    """The parameters read, and the local shear rate the analysis sets point by point."""
    return list(PARAMS)


def needs(options: dict, *, internal: bool) -> set[str]:
    """The rates and their Jacobian (the local law), and the residual/tangent the system's flow needs."""
    return {"residual", "tangent", "rates", "rates_tangent"}


def base_rates(y: np.ndarray, G: float, epsilon: float, xi: float) -> np.ndarray:
    """g_b(y) = -sign(y) g(G |y|) on the classical branch."""
    return np.array([-np.sign(v) * classical_rate(G * abs(v), epsilon, xi) for v in y])


def kernel_law(system):
    """The model's local law at P points, (g, sigma (P, 3)) -> (f, J_sigma, J_g), from its generated rates and their
    Jacobian at shear_rate = 0 and 1: the law is affine in g (f = f0 + g (f1 - f0)), checked at g = 2.5 on a sample
    state (else an InputError: the analysis assumes it)."""
    order = [list(system.metadata.internal).index(name) for name in STRESSES]
    at = {g: system.with_params(shear_rate=g) for g in (0.0, 1.0, 2.5)}
    probe = np.array([0.3, -0.2, 0.7])
    affine = at[0.0].rhs(0.0, probe) + 2.5 * (at[1.0].rhs(0.0, probe) - at[0.0].rhs(0.0, probe))
    if not np.allclose(at[2.5].rhs(0.0, probe), affine, rtol=1e-12, atol=1e-12):
        raise InputError(f"channel_spectrum: the stress laws of model {system.metadata.model} are not affine in "
                         "shear_rate", key="model", expected="a local law linear in the shear rate (js_channel)")

    def law(g: np.ndarray, sigma: np.ndarray):
        f, J_sigma, J_g = [], [], []
        for gj, sj in zip(g, sigma):
            z = np.empty(3)
            z[order] = sj
            f0, f1 = at[0.0].rhs(0.0, z), at[1.0].rhs(0.0, z)
            J0, J1 = at[0.0].jacobian(0.0, z), at[1.0].jacobian(0.0, z)
            f.append((f0 + gj * (f1 - f0))[order])
            J_sigma.append((J0 + gj * (J1 - J0))[np.ix_(order, order)])
            J_g.append((f1 - f0)[order])
        return np.array(f), np.array(J_sigma), np.array(J_g)

    return law


def local_blocks(law, rates: np.ndarray, xi: float) -> tuple[LocalBlocks, float]:
    """J_sigma and J_g at each point at the closed-form base stresses, and the largest base residual
    |f(sigma_b; g_b)| relative to max(1, |sigma_b|)."""
    sigma = np.array(polymer_stresses(rates, xi), dtype=float).T
    f, J_sigma, J_g = law(rates, sigma)
    worst = float(np.max(np.abs(f) / np.maximum(1.0, np.max(np.abs(sigma), axis=1))[:, None]))
    return LocalBlocks(J_sigma, J_g, STRESSES.index("txy")), worst


def base_values(system) -> tuple[float, float, float, float]:
    """(epsilon, xi, Re, G), refused beyond the classical branch."""
    v = parameter_dict(system, system.params)
    epsilon, xi, Re, G = v["epsilon"], v["xi"], v["Re"], v["G"]
    if not (epsilon > 0 and 0 <= xi <= 2 and Re >= 0 and G >= 0):
        raise InputError("channel_spectrum needs epsilon > 0, 0 <= xi <= 2, Re >= 0 and G >= 0", key="params",
                         expected="epsilon > 0, 0 <= xi <= 2, Re >= 0 and G >= 0")
    top = extrema(epsilon, xi)
    if top is not None and G > top[0][1]:
        raise InputError(f"channel_spectrum linearises the classical steady state, which exists for G <= "
                         f"{top[0][1]:.10g} (the spurt gradient); G = {G:g}", key="params.G",
                         expected="G at or below the spurt gradient")
    return epsilon, xi, Re, G


def band(system, epsilon: float, xi: float, G: float, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(y, lambda_loc(y)) for 0 <= y <= 1."""
    y = np.linspace(0.0, 1.0, samples)
    blocks, _ = local_blocks(kernel_law(system), base_rates(-y, G, epsilon, xi), xi)
    return y, local_eigenvalues(blocks, epsilon)


def spectra(system, options: dict, values) -> tuple[np.ndarray, np.ndarray, float]:
    """The eigenvalues at N and N_check and the worst base residual."""
    epsilon, xi, Re, G = values
    out, worst, law = [], 0.0, kernel_law(system)
    for N in (options["N"], options["N_check"]):
        blocks, res = local_blocks(law, base_rates(points(N), G, epsilon, xi), xi)
        worst = max(worst, res)
        out.append(eigenvalues(N, epsilon, Re, blocks, options["stress_diffusion"]))
    return out[0], out[1], worst


def run_channel_spectrum(system, options: dict, context: dict) -> dict:
    """Point spectrum, essential band, verdict."""
    values = base_values(system)
    epsilon, xi, Re, G = values
    coarse, fine, worst = spectra(system, options, values)
    if worst > BASE_TOL:
        raise KernelError(f"channel_spectrum: the model's rates do not vanish at the Johnson-Segalman base state "
                          f"(residual {worst:.3g}): the model is not the law the base state is for")
    kept, rejected = resolved(coarse, fine, options["tol"])
    y, loc = band(system, epsilon, xi, G, options["band_samples"])
    # with stress diffusion the band is no longer essential: every resolved eigenvalue is a point eigenvalue
    point, on_band = off_band(kept, loc, 1e-3) if options["stress_diffusion"] == 0.0 else (kept, kept[:0])
    point = rightmost_first(point)
    top = max([v.real for v in point] + [float(np.max(loc.real))])
    out = {"eigenvalues": [pair(v) for v in point[:options["count"]]], "verdict": "unstable" if top > 0 else "stable",
           "essential_spectrum": [[pair(v) for v in loc[0]], [pair(v) for v in loc[-1]]],
           "essential_rightmost": float(np.max(loc.real)), "band_eigenvalues": int(on_band.size),
           "rejected": int(rejected.size), "resolution": [options["N"], options["N_check"]], "base_residual": worst,
           "band_y": y.tolist(), "band": [[pair(v) for v in row] for row in loc]}
    if point.size:
        out["rightmost"] = pair(point[0])
    return out


def lines(outputs: dict) -> list[str]:
    """Every output but the band's samples."""
    return summary.output_lines(outputs, skip=("band_y", "band"))


def plot(plt, entry: dict, path) -> list:
    """Point eigenvalues and the essential band in the complex plane."""
    out = entry["outputs"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    band = np.asarray(out["band"], dtype=float)
    ax.plot(band[:, :, 0].ravel(), band[:, :, 1].ravel(), ".", ms=2, color="0.6", label="essential band (local)")
    if out["eigenvalues"]:
        pts = np.asarray(out["eigenvalues"], dtype=float)
        ax.plot(pts[:, 0], pts[:, 1], "o", mfc="none", color="tab:blue", label="point eigenvalues (resolved)")
    ax.axvline(0.0, color="k", lw=0.5)
    ax.set(xlabel="Re lambda (1/lambda)", ylabel="Im lambda (1/lambda)", title=f"{entry['name']}: channel spectrum")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("channel_spectrum", SCHEMA, run_channel_spectrum, needs, lines, check=check,
                      frees=frees, plot=plot, sweepable=True))
