"""The energy balance of a ``simulate`` run of a lumped model or a continuum: a dissipative or forced run checked,
not labelled.

Along a solution of Lagrange's equations with non-conservative forces Q and Rayleigh dissipation R
(mechgen.symbolic.derive.energy_powers), the energy function h = v.dT/dv - T + V obeys

    dh/dt = Q.v - v.dR/dv - dL/dt,        h = E + (v.dT/dv - 2 T),   E = T + V,

so with the work W(t) = int_0^t (Q.v - dL/dt) dt (the forces' work and that of an explicit time dependence of
T or V) and the dissipated energy D(t) = int_0^t v.dR/dv dt,

    energy_balance_error = max_t |h(t) - h(0) - W(t) + D(t)| / S,   S = max_t (|T| + |V|, |W|, D),

which is E(t) - E(0) - W(t) + D(t) when T is a quadratic form in v (the excess v.dT/dv - 2 T is zero). W and D
are integrated with the state, as three more components of dx/dt (the generated ``energy_rates`` kernel: the
internal rates followed by Q.v, v.dR/dv and -dL/dt), by the same integrator under the same error control, so
the figure measures the run's accuracy. A continuum's kernel gives the power densities at a point, and the
quadrature over the domain (with the end and part terms) is the discretised system's Q.v, v.dR/dv and -dL/dt
(mechgen.symbolic.field), so its balance is checked the same way. A run is *conservative* when the three
powers and the excess are zero at every sample (exactly: a term the model does not declare is a generated
zero): it reports ``energy_drift``
(mechgen.analyses.time_series); any other reports ``energy_balance_error``, ``work`` and ``dissipated`` (their
values at the end; in the trajectory too, when kept) instead.
"""
from __future__ import annotations

import numpy as np

from mechgen.runtime.integration.augmented import INTEGRALS, balance_kernels

#: the integrated powers appended to the state (mechgen.runtime.integration.augmented): W_forces, D, W_explicit
EXTRA = INTEGRALS


def accounted(system, method: str) -> bool:
    """Whether the run integrates the balance: a smooth lumped system with the energy_rates kernel (every method:
    scipy's and the compiled loop on the augmented flow, CVODES on the augmented CasADi expression), or a
    continuum with its pointwise energy_rates kernels (power densities integrated over the domain with the end and
    part terms; scipy's methods and the compiled loop)."""
    return ("energy_rates" in system.kernels and not hasattr(system, "modes") and not system.is_lattice
            and (not system.is_field or method != "cvodes"))


def hybrid_accounted(system) -> bool:
    """Whether a hybrid run carries the balance's integrals across its events: every mode has its energy_rates
    kernel (mechgen.runtime.integration.augmented.BalancedHybrid)."""
    return hasattr(system, "modes") and balance_kernels(system)


def excess(system, t: np.ndarray, X: np.ndarray) -> np.ndarray:
    """v.dT/dv - 2 T at each sample (zero for a kinetic energy quadratic in v), in one batched call (a
    continuum's: integrated over the domain, mechgen.runtime.fields.operators.integrated_series)."""
    if system.is_field:
        from mechgen.runtime.fields.operators import integrated_series

        return integrated_series(system, "energy_rates", t, X)["excess"][:, 0]
    return np.asarray(system.evaluate_series("energy_rates", t, X)["excess"], float).reshape(len(t))


def figures(system, t: np.ndarray, X: np.ndarray, series: dict) -> dict | None:
    """``energy_balance_error``, ``work``, ``dissipated`` (and their series, ``_work_series`` ...) of a run whose
    state carries the integrals (X: samples of the augmented state), or None when the run is conservative."""
    W = X[:, -3] + X[:, -1]
    D = X[:, -2]
    h = series["energy"] + excess(system, t, X)
    if not (np.any(X[:, -EXTRA:]) or np.any(h - series["energy"])):
        return None
    scale = max(float(np.max(np.abs(series["kinetic_energy"]) + np.abs(series["potential_energy"]))),
                float(np.max(np.abs(W))), float(np.max(np.abs(D))))
    error = h - h[0] - W + D
    return {"energy_balance_error": float(np.max(np.abs(error)) / scale) if scale > 0 else 0.0,
            "work": float(W[-1]), "dissipated": float(D[-1]), "_work_series": W, "_dissipated_series": D}


def mode_powers(mode_system, t: np.ndarray, X: np.ndarray, modes: np.ndarray) -> np.ndarray | None:
    """The powers (Q.v, v.dR/dv, -dL/dt) and the excess at each sample of a hybrid run, each in its own mode's
    energy_rates kernel (rows: samples, columns: the four), or None where a mode has no such kernel."""
    out = np.zeros((len(t), EXTRA + 1))
    for k in np.unique(modes):
        flow = mode_system(int(k))
        if "energy_rates" not in flow.kernels:
            return None
        rows = np.flatnonzero(modes == k)
        raw = flow.evaluate_series("energy_rates", t[rows], X[rows])
        out[rows, :EXTRA] = np.asarray(raw["g"], float).reshape(len(rows), -1)[:, flow.m:]
        out[rows, EXTRA] = np.asarray(raw["excess"], float).reshape(len(rows))
    return out


