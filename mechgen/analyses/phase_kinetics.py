"""``phase_kinetics``: a phase boundary moving under its kinetic law in a bar pulled quasi-statically, as an
event-driven hybrid run.

For a hybrid model like the built-in ``phase_bar``: internal variables ``s`` (the boundary's position, m, phase 2
on 0 < x < s), ``gamma`` (the strain, W's argument), ``work`` and ``dissipated`` (J/m^2, int sigma d delta and
int f V dt carried with the state), modes ``phase_1`` -> ``two_phase`` (guard ``nucleation``: the stress reaches
``sigma_nucleation``) -> ``phase_2`` (guard ``arrival``: s reaches L) -> ``two_phase`` (``reversion``: the stress
falls to ``sigma_reversion``) -> ``phase_1`` (``retreat``: s reaches 0), and the outputs ``stress``, ``elongation``,
``driving_traction``, ``velocity``, ``stored_energy``, ``modulus``, and the parameters it checks as outputs
``nucleation_stress``, ``reversion_stress``. The kinetic law V = ds/dt = phi(f) is the
model's (``phase_bar``: f/eta). The run is ``simulate``'s hybrid path (mechgen.analyses.simulate_hybrid: events
located on the dense output, the compiled DOP853 loop), from t = 0 to ``t_end``.

Nucleation is a critical stress. A critical driving traction f_c is the same criterion: between valley and peak the
driving traction of the two phase strains at equal stress increases with the stress (df/dsigma = gamma_2 - gamma_1
> 0), so f_c names one stress sigma_c (``phase_boundary``'s ``family`` tabulates f(sigma); trilinear:
sigma_c = sigma_M + f_c/gamma_T).

Before it runs, the law is sampled on ``strain_range`` (mechgen.runtime.steady.phases): a law without two phases
there (a convex W) is bad input at ``params`` (no boundary can nucleate), and so are nucleation stresses outside
(sigma_M, peak) and reversion stresses outside (valley, sigma_M) (the boundary would never nucleate, or would move
the wrong way). After it, a strain past the peak or the valley (sigma' <= 0 at a sample: a boundary too slow for
the loading rate strains phase 1 onto the unstable branch) is bad input at ``params.eta``.

Outputs: ``t``, ``s``, ``stress``, ``elongation``, ``driving_traction`` (the time history at ``samples`` times:
the stress-elongation hysteresis loop and s(t)), ``events`` (simulate's log), ``nucleation_time``,
``arrival_time``, ``reversion_time``, ``retreat_time`` (the first event of each guard, null if none),
``maxwell_stress``, the dissipation check ``dissipated`` = int f V dt, ``work`` = int sigma d delta,
``stored_energy_change`` E(t_end) - E(0) (J/m^2) and ``dissipation_residual`` = work - stored_energy_change -
dissipated (zero to the integrator's tolerance).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import phase_figures, schema, summary
from mechgen.analyses.phase_boundary import KernelLaw, checked_law, strain_range
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import REQUIRED, Option
from mechgen.errors import InputError
from mechgen.runtime.steady import phases

GUARDS = {"nucleation_time": "nucleation", "arrival_time": "arrival", "reversion_time": "reversion",
          "retreat_time": "retreat"}
SERIES = ("s", "stress", "elongation", "driving_traction")

SCHEMA = {
    "t_end": Option(schema.positive, REQUIRED, "a positive time (s)", doc="end time of the run (s): 2 t_turn "
                    "for the ramp up and back"),
    "strain_range": Option(strain_range, REQUIRED, "two strains [low, high]", doc="the strains [low, high] the law "
                           "is sampled on to find its two phases and Maxwell stress (as phase_boundary's)"),
    "samples": Option(schema.count_within("samples"), 401, doc="how many equally spaced times the time history "
                      "holds"),
    "law_samples": Option(schema.count_within("samples"), 2001, doc="how many strains of strain_range sample the "
                          "law"),
    "rtol": Option(schema.positive, 1e-10, doc="relative tolerance of the integrator (DOP853)"),
    "atol": Option(schema.positive, 1e-12, doc="absolute tolerance of the integrator (the state's units)"),
    "loop": Option(schema.one_of("loop", ("auto", "python", "c")), "auto", doc="the event loop: auto (compiled "
                   "where it can run), python (scipy's steppers) or c"),
    "progress": Option(schema.boolean, False, doc="draw a progress bar on stderr"),
}


def needs(options: dict, *, internal: bool) -> set[str]:
    """simulate's kernels (every mode's, with the guards and resets)."""
    return {"residual", "tangent", "flow", "energy_rates", "outputs"} | ({"rates", "rates_tangent"} if internal else set())


def checked_phases(system, options: dict) -> phases.Maxwell:
    """The law's Maxwell stress, refusing a law without two phases and nucleation stresses outside their ranges."""
    law = KernelLaw(system)
    low, high = options["strain_range"]
    grid = np.linspace(low, high, int(options["law_samples"]))
    checked_law(law, grid)
    sp_ = phases.spinodal(law.stress, law.modulus, grid)
    model = system.metadata.model
    if sp_ is None:
        raise InputError(f"the law of model {model} has no two phases on strain_range [{low:g}, {high:g}] (its stress "
                         "increases: a convex stored energy), so no phase boundary can nucleate", key="params",
                         expected="a non-convex law (cubic: beta^2 > 3 c; trilinear: gamma_m - gamma_T < gamma_M)")
    m = phases.maxwell(law.stress, law.energy, sp_, low, high)
    for key, output, lo, hi in (("sigma_nucleation", "nucleation_stress", m.stress, sp_.sigma_a),
                                ("sigma_reversion", "reversion_stress", sp_.sigma_b, m.stress)):
        value = law.constant(output, 0.5 * (lo + hi))
        if not lo < value < hi:
            raise InputError(f"{key} = {value:.6g} of model {model} is outside ({lo:.6g}, {hi:.6g})",
                             key=f"params.{key}", expected=f"a stress between {lo:.6g} and {hi:.6g} (the Maxwell "
                             "stress and the law's peak for nucleation; its valley and the Maxwell stress for reversion)")
    return m


