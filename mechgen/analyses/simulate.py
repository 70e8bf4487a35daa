"""``simulate``: the time response from an initial state.

Scene keys: ``t_end`` (required), ``method`` (BDF, Radau, LSODA, RK45, DOP853, ``leapfrog`` with a
step ``dt`` (a model whose equations are q'' = M^-1 (-dV/dq) with a constant diagonal M only, else refused at
``method``: mechgen.runtime.core.splitting.require_separable), ``cvodes``: SUNDIALS' variable-order BDF with the
exact Jacobian, compiled through CasADi, for a lumped model built with ``backend = "casadi"``:
mechgen.runtime.core.sundials, or ``variational`` with ``dt`` and ``stages``: the variational integrator of
the model's own Lagrangian, mechgen.analyses.simulate_variational), ``rtol``, ``atol``, ``q0`` / ``v0`` (tables
of coordinates), ``initial_mode`` with
``amplitude`` (start from a linear mode), ``outputs`` (which model outputs to report), ``series``
(also report ``t`` and ``energy_series``), ``samples``. Outputs: the model's outputs at ``t_end``,
``energy_drift``, ``t_end``; a fixed-end chain also ``mode_energies``. A model with modes is run by
mechgen.analyses.simulate_hybrid, with the keys ``mode``, ``max_events``, ``zeno_events``, ``zeno_span``
and ``loop`` (the event loop: ``auto``, ``python`` or ``c``).

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

from mechgen.analyses import schema, summary
from mechgen.analyses.context import NAME
from mechgen.analyses.operating_point import vector
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, ALL_OUTPUTS, REQUIRED, Option
from mechgen.analyses.simulate_variational import check_fixed_step, simulate_variational
from mechgen.errors import ConvergenceError, InputError, SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget, BudgetExceeded
from mechgen.runtime.core.diagnose import explain_state
from mechgen.runtime.core.integrate import MIN_RTOL, integrate_first_order, leapfrog
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.core.splitting import require_separable
from mechgen.runtime.linear.modes import modes as solve_modes
from mechgen.scene.values import fail, listing, show, type_name

METHODS = ("BDF", "Radau", "LSODA", "RK45", "DOP853", "leapfrog", "cvodes", "variational")
#: the fixed-step methods (a dt, a step budget refused up front)
FIXED_STEP = ("leapfrog", "variational")
STEP = "a number > 0 (or an expression)"
#: default max_steps: the leapfrog's fixed steps, the adaptive methods' accepted steps
DEFAULT_STEPS = {"leapfrog": 10_000_000, "adaptive": 100_000}
#: stability intervals of the explicit methods, doubled (RK45: ~3.3, DOP853: ~6): steps >= t_end |lambda| / c
EXPLICIT_REACH = {"RK45": 7.0, "DOP853": 12.0}
#: what a model unfit for the leapfrog uses instead (mechgen.runtime.core.splitting.require_separable)
INSTEAD = ("method = 'variational' (a variational integrator of the model's own Lagrangian, any kinetic energy), "
           "or an implicit method ('Radau', 'BDF')")
#: the explicit methods' up-front stiffness estimate is made for first-order states up to this size
ESTIMATE_SIZE = 400


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
    """The event loop of a hybrid model (mechgen.runtime.core.events.LOOPS)."""
    from mechgen.runtime.core.events import LOOPS

    if not getattr(ctx.model, "modes", ()):
        raise fail(ctx.file, key, f"model {ctx.model.name} has no modes", "no 'loop' key (a smooth model)")
    return schema.one_of("loop", LOOPS)(ctx, key, value)


def _method(ctx, key: str, value: object) -> str:
    if not isinstance(value, str) or value not in METHODS:
        raise fail(ctx.file, key, f"unknown method {show(value)}", "one of: " + ", ".join(METHODS))
    return value


SCHEMA = {"t_end": Option(schema.positive, REQUIRED, STEP), "method": Option(_method, "BDF"),
          "dt": Option(schema.positive, ABSENT), "rtol": Option(schema.positive, 1e-8),
          "atol": Option(schema.positive, 1e-10), "q0": Option(schema.coordinate_table, {}),
          "v0": Option(schema.coordinate_table, {}), "initial_mode": Option(schema.count),
          "amplitude": Option(schema.number, 1.0), "outputs": Option(_outputs, ALL_OUTPUTS),
          "series": Option(schema.boolean, False), "samples": Option(schema.count_within("samples"), 201),
          "max_steps": Option(schema.count, ABSENT), "max_seconds": Option(schema.positive, ABSENT),
          "progress": Option(schema.boolean, ABSENT), "mode": Option(_mode, ABSENT),
          "max_events": Option(schema.count, ABSENT), "zeno_events": Option(schema.count, ABSENT),
          "zeno_span": Option(schema.positive, ABSENT), "loop": Option(_loop, ABSENT),
          "stages": Option(schema.count, ABSENT)}


def check(ctx, base: str, options: dict) -> None:
    """leapfrog and variational need dt (mechgen.analyses.simulate_variational.check_fixed_step); dt <= t_end;
    initial_mode within the coordinates; rtol at least MIN_RTOL."""
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
    if options.get("initial_mode", 0) > len(ctx.coordinates):
        raise fail(ctx.file, f"{base}.initial_mode", f"initial_mode {options['initial_mode']} exceeds the "
                   f"{len(ctx.coordinates)} coordinates", f"an integer from 1 to {len(ctx.coordinates)}")


def needs(options: dict, *, internal: bool) -> set[str]:
    """Residual, tangent and outputs (force and M for leapfrog; M, K for an initial mode)."""
    if options.get("method") == "leapfrog":
        return {"force", "outputs", "linear"}
    start = {"linear"} if options.get("initial_mode") else set()
    if options.get("method") == "variational":
        return {"lagrangian", "outputs"} | start
    return {"residual", "tangent", "outputs"} | start | ({"rates", "rates_tangent"} if internal else set())


def declared_start(system) -> np.ndarray | None:
    """The model's declared initial state (q, v, z) at the system's parameters (kernel ``initial``), or None."""
    if "initial" not in system.kernels:
        return None
    return np.asarray(system.call("initial")["x"], float).ravel()


def initial_state(system, options: dict) -> tuple[np.ndarray, np.ndarray]:
    """(q0, v0) from the options: tables of coordinates over the model's declared initial state (zero when it
    declares none), or a linear mode times an amplitude."""
    start = declared_start(system)
    n = system.n
    q0 = vector(system, options.get("q0"), None if start is None else start[:n])
    v0 = vector(system, options.get("v0"), None if start is None else start[n:2 * n])
    if options.get("initial_mode"):
        k = int(options["initial_mode"])
        if k > system.n:
            raise SceneError(f"initial_mode {k} exceeds the {system.n} degrees of freedom", key="initial_mode",
                             expected=f"an integer from 1 to {system.n}")
        mats = system.linear(np.zeros(system.n))
        shapes = solve_modes(mats["M"], mats["K"], count=k).shapes  # sparse shift-invert for a long chain
        shape = shapes[:, k - 1] / np.max(np.abs(shapes[:, k - 1]))
        q0 = q0 + options.get("amplitude", 1.0) * shape * np.sign(shape[np.argmax(np.abs(shape))])
    return q0, v0


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


def budget_of(options: dict, method: str) -> Budget:
    """The run's work budget: ``max_steps`` (default DEFAULT_STEPS of the method) and ``max_seconds``."""
    steps = options.get("max_steps", DEFAULT_STEPS["leapfrog" if method in FIXED_STEP else "adaptive"])
    what = f"{method} steps"
    return Budget(what, limit=int(steps), key="max_steps", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))


