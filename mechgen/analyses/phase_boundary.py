"""``phase_boundary``: the Maxwell stress, the phase strains and the two-phase equilibria of a bar.

For a model that declares its stress-strain law as outputs of a state entry ``gamma`` (the strain): ``stress``
sigma(gamma), ``energy_density`` W(gamma) (Pa) and, optionally, ``modulus`` sigma'(gamma) (the built-in
``phase_bar``). The law is sampled on ``strain_range`` (``samples`` points); where sigma rises, falls and rises
again (a non-convex W: phase 1, an unstable branch, phase 2), mechgen.runtime.steady.phases finds the peak and the
valley, the Maxwell stress sigma_M where the driving traction f = [[W]] - sigma [[gamma]] of the two phase strains
vanishes (equal areas: int_{gamma_1}^{gamma_2} sigma dgamma = sigma_M (gamma_2 - gamma_1), Abeyaratne & Knowles),
and, for each mean strain delta/L of ``elongation`` (m; L the model's output ``bar_length``, else 1), the equilibria with one
phase boundary: the Maxwell one (phase-2 fraction, boundary position s with phase 2 on 0 < x < s, f = 0) and the
family at every stress between valley and peak (``equilibrium_samples`` of them), each with its interface's
driving traction (nonzero but at sigma_M: a boundary at rest there is not at rest under kinetics).

Where sigma increases over the whole range (a convex W), there is no phase boundary: ``phase_boundary`` is false,
``maxwell_stress`` null, ``phase_strains`` and ``equilibria`` empty, and ``note`` says why. Outputs:
``phase_boundary``, ``maxwell_stress`` (Pa), ``phase_strains`` [gamma_1, gamma_2], ``spinodal_strains``
[gamma_a, gamma_b], ``peak_stress``, ``valley_stress`` (Pa), ``equilibria`` (one per elongation: ``elongation``,
``phase_fraction``, ``boundary_position`` (m), ``driving_traction`` (Pa) of the Maxwell equilibrium, null when the
mean strain is outside [gamma_1, gamma_2]: one phase), and ``family`` {``stress``, ``phase_fraction``,
``boundary_position``, ``driving_traction``}), ``law`` (``strain``, ``stress``, ``energy_density`` at the samples:
the curve the plot draws). A law whose W' disagrees with sigma (parameters out of the law's range, e.g. a
trilinear law with gamma_m <= gamma_M) or that is not finite is bad input (exit 2, key ``params``); a range too
narrow to hold both phases at the stresses between peak and valley is bad input at ``strain_range``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import phase_figures, schema, summary
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import REQUIRED, Option
from mechgen.errors import InputError
from mechgen.runtime.steady import phases
from mechgen.scene.values import fail

LAW_OUTPUTS = ("stress", "energy_density")


def strain_range(ctx, key: str, value: object) -> list[float]:
    """Two increasing strains [low, high]."""
    if not isinstance(value, list) or len(value) != 2:
        raise fail(ctx.file, key, f"value is {value!r}", "two strains [low, high]")
    low, high = (schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1))
    if not low < high:
        raise fail(ctx.file, key, f"[{low:g}, {high:g}] is not increasing", "two strains [low, high], low < high")
    return [low, high]


def _elongations(ctx, key: str, value: object) -> list[float]:
    """A number or a list of numbers (m)."""
    values = value if isinstance(value, list) else [value]
    return [schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(values, 1)]


SCHEMA = {
    "strain_range": Option(strain_range, REQUIRED, "two strains [low, high]", doc="the strains [low, high] the law is "
                           "sampled on: phase 1's and phase 2's stresses between peak and valley must lie in it"),
    "samples": Option(schema.count_within("samples"), 2001, doc="how many strains of strain_range sample the "
                      "law (finds its peak and valley, then refined)"),
    "elongation": Option(_elongations, [], doc="end displacements delta (m) of the bar of length L whose "
                         "equilibria with one phase boundary are reported"),
    "equilibrium_samples": Option(schema.count, 21, doc="stresses between valley and peak at which each "
                                  "elongation's family of two-phase equilibria is reported"),
}


def needs(options: dict, *, internal: bool) -> set[str]:
    """The outputs kernel (the law at chosen strains)."""
    return {"outputs"}


def output_names(system) -> set[str]:
    """The names the system's outputs kernel returns (none without one)."""
    kernel = system.kernels.get("outputs")
    return {port["name"] for port in kernel.spec["outputs"]} if kernel is not None else set()


class KernelLaw:
    """sigma, W, sigma' of a system's outputs kernel at strains put into the state entry ``gamma``."""

    def __init__(self, system) -> None:
        names = list(system.metadata.coordinates) + list(getattr(system.metadata, "internal", ()))
        outputs = output_names(system)
        if "gamma" not in names or not set(LAW_OUTPUTS) <= outputs:
            raise InputError(f"model {system.metadata.model} declares no strain law (a state entry 'gamma' and "
                             "outputs 'stress', 'energy_density')", key="kind",
                             expected="a model like phase_bar, or another analysis kind")
        self.system, self.column = system, self._column(system, names)

    @staticmethod
    def _column(system, names: list[str]) -> int:
        """The column of gamma in a state row (q, v, z)."""
        n = system.n
        i = names.index("gamma")
        return i if i < n else 2 * n + (i - n)

    def _out(self, name: str, g: np.ndarray) -> np.ndarray:
        g = np.atleast_1d(np.asarray(g, float))
        X = np.zeros((g.size, 2 * self.system.n + self.system.m))
        X[:, self.column] = g
        return np.asarray(self.system.evaluate_series("outputs", np.zeros(g.size), X)[name], float).reshape(g.size)

    def constant(self, name: str, default: float) -> float:
        """An output that does not depend on the state (a parameter the model reports: ``bar_length``), else
        ``default``."""
        return float(self._out(name, 0.0)[0]) if name in output_names(self.system) else default

    def stress(self, g):
        return self._out("stress", g)

    def energy(self, g):
        return self._out("energy_density", g)

    def modulus(self, g):
        return self._out("modulus", g)


