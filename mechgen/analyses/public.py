"""One Python function per analysis kind: ``mechgen.modes(system, count=4)`` ... each returning a Result.

Every function takes a compiled system (``mechgen.compile``) and the options of its kind under
the names a scene uses for them (the same checks and defaults: a bad name raises an InputError
naming the function, the key and the accepted keys; a bad value one naming ``<function>.<key>``).
An analysis that builds on another takes that one's Result where a scene takes its name
(``about=steady_result``). ``name=`` names the Result (default: the kind).

The functions are those of ``mechgen.run(scene)``: a scene's analysis and the same call here give
the same outputs, and ``Result.to_json()`` is the scene JSON's entry.
"""
from __future__ import annotations

import re
from typing import Any, Mapping

from mechgen.analyses.option_text import default_text, escape_bars, first_sentence
from mechgen.analyses.registry import get, kinds
from mechgen.analyses.result import Result, run_analysis
from mechgen.analyses.schema import OptionContext, validate
from mechgen.errors import InputError, did_you_mean

__all__ = ["analysis", "campbell", "continuation", "fit", "impact", "modes", "restitution", "simulate", "stability",
           "steady", "sweep", "cross_section", "symplectic", "rod_statics", "rod_dynamics", "periodic", "periodic_orbit", "spectrum",
           "stability_boundary", "response", "phase_boundary", "phase_kinetics", "orr_sommerfeld", "shear_curve",
           "channel_flow", "channel_spectrum", "crack_integrals",
           "option_lines"]


def _model_info(system):
    """The ModelInfo of the system's model: the facts compiled into it (mechgen.compile), else looked up by the
    model's reference."""
    if getattr(system, "facts", None) is not None:
        return system.facts
    from mechgen.scene.info import lookup_model

    name = system.metadata.reference  # the canonical reference, for users' models
    info = lookup_model(name) if name else None
    if info is None:
        raise InputError(f"the system's model {name!r} is not one mechgen can look up", key="system",
                         expected="a system compiled by mechgen.compile")
    return info


def _context(system, function: str, earlier: Mapping[str, Result]) -> OptionContext:
    """The checks' view of a compiled system: its model's names, its coordinates and parameter values."""
    info = _model_info(system)
    coordinates = tuple(info.coordinates) if system.is_field else tuple(system.coordinates)
    active = None if set(coordinates) == set(info.coordinates) else coordinates
    from mechgen.scene.bounds import LIMITS, MAX_LIMIT

    # the scene's safety limits guard typos in a file a user cannot raise from Python: a caller is bounded
    # by the memory estimate before allocating (mechgen.runtime.core.memory) instead
    return OptionContext(file=None, model=info, params=_known_values(system), depends={},
                         coordinates=coordinates, active=active, all_names=tuple(earlier),
                         earlier={n: r.kind for n, r in earlier.items()}, current=function,
                         limits={name: MAX_LIMIT for name in LIMITS}, trusted=True)


def _known_values(system) -> dict:
    """The parameter values the system itself records (its free ones, a continuum's fixed ones), for
    expression strings in options; a value folded into the kernels and not recorded is not guessed."""
    values = {k: float(v) for k, v in getattr(system, "fixed", {}).items()}
    values.update(zip(system.metadata.params, (float(v) for v in system.params)))
    return values


def _check_keys(function: str, kind: str, options: Mapping[str, Any]) -> None:
    schema = get(kind).schema
    for key in options:
        if key not in schema:
            raise InputError(f"{function}() got an unknown option {key!r}{did_you_mean(key, schema)}", key=key,
                             expected=f"one of the {function}() options: " + ", ".join(schema))


def _named(value, earlier: dict):
    """An option's value as a scene would hold it: a Result (or a list of them) given for an option that names
    an earlier analysis becomes its name (names); arrays and tuples become lists, numpy numbers Python ones."""
    if isinstance(value, Result):
        earlier[value.name] = value
        return value.name
    if isinstance(value, Mapping):
        return {k: _named(v, earlier) for k, v in value.items()}
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        value = value.tolist() if hasattr(value, "tolist") else list(value)
        return [_named(v, earlier) for v in value] if isinstance(value, list) else value
    return value


