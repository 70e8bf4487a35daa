"""``simulate`` of a hybrid model (mechgen.symbolic.hybrid): integration between events, resets, an event log.

The same scene keys as a smooth model's simulate (mechgen.analyses.simulate) plus ``mode`` (the mode
the run starts in; default the model's initial mode), ``max_events`` (default 10^4), ``zeno_events``
(default 100) and ``zeno_span`` (default 1e-9 t_end): more than ``zeno_events`` events within
``zeno_span`` is a Zeno or chattering approach and ends the run (exit 1, naming time and mode).
The rules for grazing, simultaneous events, events at t = 0 and events inside a step are those of
mechgen.runtime.integration.events; ``loop`` chooses the event loop that applies them (default ``auto``: the
compiled one of mechgen.runtime.integration.events_c for DOP853 on the C backend, else the Python one;
``python`` or ``c`` to choose). Outputs: the model's outputs at the end of the run (in the mode it
ended in), ``events`` (a list of ``{t, from, to, guard}``; ``to`` is null for a terminal event),
``final_mode``, ``t_final`` (t_end, or the time of the terminal event), ``energy_drift`` (a conservative
run) or the energy balance (``energy_balance_error``, ``work``, ``dissipated``: the powers of every mode
integrated with the state and carried across the events, mechgen.runtime.integration.augmented.BalancedHybrid, and
the energy each reset takes; mechgen.analyses.energy_balance.hybrid_balance) and ``t_end``; with the time history (mechgen.analyses.time_series: ``t``, ``trajectory``, ``energy_series``)
``mode_series``, the mode at each sample (the state where the run ended is the last sample). ``on_zeno =
"stop"`` ends a run at a Zeno approach instead of failing: the events so far, ``t_final`` at the event that
made it Zeno, and ``zeno = true``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import energy_balance, time_series
from mechgen.analyses.context import NAME
from mechgen.analyses.simulate_start import balanced, budget_of, declared_start, initial_state, report
from mechgen.errors import SceneError
from mechgen.runtime.integration.augmented import BalancedHybrid
from mechgen.runtime.core.diagnose import explain_state
from mechgen.runtime.integration.events import EventRules, ZenoApproach, integrate_hybrid
from mechgen.runtime.integration.run_options import RunOptions
from mechgen.runtime.core.memory import dense_bytes, require


def start_mode(system, options: dict) -> int:
    """Index of the mode named by ``mode`` (default: the model's initial mode)."""
    name = options.get("mode")
    if name is None:
        return system.initial_mode
    if name not in system.modes:
        raise SceneError(f"unknown mode {name!r} of model {system.metadata.model}", key="mode",
                         expected="one of: " + ", ".join(system.modes))
    return system.mode_index(name)


def rules_of(options: dict) -> EventRules:
    """The event bounds of the options (EventRules defaults where absent)."""
    base = EventRules()
    return EventRules(int(options.get("max_events", base.max_events)),
                      int(options.get("zeno_events", base.zeno_events)), options.get("zeno_span"))


#: memory of one stored event beyond its two states (the Event record, its JSON log entry, the Zeno ring's time),
#: bytes: a bouncing ball (2 states) peaked at 116 MB with 10^4 events and 145 MB with 10^5 in the compiled loop
#: (330 B per event), 98 MB and 167 MB in the Python loop (770 B per event, its Event objects); with a margin
EVENT_BYTES = 1_000


def require_event_memory(options: dict, states: int) -> None:
    """Refuse up front (exit 2 at ``max_events``) a hybrid run whose event store could outgrow the memory limit:
    max_events x (EVENT_BYTES + 3 x 8 x states) bytes (the states before and after each event, and one copy in the
    outputs), mechgen.runtime.core.memory.require."""
    events = int(options.get("max_events", EventRules.max_events))
    require(events * (EVENT_BYTES + 3 * 8 * int(states)), f"{events:,} stored events (a state of {int(states)} entries each)",
            key="max_events", expected="a smaller max_events")


def event_log(system, events) -> list[dict]:
    """The events as JSON records ``{t, from, to, guard}`` (mode names; ``to`` None when the run ended)."""
    names = system.modes
    return [{"t": float(e.t), "from": names[e.source], "to": None if e.target is None else names[e.target],
             "guard": e.guard} for e in events]


def run_hybrid(system, options: dict, context: dict) -> dict:
    """Time response of a hybrid system; see the module doc."""

    if options.get("method") == "leapfrog":
        raise SceneError("method 'leapfrog' cannot integrate a hybrid model (its modes switch at events)",
                         key="method", expected="BDF, Radau, LSODA, RK45 or DOP853")
    q0, v0 = initial_state(system, options)
    start = declared_start(system)
    x0 = np.concatenate([q0, v0, np.zeros(system.m) if start is None else start[2 * system.n:]])
    n_out = int(options.get("samples", 201))
    require(dense_bytes(n_out, 3 * x0.size + 6), f"{n_out} output samples", key="samples")
    require_event_memory(options, x0.size)
    carry = energy_balance.hybrid_accounted(system)
    runner = BalancedHybrid(system) if carry else system
    x_run = np.concatenate([x0, np.zeros(energy_balance.EXTRA)]) if carry else x0
    traj, zeno, method = hybrid_run(runner, options, x_run, context.get(NAME, "simulate"))
    t, X_run, modes = with_final(traj)
    X = X_run[:, :x0.size]
    mode_system = mode_views(system)
    series = time_series.sampled_outputs_by_mode(mode_system, t, X, modes)
    out = report(system, options, t, X, series)
    if carry:  # the powers integrated through every mode, the resets' losses from the states at the events
        figures = energy_balance.hybrid_balance(mode_system, t, X_run, modes, traj.events, series)
    else:
        figures = energy_balance.hybrid_figures(mode_system, t, X, modes, traj.events, series)
    if figures is not None and "_work_series" in figures:
        balanced(out, figures)
    elif figures is not None:  # resets that change the energy, or modes that are not conservative
        del out["energy_drift"]
        out.update(figures)
    out["t_final"] = float(traj.t_final)
    out["events"] = event_log(system, traj.events)
    out["final_mode"] = system.modes[traj.final_mode]
    if "trajectory" in out:
        out["mode_series"] = [system.modes[int(k)] for k in modes]
    if zeno:
        out["zeno"] = True
    out["method"], out["loop"] = method, traj.extra.get("loop", "python")
    return out


def hybrid_run(system, options: dict, x0: np.ndarray, desc: str):
    """(the HybridTrajectory, whether it ended at a Zeno approach, the method that ran): ``on_zeno = "stop"`` keeps
    the run up to the event that made it Zeno (mechgen.runtime.integration.events.ZenoApproach); the default lets the
    error end it. ``method = "auto"`` is decided on the initial mode (mechgen.analyses.simulate_flow)."""

    plain = getattr(system, "system", system)  # a BalancedHybrid's own system: the state without the integrals
    method, t_end = options.get("method", "auto"), float(options["t_end"])
    if method == "auto":  # decided on the initial mode's linearisation (mechgen.analyses.simulate_flow)
        from mechgen.analyses.simulate_flow import chosen_method

        method = chosen_method(system.mode(start_mode(system, options)), x0, t_end)
    run = RunOptions(method=method, rtol=options.get("rtol", 1e-8), atol=options.get("atol", 1e-10),
                     t_eval=np.linspace(0.0, t_end, int(options.get("samples", 201))),
                     budget=budget_of(options, method), rules=rules_of(options),
                     progress=bool(options.get("progress", True)), desc=desc,
                     explain=lambda t, x: explain_state(plain, t, np.asarray(x)[:2 * plain.n + plain.m]),
                     loop=options.get("loop", "auto"))
    try:
        traj = integrate_hybrid(system, x0, t_end, mode=start_mode(system, options), options=run)
    except ZenoApproach as exc:
        if options.get("on_zeno", "error") != "stop" or exc.trajectory is None:
            raise
        return exc.trajectory, True, method
    return traj, False, method


def with_final(traj) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The samples (t, x rows, mode per sample) with the state where the run ended appended when it ended after
    the last sample (a terminal event or a Zeno stop before t_end, or no sample at all)."""
    t, X, modes = np.asarray(traj.t, float), np.asarray(traj.x, float), np.asarray(traj.mode, int)
    if t.size and t[-1] >= traj.t_final and modes[-1] == traj.final_mode:
        return t, X, modes
    return (np.append(t, traj.t_final), np.vstack([X.reshape(len(t), -1), traj.x_final[None, :]]),
            np.append(modes, traj.final_mode))


def mode_views(system):
    """``mode_system(k)``: the system of mode k (System.mode), each made once."""
    views: dict = {}

    def mode_system(k: int):
        if k not in views:
            views[k] = system.mode(k)
        return views[k]

    return mode_system
