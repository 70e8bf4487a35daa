"""``impact``: one compliant impact of a hybrid model, measured from contact to release.

The run starts at the model's declared initial state (``@model.initial``) with the entries of ``q0`` /
``v0`` (tables of coordinates) replacing those they name (an impact model starts at x = 0 moving in, so
the contact guard fires at t = 0) in the model's initial mode and ends at the first event that
leaves the contact mode (``contact_mode``, default the mode the first event enters), or at ``t_end``
when the body never leaves it (``released`` false: a perfectly plastic impact, e = 0). Along
``coordinate`` (default the first), with v_c the velocity entering contact and v_r the velocity
at release:

    restitution e = -v_r / v_c,   contact_duration = t_r - t_c,
    energy_lost = 1 - E(t_r) / E(t_c)     (E: the model's energy, the contact's stored energy included;
                                           at t_end when there is no release).

With ``curve = true`` the outputs also hold ``penetration_series`` and ``force_series`` (the
coordinate and the output ``force_output``, default ``force``) at ``samples`` times over the
contact: the force-penetration hysteresis. Integration keys as simulate (mechgen.analyses.simulate):
``method`` (default DOP853), ``rtol`` (1e-10), ``atol`` (1e-12), ``max_steps``, ``max_seconds``, and
``loop`` (default ``auto``: the compiled event loop of mechgen.runtime.integration.events_c for DOP853 on the C
backend, else the Python one; ``python`` or ``c`` to choose).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.operating_point import vector
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, REQUIRED, Option
from mechgen.analyses.simulate_start import budget_of, declared_start
from mechgen.errors import SceneError
from mechgen.runtime.integration.events import LOOPS, integrate_hybrid
from mechgen.scene.values import fail, listing, show

STEP = "a number > 0 (or an expression)"


def _method(ctx, key: str, value: object) -> str:
    from mechgen.analyses.simulate import METHODS

    return schema.one_of("method", [m for m in METHODS if m not in ("leapfrog", "auto")])(ctx, key, value)


def _coordinate(ctx, key: str, value: object) -> str:
    if not isinstance(value, str) or value not in ctx.coordinates:
        raise fail(ctx.file, key, f"unknown coordinate {show(value)}", "one of: " + listing(ctx.coordinates))
    return value


def hybrid_only(ctx, base: str, options: dict) -> None:
    """The model has modes; ``contact_mode`` is one of them."""
    modes = tuple(getattr(ctx.model, "modes", ()))
    if not modes:
        raise fail(ctx.file, f"{base}.kind", f"model {ctx.model.name} has no modes",
                   "a hybrid model (modes, guards and resets: mechgen.symbolic.hybrid)")
    if "contact_mode" in options and options["contact_mode"] not in modes:
        raise fail(ctx.file, f"{base}.contact_mode", f"unknown mode {show(options['contact_mode'])}",
                   "one of the model's modes: " + ", ".join(modes))


SCHEMA = {
    "t_end": Option(schema.positive, REQUIRED, STEP, doc="the latest end time of the run, reached when the body "
                    "never leaves contact (s, or the model's time unit)"),
    "method": Option(_method, "DOP853", doc="the integrator (as simulate's adaptive methods)"),
    "rtol": Option(schema.positive, 1e-10, doc="the integrator's relative tolerance"),
    "atol": Option(schema.positive, 1e-12, doc="the integrator's absolute tolerance (the state's units)"),
    "q0": Option(schema.coordinate_table, {}, doc="initial coordinates replacing those of the model's declared "
                 "initial state, coordinate = value"),
    "v0": Option(schema.coordinate_table, {}, doc="initial velocities replacing those of the model's declared "
                 "initial state, coordinate = value (the coordinate's unit per s; required without one)"),
    "coordinate": Option(_coordinate, ABSENT, doc="the coordinate along which restitution is measured (default "
                         "the first)"),
    "contact_mode": Option(schema.name, ABSENT, doc="the contact mode whose leaving ends the impact (default "
                           "the mode the first event enters)"),
    "force_output": Option(schema.name, "force", doc="the model output that is the contact force (N) of the "
                           "hysteresis curve"),
    "curve": Option(schema.boolean, False, doc="also report the force-penetration hysteresis "
                    "(penetration_series, force_series)"),
    "samples": Option(schema.count_within("samples"), 200, doc="points of the hysteresis curve over the "
                      "contact"),
    "max_steps": Option(schema.count, ABSENT, doc="the work budget in integrator steps"),
    "max_seconds": Option(schema.positive, ABSENT, doc="the wall-time budget (s, default 600)"),
    "loop": Option(schema.one_of("loop", LOOPS), "auto", doc="the event loop: auto (compiled for DOP853 on the "
                   "C backend, else Python), python or c"),
}


def needs(options: dict, *, internal: bool) -> set[str]:
    """What simulate needs (residual, tangent, outputs, the internal rates), guards and resets with them."""
    return {"residual", "tangent", "outputs"} | ({"rates", "rates_tangent"} if internal else set())


def measure(system, options: dict) -> dict:
    """One impact: restitution, contact duration, energy lost, released (and the hysteresis with ``curve``)."""

    if not hasattr(system, "modes"):
        raise SceneError(f"model {system.metadata.model} has no modes", key="kind",
                         expected="a hybrid model for an impact analysis")
    n = system.n
    coordinate = options.get("coordinate", system.coordinates[0])
    i = list(system.coordinates).index(coordinate)

    start = declared_start(system)
    if start is None and not options.get("v0"):
        raise SceneError(f"model {system.metadata.model} declares no initial state and the impact gives no v0",
                         key="v0", expected="a table v0 = {coordinate = speed} (or @model.initial in the model)")
    base = np.zeros(2 * n + system.m) if start is None else start
    x0 = np.concatenate([vector(system, options.get("q0"), base[:n]), vector(system, options.get("v0"), base[n:2 * n]),
                         base[2 * n:]])
    contact = options.get("contact_mode")
    contact = None if contact is None else system.mode_index(contact)
    state = {"contact": contact}

    def left_contact(event) -> bool:
        if state["contact"] is None and event.target is not None and event.source == system.initial_mode:
            state["contact"] = event.target
            return False
        return event.source == state["contact"]

    method = options.get("method", "DOP853")
    run = dict(method=method, rtol=options.get("rtol", 1e-10), atol=options.get("atol", 1e-12),
               loop=options.get("loop", "auto"))
    t_end = float(options["t_end"])
    traj = integrate_hybrid(system, x0, t_end, budget=budget_of(options, method), stop_after=left_contact, **run)
    entry = next((e for e in traj.events if e.target == state["contact"]), None)
    leave = next((e for e in traj.events if state["contact"] is not None and e.source == state["contact"]), None)
    if entry is None:
        raise SceneError(f"the body never entered a contact mode by t_end = {t_end:g}", key="v0",
                         expected="an initial state that meets the contact (x = 0 moving in)")
    energy = _energy(system)
    v_c = entry.x_after[n + i]
    e0 = energy(state["contact"], entry.t, entry.x_after)
    if leave is None:
        out = {"restitution": 0.0, "contact_duration": None, "released": False,
               "energy_lost": float(1 - energy(traj.final_mode, traj.t_final, traj.x_final) / e0)}
        t_r = traj.t_final
    else:
        out = {"restitution": float(-leave.x_before[n + i] / v_c), "contact_duration": float(leave.t - entry.t),
               "released": True, "energy_lost": float(1 - energy(state["contact"], leave.t, leave.x_before) / e0)}
        t_r = leave.t
    if options.get("curve"):
        times = np.linspace(entry.t, t_r, int(options.get("samples", 200)))
        again = integrate_hybrid(system, x0, t_r, t_eval=times, stop_after=left_contact, **run)
        view = system.mode(state["contact"])
        force = options.get("force_output", "force")
        out["penetration_series"] = [float(x[i]) for x in again.x]
        out["force_series"] = [float(view.outputs(x[:n], x[n:2 * n], x[2 * n:] if system.m else None, t)[force])
                               for t, x in zip(again.t, again.x)]
    return out


def _energy(system):
    views = {}

    def energy(mode: int, t: float, x: np.ndarray) -> float:
        if mode not in views:
            views[mode] = system.mode(mode)
        n = system.n
        return views[mode].outputs(x[:n], x[n:2 * n], x[2 * n:] if system.m else None, t)["energy"]

    return energy


def run_impact(system, options: dict, context: dict) -> dict:
    """See the module doc."""
    return measure(system, options)


def plot(plt, a: dict, path) -> list:
    """The force-penetration hysteresis (``curve = true``); nothing otherwise."""
    out = a["outputs"]
    if "force_series" not in out:
        return []
    return figures.loop(plt, out["penetration_series"], out["force_series"], path, xlabel="penetration",
                        title=f"{a['name']}: e = {out['restitution']:.4g}")


def summary_lines(outputs: dict) -> list[str]:
    """Every output but the series."""
    return summary.output_lines(outputs, skip=("penetration_series", "force_series"))


register(AnalysisKind("impact", SCHEMA, run_impact, needs, summary_lines, check=hybrid_only, plot=plot,
                      sweepable=True))
