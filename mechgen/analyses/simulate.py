"""``simulate``: the time response from an initial state.

Scene keys: ``t_end`` (required), ``method`` (``auto``, the default, and the compiled loop:
mechgen.analyses.simulate_flow; BDF, Radau, LSODA, RK45, DOP853, ``leapfrog`` with a step ``dt`` and
``save_every`` (a model whose equations are q'' = M^-1 (-dV/dq) with a constant diagonal M only, else refused
at ``method``: mechgen.runtime.core.splitting.require_separable), ``cvodes``: SUNDIALS' variable-order BDF with
the exact Jacobian, compiled through CasADi, for a lumped model built with ``backend = "casadi"``:
mechgen.runtime.core.sundials, or ``variational`` with ``dt``, ``stages`` and ``save_every``: the variational
integrator of the model's own Lagrangian, mechgen.analyses.simulate_variational), ``loop`` (``auto``,
``python`` or ``c``), ``rtol``, ``atol``, ``q0`` / ``v0`` (tables of coordinates), ``initial_mode`` with
``amplitude`` (start from a linear mode), ``outputs`` (which model outputs to report), ``series`` (the time
history; left out: kept while small, mechgen.analyses.time_series), ``samples``, ``plot`` (``time`` or
``phase``). Outputs: ``t`` and ``trajectory`` (with ``energy_series``), the model's outputs at ``t_end``,
``energy_drift`` (a conservative run) or ``energy_balance_error``, ``work`` and ``dissipated``
(mechgen.analyses.energy_balance), ``t_end``, ``method`` and ``loop`` (what ran); a fixed-end chain also
``mode_energies``. A model with modes is run by mechgen.analyses.simulate_hybrid, with the keys ``mode``,
``max_events``, ``zeno_events``, ``zeno_span`` and ``on_zeno``; a continuum whose fields carry no mass (first-order
fields, ``js_fluid``) by mechgen.analyses.simulate_first_order: the state is q, its rate the root of
r(q, q', 0) = 0 (``auto``: BDF). A ``zeno_events`` or ``max_events`` given that could not be reached within
``max_seconds`` at EVENT_SECONDS an event is refused at load (exit 2 at that key).

Work budget (mechgen.runtime.core.budget): ``max_steps`` (integrator steps; default 10^7 for the
leapfrog, whose t_end / dt steps are refused before the first one when they exceed it, and 10^5
accepted steps for the adaptive methods), ``max_seconds`` (wall time, default 600) and
``progress`` (default true: a bar with the remaining time on stderr when it is a terminal and the
run lasts over 2 s). An explicit method (RK45, DOP853) is also refused up front when the fastest
rate of the linearisation at the start, |lambda|max, needs more than ``max_steps`` steps for
stability alone (at least t_end |lambda|max / c steps, c = 7 for RK45 and 12 for DOP853, twice
their stability intervals): the implicit BDF and Radau have no such limit. Reaching a budget ends the run
with exit 1 naming the analysis, the t reached of t_end and the key to raise.

``samples`` above the safety limit 10^6 (raised by the scene's ``[limits] samples``) is refused at the key, and
any count whose states would not fit in memory (runtime.core.memory) too; each sample is a state kept and an
energy evaluated.
``rtol`` below 100 machine epsilons (2.2e-14, what scipy's integrators can honour; they would
raise it silently) is refused at the key. A failed step (a step size below the spacing of the
numbers), a singular mass matrix (a zero mass) or a kernel giving NaN/Inf ends the run with
exit 1 naming the t reached and, from mechgen.runtime.core.diagnose, the kernel, output entry
and inputs, or the coordinate without inertia, or the fastest rate at the failing state.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from mechgen.analyses import energy_balance, schema, simulate_flow, summary, time_figures, time_series
from mechgen.analyses.context import NAME
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, ALL_OUTPUTS, REQUIRED, Option
from mechgen.analyses.simulate_start import (DEFAULT_STEPS, FIXED_STEP, balanced, budget_of, declared_start,
                                             initial_state, report)
from mechgen.analyses.simulate_variational import check_fixed_step, simulate_variational
from mechgen.errors import ConvergenceError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.core.integrate import MIN_RTOL, leapfrog
from mechgen.runtime.core.splitting import require_separable
from mechgen.runtime.core.sundials import cvodes_problem
from mechgen.scene.values import fail, listing, show, type_name

METHODS = ("auto", "BDF", "Radau", "LSODA", "RK45", "DOP853", "leapfrog", "cvodes", "variational")
#: the default figure: coordinates against time, or each coordinate against its velocity
PLOTS = ("time", "phase")
#: what a hybrid run does when its events accumulate (Zeno): end with an error, or stop there
ON_ZENO = ("error", "stop")
STEP = "a number > 0 (or an expression)"
#: what a model unfit for the leapfrog uses instead (mechgen.runtime.core.splitting.require_separable)
INSTEAD = ("method = 'variational' (a variational integrator of the model's own Lagrangian, any kinetic energy), "
           "or an adaptive one ('auto', the default, or 'Radau')")


def _outputs(ctx, key: str, value: object) -> list[str]:
    known = ctx.model.outputs
    if not isinstance(value, list):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "an array of output names: " + listing(known))
    names: list[str] = []
    for i, name in enumerate(value, 1):
        if not isinstance(name, str) or name not in known:
            raise fail(ctx.file, f"{key}[{i}]", f"unknown output {show(name)}",
                       "one of the model's outputs: " + listing(known))
        if name not in names:
            names.append(name)
    return names


def _mode(ctx, key: str, value: object) -> str:
    modes = tuple(getattr(ctx.model, "modes", ()))
    if not modes:
        raise fail(ctx.file, key, f"model {ctx.model.name} has no modes", "no 'mode' key (a smooth model)")
    if not isinstance(value, str) or value not in modes:
        raise fail(ctx.file, key, f"unknown mode {show(value)}", "one of the model's modes: " + ", ".join(modes))
    return value


def _loop(ctx, key: str, value: object) -> str:
    """The loop that steps the integrator (mechgen.runtime.integration.events.LOOPS): the compiled one where it can run
    (``auto``), scipy's steppers in Python, or the compiled one (``c``, an input error where it cannot run)."""
    from mechgen.runtime.integration.events import LOOPS

    return schema.one_of("loop", LOOPS)(ctx, key, value)