def _run(kind: str, system, options: dict, name: str | None) -> Result:
    """Check ``options`` through the kind's schema, run it, return its Result."""
    _check_keys(kind, kind, options)
    earlier: dict[str, Result] = {}
    table = {key: _named(value, earlier) for key, value in options.items()}
    ctx = _context(system, kind, earlier)
    checked = validate(ctx, kind, get(kind), table)
    context = {n: r.state for n, r in earlier.items()}
    return run_analysis(name or kind, kind, system, checked, context)


def analysis(kind: str, system, *, name: str | None = None, **options) -> Result:
    """Any registered kind by name (``analysis("modes", system, count=4)`` is ``modes(system, count=4)``):
    a kind added to the registry is callable here without a function of its own."""
    get(kind)
    return _run(kind, system, options, name)


def modes(system, *, name: str | None = None, **options) -> Result:
    """Natural frequencies (and a continuum's mode shapes) about an operating point.

    Options (scene keys of ``kind = "modes"``): ``about`` (a steady Result), ``at`` ({coordinate:
    value}), ``count``. Outputs: ``frequencies`` (ascending, rad/s or the model's unit; elastic
    modes), ``rigid_modes`` (how many rigid-body modes); with damping or gyroscopic terms, and for
    rotors, the damped modes (``eigenvalues``, ``log_dec``, ``whirl``). A point that is not an
    equilibrium is replaced by the one Newton finds from it (``operating_point`` says so), or the call
    raises ConvergenceError naming the residual.
    """
    return _run("modes", system, options, name)


def stability(system, *, name: str | None = None, **options) -> Result:
    """Eigenvalues of M q'' + (D + G) q' + K q = 0 and the verdict (stable, neutral, divergence, flutter,
    unconverged; neutral: stable apart from rigid-body modes).

    Options: ``about``, ``at``, ``count``, ``tolerance`` (left out: each eigenvalue's own error bound; a
    number: that times max|s| for all), ``refine``, ``refine_rtol``. Outputs: ``eigenvalues`` ([re, im]
    pairs), ``verdict``, ``frequencies``, ``growth_rate``, ``rigid_modes``, ``unstable``, and for a
    continuum ``refinement``.
    """
    return _run("stability", system, options, name)


def steady(system, *, name: str | None = None, **options) -> Result:
    """An equilibrium (Newton), or a continuum's steady state as a boundary value problem (``method``).

    Options: ``guess``, ``tol``, ``max_iter``, ``method``, ``mesh``, ``nodes``, ``bulge``, ``form``,
    ``aliases``, ``stability``, ``hold`` with ``free``, ``params``, ``shape``. Outputs:
    ``iterations``, ``residual_norm``, ``coordinates`` (lumped), the model's outputs. The Result can
    be given as ``about=`` to modes, stability, campbell and continuation.
    """
    return _run("steady", system, options, name)


def simulate(system, *, name: str | None = None, **options) -> Result:
    """The time response from ``q0``, ``v0`` (or ``initial_mode``) to ``t_end`` (required).

    ``method="variational"`` with ``dt`` (and ``stages`` 1, 2 or 3: orders 2, 4, 6) steps a variational
    integrator of the model's own Lagrangian (mechgen.analyses.simulate_variational); ``method="leapfrog"``
    serves only q'' = M^-1 (-dV/dq) with a constant diagonal M (else InputError at ``method``).

    Outputs: ``t`` and ``trajectory`` (each coordinate, ``<coordinate>_dot``, internal variable and output at
    the sample times, as numpy arrays; left out for a very large state unless ``series=True``), the model's
    outputs at ``t_end``, ``energy_drift`` (conservative runs) or ``energy_balance_error``, ``work`` and
    ``dissipated``, ``method`` and ``loop`` (what ran: ``method="auto"`` picks DOP853 in the compiled loop, or
    Radau when the start is stiff). A hybrid model (mechgen.symbolic.hybrid) also reports ``events``
    (``{t, from, to, guard}``), ``final_mode``, ``t_final`` and ``mode_series`` (mechgen.analyses.simulate_hybrid);
    ``on_zeno="stop"`` ends it at a Zeno accumulation point with ``zeno=True``. A spent budget raises
    BudgetExceeded.
    """
    return _run("simulate", system, options, name)


