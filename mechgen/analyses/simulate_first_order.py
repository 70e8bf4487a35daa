"""How ``simulate`` integrates a first-order continuum: fields without a kinetic density (the Johnson-Segalman
channel ``js_fluid``), whose residual r(q, q', 0) = 0 gives the rates, D(q) q' + f(q) = 0.

The state is q alone: q' = v(q), the root of r(q, v, 0) = 0 (mechgen.runtime.fields.continuum.FieldSystem.
first_order_rate), integrated by scipy's methods with the Jacobian dv/dq = -r_v^-1 r_q (``auto``: BDF, since a
mesh's diffusion makes such fields stiff). The samples are reported as (q, v(q)) rows, as for any continuum, so
the outputs, the time history and the figures are those of every run. An unknown with neither mass nor rate (an
inertialess field, a DAE) is refused, naming the model.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.budget import Budget
from mechgen.runtime.core.integrate import integrate_first_order
from mechgen.runtime.integration.run_options import RunOptions

#: the methods that integrate q' = v(q): scipy's
METHODS = ("BDF", "Radau", "LSODA", "RK45", "DOP853")


def first_order_run(system, options: dict, q0: np.ndarray, budget: Budget, desc: str):
    """(t, rows (q, v(q)) at the samples, {method, loop}) of a first-order continuum's run from q0."""
    method = options.get("method", "auto")
    method = "BDF" if method == "auto" else method
    if method not in METHODS:
        raise InputError(f"method {method!r} integrates second-order motion; model {system.meta.get('model')} is a "
                         "first-order continuum (no mass)", key="method", expected="auto, " + ", ".join(METHODS))
    if options.get("v0") or options.get("initial_mode"):
        key = "v0" if options.get("v0") else "initial_mode"
        raise InputError(f"{key} sets velocities or mode shapes of a second-order system; a first-order continuum's "
                         "rates follow from its state", key=key, expected="no v0 and no initial_mode")
    t_end = float(options["t_end"])
    t_eval = np.linspace(0.0, t_end, max(int(options.get("samples", 201)), 2))
    run = RunOptions(method=method, rtol=options.get("rtol", 1e-8), atol=options.get("atol", 1e-10), t_eval=t_eval,
                     budget=budget, progress=bool(options.get("progress", True)), desc=desc)
    traj = integrate_first_order(system.first_order_rate, np.asarray(q0, float), t_end,
                                 jac=system.first_order_jacobian, options=run)
    qs = traj.x if traj.x.shape[0] == len(traj.t) else traj.x.T
    rows = np.array([np.concatenate([q, system.first_order_rate(t, q)]) for t, q in zip(traj.t, qs)])
    return np.asarray(traj.t, float), rows, {"method": method, "loop": "python"}
