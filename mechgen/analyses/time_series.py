"""What a ``simulate`` run reports from its samples: the time history and the energy figures.

* ``t`` and ``trajectory``: an object mapping each coordinate ``q``, its velocity ``q_dot``, each internal
  variable and each requested model output to its values at the sample times. Kept when ``series = true``, or
  when ``series`` is left out while the values it holds, (2 n + m + outputs) x samples, are at most
  :data:`SERIES_VALUES` (10^6 numbers: 8 MB in memory, about 20 MB of JSON); above that only the end values
  are reported and ``series_note`` says why. ``energy_series`` (the energy at the same times) comes with them.
* ``energy_drift`` = max_k |E_k - E_0| / S, relative to the run's energy scale
  S = max_k (|T_k| + |V_k|) (kinetic and potential energy at the samples), not to |E_0| (zero for a run from
  rest): 0 when S = 0 (nothing moves and nothing is stored). Reported for a conservative run only; a run
  with forces, dissipation or resets that change the energy reports ``energy_balance_error`` instead
  (mechgen.analyses.energy_balance).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

#: the most values (states and outputs times samples) a trajectory keeps when ``series`` is left out
SERIES_VALUES = 1_000_000


def state_names(system) -> list[str]:
    """The names of a first-order state x = (q, v, z): the coordinates, their velocities ``<q>_dot`` (the
    name mechgen.symbolic.names reserves) and the internal variables."""
    coordinates = list(system.coordinates)
    internal = list(getattr(system.metadata, "internal", ())) or [f"z{i + 1}" for i in range(system.m)]
    return coordinates + [f"{c}_dot" for c in coordinates] + internal[:system.m]


def keep_series(options: dict, states: int, outputs: int, samples: int) -> tuple[bool, str | None]:
    """(keep the trajectory?, the note when it is left out for its size): ``series`` decides when given."""
    given = options.get("series")
    if given is not None:
        return bool(given), None
    values = (states + outputs) * samples
    if values <= SERIES_VALUES:
        return True, None
    return False, (f"trajectory left out: {states} states and {outputs} outputs x {samples} samples = {values:.3g} "
                   f"values, more than {SERIES_VALUES:.0e}; series = true keeps it")


def sampled_outputs(system, t: np.ndarray, X: np.ndarray) -> dict[str, np.ndarray]:
    """Each model output at every sample (row k of X: the state at t[k]) as arrays: one batched kernel call where
    the system has one (System.outputs_series), else one call a sample."""
    if hasattr(system, "outputs_series"):
        return system.outputs_series(t, X)
    n, m = system.n, system.m
    rows = [system.outputs(x[:n], x[n:2 * n], x[2 * n:] if m else None, float(tk)) for tk, x in zip(t, X)]
    return {name: np.array([r[name] for r in rows], float) for name in (rows[0] if rows else {})}


def sampled_outputs_by_mode(mode_system, t: np.ndarray, X: np.ndarray, modes: np.ndarray) -> dict[str, np.ndarray]:
    """:func:`sampled_outputs` of a hybrid run: each sample's outputs in its own mode (``mode_system(k)``: the
    system of mode k), the samples of one mode in one call."""
    out: dict[str, np.ndarray] = {}
    for k in np.unique(modes):
        rows = np.flatnonzero(modes == k)
        for name, values in sampled_outputs(mode_system(int(k)), t[rows], X[rows]).items():
            out.setdefault(name, np.full(len(t), np.nan))[rows] = values
    return out


def energy_drift(series: dict[str, np.ndarray]) -> float:
    """max |E - E_0| / max(|T| + |V|) over the samples (module doc); 0 when the scale is 0."""
    E = series["energy"]
    scale = float(np.max(np.abs(series["kinetic_energy"]) + np.abs(series["potential_energy"])))
    if scale == 0.0 or E.size == 0:
        return 0.0
    return float(np.max(np.abs(E - E[0])) / scale)


def time_history(system, t: np.ndarray, X: np.ndarray, series: dict[str, np.ndarray],
                 wanted: Sequence[str] | None) -> dict:
    """``t``, ``trajectory`` (states and the wanted outputs, lists for JSON) and ``energy_series``."""
    trajectory = {name: X[:, i].tolist() for i, name in enumerate(state_names(system))}
    for name in (wanted if wanted is not None else series):
        if name in series and name not in trajectory:
            trajectory[name] = series[name].tolist()
    return {"t": np.asarray(t, float).tolist(), "trajectory": trajectory, "energy_series": series["energy"].tolist()}


def summary_lines(outputs: dict) -> list[str]:
    """The trajectory in one line (its samples and names), or the note saying why it was left out."""
    if "trajectory" in outputs:
        names = list(outputs["trajectory"])
        shown = ", ".join(names[:8]) + (f", ... ({len(names)})" if len(names) > 8 else "")
        return [f"    trajectory: {len(outputs['t'])} samples of {shown} (series = false leaves it out)"]
    return []
