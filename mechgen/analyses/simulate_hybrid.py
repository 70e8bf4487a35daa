"""``simulate`` of a hybrid model (mechgen.symbolic.hybrid): integration between events, resets, an event log.

The same scene keys as a smooth model's simulate (mechgen.analyses.simulate) plus ``mode`` (the mode
the run starts in; default the model's initial mode), ``max_events`` (default 10^4), ``zeno_events``
(default 100) and ``zeno_span`` (default 1e-9 t_end): more than ``zeno_events`` events within
``zeno_span`` is a Zeno or chattering approach and ends the run (exit 1, naming time and mode).
The rules for grazing, simultaneous events, events at t = 0 and events inside a step are those of
mechgen.runtime.core.events; ``loop`` chooses the event loop that applies them (default ``auto``: the
compiled one of mechgen.runtime.core.events_c for DOP853 on the C backend, else the Python one;
``python`` or ``c`` to choose). Outputs: the model's outputs at the end of the run (in the mode it
ended in), ``events`` (a list of ``{t, from, to, guard}``; ``to`` is null for a terminal event),
``final_mode``, ``t_final`` (t_end, or the time of the terminal event), ``energy_drift`` and
``t_end``; with ``series``: ``t``, ``energy_series`` and ``mode_series``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.context import NAME
from mechgen.errors import SceneError
from mechgen.runtime.core.diagnose import explain_state
from mechgen.runtime.core.events import EventRules, integrate_hybrid
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


def event_log(system, events) -> list[dict]:
    """The events as JSON records ``{t, from, to, guard}`` (mode names; ``to`` None when the run ended)."""
    names = system.modes
    return [{"t": float(e.t), "from": names[e.source], "to": None if e.target is None else names[e.target],
             "guard": e.guard} for e in events]


def run_hybrid(system, options: dict, context: dict) -> dict:
    """Time response of a hybrid system; see the module doc."""
    from mechgen.analyses.simulate import budget_of, initial_state

    if options.get("method") == "leapfrog":
        raise SceneError("method 'leapfrog' cannot integrate a hybrid model (its modes switch at events)",
                         key="method", expected="BDF, Radau, LSODA, RK45 or DOP853")
    q0, v0 = initial_state(system, options)
    t_end = float(options["t_end"])
    method = options.get("method", "BDF")
    mode = start_mode(system, options)
    from mechgen.analyses.simulate import declared_start

    start = declared_start(system)
    x0 = np.concatenate([q0, v0, np.zeros(system.m) if start is None else start[2 * system.n:]])
    n_out = int(options.get("samples", 201))
    require(dense_bytes(n_out, 3 * x0.size + 6), f"{n_out} output samples", key="samples")
    traj = integrate_hybrid(system, x0, t_end, mode=mode, method=method, rtol=options.get("rtol", 1e-8),
                            atol=options.get("atol", 1e-10), t_eval=np.linspace(0.0, t_end, n_out),
                            budget=budget_of(options, method), rules=rules_of(options),
                            progress=bool(options.get("progress", True)), desc=context.get(NAME, "simulate"),
                            explain=lambda t, x: explain_state(system, t, x), loop=options.get("loop", "auto"))
    n = system.n
    views = {}

    def outputs(k: int, x: np.ndarray, t: float) -> dict:
        if k not in views:
            views[k] = system.mode(k)
        return views[k].outputs(x[:n], x[n:2 * n], x[2 * n:] if system.m else None, t)

    out = outputs(traj.final_mode, traj.x_final, traj.t_final)
    wanted = options.get("outputs")
    if wanted:
        out = {k: v for k, v in out.items() if k in wanted}
    energies = np.array([outputs(int(k), x, float(t))["energy"] for t, x, k in zip(traj.t, traj.x, traj.mode)]
                        + [outputs(traj.final_mode, traj.x_final, traj.t_final)["energy"]])
    e0 = energies[0]
    out["energy_drift"] = float(np.max(np.abs(energies - e0)) / max(abs(e0), 1e-300))
    out["t_end"] = t_end
    out["t_final"] = float(traj.t_final)
    out["events"] = event_log(system, traj.events)
    out["final_mode"] = system.modes[traj.final_mode]
    if options.get("series"):
        out["t"] = [float(t) for t in traj.t]
        out["energy_series"] = [float(e) for e in energies[:-1]]
        out["mode_series"] = [system.modes[int(k)] for k in traj.mode]
    return out
