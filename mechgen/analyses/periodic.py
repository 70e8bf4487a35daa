"""``periodic``: the periodic steady state of a hybrid model under a drive of period T, and its hysteresis.

The run starts at the model's declared initial state in its initial mode (``mode`` to choose) at t = 0
and is integrated over P = 2, 4, 8, ... periods (up to ``max_periods``); the state x(kT) at the start
of each period, with the loop's force and displacement outputs there (a model's state need not carry
the drive's phase: a slipping contact's force is mu N at any phase), is compared with its value at
(k-1)T: the steady period is the first [(k-1)T, kT] with

    |y_i(kT) - y_i((k-1)T)| <= atol_periodic + tolerance |y_i(kT)|   for every entry i of y = (x, f, x_out),
    in the same mode,

else a ConvergenceError names the last time, mode and difference. Over that period, split at its
events (where the outputs have kinks) and each smooth piece into ``pieces`` equal parts with ``nodes``
Gauss-Legendre points each, the force f = output ``force_output`` (N) and the displacement x = output
``displacement_output`` (m) give, with omega = 2 pi / T (rad/s):

    energy_per_cycle W = integral of f dx over the period (J; the loop area, > 0 when dissipated),
        with dx/dt the derivative of the Legendre interpolant of x on each part (exact to round-off for
        a smooth drive);
    first harmonics F1 = (2/T) int f exp(-i omega t) dt, X1 = (2/T) int x exp(-i omega t) dt, so that
        f ~ Re(F1 exp(i omega t)); complex stiffness K = F1 / X1 and
    equivalent_stiffness k_eq = Re K (N/m),  equivalent_damping c_eq = Im K / omega (N s/m):
        f ~ k_eq x + c_eq dx/dt in the first harmonic (for x = U cos(omega t): k_eq = (1/(pi U)) int f
        cos(theta) d theta, c_eq = -(1/(pi U omega)) int f sin(theta) d theta, theta = omega t, and a
        linear element has W = pi omega c_eq U^2).

Outputs: ``energy_per_cycle``, ``equivalent_stiffness``, ``equivalent_damping``, ``steady_period``
(k: the period [(k-1)T, kT] used), ``periodicity_error`` (max |y(kT) - y((k-1)T)|: state and loop point), ``cycle_events``
(the events of that period); with ``curve``, ``displacement_series`` and ``force_series`` (the loop).
Integration keys as impact: ``method`` (DOP853), ``rtol`` (1e-12), ``atol`` (1e-14), ``max_steps``,
``max_seconds``, ``loop``; ``max_events`` and ``zeno_events`` as simulate.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, REQUIRED, Option
from mechgen.analyses.simulate_start import budget_of, declared_start
from mechgen.errors import ConvergenceError, SceneError
from mechgen.runtime.integration.events import LOOPS, integrate_hybrid

SCHEMA = {
    "period": Option(schema.positive, REQUIRED, "a number > 0", doc="the drive's period T (s, or the model's time "
                     "unit)"),
    "force_output": Option(schema.name, "force", doc="the model output that is the loop's force f (N)"),
    "displacement_output": Option(schema.name, "displacement", doc="the model output that is the loop's "
                                  "displacement x (m)"),
    "max_periods": Option(schema.count, 64, doc="the most periods integrated while looking for the steady one"),
    "tolerance": Option(schema.positive, 1e-9, doc="the relative periodicity tolerance of the state and loop "
                        "point between consecutive periods"),
    "atol_periodic": Option(schema.positive, 1e-12, doc="the absolute periodicity tolerance (the entries' units)"),
    "mode": Option(schema.name, ABSENT, doc="the mode to start in (default the model's initial mode)"),
    "nodes": Option(schema.count, 16, doc="Gauss-Legendre points per part of a smooth piece of the period"),
    "pieces": Option(schema.count, 4, doc="equal parts each smooth piece of the period is split into for the "
                     "quadratures"),
    "method": Option(schema.name, "DOP853", doc="the integrator (as impact's)"),
    "rtol": Option(schema.positive, 1e-12, doc="the integrator's relative tolerance"),
    "atol": Option(schema.positive, 1e-14, doc="the integrator's absolute tolerance (the state's units)"),
    "curve": Option(schema.boolean, False, doc="also report the loop: displacement_series and force_series"),
    "max_events": Option(schema.count, ABSENT, doc="the most events of the whole run (default 10^4; at most max_steps, "
                         "and its stored events must fit in memory)"),
    "zeno_events": Option(schema.count, ABSENT, doc="more than this many events within 1e-9 times the run's end time "
                          "is a Zeno approach (default 100; at most max_events)"),
    "max_steps": Option(schema.count, ABSENT, doc="the work budget in integrator steps"),
    "max_seconds": Option(schema.positive, ABSENT, doc="the wall-time budget (s, default 600)"),
    "loop": Option(schema.one_of("loop", LOOPS), "auto", doc="the event loop: auto (compiled for DOP853 on the "
                   "C backend, else Python), python or c"),
}


def needs(options: dict, *, internal: bool) -> set[str]:
    """What simulate needs, the internal rates with it."""
    return {"residual", "tangent", "outputs"} | ({"rates", "rates_tangent"} if internal else set())


def check(ctx, base: str, options: dict) -> None:
    """The model has modes; max_events <= max_steps and zeno_events <= max_events (as simulate: a larger count
    can never be reached within the step budget, refused at load at the key)."""
    from mechgen.analyses.impact import hybrid_only
    from mechgen.analyses.simulate import check_event_bounds

    hybrid_only(ctx, base, options)
    check_event_bounds(ctx, base, options)


def loop_outputs(system, traj, names: tuple[str, str]) -> np.ndarray:
    """The outputs ``names`` (force, displacement) at each sample of a hybrid trajectory, (samples, 2)."""
    n, m = system.n, system.m
    views, rows = {}, []
    for ti, xi, mi in zip(traj.t, traj.x, traj.mode):
        view = views.setdefault(int(mi), system.mode(int(mi)))
        out = view.outputs(xi[:n], xi[n:2 * n], xi[2 * n:] if m else None, float(ti))
        for name, key in zip(names, ("force_output", "displacement_output")):
            if name not in out:
                raise SceneError(f"model {system.metadata.model} has no output {name!r}", key=key,
                                 expected="one of: " + ", ".join(out))
        rows.append([out[names[0]], out[names[1]]])
    return np.array(rows, dtype=float).reshape(-1, 2)


def steady_period(system, x0, mode, period: float, options: dict, run: dict) -> tuple[int, float, object]:
    """(k, error, trajectory): the first period [(k-1)T, kT] whose end state and loop point repeat its start
    (module doc)."""
    from mechgen.analyses.simulate_hybrid import require_event_memory, rules_of

    require_event_memory(options, np.asarray(x0).size)
    limit = int(options.get("max_periods", 64))
    tol, floor = float(options.get("tolerance", 1e-9)), float(options.get("atol_periodic", 1e-12))
    count = min(2, limit)
    loop = (options.get("force_output", "force"), options.get("displacement_output", "displacement"))
    while True:
        times = period * np.arange(count + 1)
        traj = integrate_hybrid(system, x0, times[-1], mode=mode, t_eval=times, rules=rules_of(options),
                                budget=budget_of(options, run["method"]), **run)
        if traj.terminated:
            raise ConvergenceError(f"periodic: the run ended at a terminal event, t = {traj.t_final:.6g} in mode "
                                   f"{system.modes[traj.final_mode]} (a periodic drive needs a model without terminal events)")
        y = np.hstack([traj.x, loop_outputs(system, traj, loop)])
        diffs = np.abs(np.diff(y, axis=0))
        bound = floor + tol * np.abs(y[1:])
        for k in range(1, count + 1):
            if np.all(diffs[k - 1] <= bound[k - 1]) and traj.mode[k] == traj.mode[k - 1]:
                return k, float(np.max(diffs[k - 1])), traj
        if count >= limit:
            raise ConvergenceError(f"periodic: no periodic steady state within {count} periods: at t = "
                                   f"{times[-1]:.6g} (mode {system.modes[int(traj.mode[-1])]}) the state differs "
                                   f"from one period before by {np.max(diffs[-1]):.3g} (key max_periods: more periods, a looser "
                                   "tolerance, or a drive that settles)")
        count = min(2 * count, limit)


def quadrature(breaks, nodes: int, pieces: int):
    """Gauss-Legendre points, weights and piece index on each of ``pieces`` parts of every interval."""
    xg, wg = np.polynomial.legendre.leggauss(nodes)
    points, weights, part = [], [], []
    edges = np.concatenate([np.linspace(a, b, pieces + 1)[:-1] for a, b in zip(breaks[:-1], breaks[1:])]
                           + [breaks[-1:]])
    for j, (a, b) in enumerate(zip(edges[:-1], edges[1:])):
        if b <= a:
            continue
        points.append((a + b) / 2 + (b - a) / 2 * xg)
        weights.append((b - a) / 2 * wg)
        part.append(np.full(nodes, j))
    return np.concatenate(points), np.concatenate(weights), np.concatenate(part), xg


def run_periodic(system, options: dict, context: dict) -> dict:
    """See the module doc."""
    from mechgen.analyses.simulate_hybrid import event_log, rules_of, start_mode

    if not hasattr(system, "modes"):
        raise SceneError(f"model {system.metadata.model} has no modes", key="kind",
                         expected="a hybrid model for a periodic analysis")
    period = float(options["period"])
    start = declared_start(system)
    n, m = system.n, system.m
    x0 = np.zeros(2 * n + m) if start is None else start
    mode = start_mode(system, options)
    run = dict(method=options.get("method", "DOP853"), rtol=options.get("rtol", 1e-12),
               atol=options.get("atol", 1e-14), loop=options.get("loop", "auto"))
    k, error, traj = steady_period(system, x0, mode, period, options, run)
    t0, t1 = (k - 1) * period, k * period
    events = [e for e in traj.events if t0 < e.t < t1]
    breaks = np.array([t0] + sorted({float(e.t) for e in events}) + [t1])
    nodes, pieces = int(options.get("nodes", 16)), int(options.get("pieces", 4))
    t, w, part, xg = quadrature(breaks, nodes, pieces)
    again = integrate_hybrid(system, x0, t1, mode=mode, t_eval=t, rules=rules_of(options), **run)
    force, disp = options.get("force_output", "force"), options.get("displacement_output", "displacement")
    f, x = loop_outputs(system, again, (force, disp)).T
    # dx/dt on each part: derivative of the Legendre interpolant through its nodes
    rate = np.empty(t.size)
    for j in np.unique(part):
        sel = part == j
        h = (t[sel][-1] - t[sel][0]) / (xg[-1] - xg[0])
        coef = np.polynomial.legendre.legfit(xg, x[sel], nodes - 1)
        rate[sel] = np.polynomial.legendre.legval(xg, np.polynomial.legendre.legder(coef)) / h
    omega = 2 * np.pi / period
    phase = np.exp(-1j * omega * t)
    f1, x1 = 2 / period * np.sum(w * f * phase), 2 / period * np.sum(w * x * phase)
    if abs(x1) == 0:
        raise ConvergenceError(f"periodic: the displacement {disp!r} has no first harmonic over t = [{t0:.6g}, "
                               f"{t1:.6g}] (key displacement_output: a displacement driven at the period)")
    stiff = f1 / x1
    out = {"energy_per_cycle": float(np.sum(w * f * rate)), "equivalent_stiffness": float(stiff.real),
           "equivalent_damping": float(stiff.imag / omega), "steady_period": k, "periodicity_error": error,
           "cycle_events": event_log(system, events)}
    if options.get("curve"):
        out["displacement_series"] = [float(v) for v in x]
        out["force_series"] = [float(v) for v in f]
    return out


def plot(plt, a: dict, path) -> list:
    """The force-displacement hysteresis loop (``curve = true``); nothing otherwise."""
    out = a["outputs"]
    if "force_series" not in out:
        return []
    return figures.loop(plt, out["displacement_series"], out["force_series"], path, xlabel="displacement",
                        title=f"{a['name']}: W = {out['energy_per_cycle']:.4g}", style=".-")


def summary_lines(outputs: dict) -> list[str]:
    """Every output but the series."""
    return summary.output_lines(outputs, skip=("displacement_series", "force_series", "cycle_events"))


register(AnalysisKind("periodic", SCHEMA, run_periodic, needs, summary_lines, check=check, plot=plot,
                      sweepable=True))
