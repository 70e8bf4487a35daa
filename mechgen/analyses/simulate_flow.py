"""How ``simulate`` integrates a smooth model with an adaptive method: the method ``auto``, and the loop.

* ``method = "auto"`` (the default) looks at the linearisation of dx/dt at the start, J = d(dx/dt)/dx: when
  its fastest *decaying* rate, max(-Re lambda), would hold an explicit method to more than :data:`STIFF_STEPS`
  steps for stability alone over t_end (t_end max(-Re lambda) / 12, DOP853's stability interval doubled), the
  problem is stiff and ``Radau`` (implicit, order 5, Newton on the generated Jacobian) runs it; otherwise
  ``DOP853`` (explicit, order 8). Fast *oscillations* (Re lambda ~ 0) do not make it stiff: any method must
  resolve them to be accurate, and the explicit one does so cheapest. Above :data:`ESTIMATE_SIZE` first-order
  states (no dense eigen-solve) the rule weighs a continuum's :data:`LARGEST` eigenvalues of largest magnitude
  (ARPACK on the sparse linearisation: :func:`largest_rates`); any other system's ``auto`` is ``BDF``, the
  sparse-friendly implicit method.
* ``DOP853`` on the C backend runs in the compiled loop (mechgen.runtime.integration.smooth_c for a lumped model,
  mechgen.runtime.fields.flow_c for a continuum with a constant mass: no Python between the steps; the same steps
  as scipy's DOP853) unless ``loop = "python"``; so does ``Radau`` for a lumped model on the C backend
  (mechgen.runtime.integration.radau_c: scipy's Radau step for step, Newton on the generated Jacobian), so that
  ``auto``'s stiff choice runs compiled there; every other method (``BDF``, ``LSODA``, ``RK45``, ``Radau`` on a
  continuum, and both on the numpy or CasADi backends) is scipy's, stepped in Python
  (mechgen.runtime.core.integrate), and ``cvodes`` SUNDIALS' (mechgen.runtime.core.sundials).

The outputs ``method`` and ``loop`` say what ran.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import energy_balance
from mechgen.errors import InputError
from mechgen.runtime.integration.augmented import AugmentedFlow
from mechgen.runtime.core.budget import Budget, BudgetExceeded
from mechgen.runtime.core.diagnose import explain_state
from mechgen.runtime.core.integrate import integrate_first_order
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.integration.run_options import RunOptions

#: the methods with a compiled loop on the C backend (DOP853: lumped models and continua; Radau: lumped models)
COMPILED = ("DOP853", "Radau")
#: an explicit method needing more steps than this for stability alone makes ``auto`` choose Radau
STIFF_STEPS = 10_000
#: DOP853's stability interval on the negative real axis, doubled (steps >= t_end |lambda| / c)
DOP853_REACH = 12.0
#: h |lambda|max that DOP853 reaches on a continuum's fastest (oscillating) mesh modes, measured: about 2.2 on a
#: 64-element cantilever (its stability along the imaginary axis, well below DOP853_REACH); a continuum whose
#: stability alone needs more than STIFF_STEPS such steps is stiff: its fastest modes are artefacts of the mesh
#: that an implicit method need not resolve (a lumped model's fast oscillation is physics: any method resolves it)
DOP853_MESH_STEP = 2.0
#: stability intervals of the explicit methods, doubled (RK45: ~3.3, DOP853: ~6): steps >= t_end |lambda| / c
EXPLICIT_REACH = {"RK45": 7.0, "DOP853": 12.0}
#: ``auto`` estimates the start's rates for first-order states up to this size (a dense eigen-solve)
ESTIMATE_SIZE = 400
#: above it, a continuum's estimate is this many eigenvalues of largest magnitude (ARPACK)
LARGEST = 6


def start_rates(system, x0: np.ndarray) -> np.ndarray | None:
    """The eigenvalues of J = d(dx/dt)/dx at (t = 0, x0), or None (too large, or no finite J); above
    ESTIMATE_SIZE states a continuum's largest ones (:func:`largest_rates`)."""
    if x0.size > ESTIMATE_SIZE:
        return largest_rates(system, x0) if system.is_field else None
    try:
        J = system.jacobian(0.0, x0)
        J = J.toarray() if hasattr(J, "toarray") else np.asarray(J, float)
        return np.linalg.eigvals(J) if np.all(np.isfinite(J)) else None
    except Exception:  # no estimate: auto falls back to the sparse-friendly implicit method
        return None


