"""The outputs of each analysis kind, for the reference pages (mechgen.analyses.reference).

One :class:`OutputDoc` per output: its name (the key of ``Result[...]`` and of the scene JSON's entry), its
shape, its unit and its meaning. Filled by hand from the kinds' module docstrings and the README until the
kinds declare their outputs beside their schemas; a kind not listed in :data:`OUTPUTS` gets a pointer to its
module docstring (:func:`outputs_of`). The names here are a contract: a test checks them against what the
kinds return (tests/test_docs_site.py).
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class OutputDoc:
    """One output: ``name``, ``shape`` (e.g. ``(count,)``, ``scalar``, ``{name: (samples,)}``), ``unit`` and
    ``meaning`` (reStructuredText)."""

    name: str
    shape: str
    unit: str
    meaning: str


def _o(name: str, shape: str, unit: str, meaning: str) -> OutputDoc:
    return OutputDoc(name, shape, unit, meaning)


MODEL_UNIT = "the model's"

OUTPUTS: dict[str, tuple[OutputDoc, ...]] = {
    "modes": (
        _o("frequencies", "(count,)", "rad/s (or the model's time unit)",
           "The natural frequencies of the elastic modes, ascending; with damping or gyroscopic terms, and "
           "for rotors, the damped natural frequencies."),
        _o("rigid_modes", "scalar (int)", "-", "How many rigid-body modes (K phi = 0 to the solver's accuracy); "
           "they are not among ``frequencies``, and ``count`` counts the elastic modes after them."),
        _o("rigid_shapes", "list of {coordinate: value}", MODEL_UNIT,
           "A lumped model's rigid-body modes, largest entry 1 (only when there are rigid modes)."),
        _o("operating_point", "{coordinate: value}", MODEL_UNIT,
           "The equilibrium Newton found, when the point given (``at``, or zero) was not one."),
        _o("s", "(points,)", "m (the field's length unit)", "A continuum's stations along s (with ``count``)."),
        _o("shapes", "(count, points) or list of {coordinate: {amplitude, phase}}", "-, phase in rad",
           "A continuum's mode shapes at ``s`` (with ``count``); a lumped model's damped modes: the complex "
           "shape X of each mode (q(t) = Re(X e^{st})) as amplitude \\|X_i\\| and phase arg X_i, the first "
           "largest amplitude 1 with phase 0 (mechgen.analyses.whirl)."),
        _o("eigenvalues", "(modes, 2)", "1/s", "Damped modes only: the eigenvalues s as [re, im] pairs."),
        _o("log_dec", "(modes,)", "-", "Damped modes only: the logarithmic decrement of each mode."),
        _o("whirl", "(modes,)", "-", "Rotors only: each mode's whirl, ``forward`` (counter-clockwise about "
           "z = x cross y), ``backward``, ``linear`` (a straight-line orbit) or ``none`` (the whirl stations at "
           "rest)."),
        _o("whirl_ratio", "(modes,)", "-", "Rotors only: the signed ratio b / a of the orbit's semi-axes (+1 a "
           "forward circle, -1 a backward one, 0 a line)."),
        _o("orbits", "list of {major, minor, angle}", "-, angle in rad", "Rotors only: per mode, the ellipse "
           "of the normalised shape at the whirl station with the largest orbit (semi-axes and the major "
           "axis's angle from x towards y)."),
    ),
    "stability": (
        _o("eigenvalues", "(n, 2)", "1/s", "The eigenvalues s of M q'' + (D + G) q' + K q = 0 as [re, im] "
           "pairs (with ``count``: the 2 count of smallest \\|s\\|)."),
        _o("verdict", "string", "-", "``stable``, ``neutral`` (stable apart from rigid-body modes), "
           "``divergence``, ``flutter`` or ``unconverged``."),
        _o("frequencies", "(count,)", "rad/s", "The lowest natural frequencies, Im s of the modes."),
        _o("growth_rate", "scalar", "1/s", "The largest Re s of the modes that are not rigid."),
        _o("rigid_modes", "scalar (int)", "-", "How many rigid-body modes."),
        _o("unstable", "{real, complex}", "-", "How many eigenvalues have Re s above their threshold (complex "
           "ones counted once per pair)."),
        _o("operating_point", "{coordinate: value}", MODEL_UNIT,
           "The equilibrium Newton found, when the given point was not one."),
        _o("refinement", "table", "-", "With ``refine``: sizes, verdicts, ``unstable`` and growth rates at N "
           "and 2N and whether they agree to ``refine_rtol`` (``growth_rate_converged``)."),
    ),
    "steady": (
        _o("iterations", "scalar (int)", "-", "Newton iterations (or the BVP solver's)."),
        _o("residual_norm", "scalar", "the residual's", "The norm of the residual at the answer."),
        _o("coordinates", "{coordinate: value}", MODEL_UNIT, "A lumped model's equilibrium."),
        _o("<output>", "scalar", "the output's", "Each model output (with the built-in ``kinetic_energy``, "
           "``potential_energy`` and ``energy``) at the equilibrium (Newton), or at the ends and its extremes "
           "along s (a boundary value problem)."),
        _o("s", "(points,)", "m", "A continuum's stations along s."),
        _o("deflection", "(points,)", MODEL_UNIT, "A continuum's steady deflection at ``s``."),
        _o("reactions", "table", MODEL_UNIT, "A continuum solved by Newton: the constraint reactions."),
    ),
    "simulate": (
        _o("t", "(samples,)", "s", "The sample times, from 0 to ``t_end`` (or to where the run stopped)."),
        _o("trajectory", "{name: (samples,)}", "each coordinate's and output's",
           "The time history: each coordinate, ``<coordinate>_dot``, internal variable and model output at "
           "``t`` (numpy arrays through ``result['trajectory']['x']``), with ``energy_series``; left out for a "
           "very large state unless ``series = true``."),
        _o("<output>", "scalar", "the output's", "Each model output and the built-in ``kinetic_energy``, "
           "``potential_energy`` and ``energy`` at ``t_end``."),
        _o("energy_series", "(samples,)", "J (the model's energy unit)", "The energy E = T + V at ``t`` (with "
           "``trajectory``)."),
        _o("series_note", "string", "-", "Why the time history was left out (a very large state)."),
        _o("energy_drift", "scalar", "-",
           "A conservative run: max \\|E - E(0)\\| / max(\\|T\\| + \\|V\\|) over the samples."),
        _o("energy_balance_error", "scalar", "-", "A run with forcing or dissipation: max_t \\|h(t) - h(0) - W(t) + "
           "D(t)\\| / S, S = max_t (\\|T\\| + \\|V\\|, \\|W\\|, D) (mechgen.analyses.energy_balance)."),
        _o("work", "scalar", "J (the model's energy unit)", "The work done on the system by forces and by "
           "explicit time dependence, integrated with the state."),
        _o("dissipated", "scalar", "J (the model's energy unit)", "The energy dissipated by the dissipation "
           "function and, for a hybrid model, taken by the resets (the flow's part integrated through every "
           "mode and carried across the events)."),
        _o("t_end", "scalar", "s", "The end time asked for."),
        _o("method", "string", "-", "The integrator that ran (``auto`` resolved)."),
        _o("loop", "string", "-", "The loop that stepped it: ``c`` (compiled) or ``python``."),
        _o("mode_energies", "(modes,)", "J", "A fixed-end chain: the energy of each normal mode at ``t_end``."),
        _o("events", "list of {t, from, to, guard}", "s", "A hybrid model: each event (a guard crossed and the "
           "mode switch it makes)."),
        _o("final_mode", "string", "-", "A hybrid model: the mode at the end."),
        _o("t_final", "scalar", "s", "A hybrid model: where the run ended (before ``t_end`` at a terminal "
           "event or a Zeno stop)."),
        _o("mode_series", "(samples,)", "-", "A hybrid model: the mode at each sample time."),
        _o("energy_note", "string", "-", "Why a run gives no energy figure: a hybrid model with forces or "
           "dissipation compiled without its modes' ``energy_rates`` kernels (their work is not integrated)."),
        _o("zeno", "bool", "-", "``on_zeno = \"stop\"``: whether the run ended at a Zeno accumulation point."),
    ),
    "sweep": (
        _o("grid", "list of {parameter: value}", "the parameters'", "The grid's points, the first parameter "
           "outermost."),
        _o("<inner output>", "(points, ...)", "the inner analysis's", "One list per output of the inner "
           "analysis, in grid order (None at a failed point)."),
        _o("status", "(points,)", "-", "Per point: ``ok`` or ``failed: <error>``."),
        _o("failed", "scalar (int)", "-", "How many points failed."),
        _o("retried", "list of {parameter: value}", "-", "The points run again after a Dask worker was lost."),
        _o("executor", "string", "-", "What ran the points: ``serial``, ``processes`` or ``dask``."),
        _o("tasks", "scalar (int)", "-", "What the executor ran: points, or Dask chunks."),
    ),
    "campbell": (
        _o("speeds", "(speeds,)", "rad/s (the swept parameter's)", "The spin speeds."),
        _o("frequencies", "(speeds, count)", "rad/s", "The damped natural frequencies at each speed, tracked "
           "across speeds."),
        _o("whirl", "(speeds, count)", "-", "Each tracked mode's whirl direction at each speed."),
        _o("log_dec", "(speeds, count)", "-", "Each tracked mode's logarithmic decrement at each speed."),
        _o("critical_speeds", "list", "rad/s", "Where a whirl frequency crosses a multiple of the speed "
           "(``multiples``)."),
        _o("parameter", "string", "-", "The swept parameter's name."),
        _o("method", "string", "-", "``exact`` or ``reduced``: what ran."),
        _o("exact_solves", "scalar (int)", "-", "How many full-size eigen-solves ran."),
        _o("executor", "string", "-", "Where the per-speed solves ran."),
    ),
}


def outputs_of(kind: str) -> tuple[OutputDoc, ...]:
    """The documented outputs of ``kind``; empty for a kind not documented here yet (its page then points to
    its module docstring)."""
    return OUTPUTS.get(kind, ())