def impact(system, *, name: str | None = None, **options) -> Result:
    """One impact of a hybrid model from contact to release (mechgen.analyses.impact).

    Options: ``t_end`` and ``v0`` (required), ``q0``, ``method``, ``rtol``, ``atol``, ``coordinate``,
    ``contact_mode``, ``force_output``, ``curve``, ``samples``. Outputs: ``restitution``,
    ``contact_duration``, ``energy_lost``, ``released`` (and the hysteresis series with ``curve=True``).
    """
    return _run("impact", system, options, name)


def restitution(system, *, name: str | None = None, **options) -> Result:
    """Impacts over a grid ``over = {"zeta": [...]}`` of a parameter left free (mechgen.analyses.restitution).

    Options: ``over`` (required), the impact's options, ``hysteresis``. Outputs: the parameter's values
    under its name, ``restitution``, ``contact_duration``, ``energy_lost``, ``released``, ``hysteresis``.
    """
    return _run("restitution", system, options, name)


def periodic(system, *, name: str | None = None, **options) -> Result:
    """The periodic steady state of a hybrid model under a periodic drive (mechgen.analyses.periodic).

    Options: ``period`` (required), ``force_output``, ``displacement_output``, ``max_periods``,
    ``tolerance``, ``nodes``, ``pieces`` and the integration keys. Outputs: ``energy_per_cycle``,
    ``equivalent_stiffness``, ``equivalent_damping`` and the hysteresis loop of the detected period.
    """
    return _run("periodic", system, options, name)


def periodic_orbit(system, *, name: str | None = None, **options) -> Result:
    """A periodic orbit of a smooth lumped model, forced (``frequency``) or autonomous (``period`` the guess), by
    harmonic balance, shooting or collocation, with its Floquet multipliers and stability
    (mechgen.analyses.periodic_orbit).

    ``from`` is a Python keyword: start from an earlier simulate with ``periodic_orbit(system, **{"from": run})``
    (``run`` the simulate's Result, kept with its trajectory).
    """
    return _run("periodic_orbit", system, options, name)


def response(system, *, name: str | None = None, **options) -> Result:
    """The steady harmonic response X(omega) = H(omega) f, H(omega) = (K - omega^2 M + i omega (D + G))^-1,
    about an operating point (mechgen.analyses.response), to a unit force (``input``), a force pattern
    (``force``: ``{"x": 1.0, "y": {"amplitude": 1.0, "phase": 90}}``, phases in degrees) or an unbalance
    (``unbalance``: ``{"coordinates": ["x", "y"], "mass": kg, "eccentricity": m}``, over the speeds ``over``
    with the matrices re-linearised at each speed).

    Options: one of ``input``, ``force``, ``unbalance``; ``omega`` (with input or force) or ``over`` (with
    unbalance); ``speed_unit`` (rad/s, Hz, rpm), ``outputs``, ``orbits``, ``orbit_at``, ``about``, ``at``,
    ``max_seconds``. Outputs: ``omega`` (rad/s), ``amplitude`` and ``phase`` per output coordinate (rad),
    ``forcing``, ``speed_unit``, ``omega_in_unit``, and with orbits ``orbit`` per coordinate pair.
    """
    return _run("response", system, options, name)


def spectrum(system, *, name: str | None = None, **options) -> Result:
    """A travelling impulse train summed in modal coordinates and its Hann spectrum (mechgen.analyses.spectrum).

    Options: ``speed``, ``spacing``, ``impulse`` (expressions of x and the parameters), ``start``, ``stop``,
    ``modes``, ``damping``, ``observe`` or ``output``/``input``, ``t_end``, ``sample_rate``. Outputs:
    ``natural_frequencies`` and ``spectrum_peaks`` (Hz), ``frequency_bin``, ``impulses``, ``impulse_rate``.
    """
    return _run("spectrum", system, options, name)


def stability_boundary(system, *, name: str | None = None, **options) -> Result:
    """Where the growth rate of the linearisation crosses zero in a parameter (mechgen.analyses.stability_boundary).

    Options: ``parameter`` and ``bracket`` (required), ``labels``, the steady state's keys. Outputs:
    ``<parameter>_critical``, ``frequency_critical``, ``crossing``, and ``verdict`` at the system's own value.
    """
    return _run("stability_boundary", system, options, name)