def largest_rates(system, x0: np.ndarray, count: int = LARGEST) -> np.ndarray | None:
    """The ``count`` eigenvalues of largest magnitude of a continuum's J = [[0, I], [-M^-1 r_q, -M^-1 r_v]] at
    (t = 0, x0), by ARPACK on J as an operator (the sparse tangent, a sparse LU of M), or None. Converged to
    1e-10: the real parts, small beside |lambda| (weak damping), are what the rule weighs.

    They hold the fastest rate |lambda|max; the fastest decay max(-Re lambda) is taken among them (for a
    continuum the highest modes decay fastest under stiffness-proportional damping, and all alike under
    mass-proportional damping); any faster decay belongs to an eigenvalue no larger than these, which an
    explicit method must resolve for stability anyway."""
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    n = system.n
    try:
        tan = system.tangent(x0[:n], x0[n:2 * n], t=0.0)
        mass = spla.splu(sps.csc_matrix(tan["r_a"]))
        r_q, r_v = tan["r_q"], tan["r_v"]

        def times(x):
            return np.concatenate([x[n:], -mass.solve(np.asarray(r_q @ x[:n] + r_v @ x[n:], float))])

        J = spla.LinearOperator((2 * n, 2 * n), matvec=times, dtype=float)
        start = np.random.default_rng(0).standard_normal(2 * n)  # a fixed start vector: the same rates every call
        return spla.eigs(J, k=count, which="LM", return_eigenvectors=False, tol=1e-10, maxiter=50 * n, v0=start)
    except Exception:  # no estimate: auto falls back to the sparse-friendly implicit method
        return None


def chosen_method(system, x0: np.ndarray, t_end: float, max_steps: int | None = None, *,
                  rates: np.ndarray | None = None) -> str:
    """What ``auto`` runs (module doc): Radau when stiff at the start (a continuum also when its fastest mesh modes
    alone need more than STIFF_STEPS explicit steps, t_end max|lambda| / DOP853_MESH_STEP), or when an explicit
    method's stability alone (t_end max|lambda| / 12) would take more than ``max_steps`` steps (it would be
    refused); DOP853 otherwise; BDF without an estimate. ``rates``: the start's eigenvalues when the caller has
    them."""
    rates = start_rates(system, x0) if rates is None else rates
    if rates is None:
        return "BDF"
    decay = float(np.max(-rates.real, initial=0.0))
    fastest = float(np.max(np.abs(rates), initial=0.0))
    if t_end * decay / DOP853_REACH > STIFF_STEPS:
        return "Radau"
    if system.is_field and t_end * fastest / DOP853_MESH_STEP > STIFF_STEPS:
        return "Radau"  # a mesh's fastest modes are artefacts an implicit method need not resolve
    if max_steps is not None and t_end * fastest / DOP853_REACH > max_steps:
        return "Radau"
    return "DOP853"