def run_phase_kinetics(system, options: dict, context: dict) -> dict:
    """The hybrid run and its reading; see the module doc."""
    from mechgen.analyses.simulate_hybrid import run_hybrid

    m = checked_phases(system, options)
    run = run_hybrid(system, {"t_end": options["t_end"], "samples": options["samples"], "method": "DOP853",
                              "rtol": options["rtol"], "atol": options["atol"], "loop": options["loop"],
                              "progress": options["progress"], "series": True}, context)
    traj = run["trajectory"]
    too_slow(system, run["t"], traj)
    out = {"t": list(run["t"]), **{k: list(traj[k]) for k in SERIES}, "events": run["events"],
           "maxwell_stress": m.stress}
    for key, guard in GUARDS.items():
        out[key] = next((e["t"] for e in run["events"] if e["guard"] == guard), None)
    energy = np.asarray(traj["stored_energy"], float)
    work, dissipated = float(traj["work"][-1]), float(traj["dissipated"][-1])
    out.update({"dissipated": dissipated, "work": work, "stored_energy_change": float(energy[-1] - energy[0]),
                "dissipation_residual": work - float(energy[-1] - energy[0]) - dissipated})
    return out


def too_slow(system, t, traj: dict) -> None:
    """Refuse (params.eta) a run whose strain left the stable branches: sigma' <= 0 at a sample."""
    modulus = np.asarray(traj["modulus"], float)
    if np.any(modulus <= 0):
        at = float(np.asarray(t)[int(np.argmax(modulus <= 0))])
        raise InputError(f"the strain of model {system.metadata.model} reached the falling branch of its law at "
                         f"t = {at:.6g}: the boundary moves too slowly for the loading rate", key="params.eta",
                         expected="a faster kinetic law (smaller eta) or a slower ramp (smaller rate)")


def lines(outputs: dict) -> list[str]:
    """The event times and the dissipation check."""
    return summary.output_lines(outputs, skip=SERIES + ("t", "events"))


register(AnalysisKind("phase_kinetics", SCHEMA, run_phase_kinetics, needs, lines, plot=phase_figures.kinetics_figure))