def refuse_explicit_stiff(system, x0: np.ndarray, t_end: float, method: str, budget: Budget) -> None:
    """An explicit method needs at least t_end |lambda|max / c steps for stability alone (|lambda|max: the
    largest eigenvalue magnitude of d(dx/dt)/dx at the start; c: EXPLICIT_REACH); refuse when that is
    more than the budget (the problem is stiff: the implicit methods have no such stability limit)."""
    if method not in EXPLICIT_REACH or x0.size > ESTIMATE_SIZE or budget.limit is None:
        return
    try:
        J = system.jacobian(0.0, x0)
        J = J.toarray() if hasattr(J, "toarray") else np.asarray(J, float)
        fastest = float(np.max(np.abs(np.linalg.eigvals(J)))) if np.all(np.isfinite(J)) else 0.0
    except Exception:  # no estimate: the step budget still holds during the run
        return
    needed = t_end * fastest / EXPLICIT_REACH[method]
    if needed > budget.limit:
        raise BudgetExceeded(f"{method} steps: an explicit method needs at least {needed:.3g} steps to stay stable "
                             f"over t_end = {t_end:g} (the fastest rate at the start is |lambda| = {fastest:.3g}/s), "
                             f"more than max_steps = {budget.limit:,}; the problem is stiff: the implicit methods "
                             "BDF and Radau are not bound by this limit", key="max_steps",
                             reached="nothing (refused before starting)")


def leapfrog_masses(system, M) -> np.ndarray:
    """1 / diag(M) for the leapfrog (a chain's lumped masses); a zero or non-finite mass is named."""
    diag = np.asarray(M.diagonal() if hasattr(M, "diagonal") else np.diag(M), float)
    bad = np.flatnonzero(~(np.isfinite(diag) & (diag > 0)))
    if bad.size:
        names = list(system.coordinates)
        raise ConvergenceError(f"leapfrog: the mass matrix's diagonal entry of coordinate '{names[bad[0]]}' is "
                               f"{diag[bad[0]]:.6g}; the leapfrog needs positive masses (a mass parameter of 0?)")
    return 1.0 / diag