def adaptive_run(system, options: dict, x0: np.ndarray, method: str, budget: Budget, desc: str, *,
                 rates: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """(t, x rows, {method, loop, _extra}) of a run of ``method`` (not ``auto``: :func:`chosen_method` resolves it)
    from x0 (``rates``: the start's eigenvalues, when already solved for), sampled at ``samples`` equally spaced
    times; ``_extra`` integrals of the energy balance
    (mechgen.analyses.energy_balance) follow the state in each row where the run integrates them."""
    t_end = float(options["t_end"])
    refuse_explicit_stiff(system, x0, t_end, method, budget, rates)
    extra = energy_balance.EXTRA if energy_balance.accounted(system, method) else 0
    x0 = np.concatenate([x0, np.zeros(extra)])
    n_out = int(options.get("samples", 201))
    require(dense_bytes(n_out, 3 * x0.size + 6), f"{n_out} output samples", key="samples")
    t_eval = np.linspace(0.0, t_end, max(n_out, 2))
    size = 2 * system.n + system.m  # the diagnosis reads the model's state, not the integrals after it
    run = RunOptions(method=method, rtol=options.get("rtol", 1e-8), atol=options.get("atol", 1e-10), t_eval=t_eval,
                     budget=budget, progress=bool(options.get("progress", True)), desc=desc,
                     explain=lambda t, x: explain_state(system, t, np.asarray(x)[:size]),
                     loop=options.get("loop", "auto"))
    if method in COMPILED and run.loop != "python":
        why = compiled_loop_problem(system, run, extra)
        if why is None:
            t, X = compiled_run(system, x0, t_end, run, extra)
            return t, X, {"method": method, "loop": "c", "_extra": extra}
        if run.loop == "c":
            raise InputError(f"loop 'c' cannot run here: {why}", key="loop",
                             expected="method DOP853, Radau (or auto) on the C backend with a C compiler (Radau: a "
                                      "lumped model), or loop 'auto' / 'python'")
    if method == "cvodes":
        traj = cvodes_run(system, x0, t_end, run)
    else:
        flow = AugmentedFlow(system) if extra else system
        traj = integrate_first_order(flow.rhs, x0, t_end, jac=flow.jacobian, options=run)
    xs = traj.x if traj.x.shape[0] == len(traj.t) else traj.x.T
    return np.asarray(traj.t, float), np.asarray(xs, float), {"method": method, "loop": "python", "_extra": extra}


def compiled_loop(system, method: str) -> tuple:
    """(why-not function, run function) of the compiled loop of ``method``: Radau's
    (mechgen.runtime.integration.radau_c, lumped models), DOP853's for a continuum (mechgen.runtime.fields.flow_c)
    or for a lumped model (mechgen.runtime.integration.smooth_c). Each why-not function takes (system, rtol,
    atol, extra) and each run function (system, x0, t_end, run options, extra=...) -> (t, X, counts)."""
    if method == "Radau":
        from mechgen.runtime.integration.radau_c import integrate_radau_c, radau_loop_problem

        return radau_loop_problem, integrate_radau_c
    if system.is_field:
        from mechgen.runtime.fields.flow_c import field_loop_problem, integrate_field_c

        return field_loop_problem, integrate_field_c
    from mechgen.runtime.integration.smooth_c import integrate_smooth_c, smooth_loop_problem

    return smooth_loop_problem, integrate_smooth_c


def compiled_loop_problem(system, run: RunOptions, extra: int) -> str | None:
    """Why the compiled loop of ``run.method`` cannot run ``system`` (None when it can; :func:`compiled_loop`)."""
    if getattr(system, "is_plane", False):
        return "a plane continuum's flow (assembled over its mesh) runs in Python"
    return compiled_loop(system, run.method)[0](system, run.rtol, run.atol, extra)


def compiled_run(system, x0: np.ndarray, t_end: float, run: RunOptions, extra: int) -> tuple[np.ndarray, np.ndarray]:
    """(t, x rows at the samples) of the compiled loop of ``run.method`` (where :func:`compiled_loop_problem` says
    it can)."""
    t, X, _ = compiled_loop(system, run.method)[1](system, x0, t_end, run, extra=extra)
    return t, X


def cvodes_run(system, x0, t_end: float, run: RunOptions):
    """The run with SUNDIALS' CVODES on the system's CasADi kernels (mechgen.runtime.core.sundials)."""
    from mechgen.runtime.core.sundials import cvodes_problem, integrate_cvodes

    why = cvodes_problem(system)
    if why:
        raise InputError(why, key="method", expected="a method of this system's backend: auto, BDF, Radau, LSODA, "
                         "RK45, DOP853 or leapfrog, or backend 'casadi' for 'cvodes'")
    return integrate_cvodes(system, x0, t_end, t_eval=run.t_eval, rtol=run.rtol, atol=run.atol, budget=run.budget,
                            progress=run.progress, desc=run.desc, explain=run.explain,
                            integrals=x0.size - (2 * system.n + system.m))


def refuse_explicit_stiff(system, x0: np.ndarray, t_end: float, method: str, budget: Budget,
                          rates: np.ndarray | None = None) -> None:
    """An explicit method needs at least t_end |lambda|max / c steps for stability alone (|lambda|max: the
    largest eigenvalue magnitude of d(dx/dt)/dx at the start, ``rates`` when the caller has them, else
    start_rates; c: EXPLICIT_REACH); refuse when that is more than the budget (the problem is
    stiff: the implicit methods have no such stability limit). Beyond ESTIMATE_SIZE states only a continuum has an
    estimate (its largest rates, largest_rates)."""
    if method not in EXPLICIT_REACH or (x0.size > ESTIMATE_SIZE and not system.is_field) or budget.limit is None:
        return
    rates = start_rates(system, x0) if rates is None else rates
    if rates is None:  # no estimate: the step budget still holds during the run
        return
    fastest = float(np.max(np.abs(rates), initial=0.0))
    needed = t_end * fastest / EXPLICIT_REACH[method]
    if needed > budget.limit:
        raise BudgetExceeded(f"{method} steps: an explicit method needs at least {needed:.3g} steps to stay stable "
                             f"over t_end = {t_end:g} (the fastest rate at the start is |lambda| = {fastest:.3g}/s), "
                             f"more than max_steps = {budget.limit:,}; the problem is stiff: the implicit methods "
                             "BDF and Radau are not bound by this limit", key="max_steps",
                             reached="nothing (refused before starting)")
