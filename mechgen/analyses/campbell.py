"""Damped (gyroscopic) modes and Campbell diagrams of a scene's system: the rotordynamics analyses.

``modes`` of a system with gyroscopic or damping terms (or a non-symmetric
stiffness) solves M q'' + (D + G) q' + K q = 0 instead of the symmetric problem
and reports the damped natural frequencies wd = Im s (ascending), the
eigenvalues s, logarithmic decrements and, for a model that declares a whirl
pair (Model.whirl_pair), each mode's whirl. ``campbell`` does so over a range of
one parameter (the spin speed), tracking the modes across speeds
(mechgen.runtime.campbell), and finds critical speeds where a whirl frequency
crosses a multiple of the speed.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError, SceneError
from mechgen.runtime.campbell import campbell, critical_speeds, fit_speed_polynomial
from mechgen.runtime.damped import damped_modes, whirl

#: above this many unknowns a damped-modes analysis with a ``count`` uses sparse shift-invert
SPARSE_N = 100


def is_gyroscopic(mats: dict) -> bool:
    """True when D or G has a nonzero entry or K is not symmetric (the symmetric eigenproblem would be wrong)."""
    dense = {k: v.toarray() if hasattr(v, "toarray") else np.asarray(v) for k, v in mats.items()}
    K = dense["K"]
    scale = max(np.abs(K).max(), 1e-300)
    return bool(np.any(dense["D"]) or np.any(dense["G"]) or np.abs(K - K.T).max() > 1e-12 * scale)


def whirl_stations(system) -> tuple[np.ndarray, np.ndarray] | None:
    """Indices (into the unknowns) of the x and y displacements whose orbits classify whirl, or None
    (no whirl pair, or unknowns that are not a selection of nodal values)."""
    pair = system.meta.get("whirl")
    if not pair:
        return None
    if system.is_field:
        return system.nodal_indices(pair)
    names = system.coordinates
    return np.array([names.index(pair[0])]), np.array([names.index(pair[1])])


def run_damped_modes(system, mats: dict, options: dict) -> dict:
    """Damped modes about the operating point: frequencies (wd, rad/s), eigenvalues, log_dec, whirl."""
    count = options.get("count")
    massless = np.flatnonzero(np.asarray(mats["M"].diagonal()) <= 0)
    if len(massless) and not getattr(system, "has_multipliers", False):
        names = ", ".join(system.coordinates[i] for i in massless[:5])
        raise InputError(f"the mass matrix is singular: unknowns {names} carry no inertia", key="M",
                         expected="a positive definite mass matrix (every coordinate with inertia)")
    sparse = bool(count) and system.n > SPARSE_N and hasattr(mats["M"], "toarray")
    res = damped_modes(mats["M"], mats["D"] + mats["G"], mats["K"], count, sparse=sparse)
    out = {"frequencies": [float(w) for w in res.wd],
           "eigenvalues": [[float(s.real), float(s.imag)] for s in res.eigenvalues],
           "log_dec": [float(d) for d in res.log_dec], "_shapes": res.shapes}
    pair = system.meta.get("whirl")
    if pair:
        stations = whirl_stations(system)
        shapes = res.shapes
        if stations is None:  # unknowns are no selection of nodal values: observe them through x = Z q
            shapes = system.nodal_rows(pair) @ shapes
            half = shapes.shape[0] // 2
            stations = (np.arange(half), half + np.arange(half))
        out["whirl"] = _paired(whirl(shapes, *stations), res.wd)
    return out


def _paired(labels: list[str], wd: np.ndarray, rtol: float = 1e-6) -> list[str]:
    """Whirl of repeated frequencies (an isotropic rotor at rest): the eigenvectors of a double frequency are
    an arbitrary basis of a plane that holds one backward and one forward circular whirl, so such a pair is
    labelled (backward, forward), the order a Campbell diagram gives as the spin grows from zero."""
    out = list(labels)
    i = 0
    while i + 1 < len(out):
        if abs(wd[i + 1] - wd[i]) <= rtol * abs(wd[i]):
            out[i], out[i + 1] = "backward", "forward"
            i += 2
        else:
            i += 1
    return out


def _speed_parameter(system, options: dict) -> tuple[str, list[float]]:
    (name, values), = options["over"].items()
    if name not in system.meta.get("params", []):
        raise SceneError(f"campbell over {name!r}, which the compiled kernels fold as a constant",
                         key="over", expected="a numeric model parameter (kept free by the scene)")
    return name, [float(v) for v in values]


def run_campbell(system, options: dict, context: dict) -> dict:
    """Campbell diagram: tracked damped frequencies over the speed range, whirl, log_dec, critical speeds.

    With more than four speeds the matrices are tested for a polynomial dependence on the speed
    (fit_speed_polynomial: three or four assemblies); when it holds, no further assembly is needed and
    the Campbell runs on the reduced basis (mechgen.runtime.campbell), else it assembles at every speed.
    ``options['method'] = 'exact'`` forces full-size solves at every speed."""
    from mechgen.scene.analyses import operating_point

    name, speeds = _speed_parameter(system, options)
    if not system.meta.get("whirl"):
        raise SceneError(f"model {system.meta.get('model')} declares no whirl pair", key="kind",
                         expected="a model with Model.whirl_pair (a rotor) for a campbell analysis")
    stations = whirl_stations(system)
    if stations is None:
        raise SceneError("a campbell diagram tracks whirl at nodal values; substructures joined by multipliers have "
                         "none", key="joints", expected="joints = 'assembly' for campbell (the same frequencies)")
    index = system.meta["params"].index(name)
    q = operating_point(system, options, context)
    saved = float(system.params[index])

    def assembled(speed: float) -> dict:
        system.params[index] = speed
        mats = system.linear(q)
        return {"M": mats["M"], "D": mats["D"], "G": mats["G"], "K": mats["K"]}

    def assembled_at(speed: float) -> dict:
        mats = assembled(speed)
        return {"M": mats["M"], "C": mats["D"] + mats["G"], "K": mats["K"]}

    count = int(options.get("count", 8))
    sparse = system.n > SPARSE_N
    try:
        # matrices polynomial in the speed (a rotor's G = Omega G1): four assemblies, then sparse adds
        poly = fit_speed_polynomial(assembled, speeds[0], speeds[-1]) if len(speeds) > 4 else None
        matrices_at = assembled_at if poly is None else poly.combined({"M": ("M",), "C": ("D", "G"), "K": ("K",)})
        res = campbell(matrices_at, speeds, count, x_index=stations[0], y_index=stations[1], sparse=sparse,
                       method=options.get("method", "auto"))
        crit = critical_speeds(res, options.get("multiples", [1.0]), refine=matrices_at, sparse=sparse)
    finally:
        system.params[index] = saved
    freqs = np.asarray(res.frequencies)
    return {"speeds": [float(w) for w in res.speeds], "frequencies": [[float(f) for f in row] for row in freqs],
            "whirl": [list(row) for row in res.whirl], "log_dec": [[float(d) for d in row] for row in res.log_dec],
            "critical_speeds": [{"mode": int(c["mode"]) + 1, "multiple": float(c["multiple"]),
                                 "speed": float(c["speed"]), "frequency": float(c["frequency"]), "whirl": c["whirl"]}
                                for c in crit],
            "parameter": name, "method": res.method, "exact_solves": int(res.exact_solves)}