def _on_zeno(ctx, key: str, value: object) -> str:
    """What a hybrid run does at a Zeno approach: ``error`` (the default) or ``stop`` there."""
    if not getattr(ctx.model, "modes", ()):
        raise fail(ctx.file, key, f"model {ctx.model.name} has no modes", "no 'on_zeno' key (a smooth model)")
    return schema.one_of("on_zeno", ON_ZENO)(ctx, key, value)


def _method(ctx, key: str, value: object) -> str:
    if not isinstance(value, str) or value not in METHODS:
        raise fail(ctx.file, key, f"unknown method {show(value)}{schema.closest_value(value, METHODS)}",
                   "one of: " + ", ".join(METHODS))
    return value


SCHEMA = {
    "t_end": Option(schema.positive, REQUIRED, STEP, doc="end time of the run (s, or the model's time unit)"),
    "method": Option(_method, "auto", doc="the integrator: auto (DOP853 in the compiled loop, or Radau for a "
                     "stiff start), BDF, Radau, LSODA, RK45, DOP853 (scipy's), leapfrog with dt (q'' = M^-1 (-dV/dq) "
                     "with a constant diagonal M only), variational with dt and stages (the model's own "
                     "Lagrangian), or cvodes (SUNDIALS' BDF, a lumped model built with backend = \"casadi\")"),
    "dt": Option(schema.positive, ABSENT, doc="the fixed time step of leapfrog and variational (s, or the model's "
                 "time unit)"),
    "rtol": Option(schema.positive, 1e-8, doc="relative tolerance of the adaptive integrators (at least 2.2e-14)"),
    "atol": Option(schema.positive, 1e-10, doc="absolute tolerance of the adaptive integrators (the state's units)"),
    "q0": Option(schema.coordinate_table, {}, doc="initial coordinates, a table coordinate = value (left out: "
                 "zero, or the model's declared initial state)"),
    "v0": Option(schema.coordinate_table, {}, doc="initial velocities, a table coordinate = value (the "
                 "coordinate's unit per s; left out: zero)"),
    "initial_mode": Option(schema.count, doc="start from this linear mode (1: the lowest) instead of q0"),
    "amplitude": Option(schema.number, 1.0, doc="the initial mode's amplitude (its largest entry, in the "
                        "coordinate's unit)"),
    "outputs": Option(_outputs, ALL_OUTPUTS, doc="which model outputs to report and keep in the trajectory"),
    "series": Option(schema.boolean, ABSENT, doc="keep the time history t and trajectory (left out: kept while "
                     "(states + outputs) x samples <= 10^6 values)"),
    "samples": Option(schema.count_within("samples"), 201, doc="how many equally spaced sample times the time "
                      "history holds"),
    "save_every": Option(schema.count, ABSENT, doc="with leapfrog or variational: keep every this many steps as "
                         "a sample"),
    "plot": Option(schema.one_of("plot", PLOTS), ABSENT, doc="the default figure with --plot: time (q(t) and "
                   "the energy) or phase (phase portraits)"),
    "on_zeno": Option(_on_zeno, ABSENT, doc="a hybrid model at a Zeno accumulation of events: error (the "
                      "default, exit 1) or stop there with zeno = true"),
    "max_steps": Option(schema.count, ABSENT, doc="the work budget in integrator steps (default 10^7 leapfrog "
                        "steps, 10^5 accepted adaptive steps)"),
    "max_seconds": Option(schema.positive, ABSENT, doc="the wall-time budget of the run (s, default 600)"),
    "progress": Option(schema.boolean, ABSENT, doc="draw a progress bar with the remaining time on stderr "
                       "(default true, when stderr is a terminal and the run lasts over 2 s)"),
    "mode": Option(_mode, ABSENT, doc="a hybrid model's mode to start in (default its initial mode)"),
    "max_events": Option(schema.count, ABSENT, doc="a hybrid run's most events before it ends (default 10^4; at most "
                         "max_steps, every event but one at a mode's start ending an accepted step)"),
    "zeno_events": Option(schema.count, ABSENT, doc="more than this many events within zeno_span is a Zeno or "
                          "chattering approach (default 100; at most max_events)"),
    "zeno_span": Option(schema.positive, ABSENT, doc="the time window of the Zeno test (s, or the model's time "
                        "unit; default 1e-9 t_end)"),
    "loop": Option(_loop, ABSENT, doc="the loop that steps the integrator: auto (compiled where it can run), "
                   "python (scipy's steppers) or c (compiled, else an input error)"),
    "stages": Option(schema.count, ABSENT, doc="with method = \"variational\": Gauss-Legendre points per step, "
                     "1, 2 or 3 (orders 2, 4, 6; default 1)"),
}