def checked_law(law: KernelLaw, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sigma, W) at the samples: finite, and W' = sigma (each interval's trapezoid within 1 % of the stress scale
    times its width: a stress jump of 2 % of the scale fails), else an InputError at ``params``."""
    sig, w = law.stress(grid), law.energy(grid)
    model = law.system.metadata.model
    bad = ~(np.isfinite(sig) & np.isfinite(w))
    if bad.any():
        raise InputError(f"the law of model {model} is not finite at strain {grid[np.argmax(bad)]:.6g}", key="params",
                         expected="parameters in the law's range (trilinear: 0 < gamma_M < gamma_m)")
    scale = max(float(np.max(np.abs(sig))), np.finfo(float).tiny)
    h = np.diff(grid)
    gap = np.abs(np.diff(w) - h * (sig[1:] + sig[:-1]) / 2)
    if np.any(gap > 1e-2 * scale * h):
        at = grid[int(np.argmax(gap / h))]
        raise InputError(f"the stored energy of model {model} is not the integral of its stress near strain "
                         f"{at:.6g} (a stress jump)", key="params",
                         expected="parameters in the law's range (trilinear: 0 < gamma_M < gamma_m)")
    return sig, w


def run_phase_boundary(system, options: dict, context: dict) -> dict:
    """The law, its spinodal and Maxwell stress, the equilibria under each elongation; see the module doc."""
    law = KernelLaw(system)
    low, high = options["strain_range"]
    grid = np.linspace(low, high, int(options["samples"]))
    sig, w = checked_law(law, grid)
    out: dict = {"phase_boundary": False, "maxwell_stress": None, "phase_strains": [], "spinodal_strains": [],
                 "equilibria": [], "law": {"strain": grid.tolist(), "stress": sig.tolist(), "energy_density": w.tolist()}}
    has_modulus = "modulus" in output_names(system)
    sp_ = phases.spinodal(law.stress, law.modulus if has_modulus else None, grid)
    if sp_ is None and np.any(np.diff(sig) < 0):
        raise InputError(f"the stress falls on strain_range [{low:g}, {high:g}] but does not rise again after it",
                         key="strain_range", expected="a wider range: both phases at every stress between valley and peak")
    if sp_ is None:
        out["note"] = (f"the stress increases over strains [{low:g}, {high:g}]: the stored energy is convex there, "
                       "so no phase boundary (no Maxwell stress, no two-phase equilibrium)")
        return out
    if not (sig[0] < sp_.sigma_b and sig[-1] > sp_.sigma_a):
        raise InputError(f"strain_range [{low:g}, {high:g}] holds stresses {sig[0]:.6g} to {sig[-1]:.6g} at its "
                         f"ends, not beyond the valley {sp_.sigma_b:.6g} and the peak {sp_.sigma_a:.6g}", key="strain_range",
                         expected="a wider range: both phases at every stress between valley and peak")
    m = phases.maxwell(law.stress, law.energy, sp_, low, high)
    length = law.constant("bar_length", 1.0)
    out.update({"phase_boundary": True, "maxwell_stress": m.stress, "phase_strains": [m.gamma_1, m.gamma_2],
                "spinodal_strains": [sp_.gamma_a, sp_.gamma_b], "peak_stress": sp_.sigma_a,
                "valley_stress": sp_.sigma_b})
    out["equilibria"] = [_equilibrium(law, sp_, m, (low, high), delta, length, options) for delta in options["elongation"]]
    return out


def _equilibrium(law: KernelLaw, sp_, m, span: tuple, delta: float, length: float, options: dict) -> dict:
    """The Maxwell equilibrium and the family under elongation ``delta`` of a bar of length ``length``."""
    e = delta / length
    nu = (e - m.gamma_1) / (m.gamma_2 - m.gamma_1)
    inside = 0.0 <= nu <= 1.0
    family = phases.equilibria(law.stress, law.energy, sp_, span[0], span[1], e, int(options["equilibrium_samples"]))
    family["boundary_position"] = [x * length for x in family["phase_fraction"]]
    return {"elongation": delta, "phase_fraction": nu if inside else None,
            "boundary_position": nu * length if inside else None,
            "driving_traction": phases.traction(law.energy, m.stress, m.gamma_1, m.gamma_2) if inside else None,
            "family": family}


def lines(outputs: dict) -> list[str]:
    """The Maxwell stress and strains, or the note; one line per equilibrium."""
    if not outputs["phase_boundary"]:
        return [f"    {outputs['note']}"]
    rows = summary.output_lines(outputs, skip=("law", "equilibria"))
    for eq in outputs["equilibria"]:
        where = ("one phase" if eq["phase_fraction"] is None else
                 f"phase-2 fraction {eq['phase_fraction']:.6g}, boundary at s = {eq['boundary_position']:.6g}")
        rows.append(f"    elongation {eq['elongation']:.6g}: {where}")
    return rows


register(AnalysisKind("phase_boundary", SCHEMA, run_phase_boundary, needs, lines, plot=phase_figures.law_figure))