def cross_section(system, *, name: str | None = None, **options) -> Result:
    """The stiffness K (6 x 6, [K_uu, K_uw; K_wu, K_ww]) of the rod section a model declares with
    ``@model.section_stiffness``, at the system's parameters (mechgen.analyses.cross_section).

    No options. Outputs: ``K`` and its ``eigenvalues``; a K that is not finite or not positive definite
    raises an InputError naming the parameters.
    """
    return _run("cross_section", system, options, name)


def rod_statics(system, *, name: str | None = None, **options) -> Result:
    """The static equilibrium of the Cosserat rod a model declares with ``Model.rod`` (initially along x from
    the origin), by load continuation (mechgen.analyses.rod_statics).

    Options: ``method`` (shooting, collocation), ``elements`` (or ``N``), ``base``, ``tip`` (clamped, pinned,
    free), ``tip_force``, ``tip_torque`` ([x, y, z], spatial, dead), ``steps``, ``tol``, ``min_step``,
    ``bending_axis``, ``frame_rate``.
    Outputs: ``tip_position``, ``tip_rotation``, ``tip_orientation``, ``s``, ``shape``, ``strain``,
    ``stress_resultant``, ``branch`` (the tip pose per load step), ``velocity``, ``orthonormality_error``.
    """
    return _run("rod_statics", system, options, name)


def rod_dynamics(system, *, name: str | None = None, **options) -> Result:
    """The motion of the Cosserat rod a model declares with ``Model.rod(..., inertia=...)`` (initially along
    x from the origin, at rest or moving rigidly), loads applied at t = 0: N two-node SO(3) x R^3 elements and
    the implicit Lie-group midpoint step (mechgen.analyses.rod_dynamics).

    Options: ``dt``, ``t_end`` (required, s), ``elements`` (or ``N``), ``base``, ``tip``, ``tip_force``,
    ``tip_torque``, ``damping`` (1/s), ``initial_velocity``, ``initial_angular_velocity``, ``save_every``,
    ``shape_every``, ``tol``, ``bending_axis``.
    Outputs: ``t``, ``tip_trajectory``, ``tip_rotations``, ``tip_position``, ``tip_rotation``, ``energy``,
    ``work``, ``energy_error``, ``orthonormality_error``, ``shape``, ``shapes``, ``strain``, ``stress_resultant``,
    ``steps``, ``newton_iterations``.
    """
    return _run("rod_dynamics", system, options, name)


def campbell(system, *, name: str | None = None, **options) -> Result:
    """A Campbell diagram over ``over = {"Omega": [speeds]}`` (a parameter left free in the kernels).

    Options: ``over`` (required; values or {start, stop, num}), ``count``, ``multiples``, ``method``,
    ``about``, ``at``, ``max_seconds``, and where the per-speed eigen-solves run: ``executor`` ("serial",
    "processes" or "dask"), ``workers``, ``scheduler`` (as for :func:`sweep`; a parallel executor solves every
    speed exactly and gives the serial exact result; ``method="reduced"`` runs serially only). Outputs:
    ``speeds``, ``frequencies``, ``whirl``, ``log_dec`` (one row per speed), ``critical_speeds``, ``method``,
    ``exact_solves``, ``executor``.
    """
    return _run("campbell", system, options, name)


def continuation(system, about, *, name: str | None = None, **options) -> Result:
    """The branch of steady states through ``about`` (a steady Result, or a list of them) as ``parameter`` goes
    to ``stop``, with its special points (folds LP, branch points BP, Hopf points H with the first Lyapunov
    coefficient); or, with ``about`` a continuation Result and ``special_point``, the curve of one of its LP or H
    points in two parameters.

    Options: ``parameter`` and ``stop`` (required), ``step``, ``max_step``, ``max_points``, ``method``,
    ``stages``, ``mesh``, ``stability``, ``minimize``, ``aliases``, ``direction``, ``bounds``, ``at``,
    ``eigenvalues``, ``special_points``, ``switch_branches``, ``special_point``. Outputs: ``branch`` (points with
    the parameter, outputs and ``verdict``), ``folds``, ``special_points``, ``switched_branches``, ``curve``,
    ``status``, ``points`` ...
    """
    return _run("continuation", system, {"about": about, **options}, name)