def check(ctx, base: str, options: dict) -> None:
    """leapfrog and variational need dt (mechgen.analyses.simulate_variational.check_fixed_step); dt <= t_end;
    initial_mode within the coordinates (a continuum's unknowns, set by N, are counted when it runs:
    initial_state); rtol at least MIN_RTOL."""
    check_fixed_step(ctx, base, options)
    if options["method"] not in FIXED_STEP and options["rtol"] < MIN_RTOL:
        raise fail(ctx.file, f"{base}.rtol", f"rtol {options['rtol']!r} is below what the integrators can honour "
                   "in double precision", f"a relative tolerance >= {MIN_RTOL:.3g} (100 machine epsilons)")
    if options["method"] == "cvodes" and getattr(ctx.model, "modes", ()):
        raise fail(ctx.file, f"{base}.method", f"method 'cvodes' has no event location, and model {ctx.model.name} "
                   "has modes", "one of the event loops' methods: BDF, Radau, LSODA, RK45, DOP853")
    if options["method"] == "leapfrog" and "dt" not in options:
        raise fail(ctx.file, f"{base}.dt", "method 'leapfrog' needs a time step dt", STEP)
    if "dt" in options and options["dt"] > options["t_end"]:
        raise fail(ctx.file, f"{base}.dt", f"dt {options['dt']!r} exceeds t_end {options['t_end']!r}",
                   "a time step no larger than t_end")
    if ctx.coordinates and options.get("initial_mode", 0) > len(ctx.coordinates):  # (a continuum's: at run time)
        raise fail(ctx.file, f"{base}.initial_mode", f"initial_mode {options['initial_mode']} exceeds the "
                   f"{len(ctx.coordinates)} coordinates", f"an integer from 1 to {len(ctx.coordinates)}")
    check_event_bounds(ctx, base, options)


#: the least wall time of one event of a hybrid run, seconds: the compiled loop (the quicker one) on the smallest model,
#: a bouncing ball (2 states, DOP853, the event located and the state reset), measured 13-15 us per event over 10^4
#: and 10^5 events on a 2-core machine (the Python loop: 1.4 ms); rounded down (issue 33)
EVENT_SECONDS = 1.0e-5