def reset_losses(mode_system, events) -> list[tuple[float, float]]:
    """(t, E before - E after) of each event that resets the state into a mode (terminal events excluded)."""
    return [(float(e.t), _energy(mode_system(e.source), e.t, e.x_before) - _energy(mode_system(e.target), e.t,
                                                                                  e.x_after))
            for e in events if e.target is not None]


def _energy(flow, t: float, x: np.ndarray) -> float:
    n, m = flow.n, flow.m
    return flow.outputs(x[:n], x[n:2 * n], x[2 * n:2 * n + m] if m else None, t)["energy"]


def hybrid_figures(mode_system, t: np.ndarray, X: np.ndarray, modes: np.ndarray, events, series: dict) -> dict | None:
    """The energy figures of a hybrid run in place of ``energy_drift``, or None when it is conservative (no
    powers in any mode, no reset that changes the energy). Modes without powers but resets that change the
    energy: ``energy_balance_error`` of E(t) - E(0) + D(t), D the energy the resets took up to t (a sample at an
    event's instant is compared on the side of it that fits), ``dissipated`` = D at the end, ``work`` = 0.
    Modes with forces, dissipation or an explicit time dependence: their powers were not integrated across the
    events (a run without every mode's energy_rates kernel; hybrid_balance where they were), so no figure is
    given (``energy_note`` says so)."""
    powers = mode_powers(mode_system, t, X, modes)
    losses = reset_losses(mode_system, events)
    E = series["energy"]
    scale = float(np.max(np.abs(series["kinetic_energy"]) + np.abs(series["potential_energy"])))
    jumps = np.array([loss for _, loss in losses])
    quiet = not np.any(jumps) or float(np.max(np.abs(jumps))) <= 1e-14 * max(scale, 1e-300)
    if powers is not None and not np.any(powers) and quiet:
        return None
    if powers is None or np.any(powers):
        return {"energy_note": "the modes have forces, dissipation or an explicit time dependence whose work "
                               "is not integrated across events: no energy figure"}
    before, through, total = _reset_steps(losses, t)
    error = np.minimum(np.abs(E - E[0] + before), np.abs(E - E[0] + through))
    scale = max(scale, abs(total))
    return {"energy_balance_error": float(np.max(error) / scale) if scale > 0 else 0.0, "work": 0.0,
            "dissipated": total}


def _reset_steps(losses, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The energy the resets took up to each sample time, counting an event at the sample's instant out
    (``before``) and in (``through``), and in all (a sample at an event's instant may hold either side)."""
    times = np.array([tl for tl, _ in losses])
    cumulative = np.concatenate([[0.0], np.cumsum([loss for _, loss in losses])])
    return (cumulative[np.searchsorted(times, t, side="left")], cumulative[np.searchsorted(times, t, side="right")],
            float(cumulative[-1]))


def hybrid_balance(mode_system, t: np.ndarray, X: np.ndarray, modes: np.ndarray, events, series: dict) -> dict | None:
    """The energy balance of a hybrid run whose state carried the integrals (X: samples of the augmented state,
    the three integrals last; mechgen.runtime.integration.augmented.BalancedHybrid), or None when it is conservative:

        error(t) = h(t) - h(0) - W(t) + D(t) + D_resets(t),   h = E + (v.dT/dv - 2 T) in the sample's mode,

    W the forces' and the explicit work, D the energy dissipated in the flow (both integrated through every mode),
    D_resets the energy the resets took up to t (E before - E after each; a sample at an event's instant is
    compared on the side of it that fits). ``dissipated`` = D + D_resets at the end, ``work`` = W at the end."""
    state = X[:, :X.shape[1] - EXTRA]
    powers = mode_powers(mode_system, t, state, modes)
    if powers is None:
        return hybrid_figures(mode_system, t, state, modes, events, series)
    W, D = X[:, -3] + X[:, -1], X[:, -2]
    E = series["energy"]
    before, through, total = _reset_steps(reset_losses(mode_system, events), t)
    scale = float(np.max(np.abs(series["kinetic_energy"]) + np.abs(series["potential_energy"])))
    quiet = float(np.max(np.abs(through), initial=0.0)) <= 1e-14 * max(scale, 1e-300) and abs(total) <= 1e-14 * max(
        scale, 1e-300)
    if quiet and not np.any(X[:, -EXTRA:]) and not np.any(powers[:, EXTRA]):
        return None
    h = E + powers[:, EXTRA]
    drift = h - h[0] - W + D
    error = np.minimum(np.abs(drift + before), np.abs(drift + through))
    scale = max(scale, float(np.max(np.abs(W))), float(np.max(np.abs(D + through))), abs(total))
    return {"energy_balance_error": float(np.max(error) / scale) if scale > 0 else 0.0, "work": float(W[-1]),
            "dissipated": float(D[-1] + total), "_work_series": W, "_dissipated_series": D + through}