def _cvodes(system, x0, t_end, t_eval, options, budget, progress, desc):
    """The run with SUNDIALS' CVODES on the system's CasADi kernels (mechgen.runtime.core.sundials)."""
    from mechgen.runtime.core.sundials import cvodes_problem, integrate_cvodes

    why = cvodes_problem(system)
    if why:
        raise InputError(why, key="method", expected="a method of this system's backend: BDF, Radau, LSODA, RK45, "
                         "DOP853 or leapfrog, or backend 'casadi' for 'cvodes'")
    return integrate_cvodes(system, x0, t_end, t_eval=t_eval, rtol=options.get("rtol", 1e-8),
                            atol=options.get("atol", 1e-10), budget=budget, progress=progress, desc=desc,
                            explain=lambda t, x: explain_state(system, t, x))


def run_simulate(system, options: dict, context: dict) -> dict:
    """Time response; reports the model's outputs at t_end and the energy drift."""
    if hasattr(system, "modes"):
        from mechgen.analyses.simulate_hybrid import run_hybrid

        return run_hybrid(system, options, context)
    q0, v0 = initial_state(system, options)
    t_end = float(options["t_end"])
    method = options.get("method", "BDF")
    budget = budget_of(options, method)
    progress = bool(options.get("progress", True))
    desc = context.get(NAME, "simulate")
    energy = lambda q, v: system.outputs(q, v)["energy"]  # noqa: E731
    if method == "leapfrog":
        require_separable(system, "method", "method 'leapfrog'", INSTEAD)
        dt = float(options["dt"])
        steps = int(round(t_end / dt))
        budget.refuse(steps, f"nothing (refused before starting: t_end / dt = {steps:,} steps)")
        mats = system.linear(np.zeros(system.n))
        minv = leapfrog_masses(system, mats["M"])
        traj = leapfrog(lambda q: system.force(q) * minv, q0, v0, dt, steps,
                        record_every=max(1, steps // 1000), energy=energy, budget=budget, progress=progress,
                        desc=desc)
        q_end, v_end, ts, energies = traj.q[-1], traj.v[-1], traj.t, np.asarray(traj.energy)
        z_end = None
    elif method == "variational":
        traj = simulate_variational(system, q0, v0, options, budget, progress, desc)
        q_end, v_end, ts, energies, z_end = traj.q[-1], traj.v[-1], traj.t, traj.energy, None
    else:
        start = declared_start(system)
        x0 = np.concatenate([q0, v0, np.zeros(system.m) if start is None else start[2 * system.n:]])
        refuse_explicit_stiff(system, x0, t_end, method, budget)
        n_out = int(options.get("samples", 201))
        require(dense_bytes(n_out, 3 * (2 * system.n + system.m) + 6), f"{n_out} output samples", key="samples")
        t_eval = np.linspace(0.0, t_end, max(n_out, 2))
        if method == "cvodes":
            traj = _cvodes(system, x0, t_end, t_eval, options, budget, progress, desc)
        else:
            traj = integrate_first_order(system.rhs, x0, t_end, jac=system.jacobian, method=method,
                                         rtol=options.get("rtol", 1e-8), atol=options.get("atol", 1e-10),
                                         t_eval=t_eval, budget=budget, progress=progress, desc=desc,
                                         explain=lambda t, x: explain_state(system, t, x))
        xs = traj.x if traj.x.shape[0] == len(traj.t) else traj.x.T
        n = system.n
        q_end, v_end, z_end = xs[-1, :n], xs[-1, n:2 * n], xs[-1, 2 * n:]
        ts = traj.t
        energies = np.array([system.outputs(x[:n], x[n:2 * n], x[2 * n:] if system.m else None)["energy"]
                             for x in xs])
    out = system.outputs(q_end, v_end, z_end if system.m else None)
    wanted = options.get("outputs")
    if wanted:
        out = {k: v for k, v in out.items() if k in wanted}
    e0 = energies[0]
    out["energy_drift"] = float(np.max(np.abs(energies - e0)) / max(abs(e0), 1e-300))
    out["t_end"] = t_end
    if system.is_lattice and system.metadata.ends == "fixed":
        out["mode_energies"] = mode_energies(system, q_end, v_end)
    if options.get("series"):
        out["t"] = [float(t) for t in ts]
        out["energy_series"] = [float(e) for e in energies]
    return out


def plot(plt, a: dict, path: Path) -> list[Path]:
    """Energy against time (``series = true``), else a chain's final mode energies; nothing otherwise."""
    out = a["outputs"]
    if "energy_series" not in out and "mode_energies" not in out:
        return []
    fig, ax = plt.subplots(figsize=(6, 4))
    if "energy_series" in out:
        ax.plot(out["t"], out["energy_series"])
        ax.set_xlabel("t")
        ax.set_ylabel("energy")
    else:
        ax.bar(range(1, len(out["mode_energies"]) + 1), out["mode_energies"])
        ax.set_xlabel("mode k")
        ax.set_ylabel("E_k at t_end")
    ax.set_title(a["name"])
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("simulate", SCHEMA, run_simulate, needs, summary.lines, check=check, plot=plot,
                      sweepable=True))