def fit(system, *, name: str | None = None, **options) -> Result:
    """Least-squares estimates of ``parameters`` from ``data`` (scipy.optimize.least_squares).

    Options (scene keys of ``kind = "fit"``, mechgen.analyses.fit): ``parameters`` (names, required),
    ``data`` ({column: values} or a CSV path, relative to the working directory), ``observed`` (the
    column to reproduce), ``sigma``, ``group``, ``start``, ``tol``, ``max_seconds``,
    ``max_evaluations``, and the model: ``expression`` (a formula of columns, ``constants`` and the
    parameters; ``system`` is then not used) or ``analysis`` ({"kind": "modes", ...}) with ``output``
    ("name" or "name[i]") and ``inputs`` (columns that set model parameters per row; they and the
    parameters must be free in ``system``), ``jacobian``, ``diff_step``. Outputs: each parameter
    ``p`` and ``p_stderr``, ``residuals``, ``fitted``, ``observed``, ``rms``, ``dof``,
    ``covariance``, ``converged``, ``evaluations`` (``groups`` when grouped) ...
    """
    return _run("fit", system, options, name)


def sweep(system, analysis: str = "modes", grid: Mapping[str, Any] | None = None, *, name: str | None = None,
          workers: int = 0, progress: bool = False, executor: str | None = None, scheduler: str | None = None,
          on_error: str = "record", **inner_options) -> Result:
    """``analysis`` (modes, stability, steady or simulate, with ``inner_options``) at every point of ``grid``.

    ``grid`` maps each parameter (free in the kernels) to its values or {start, stop, num}; several
    parameters give their cartesian product, the first outermost. Each point runs on a new system
    with the point's values (``system`` is not changed). ``executor``: "serial", "processes"
    (``workers`` local processes) or "dask" (a LocalCluster of ``workers`` processes, or the running
    ``scheduler`` at "tcp://host:port"); left out, ``workers`` > 1 means processes (the system must then
    pickle; a scene's sweep compiles in each process instead). ``on_error``: "record" (a failed point's
    error in ``status``, the sweep goes on) or "raise";
    ``progress`` draws a bar on stderr (off by default here, on in scenes). Outputs: ``grid`` (the
    points) and one list per output of the inner analysis. Keywords other than these go to the inner
    analysis (``max_seconds`` there is each point's budget); the sweep's own wall-time budget is the
    scene's ``max_seconds``: ``analysis("sweep", system, over=grid, analysis={"kind": ...}, max_seconds=60)``.
    """
    if grid is None:
        raise InputError("sweep() needs a grid", key="grid", expected="grid = {parameter: [values]}")
    if analysis not in [k for k in kinds() if get(k).sweepable]:
        raise InputError(f"sweep() cannot repeat {analysis!r}", key="analysis",
                         expected="one of: " + ", ".join(k for k in kinds() if get(k).sweepable))
    _check_keys("sweep", analysis, inner_options)
    table = {"over": grid, "analysis": {"kind": analysis, **inner_options}, "workers": workers,
             "progress": progress, "on_error": on_error}
    if executor is not None:
        table["executor"] = executor
    if scheduler is not None:
        table["scheduler"] = scheduler
    return _run("sweep", system, table, name)


def symplectic(system, *, name: str | None = None, **options) -> Result:
    """A chain run by a splitting method with the time loop in C (mechgen.analyses.symplectic).

    Options: ``integrator`` (leapfrog, yoshida4, yoshida6, aba864), ``dt``, ``t_end`` (required), ``stride``,
    ``initial_mode``, ``amplitude``, ``modes``, ``loop``, ``max_steps``. Outputs: ``energy_error``,
    ``steps_per_second``, ``bandwidth_fraction``, and for fixed ends ``recurrence_periods``,
    ``recurrence_fraction``, ``t`` and ``mode_energies_series``.
    """
    return _run("symplectic", system, options, name)


def orr_sommerfeld(system, *, name: str | None = None, **options) -> Result:
    """Plane Poiseuille flow's Orr-Sommerfeld spectrum at the model's ``alpha``, ``Re`` by Chebyshev collocation at
    two resolutions, and its critical point (mechgen.analyses.orr_sommerfeld; model ``plane_poiseuille``)."""
    return _run("orr_sommerfeld", system, options, name)


def shear_curve(system, *, name: str | None = None, **options) -> Result:
    """A Johnson-Segalman fluid's steady shear curve T(g), its closed-form extrema (or the monotone verdict) and the
    local law's no-Hopf verdict (mechgen.analyses.shear_curve; model ``js_local``)."""
    return _run("shear_curve", system, options, name)