def check_event_bounds(ctx, base: str, options: dict) -> None:
    """max_events <= max_steps (every event but one at a mode's start ends an accepted step, so a larger count
    can never be reached within the step budget) and zeno_events <= max_events (issue 33: a run with both at
    10^9 ran on, its Zeno ring alone 8 GB); refused up front at the key. A ``zeno_events`` or ``max_events`` given
    whose events would take more than ``max_seconds`` at EVENT_SECONDS each is refused too (:func:`check_event_time`)."""
    from mechgen.runtime.integration.run_options import EventRules

    method = options.get("method", "auto")
    steps = int(options.get("max_steps", DEFAULT_STEPS["leapfrog" if method in FIXED_STEP else "adaptive"]))
    events = int(options.get("max_events", EventRules.max_events))
    if "max_events" in options and events > steps:
        raise fail(ctx.file, f"{base}.max_events", f"max_events = {events:,} exceeds the step budget max_steps = "
                   f"{steps:,} (every event but one at a mode's start ends an accepted step)",
                   "max_events <= max_steps (raise max_steps with it, the run's time is bounded by max_seconds)")
    if "zeno_events" in options and int(options["zeno_events"]) > events:
        raise fail(ctx.file, f"{base}.zeno_events", f"zeno_events = {int(options['zeno_events']):,} exceeds "
                   f"max_events = {events:,}: the Zeno test could never end the run", "zeno_events <= max_events")
    check_event_time(ctx, base, options)


def check_event_time(ctx, base: str, options: dict) -> None:
    """Refuse at load (exit 2 at the key) a ``zeno_events`` (first) or ``max_events`` the scene gives that the
    wall-time budget could not reach: count x EVENT_SECONDS > max_seconds (the Zeno test, or the event limit,
    could then never be what ends the run)."""
    seconds = float(options.get("max_seconds", DEFAULT_SECONDS))
    for key, role in (("zeno_events", "the Zeno test"), ("max_events", "the event limit")):
        if key in options and int(options[key]) * EVENT_SECONDS > seconds:
            count = int(options[key])
            raise fail(ctx.file, f"{base}.{key}", f"{key} = {count:,} events would take at least "
                       f"{count * EVENT_SECONDS:.3g} s ({EVENT_SECONDS * 1e6:.3g} us an event, measured), more than "
                       f"the wall-time budget max_seconds = {seconds:g}: {role} could never end the run",
                       f"{key} <= {int(seconds / EVENT_SECONDS):,}, or max_seconds raised with it")


def needs(options: dict, *, internal: bool) -> set[str]:
    """Residual, tangent and outputs (force and M for leapfrog; M, K for an initial mode)."""
    if options.get("method") == "leapfrog":
        return {"force", "outputs", "linear"}
    start = {"linear"} if options.get("initial_mode") else set()
    if options.get("method") == "variational":
        return {"lagrangian", "outputs", "energy_rates"} | start
    return ({"residual", "tangent", "flow", "energy_rates", "outputs"} | start
            | ({"rates", "rates_tangent"} if internal else set()))


def mode_energies(system, q: np.ndarray, v: np.ndarray, count: int = 8) -> list[float]:
    """Harmonic energies E_k = (P_k^2 + omega_k^2 Q_k^2)/2 of a fixed-end chain (FPU's observable).

    Q_k = sqrt(2/(N+1)) sum_n q_n sin(n k pi/(N+1)); omega_k from the linear stiffness.
    """
    n = system.n
    idx = np.arange(1, n + 1)
    k = np.arange(1, min(count, n) + 1)
    S = np.sqrt(2.0 / (n + 1)) * np.sin(np.outer(k, idx) * np.pi / (n + 1))
    mats = system.linear(np.zeros(n))
    omega2 = np.einsum("ki,ik->k", S, mats["K"] @ S.T)  # K stays sparse (a chain of 1e6 sites)
    Q, P = S @ q, S @ v
    return [float(e) for e in 0.5 * (P**2 + omega2 * Q**2)]


def leapfrog_masses(system, M) -> np.ndarray:
    """1 / diag(M) for the leapfrog (a chain's lumped masses); a zero or non-finite mass is named."""
    diag = np.asarray(M.diagonal() if hasattr(M, "diagonal") else np.diag(M), float)
    bad = np.flatnonzero(~(np.isfinite(diag) & (diag > 0)))
    if bad.size:
        names = list(system.coordinates)
        raise ConvergenceError(f"leapfrog: the mass matrix's diagonal entry of coordinate '{names[bad[0]]}' is "
                               f"{diag[bad[0]]:.6g}; the leapfrog needs positive masses (a mass parameter of 0?)")
    return 1.0 / diag


