"""``simulate`` with ``method = "variational"``: the variational integrator of the model's own Lagrangian.

The integrator (mechgen.runtime.core.variational) steps the discrete Euler-Lagrange equations of the
midpoint discrete Lagrangian L_d(q_k, q_{k+1}) = h L((q_k + q_{k+1})/2, (q_{k+1} - q_k)/h) (``stages = 1``,
order 2), or of its Gauss-Legendre generalisation (``stages = 2`` or ``3``: orders 4 and 6), with the forces
and Rayleigh dissipation by the discrete Lagrange-d'Alembert principle, each step solved by Newton with the
Jacobians of the generated ``lagrangian`` kernel. Any kinetic energy T(q, v, t) is served; a smooth lumped
model without internal variables only (check_fixed_step: a model with modes, internal variables, a chain or a
continuum is refused at ``method``, exit 2).

Keys: ``dt`` (required: the step is h = t_end / ceil(t_end / dt) <= dt, so that t_end is reached exactly),
``stages`` (1, 2 or 3; default 1), ``save_every`` (a sample every that many steps, and the last; default
round(steps / (samples - 1)): about ``samples`` of them), ``loop`` (``auto``: the compiled loop of
mechgen.runtime.core.variational_c on the C backend, else Python; ``python``; ``c``), ``max_steps`` (default
10^7, refused before the first step). Outputs as for every simulate (the time history of q and v, the
outputs at t_end, ``energy_drift``; for a run with forces or dissipation the energy balance instead, its work
and dissipated energy integrated by the step's own Gauss quadrature of the ``energy_rates`` powers), with
``method = "variational"`` and the ``loop`` that ran.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.core.variational import VariationalOptions, run_variational, steps_for
from mechgen.runtime.core.variational_rules import STAGES
from mechgen.scene.values import fail


def check_fixed_step(ctx, base: str, options: dict) -> None:
    """``method = "variational"`` needs a smooth lumped model without internal variables and a ``dt``;
    ``stages`` belongs to it alone and is one of STAGES. ``leapfrog`` is refused here for a model with internal
    variables (it steps none); whether its mass is constant and diagonal is known from the kernels only, at the
    run's start (mechgen.runtime.core.splitting.require_separable)."""
    method = options["method"]
    if method == "leapfrog" and getattr(ctx.model, "internals", False) and not getattr(ctx.model, "chain", None):
        raise fail(ctx.file, f"{base}.method", f"method 'leapfrog' steps q'' = M^-1 (-dV/dq) alone, and model "
                   f"{ctx.model.name} has internal variables", "an implicit method ('Radau', 'BDF')")
    if "stages" in options:
        if method != "variational":
            raise fail(ctx.file, f"{base}.stages", f"'stages' is a key of method 'variational', not of {method!r}",
                       "no 'stages' key, or method = 'variational'")
        if options["stages"] not in STAGES:
            raise fail(ctx.file, f"{base}.stages", f"stages {options['stages']!r} is not tabulated",
                       "1 (midpoint, order 2), 2 (Gauss-Legendre, order 4) or 3 (order 6)")
    if method != "variational":
        return
    model = ctx.model
    why = ("it has modes (a hybrid model: use an event loop's method, e.g. 'DOP853')" if model.modes else
           "it has internal variables, which have no Lagrangian (use 'Radau' or 'BDF')" if model.internals else
           "it is a chain (use 'leapfrog' or the symplectic kind)" if model.chain else
           "it is a continuum (use 'Radau' or 'BDF')" if model.continuum else None)
    if why:
        raise fail(ctx.file, f"{base}.method", f"method 'variational' needs a smooth lumped model, and model "
                   f"{model.name} is not one: {why}", "another method for this model")
    if "dt" not in options:
        raise fail(ctx.file, f"{base}.dt", "method 'variational' needs a time step dt",
                   "a number > 0 (or an expression)")


def simulate_variational(system, q0: np.ndarray, v0: np.ndarray, options: dict, budget,
                         desc: str) -> tuple[np.ndarray, np.ndarray, dict]:
    """(t, x rows, {method, loop, _extra}) of the run, as mechgen.analyses.simulate_flow.adaptive_run gives them:
    samples of (q, v) every ``save_every`` steps (default: about ``samples`` evenly spaced ones) and at t_end, in
    the loop ``loop`` asks for (auto: the compiled one on the C backend); with the ``energy_rates`` kernel the
    ``_extra`` = 3 integrals of the energy balance (mechgen.analyses.energy_balance) follow in each row."""
    if "lagrangian" not in system.kernels:
        raise InputError(f"the system of model {system.metadata.model} was compiled without the 'lagrangian' kernel "
                         "that method 'variational' steps", key="method",
                         expected="a system compiled with kernels including 'lagrangian' (the default of "
                         "mechgen.compile), or another method")
    t_end, dt = float(options["t_end"]), float(options["dt"])
    steps, _ = steps_for(t_end, dt)
    samples = max(int(options.get("samples", 201)), 2)
    save_every = int(options.get("save_every", max(1, int(round(steps / (samples - 1))))))
    count = steps // save_every + 2
    require(dense_bytes(count, 3 * system.n + 5), f"{count} samples of the variational run", key="samples")
    balance = "energy_rates" in system.kernels
    how = VariationalOptions(stages=int(options.get("stages", 1)), save_every=save_every, balance=balance,
                             budget=budget, progress=bool(options.get("progress", True)), desc=desc,
                             loop=options.get("loop", "auto"))
    run = run_variational(system, q0, v0, t_end, dt, options=how)
    X = np.hstack([run.q, run.v] + ([run.w] if balance else []))
    return run.t, X, {"method": "variational", "loop": run.loop, "_extra": 3 if balance else 0}
