"""The parts of ``simulate`` that its smooth, hybrid and periodic runs share (mechgen.analyses.simulate,
simulate_hybrid, impact, periodic, periodic_orbit): the initial state from the options over the model's declared
one, the run's work budget, and the report of a sampled run with its energy balance."""
from __future__ import annotations

import numpy as np

from mechgen.analyses import time_series
from mechgen.analyses.operating_point import vector
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.linear.modes import modes as solve_modes

#: the fixed-step methods (a dt, a step budget refused up front)
FIXED_STEP = ("leapfrog", "variational")
#: default max_steps: the leapfrog's fixed steps, the adaptive methods' accepted steps
DEFAULT_STEPS = {"leapfrog": 10_000_000, "adaptive": 100_000}


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


def budget_of(options: dict, method: str) -> Budget:
    """The run's work budget: ``max_steps`` (default DEFAULT_STEPS of the method) and ``max_seconds``."""
    steps = options.get("max_steps", DEFAULT_STEPS["leapfrog" if method in FIXED_STEP else "adaptive"])
    what = f"{method} steps"
    return Budget(what, limit=int(steps), key="max_steps", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))


def report(system, options: dict, t: np.ndarray, X: np.ndarray, series: dict) -> dict:
    """The outputs of a run sampled at ``t`` (states X, one row a sample; ``series``: the model's outputs at each
    sample): the outputs at the last sample (those asked for), ``energy_drift``, ``t_end`` and, when kept, the
    time history."""
    wanted = options.get("outputs")
    out = {k: float(v[-1]) for k, v in series.items() if not wanted or k in wanted}
    out["energy_drift"] = time_series.energy_drift(series)
    out["t_end"] = float(options["t_end"])
    keep, note = time_series.keep_series(options, X.shape[1], len(wanted or series), len(t))
    if keep:
        out.update(time_series.time_history(system, t, X, series, wanted))
        if options.get("plot") == "phase":
            out["plot"] = "phase"
    elif note:
        out["series_note"] = note
    return out


def balanced(out: dict, balance: dict | None) -> None:
    """A run that is not conservative reports its energy balance (mechgen.analyses.energy_balance) instead of
    ``energy_drift``; with the trajectory, ``work`` and ``dissipated`` at each sample too."""
    if balance is None:
        return
    del out["energy_drift"]
    work, dissipated = balance.pop("_work_series"), balance.pop("_dissipated_series")
    out.update(balance)
    if "trajectory" in out:
        out["trajectory"]["work"], out["trajectory"]["dissipated"] = work.tolist(), dissipated.tolist()