def run_simulate(system, options: dict, context: dict) -> dict:
    """Time response: the time history (``t``, ``trajectory``), the model's outputs at t_end and the energy
    figures (mechgen.analyses.time_series)."""
    if hasattr(system, "modes"):
        from mechgen.analyses.simulate_hybrid import run_hybrid

        return run_hybrid(system, options, context)
    q0, v0 = initial_state(system, options)
    method, desc = options.get("method", "auto"), context.get(NAME, "simulate")
    if getattr(system, "first_order", False):  # fields without mass: q' from r(q, q', 0) = 0
        from mechgen.analyses.simulate_first_order import first_order_run

        t, X, how = first_order_run(system, options, q0, budget_of(options, "BDF" if method == "auto" else method),
                                      desc)
    elif method == "leapfrog":
        require_separable(system, "method", "method 'leapfrog'", INSTEAD)
        t, X = _leapfrog_run(system, options, q0, v0, budget_of(options, method), desc)
        how = {"method": method, "loop": "python"}
    elif method == "variational":
        t, X, how = simulate_variational(system, q0, v0, options, budget_of(options, method), desc)
    else:
        start = declared_start(system)
        x0 = np.concatenate([q0, v0, np.zeros(system.m) if start is None else start[2 * system.n:]])
        rates = simulate_flow.start_rates(system, x0) if method in ("auto", *simulate_flow.EXPLICIT_REACH) else None
        if method == "auto":
            limit = budget_of(options, "DOP853").limit
            method = simulate_flow.chosen_method(system, x0, float(options["t_end"]), limit, rates=rates)
            if method in ("Radau", "BDF") and cvodes_problem(system) is None:
                method = "cvodes"  # stiff on the CasADi backend: SUNDIALS' BDF, compiled, with CasADi's Jacobian
        t, X, how = simulate_flow.adaptive_run(system, options, x0, method, budget_of(options, method), desc,
                                               rates=rates)
    n = system.n
    extra = how.pop("_extra", 0)
    state = X[:, :X.shape[1] - extra]
    series = time_series.sampled_outputs(system, t, state)
    out = {**report(system, options, t, state, series), **how}
    if extra:
        balanced(out, energy_balance.figures(system, t, X, series))
    if system.is_lattice and system.metadata.ends == "fixed":
        out["mode_energies"] = mode_energies(system, X[-1, :n], X[-1, n:2 * n])
    return out


def _leapfrog_run(system, options: dict, q0, v0, budget: Budget, desc: str) -> tuple[np.ndarray, np.ndarray]:
    """Velocity Verlet from (q0, v0) with step dt, every ``save_every``-th state kept (default: about 1000)."""
    dt, t_end = float(options["dt"]), float(options["t_end"])
    steps = int(round(t_end / dt))
    budget.refuse(steps, f"nothing (refused before starting: t_end / dt = {steps:,} steps)")
    mats = system.linear(np.zeros(system.n))
    minv = leapfrog_masses(system, mats["M"])
    every = int(options.get("save_every", max(1, steps // 1000)))
    traj = leapfrog(lambda q: system.force(q) * minv, q0, v0, dt, steps, record_every=every, budget=budget,
                    progress=bool(options.get("progress", True)), desc=desc)
    return traj.t, np.hstack([traj.q, traj.v])


def plot(plt, a: dict, path: Path) -> list[Path]:
    """The coordinates against t (``plot = "phase"``: each coordinate against its velocity), the energy against
    t beside it (``<stem>_energy.png``); a chain without a trajectory: its final mode energies."""
    out = a["outputs"]
    if "trajectory" in out:
        return time_figures.time_history(plt, a, path)
    if "mode_energies" not in out:
        return []
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.bar(range(1, len(out["mode_energies"]) + 1), out["mode_energies"])
    ax.set_xlabel("mode k")
    ax.set_ylabel("E_k at t_end (J, or the model's energy unit)")
    ax.set_title(f"{a['name']}: mode energies at t_end")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


def summary_lines(outputs: dict) -> list[str]:
    """The default summary, the trajectory in one line."""
    return summary.output_lines(outputs, skip=("trajectory",)) + time_series.summary_lines(outputs)


register(AnalysisKind("simulate", SCHEMA, run_simulate, needs, summary_lines, check=check, plot=plot,
                      sweepable=True, point_defaults={"series": False}))
