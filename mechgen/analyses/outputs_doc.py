"""The outputs of each analysis kind, for the reference pages (mechgen.analyses.reference).

One :class:`OutputDoc` per output: its name (the key of ``Result[...]`` and of the scene JSON's entry), its
shape, its unit and its meaning. Filled by hand from the kinds' module docstrings until the kinds declare their
outputs beside their schemas; every registered kind has its table (a kind left out would get a pointer to its
module docstring, :func:`outputs_of`, and fails the test). A name may hold placeholders: ``<output>`` (a model
output), ``<parameter>``, ``<alias>`` (a name of the analysis's ``aliases``), ``<field>``, ``<shape output>``
and ``<end>`` (start, end, max or min). The names here are a contract: tests/test_docs_site.py runs the shipped
scenes and checks that every output a kind returns matches a documented name.
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
        _o("modal_mass", "(count,)", "the model's mass unit (kg, kg m^2 ...)", "A lumped model's undamped modes: "
           "phi^T M phi of each mass-normalised shape (1 to round-off)."),
        _o("modal_stiffness", "(count,)", "(rad/s)^2 times the modal mass", "A lumped model's undamped modes: "
           "phi^T K phi = omega^2."),
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
        _o("roundoff_bound", "scalar", "-", "A continuum's undamped modes: the bound on the lowest frequency's "
           "relative error from round-off in the assembled M and K (about eps (omega_max / omega_1)^2, growing "
           "as N^4 for a beam; mechgen.runtime.linear.modes.roundoff_bound); above ``roundoff_rtol`` the run is "
           "refused at params.N."),
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
           "and 2N and whether they agree to ``refine_rtol`` (``growth_rate_converged``), and a continuum's "
           "``roundoff_bounds`` at N and 2N."),
        _o("roundoff_bound", "scalar", "-", "A continuum (without internal variables): the bound on the lowest "
           "frequency's relative error from round-off in the assembled M and K, as modes' (lam = min \\|s\\|^2, "
           "the spread from the symmetric pencil's lowest mode); above ``roundoff_rtol``, at N or at the 2N check, "
           "the run is refused at params.N."),
    ),
    "steady": (
        _o("iterations", "scalar (int)", "-", "Newton iterations (or the BVP solver's)."),
        _o("residual_norm", "scalar", "the residual's", "The norm of the residual at the answer."),
        _o("coordinates", "{coordinate: value}", MODEL_UNIT, "A lumped model's equilibrium."),
        _o("<output>", "scalar", "the output's", "Each model output (with the built-in ``kinetic_energy``, "
           "``potential_energy`` and ``energy``) at the equilibrium (Newton), or at the ends and its extremes "
           "along s (a boundary value problem)."),
        _o("s", "(points,)", "m", "A continuum's stations along s."),
        _o("deflection", "(points,) or {field: (points,)}", MODEL_UNIT, "A continuum's steady deflection at "
           "``s`` (per field for a boundary value problem)."),
        _o("reactions", "table", MODEL_UNIT, "A continuum solved by Newton: the constraint reactions; a plane "
           "model's {boundary: {field: force}}, the force each held boundary exerts on the body (N per unit "
           "thickness)."),
        _o("<output>_<end>", "scalar", "the output's", "A boundary value problem: each model output at the ends "
           "(``_start``, ``_end``) and its extremes along s (``_max``, ``_min``), e.g. ``tension_start`` "
           "(mechgen.analyses.bvp_states)."),
        _o("<field>_s_<end>", "scalar", MODEL_UNIT, "A boundary value problem: each field's slope at the ends "
           "(``x_s_start``, ``x_s_end``)."),
        _o("<shape output>", "scalar", "-", "A boundary value problem: each shape output the model declares "
           "(``Model.shape_output``: the balloon's ``loops``)."),
        _o("<alias>", "as its target", "its target's", "Each name of ``aliases``: the output it names, reported "
           "again under the scene's name."),
        _o("method", "string", "-", "A boundary value problem: the method that solved it (``shooting``, "
           "``multiple_shooting``, ``collocation``)."),
        _o("verdict", "string", "-", "With ``stability``: the Galerkin verdict about the state (as "
           ":doc:`stability`'s)."),
        _o("frequencies", "(modes,)", "rad/s", "With ``stability``: the lowest frequencies of the linearisation "
           "(at most 10)."),
        _o("eigenvalues", "(n, 2)", "1/s", "With ``stability``: the eigenvalues as [re, im] pairs."),
        _o("<point>_displacement", "(fields,)", MODEL_UNIT, "A plane model: the fields' values ([u_x, u_y]) at "
           "each point of ``points`` (``center_displacement``)."),
        _o("<point>_stress", "(fields, 2)", "Pa (the energy density's unit)", "A plane model with gradients: "
           "dV/d(grad u) at each point of ``points``, rows per field, columns d/dx, d/dy ([[s_xx, s_xy], "
           "[s_yx, s_yy]], Cauchy's stress for a linear law)."),
        _o("probe_displacement", "(points, fields)", MODEL_UNIT, "A plane model: the fields' values at each "
           "point of ``probe``."),
        _o("nodal", "table", MODEL_UNIT, "A plane model with ``nodal = true``: the state at every node, {x, y, "
           "displacement {field: (n,)}, gradient {field: (n, 2)}, stress {field: (n, 2)} (dV/d(grad u)), strain "
           "{xx, yy, xy} (a displacement's symmetric gradient)}; gradients averaged over the cells at a node."),
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
    "continuation": (
        _o("parameter", "string", "-", "The continued parameter's name."),
        _o("branch", "list of {<parameter>, <output>_<end> ..., verdict}", "the outputs'",
           "One entry per branch point: the parameter's value, the outputs (at the ends and extremes for a "
           "boundary value problem, the model's outputs and ``coordinates`` for Newton), the shape outputs, "
           "the aliases, ``verdict`` (with ``stability``), ``eigenvalues`` (with ``eigenvalues = true``) and "
           "``start`` (with several starts)."),
        _o("points", "scalar (int)", "-", "How many branch points."),
        _o("status", "string, or {start: string}", "-", "Why the branch ended (``lam_max``, ``bounds``, "
           "``max_points`` ...; per start with several; about an autonomous ``periodic_orbit``, ``equilibrium``: "
           "the orbits shrank onto an equilibrium, a Hopf point, and the branch ends at its smallest orbit, or at its "
           "last orbit before a step that passed through the equilibrium)."),
        _o("folds", "list of branch points", "the outputs'", "The turning points in the parameter."),
        _o("stability_changes", "list of {..., from, to}", "the outputs'", "With ``stability``: where the "
           "verdict changes between consecutive points, located by bisection along the branch."),
        _o("special_points", "list of {type, <parameter>, coordinates, ...}", "the outputs'",
           "With ``special_points`` (default): the located special points in branch order, ``type`` ``LP`` "
           "(fold), ``BP`` (branch point, with ``direction``: the other branch's unit direction per coordinate "
           "and the parameter) or ``H`` (Hopf, with stability: ``frequency`` of the critical pair +-i omega in "
           "rad per unit of the model's time, ``lyapunov`` the first Lyapunov coefficient l1 with Kuznetsov's "
           "normalisation, ``criticality`` ``supercritical`` (l1 < 0), ``subcritical`` (l1 > 0) or "
           "``degenerate`` (l1 zero to working precision: a linear model)); a boundary value "
           "problem's branch reports its folds (LP)."),
        _o("switched_branches", "list of {at, half, branch, status}", "the outputs'", "With "
           "``switch_branches = true``: the other branch through every BP, both ways (``half`` ``+`` or ``-``; "
           "``at``: the BP's position in ``special_points``, from 1; ``branch``: its points as in ``branch``)."),
        _o("method", "string", "-", "About a ``periodic_orbit``: the orbit's method (``harmonic_balance``, "
           "``collocation`` or ``shooting``) the branch is continued by."),
        _o("branch (orbits)", "list of {<parameter>, period, frequency, amplitude, start, multipliers, stability}",
           "s, rad/s, coordinates'", "About a ``periodic_orbit``: one entry per orbit of the branch: the parameter, "
           "the period T, 2 pi / T, ``amplitude`` ({coordinate: max \\|q\\| over the period}, then each internal "
           "variable's), ``start`` (the state at t = 0: each coordinate and ``<coordinate>_dot``, then each internal "
           "variable), the Floquet ``multipliers`` ([re, im] by "
           "decreasing modulus) and ``stability``; its ``special_points`` are ``LPC`` (cyclic fold), ``PD`` (period "
           "doubling: a multiplier through -1) and ``NS`` (a complex pair through the unit circle, with ``angle``)."),
        _o("doubled", "list of {at, <parameter>, amplitude, period, start, multipliers, stability}", "the outputs'",
           "About a forced ``periodic_orbit`` (by harmonic balance, collocation or shooting; or a hybrid model's), "
           "with ``switch_branches = true``: the period-2T orbit just past every PD point (``at``: the PD's position "
           "in ``special_points``, from 1), at the parameter half-way to the next branch point on the side where the "
           "period-T orbit has a multiplier below -1, by the orbit's own method over 2T (harmonic balance: 2H "
           "harmonics of omega / 2; collocation: the mesh repeated)."),
        _o("backbone", "{frequency, period, amplitude: {coordinate: (points,)}, energy, unfolding}",
           "rad/s, s, the coordinates', J, force per velocity", "About the free orbit of a conservative model (a "
           "``periodic_orbit`` without ``frequency``): the family's branch as columns, one entry per point: the "
           "orbit's frequency 2 pi / T, period, ``amplitude`` (max \\|q\\| per coordinate), ``energy`` (T + V, the "
           "model's ``energy`` output) and ``unfolding`` (the Munoz-Almaraz parameter eps, zero to the corrector's "
           "tolerance); the points of ``branch`` carry ``energy`` and ``unfolding`` too. With ``parameter = "
           "\"amplitude\"`` the backbone curve (frequency against amplitude), each point's ``level`` its "
           "q_p(0). A continued model parameter whose name is an output's keeps its name; that output is then "
           "``orbit_<name>``."),
        _o("curve", "list of {<first>, <second>, coordinates, ..., frequency}", "the outputs'", "With "
           "``special_point`` (``about`` an earlier continuation): the curve of its LP or H in two parameters, "
           "one entry per point with both parameters, ``coordinates``, the model's outputs and, on an H curve, "
           "``frequency`` (omega of the pair +-i omega); about a branch of orbits, the curve of its LPC, each "
           "point with both parameters and the orbit's ``period``, ``amplitude``, ``start``, ``multipliers``."),
        _o("type", "string", "-", "With ``special_point``: ``LP`` or ``H``, the kind of point the curve follows."),
        _o("hopf", "{<parameter>, frequency, lyapunov, growth_rate_slope, start_parameter}", "the parameter's, "
           "rad/s", "With ``special_point`` an H point and ``parameter`` the earlier continuation's own: the Hopf "
           "point the branch of limit cycles (``branch``, as about a ``periodic_orbit``) starts from, d Re(lambda)/dp "
           "there and the parameter of the first cycle."),
        _o("parameters", "list of two strings", "-", "With ``special_point``: the earlier continuation's "
           "parameter and the second one."),
        _o("shape_outputs", "list of strings", "-", "The shape outputs reported at every point."),
        _o("at_<output>", "list of {<parameter>, <output>, ..., verdict, refinement}", "the outputs'",
           "With ``at = {output = value}``: the points where the output crosses the value, sorted by the "
           "parameter; the verdict holds when the model discretised with 2N and 4N terms agrees."),
        _o("at_<output>_shapes", "list of {field: (101,)}", MODEL_UNIT, "The fields at each ``at_<output>`` "
           "point (for plots)."),
        _o("<output>_min", "scalar", "the output's", "With ``minimize``: the least value of the output along "
           "the branch."),
        _o("<parameter>_at_<output>_min", "scalar", "the parameter's", "With ``minimize``: the parameter where "
           "the output is least."),
        _o("<alias>", "as its target", "its target's", "Each name of ``aliases`` that names an analysis output "
           "(``balloons_at_tension = \"at_p_e\"``)."),
    ),
    "response": (
        _o("omega", "(frequencies,)", "rad/s", "The driving frequencies (with ``unbalance``: the spin speeds), in "
           "rad/s whatever ``speed_unit`` the scene writes them in."),
        _o("input", "string", "-", "With ``input``: the coordinate the unit force drives."),
        _o("amplitude", "{coordinate: (frequencies,)}", "coordinate per unit force (m/N ...) with ``input``; the "
           "coordinate's (m, rad) with ``force`` or ``unbalance``",
           "\\|X_k\\| of the response q_k(t) = \\|X_k\\| cos(omega t + phase_k) for each output coordinate k: "
           "with ``input`` the receptance's magnitude \\|H_kj(omega)\\|, else \\|(H(omega) f)_k\\|."),
        _o("phase", "{coordinate: (frequencies,)}", "rad", "arg X_k: the response's phase relative to the "
           "forcing's reference cos(omega t) (the unit force, a force pattern's phase 0, an unbalance's shaft angle "
           "Omega t); negative: the response lags."),
        _o("forcing", "string", "-", "Which forcing was applied: ``input``, ``force`` or ``unbalance``."),
        _o("speed_unit", "string", "-", "The unit the scene wrote its frequencies or speeds in (``rad/s``, "
           "``Hz`` or ``rpm``)."),
        _o("omega_in_unit", "(frequencies,)", "``speed_unit``", "``omega`` expressed in ``speed_unit`` (the plots' "
           "axis)."),
        _o("speeds", "(frequencies,)", "rad/s", "With ``unbalance``: the spin speeds (equal to ``omega``: an "
           "unbalance drives at the speed), as campbell names them."),
        _o("parameter", "string", "-", "With ``unbalance``: the speed parameter the matrices were re-linearised "
           "in at each speed."),
        _o("orbit", "{\"x,y\": {major, minor, angle, whirl, whirl_ratio: (frequencies,)}}",
           "the coordinates' (m); angle rad", "Per coordinate pair (``orbits``; default the unbalances' pairs): "
           "the ellipse x = Re(X_x e^{i omega t}), y = Re(X_y e^{i omega t}) at each frequency: ``major`` and "
           "``minor`` semi-axes, ``angle`` of the major axis from x towards y, ``whirl`` forward, backward (the "
           "sign of the angular momentum x y' - y x'), linear (a straight line) or none (at rest), "
           "``whirl_ratio`` the signed minor / major."),
        _o("orbit_at", "(picked,)", "rad/s", "The frequencies whose orbits the orbit figure draws (the computed "
           "ones nearest the scene's ``orbit_at``, else up to five spread over the range and the largest)."),
    ),
    "fit": (
        _o("<parameter>", "scalar, or (groups,)", "the parameter's", "Each estimated parameter (a list per "
           "group when grouped)."),
        _o("<parameter>_stderr", "scalar, or (groups,)", "the parameter's", "Its standard error sqrt(diag C) "
           "(null without a degree of freedom, or when the data cannot determine it)."),
        _o("residuals", "(rows,)", "the observed column's", "y - f at the estimate, in row order."),
        _o("fitted", "(rows,)", "the observed column's", "f at the estimate."),
        _o("observed", "(rows,)", "the observed column's", "The observed column y."),
        _o("rms", "scalar", "the observed column's", "The root mean square of the residuals, all rows."),
        _o("dof", "scalar (int), or (groups,)", "-", "Degrees of freedom n - p (per group)."),
        _o("covariance", "(p, p), or (groups, p, p)", "the parameters' squared", "C = s^2 (J^T J)^-1 (per "
           "group)."),
        _o("groups", "(groups,)", "the group column's", "With ``group``: the distinct values, in first-"
           "appearance order."),
        _o("group_rows", "(groups, rows)", "-", "With ``group``: the 1-based rows of each group."),
        _o("converged", "bool", "-", "Whether least_squares reported convergence."),
        _o("message", "string", "-", "least_squares' status message."),
        _o("evaluations", "scalar (int)", "-", "Evaluations of the model on all rows (the Jacobian's "
           "included)."),
        _o("x_column", "string", "-", "The first input or column of the expression (the plot's abscissa)."),
        _o("x_values", "(rows,)", "that column's", "Its values, in row order."),
    ),
    "impact": (
        _o("restitution", "scalar", "-", "e = -v_r / v_c along ``coordinate`` (0 with no release)."),
        _o("contact_duration", "scalar", "s", "t_r - t_c, from contact to release (to ``t_end`` with no "
           "release)."),
        _o("energy_lost", "scalar", "-", "1 - E(t_r) / E(t_c), the fraction of the energy at contact lost "
           "(the contact's stored energy included)."),
        _o("released", "bool", "-", "Whether the body left the contact before ``t_end``."),
        _o("penetration_series", "(samples,)", MODEL_UNIT, "With ``curve``: the coordinate over the contact."),
        _o("force_series", "(samples,)", "N (the output's)", "With ``curve``: the output ``force_output`` over "
           "the contact (the force-penetration hysteresis)."),
    ),
    "restitution": (
        _o("<parameter>", "(values,)", "the parameter's", "The numeric parameter's grid values, under its own "
           "name (``zeta``)."),
        _o("restitution", "{choice: (values,)} or (values,)", "-", "e per choice (``kelvin_voigt`` ...), "
           "aligned with the numeric parameter (a plain list without a choice parameter)."),
        _o("contact_duration", "{choice: (values,)} or (values,)", "s", "The contact durations, aligned as "
           "``restitution``."),
        _o("energy_lost", "{choice: (values,)} or (values,)", "-", "The fractions of the energy lost."),
        _o("released", "{choice: (values,)} or (values,)", "-", "Whether each impact released."),
        _o("hysteresis", "{choice: list of {<parameter>, penetration, force}}", "the model's; N",
           "Force-penetration curves at ``hysteresis`` values of the numeric parameter."),
        _o("impacts", "scalar (int)", "-", "How many impacts ran (the analysis's ``seconds`` over it: the time "
           "per impact)."),
    ),
    "stability_boundary": (
        _o("<parameter>_critical", "scalar", "the parameter's", "p_c, where the steady state loses its "
           "stability."),
        _o("frequency_critical", "scalar", "rad/s", "\\|Im s\\| of the eigenvalue that crosses at p_c (0 for a "
           "real crossing)."),
        _o("crossing", "string", "-", "``complex`` (an oscillation sets in: a Hopf bifurcation) or ``real`` (a "
           "divergence)."),
        _o("eigenvalues_critical", "(n, 2)", "1/s", "The eigenvalues at p_c as [re, im] pairs."),
        _o("verdict", "string", "-", "At the system's own value of the parameter: stable, neutral, divergence "
           "or flutter, or the scene's word for it (``labels``)."),
        _o("growth_rate", "scalar", "1/s", "At the system's own value: max Re s."),
        _o("eigenvalues", "(n, 2)", "1/s", "At the system's own value: the eigenvalues as [re, im] pairs."),
        _o("iterations", "scalar (int)", "-", "Iterations of Brent's method or of the bisection."),
        _o("method", "string", "-", "``growth_rate`` (Brent on max Re s) or ``bisection`` (on the verdict)."),
    ),
    "spectrum": (
        _o("natural_frequencies", "(modes,)", "Hz", "The retained modes' natural frequencies."),
        _o("spectrum_peaks", "(peaks,)", "Hz", "The most prominent maxima of the log amplitude below f_max, "
           "ascending."),
        _o("frequency_bin", "scalar", "Hz", "1 / record length."),
        _o("impulses", "scalar (int)", "-", "How many blows."),
        _o("impulse_rate", "scalar", "Hz", "v / lambda, the blows' rate."),
        _o("frequency", "(bins,)", "Hz", "The spectrum's frequencies, up to f_max."),
        _o("amplitude", "(bins,)", "the response's", "The windowed (Hann) spectrum's amplitude."),
        _o("t", "(samples,)", "s", "The record's times (at most ``series`` points, evenly thinned)."),
        _o("response", "(samples,)", "m (or m/s with ``signal = \"velocity\"``)", "The response u(t) at "
           "``observe`` (or the coordinate ``output``)."),
        _o("reference_frequencies", "(modes,)", "Hz", "With ``reference``: the frequencies given."),
        _o("frequency_ratio", "(modes,)", "-", "With ``reference``: ours / theirs, mode by mode."),
    ),
    "periodic": (
        _o("energy_per_cycle", "scalar", "J", "W = integral of f dx over the steady period (the loop area)."),
        _o("equivalent_stiffness", "scalar", "N/m", "k_eq = Re(F1 / X1), the first harmonic's stiffness."),
        _o("equivalent_damping", "scalar", "N s/m", "c_eq = Im(F1 / X1) / omega."),
        _o("steady_period", "scalar (int)", "-", "k: the period [(k-1)T, kT] used."),
        _o("periodicity_error", "scalar", "the state's", "max \\|y(kT) - y((k-1)T)\\| over the state and the "
           "loop point."),
        _o("cycle_events", "list of {t, from, to, guard}", "s", "The events of that period."),
        _o("displacement_series", "(samples,)", "m", "With ``curve``: the loop's displacement."),
        _o("force_series", "(samples,)", "N", "With ``curve``: the loop's force."),
    ),
    "periodic_orbit": (
        _o("period", "scalar", "s (or the model's time unit)", "T: 2 pi / ``frequency`` of a forced orbit; found "
           "with an autonomous one."),
        _o("frequency", "scalar", "rad/s", "omega = 2 pi / T: the forcing's, or the limit cycle's found."),
        _o("t", "(samples,)", "s (or the model's time unit)", "One period, ``samples`` equally spaced times from 0 "
           "to T."),
        _o("trajectory", "{name: (samples,)}", MODEL_UNIT, "The orbit at ``t``, named as simulate's: each "
           "coordinate, ``<coordinate>_dot``, each internal variable and the model's outputs."),
        _o("amplitude", "{coordinate: value}", MODEL_UNIT, "max \\|q\\| over the period (the largest of 4096 phases, "
           "refined by the parabola through it and its neighbours; a hybrid orbit's not across an event, whose "
           "states count too), then each internal variable's."),
        _o("harmonics", "{coordinate: {mean, cos, sin, amplitude, phase}}", "the coordinate's; phase in rad",
           "The Fourier coefficients of each coordinate, k = 1..H: q = mean + sum_k a_k cos(k omega t) + b_k "
           "sin(k omega t) = mean + sum_k amplitude_k cos(k omega t + phase_k) (``cos`` a_k, ``sin`` b_k, "
           "``amplitude`` sqrt(a_k^2 + b_k^2), ``phase`` atan2(-b_k, a_k))."),
        _o("multipliers", "(2n + m, 2)", "-", "The Floquet multipliers (eigenvalues of the monodromy matrix; "
           "collocation's from its own equations) as [re, im] pairs, by decreasing modulus (a conjugate pair: the "
           "positive imaginary part first)."),
        _o("stability", "string", "-", "``stable`` (every multiplier \\|mu\\| <= 1 + 1e-6, an autonomous "
           "orbit's trivial one set aside, a conservative model's free orbit's two nearest 1) or ``unstable``."),
        _o("method", "string", "-", "``harmonic_balance``, ``shooting`` or ``collocation``: the method that ran."),
        _o("residual", "scalar", "force units (harmonic balance), the state's (shooting), mixed (collocation: "
           "q's rate and force units; with internal variables each row times its interval's width)",
           "\\|\\|R\\|\\|_inf at the solution."),
        _o("iterations", "scalar (int)", "-", "Newton steps taken."),
        _o("unfolding", "scalar", "force per velocity (shooting: the state's per J)", "The free orbit of a "
           "conservative model (no ``frequency``, a model that keeps its energy): the unfolding parameter eps of "
           "Munoz-Almaraz et al. (2003) solved beside the orbit, zero to Newton's tolerance on it."),
        _o("energy", "scalar", "J (the model's energy unit)", "The free orbit of a conservative model: its energy "
           "T + V (the model's ``energy`` output), constant along it."),
        _o("loop", "string", "-", "``c``: shooting's integrations ran in the compiled DOP853 loop (the monodromy "
           "for Newton by central differences of it; a forced orbit's later segments, with ``segments`` > 1, in "
           "scipy's); ``python``: in scipy's DOP853 (harmonic balance's multipliers, and ``loop = \"python\"``), or "
           "no integration (collocation)."),
        _o("events", "list of {t, guard, from, to}", "s", "A hybrid model's orbit: the events of one period (its "
           "time from the orbit's start, the guard, the modes left and entered)."),
        _o("grazing", "list of strings", "-", "A hybrid model's orbit: the guards of the events that touch their "
           "surface tangentially (\\|dg/dt\\| < 1e-3 \\|g_x\\| \\|f\\|), where the saltation matrix and the "
           "multipliers are not to be trusted."),
        _o("section", "string", "-", "An autonomous hybrid orbit: the guard whose event is its Poincare section "
           "(the orbit starts, t = 0, just after that event and ends just after the next)."),
        _o("start_mode", "string", "-", "An autonomous hybrid orbit: the mode the orbit starts in (the one the "
           "section's event leads to)."),
    ),
    "phase_boundary": (
        _o("phase_boundary", "scalar (bool)", "-", "Whether the law's stress rises, falls and rises again on "
           "``strain_range`` (a non-convex stored energy): false means no phase boundary, and ``note`` says why."),
        _o("note", "string", "-", "With no phase boundary: why (the stress increases over the range)."),
        _o("maxwell_stress", "scalar or null", "Pa", "The Maxwell stress: the two phases' driving traction "
           "f = [[W]] - sigma [[gamma]] vanishes there (equal areas); null without a phase boundary."),
        _o("phase_strains", "(2,) or []", "-", "The phase strains [gamma_1, gamma_2] at the Maxwell stress."),
        _o("spinodal_strains", "(2,) or []", "-", "The strains of the stress's peak and valley (sigma' = 0)."),
        _o("peak_stress", "scalar", "Pa", "The stress at the peak ending phase 1."),
        _o("valley_stress", "scalar", "Pa", "The stress at the valley starting phase 2."),
        _o("equilibria", "list of {elongation, phase_fraction, boundary_position, driving_traction, family}",
           "m, -, m, Pa", "Per ``elongation``: the Maxwell equilibrium with one boundary (phase 2 on 0 < x < s; null "
           "entries when one phase holds the mean strain) and ``family``, the two-phase equilibria at stresses "
           "between valley and peak with their interface's driving traction."),
        _o("law", "{strain, stress, energy_density: (samples,)}", "-, Pa, Pa", "The law at the samples of "
           "``strain_range``."),
    ),
    "phase_kinetics": (
        _o("t", "(samples,)", "s", "The sample times."),
        _o("s", "(samples,)", "m", "The phase boundary's position s(t) (phase 2 on 0 < x < s)."),
        _o("stress", "(samples,)", "Pa", "The bar's stress: with ``elongation``, the hysteresis loop."),
        _o("elongation", "(samples,)", "m", "The end's displacement delta(t)."),
        _o("driving_traction", "(samples,)", "Pa", "The boundary's driving traction f (0 without a boundary)."),
        _o("events", "list of {t, from, to, guard}", "s", "The run's events (nucleation, arrival, reversion, "
           "retreat), as simulate's."),
        _o("nucleation_time", "scalar or null", "s", "The first nucleation of phase 2 (null if none)."),
        _o("arrival_time", "scalar or null", "s", "The first arrival of the boundary at the end x = L (null if "
           "none)."),
        _o("reversion_time", "scalar or null", "s", "The first nucleation of phase 1 at x = L (null if none)."),
        _o("retreat_time", "scalar or null", "s", "The first return of the boundary to x = 0 (null if none)."),
        _o("maxwell_stress", "scalar", "Pa", "The law's Maxwell stress (as phase_boundary's)."),
        _o("dissipated", "scalar", "J/m^2", "int f V dt over the run, integrated with the state."),
        _o("work", "scalar", "J/m^2", "int sigma d delta over the run, integrated with the state."),
        _o("stored_energy_change", "scalar", "J/m^2", "E(t_end) - E(0), E = int_0^L W dx."),
        _o("dissipation_residual", "scalar", "J/m^2", "work - stored_energy_change - dissipated: zero to the "
           "integrator's tolerance (the dissipation check)."),
    ),
    "cross_section": (
        _o("K", "(6, 6)", "N, N m, N m^2", "The section's stiffness ordered [K_uu, K_uw; K_wu, K_ww]."),
        _o("eigenvalues", "(6,)", "mixed (K's)", "K's eigenvalues, ascending."),
    ),
    "symplectic": (
        _o("energy_error", "scalar", "-", "max \\|E(t) - E(0)\\| / \\|E(0)\\| over the outputs."),
        _o("steps_per_second", "scalar", "1/s", "The loop's steps over its wall time (transforms excluded)."),
        _o("bandwidth_fraction", "scalar", "-", "Deprecated (use ``bandwidth_share``): the bandwidth bound of a "
           "step over its measured time, counting 64 N bytes per leapfrog step against a one-thread copy."),
        _o("bytes_per_step", "scalar", "B", "What the C loop's step streams: 80 N for the leapfrog (88 N with "
           "masses), 8 N per array read or written."),
        _o("bandwidth_share", "scalar", "-", "bytes_per_step x steps_per_second over the all-core copy "
           "bandwidth: the share of the machine's memory bandwidth the loop reaches."),
        _o("loop", "string", "-", "``c`` or ``numpy``."),
        _o("steps", "scalar (int)", "-", "Steps taken."),
        _o("integrator", "string", "-", "The splitting that ran (leapfrog, yoshida4, yoshida6, aba864)."),
        _o("recurrence_periods", "scalar or null", "periods T_1", "Fixed ends: the first return of the energy "
           "to mode 1 (null when none within ``t_end``)."),
        _o("recurrence_fraction", "scalar or null", "-", "Fixed ends: the share of the harmonic energy back in "
           "mode 1 then."),
        _o("t", "(outputs,)", "the model's time unit", "The output times."),
        _o("mode_energies_series", "(outputs, modes)", "the model's energy unit", "Rows of the modal energies "
           "E_1 .. E_modes."),
    ),
    "rod_statics": (
        _o("tip_position", "(3,)", "m", "The tip's position [x, y, z]."),
        _o("tip_rotation", "scalar", "rad", "The tip's rotation about ``bending_axis``, unwrapped."),
        _o("tip_orientation", "(3, 3)", "-", "The tip's rotation matrix R."),
        _o("s", "(nodes,)", "m", "The nodes along the rod."),
        _o("shape", "(nodes, 3)", "m", "The centre line."),
        _o("strain", "(nodes, 6)", "-, 1/m", "eps = f - f0 (u1 u2 u3 w1 w2 w3)."),
        _o("stress_resultant", "(nodes, 6)", "N, N m", "sigma = (n, m) in the section frame."),
        _o("branch", "list of {load, tip_force, tip_torque, tip_position, tip_rotation, shape}", "-, N, N m, m, "
           "rad", "Per load step of the continuation in the load factor."),
        _o("velocity", "(nodes, 6)", "m/s, rad/s", "eta = (R^T (Omega x r), R^T Omega) in the section frame "
           "(``frame_rate``)."),
        _o("orthonormality_error", "scalar", "-", "max \\|R^T R - I\\|."),
        _o("iterations", "scalar (int)", "-", "Newton iterations of the last step."),
        _o("method", "string", "-", "``collocation`` or ``shooting``: what ran."),
        _o("elements", "scalar (int)", "-", "RKMK4 steps or collocation elements."),
    ),
    "rod_dynamics": (
        _o("t", "(saved,)", "s", "The saved times."),
        _o("tip_trajectory", "(saved, 3)", "m", "The tip's position at each saved time."),
        _o("tip_rotations", "(saved,)", "rad", "The tip's rotation about ``bending_axis`` per saved point."),
        _o("tip_position", "(3,)", "m", "The final tip position."),
        _o("tip_rotation", "scalar", "rad", "The final tip rotation."),
        _o("tip_orientation", "(3, 3)", "-", "The final tip rotation matrix."),
        _o("energy", "(saved,)", "J", "Kinetic plus elastic energy per saved point."),
        _o("work", "(saved,)", "J", "The work of the loads and the damping since t = 0."),
        _o("energy_error", "scalar", "-", "max \\|E - E(0) - W\\| relative to max(\\|E\\|, \\|W\\|)."),
        _o("orthonormality_error", "scalar", "-", "max \\|R^T R - I\\| over the final nodes."),
        _o("shape", "(nodes, 3)", "m", "The final centre line."),
        _o("shapes", "(shapes, nodes, 3)", "m", "The saved centre lines."),
        _o("strain", "(elements, 6)", "-, 1/m", "The final strain per element, eps = f - f0."),
        _o("stress_resultant", "(elements, 6)", "N, N m", "The final sigma = K eps per element."),
        _o("steps", "scalar (int)", "-", "Time steps."),
        _o("newton_iterations", "scalar (int)", "-", "Newton iterations, all steps."),
        _o("jacobians", "scalar (int)", "-", "Jacobians assembled."),
        _o("splits", "scalar (int)", "-", "Steps split in halves for Newton."),
        _o("dt", "scalar", "s", "The time step."),
        _o("elements", "scalar (int)", "-", "Elements."),
    ),
    "orr_sommerfeld": (
        _o("least_stable_c", "(2,)", "U_c", "[Re c, Im c] of the resolved eigenvalue with the largest Im c (at N_check)."),
        _o("growth_rate", "scalar", "U_c / h", "alpha Im c of the least stable mode."),
        _o("verdict", "string", "-", "``unstable`` where Im c > 0, else ``stable``."),
        _o("eigenvalues", "(count, 2)", "U_c", "The resolved wave speeds [Re c, Im c], least stable first."),
        _o("resolved", "scalar (int)", "-", "Eigenvalues that agree between N and N_check within tol."),
        _o("rejected", "scalar (int)", "-", "Eigenvalues at N that do not reappear at N_check (not reported)."),
        _o("resolution", "(2,)", "-", "[N, N_check], the two numbers of collocation intervals."),
        _o("least_stable_change", "scalar", "U_c", "\\|c(N) - c(N_check)\\| of the least stable eigenvalue."),
        _o("critical_Re", "scalar", "-", "The smallest Re of the neutral curve (Im c = 0, d Im c / d alpha = 0), at N."),
        _o("critical_alpha", "scalar", "1/h", "The wavenumber at critical_Re."),
        _o("critical_c", "(2,)", "U_c", "[Re c, Im c] at the critical point (Im c zero to the Newton tolerance)."),
        _o("critical_Re_change", "scalar", "-", "\\|Re_c(N) - Re_c(N_check)\\|."),
    ),
    "crack_integrals": (
        _o("J", "(tips,)", "N/m", "J_1 in each tip's frame (the energy release rate G) on the first ring."),
        _o("K_I", "(tips,)", "Pa m^0.5", "Mode I stress intensity factor per tip (interaction integral with the "
           "Williams K field)."),
        _o("K_II", "(tips,)", "Pa m^0.5", "Mode II stress intensity factor per tip."),
        _o("T_stress", "(tips,)", "Pa", "The T-stress per tip (interaction with Kfouri's point-force field)."),
        _o("bueckner_K_I", "(tips,)", "Pa m^0.5", "Bueckner's work-conjugate integral with his r^-3/2 mode I field "
           "(normalised to give K_I)."),
        _o("bueckner_K_II", "(tips,)", "Pa m^0.5", "The same with the mode II field (K_II)."),
        _o("contours", "table", "as above", "The path-independence table: ``rings`` and ``crack_rings`` as given, "
           "and every integral on every contour: J, K_I, K_II, T_stress, bueckner_K_I, bueckner_K_II (one list per "
           "ring, one value per tip), M, L, bueckner (one value per crack ring)."),
        _o("M", "scalar", "N", "With ``crack_rings``: the M-integral about ``center`` around the whole crack."),
        _o("L", "scalar", "N", "With ``crack_rings``: the L-integral (rotational) about ``center``."),
        _o("bueckner", "scalar", "N", "With ``crack_rings``: Bueckner's integral with the Griffith field's "
           "rotation derivative (Shi, Liu & Li's supplemental field), 2 L for a Griffith crack."),
    ),
    "shear_curve": (
        _o("shear_rate", "(samples,)", "1/lambda", "The sampled shear rates, 0 to rate_max."),
        _o("stress", "(samples,)", "eta_p/lambda", "T(g) = epsilon g + g / (1 + xi (2 - xi) g^2) at those rates."),
        _o("monotone", "bool", "-", "Whether T(g) is monotone (epsilon >= 1/8, or xi = 0 or 2)."),
        _o("shear_rate_max", "scalar", "1/lambda", "The rate of T's local maximum (absent when monotone)."),
        _o("stress_max", "scalar", "eta_p/lambda", "T's local maximum (absent when monotone)."),
        _o("shear_rate_min", "scalar", "1/lambda", "The rate of T's local minimum (absent when monotone)."),
        _o("stress_min", "scalar", "eta_p/lambda", "T's local minimum (absent when monotone)."),
        _o("note", "string", "-", "Present when monotone: no extrema, no fold, no spurt."),
        _o("hopf", "string", "-", "``none``: no equilibrium of the stress-controlled local law has an imaginary pair."),
        _o("pair_trace_max", "scalar", "1/lambda", "The largest sum of the eigenvalue pair other than -1 over the "
           "sampled curve, -2 - 1/(epsilon (1 + k g^2)) < 0."),
        _o("off_manifold_eigenvalue", "scalar", "1/lambda", "-1: the rate of xi tau_xx + (2 - xi) tau_yy."),
    ),
    "channel_flow": (
        _o("monotone", "bool", "-", "Whether the shear curve is monotone (no spurt)."),
        _o("note", "string", "-", "Present when monotone: one steady solution at every G."),
        _o("spurt_gradient", "scalar", "eta_p/lambda", "G at which the wall stress reaches T_max (absent when monotone)."),
        _o("G", "(samples,)", "eta_p/lambda", "Pressure gradients along the classical branch, 0 to spurt_gradient."),
        _o("flow_rate", "(samples,)", "h^2/lambda", "Flux per unit width through the channel on the classical branch."),
        _o("G_above", "(samples,)", "eta_p/lambda", "Pressure gradients from spurt_gradient to G_max."),
        _o("flow_rate_top", "(samples,)", "h^2/lambda", "Flux of the top-jumping solution (jump where G y = T_max)."),
        _o("flow_rate_bottom", "(samples,)", "h^2/lambda", "Flux of the bottom-jumping solution (jump where G y = T_min)."),
        _o("jump_position_top", "(samples,)", "h", "y of the top-jumping solution's jump, T_max / G."),
        _o("jump_position_bottom", "(samples,)", "h", "y of the bottom-jumping solution's jump, T_min / G."),
        _o("flow_rate_at_G", "scalar", "h^2/lambda", "Classical flux at the model's G (G <= spurt_gradient)."),
        _o("flow_rate_top_at_G", "scalar", "h^2/lambda", "Top-jumping flux at the model's G (above the threshold)."),
        _o("flow_rate_bottom_at_G", "scalar", "h^2/lambda", "Bottom-jumping flux at the model's G (above the threshold)."),
        _o("G_up", "(samples,)", "eta_p/lambda", "The loading half of the quasi-static ramp, 0 to G_max."),
        _o("flow_rate_up", "(samples,)", "h^2/lambda", "Its flux: classical, then top-jumping above spurt_gradient."),
        _o("G_down", "(samples,)", "eta_p/lambda", "The unloading half, G_max to 0."),
        _o("flow_rate_down", "(samples,)", "h^2/lambda", "Its flux: interface latched, then bottom-jumping, then classical."),
        _o("jump_position_down", "(samples,)", "h", "The interface on unloading (1: none)."),
        _o("spurt_gradient_discrete", "(2,)", "eta_p/lambda", "With ``discrete``: the collocated steady branch's first "
           "fold at N and N_check."),
        _o("spurt_gradient_discrete_error", "(2,)", "eta_p/lambda", "\\|fold - spurt_gradient\\| at N and N_check."),
        _o("discrete_folds", "(folds,)", "eta_p/lambda", "All folds the N_check branch passed (the first, then as it turns)."),
        _o("discrete_G", "(points,)", "eta_p/lambda", "G along the N_check branch up to its first fold."),
        _o("discrete_flow_rate", "(points,)", "h^2/lambda", "Its flux, Clenshaw-Curtis quadrature of u."),
        _o("discrete_flow_rate_error", "scalar", "h^2/lambda", "The largest \\|Q_discrete - Q\\| at those G up to "
           "spurt_gradient."),
    ),
    "channel_spectrum": (
        _o("eigenvalues", "(count, 2)", "1/lambda", "The resolved point spectrum [Re, Im], rightmost first (band copies "
           "left out)."),
        _o("rightmost", "(2,)", "1/lambda", "The first of them (absent when there is none)."),
        _o("verdict", "string", "-", "``unstable`` where a point or band eigenvalue has Re > 0, else ``stable``."),
        _o("essential_spectrum", "(2, 3, 2)", "1/lambda", "The band's ends: the local stress-controlled eigenvalues "
           "at the centre y = 0 and at the wall y = 1."),
        _o("essential_rightmost", "scalar", "1/lambda", "The largest Re lambda_loc(T = G y) over 0 <= y <= 1."),
        _o("band_eigenvalues", "scalar (int)", "-", "Resolved eigenvalues lying on the band (not point eigenvalues)."),
        _o("rejected", "scalar (int)", "-", "Eigenvalues at N that do not reappear at N_check."),
        _o("resolution", "(2,)", "-", "[N, N_check]."),
        _o("base_residual", "scalar", "eta_p/lambda^2", "The generated rates at the base state (zero: the model is "
           "the law of the closed-form base state)."),
        _o("band_y", "(band_samples,)", "h", "The positions 0 <= y <= 1 where the band is sampled."),
        _o("band", "(band_samples, 3, 2)", "1/lambda", "The local stress-controlled eigenvalues at band_y, rightmost first."),
    ),
}


def outputs_of(kind: str) -> tuple[OutputDoc, ...]:
    """The documented outputs of ``kind``; empty for a kind not documented here yet (its page then points to
    its module docstring)."""
    return OUTPUTS.get(kind, ())