def crack_integrals(system, *, name: str | None = None, **options) -> Result:
    """J, K_I, K_II, the T-stress and Bueckner's integrals at each crack tip and M, L and the whole-crack Bueckner
    integral of a plane elastic steady state, in domain form on rings (mechgen.analyses.crack_integrals; model
    ``cracked_plate``)."""
    return _run("crack_integrals", system, options, name)


def channel_flow(system, *, name: str | None = None, **options) -> Result:
    """The Johnson-Segalman channel's spurt threshold, flow curve and jumping solutions from the local law, and
    optionally the collocated steady branch (mechgen.analyses.channel_flow; model ``js_channel``)."""
    return _run("channel_flow", system, options, name)


def channel_spectrum(system, *, name: str | None = None, **options) -> Result:
    """The Johnson-Segalman channel linearised about its classical state: point eigenvalues at two resolutions and
    the essential band of the local law (mechgen.analyses.channel_spectrum; model ``js_channel``)."""
    return _run("channel_spectrum", system, options, name)


def phase_boundary(system, *, name: str | None = None, **options) -> Result:
    """The Maxwell stress, the phase strains and the equilibria with one phase boundary of a bar whose model
    declares its law as outputs ``stress``, ``energy_density`` (and ``modulus``) of a strain ``gamma``
    (mechgen.analyses.phase_boundary; the built-in ``phase_bar``).

    A convex stored energy on ``strain_range`` gives ``phase_boundary = False`` and a ``note``, no Maxwell stress.
    """
    return _run("phase_boundary", system, options, name)


def phase_kinetics(system, *, name: str | None = None, **options) -> Result:
    """A phase boundary's nucleation, motion under the model's kinetic law and arrival at the bar's ends under a
    quasi-static ramp of the end displacement, as an event-driven hybrid run (mechgen.analyses.phase_kinetics;
    the built-in ``phase_bar``): s(t), the event times, the stress-elongation loop and the dissipation check.
    """
    return _run("phase_kinetics", system, options, name)


def option_lines(kind: str) -> list[str]:
    """One line per option of ``kind``, from the schema the scene loader validates against: its name, its
    default as the reference pages write it (mechgen.analyses.option_text.default_text) and its meaning (the
    Option's ``doc``, its bars escaped for reStructuredText as on the reference pages)."""

    return [f"``{name}`` ({default_text(option).replace('**', '').replace(' (no default)', '')}): "
            f"{escape_bars(option.doc)}".rstrip(": ") for name, option in get(kind).schema.items()]


def output_lines(kind: str) -> list[str]:
    """One line per output of ``kind``, from the table the reference pages show (mechgen.analyses.outputs_doc):
    its name, its unit (left out where it has none) and the first sentence of its meaning, a Sphinx role in it
    written as a plain literal (a docstring is read outside the pages too, and from another page)."""
    from mechgen.analyses.outputs_doc import outputs_of

    lines = []
    for output in outputs_of(kind):
        unit = " ".join(output.unit.split())
        unit = "" if unit in ("", "-") else f" [{unit}]"
        meaning = re.sub(r":\w+:`([^`<]*?)\s*(<[^>]*>)?`", r"``\1``", first_sentence(output.meaning))
        lines.append(f"``{output.name}``{unit}: {meaning}")
    return lines


def _with_schema_options() -> None:
    """Append to each analysis function's docstring the options its kind's schema accepts and the outputs its
    kind documents (so that the docstrings, the reference pages and the loader cannot disagree on names,
    defaults and meanings)."""
    functions = {name: globals()[name] for name in __all__ if name not in ("analysis", "option_lines")}
    for kind, function in functions.items():
        if kind in kinds():
            options = "".join(f"    * {line}\n" for line in option_lines(kind)) or "    * none\n"
            function.__doc__ = (function.__doc__ or "").rstrip() + (
                "\n\n    Options accepted (from the scene schema of kind ``%s``):\n\n" % kind + options
                + "\n    Outputs (mechgen.analyses.outputs_doc; the reference page has their shapes):\n\n"
                + "".join(f"    * {line}\n" for line in output_lines(kind)))


_with_schema_options()
