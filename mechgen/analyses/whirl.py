"""Damped (gyroscopic) modes and their whirl: shared by ``modes`` and ``campbell``.

A system with gyroscopic or damping terms (or a non-symmetric stiffness) has the modes of
M q'' + (D + G) q' + K q = 0 instead of the symmetric problem: damped natural frequencies
wd = Im s (ascending), the eigenvalues s, logarithmic decrements and:

* a lumped model: ``shapes``, the complex mode shapes X (q(t) = Re(X e^{s t})), one dict per mode (the
  order of ``frequencies``) mapping each coordinate to ``{"amplitude": |X_i|, "phase": arg X_i}`` (rad);
  normalised so that the first largest amplitude is 1 with phase 0 (:func:`complex_shapes`).
* a rotor (a model that declares a whirl pair, Model.whirl_pair): per mode, at the whirl station with the
  largest orbit, ``orbits`` ({"major": a, "minor": b, "angle": theta}: the semi-axes of the ellipse
  x = Re(X e^{i wd t}), y = Re(Y e^{i wd t}) of the normalised shape, and the major axis's angle from x
  towards y, rad), ``whirl_ratio`` (signed b / a: +1 a forward circle, -1 a backward circle, 0 a straight
  line; its sign is that of the orbit's angular momentum x y' - y x') and ``whirl``: ``forward``
  (counter-clockwise about z = x cross y), ``backward``, ``linear`` (a straight-line orbit,
  |whirl_ratio| <= 1e-6 at every station: no whirl direction) or ``none`` (a mode that leaves the whirl
  stations at rest, below 1e-6 of its largest entry). A double frequency (an isotropic rotor at rest)
  has an arbitrary eigenbasis; its pair is re-chosen as the backward and the forward circle and labelled
  (backward, forward), the order a Campbell diagram gives as the spin grows from zero.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.linear.damped import circular_pair, damped_modes, orbit_axes, whirl

#: above this many unknowns a damped-modes analysis with a ``count`` uses sparse shift-invert
SPARSE_N = 100


def is_gyroscopic(mats: dict) -> bool:
    """True when D or G has a nonzero entry or K is not symmetric (the symmetric eigenproblem would be wrong)."""
    K = mats["K"] if hasattr(mats["K"], "toarray") else np.asarray(mats["K"])  # sparse stays sparse (N = 1e6)
    scale = max(abs(K).max(), 1e-300)
    return bool(_nonzero(mats["D"]) or _nonzero(mats["G"]) or abs(K - K.T).max() > 1e-12 * scale)


def _nonzero(X) -> bool:
    """Whether a dense or sparse matrix has a nonzero entry (without densifying a sparse one)."""
    return X.count_nonzero() > 0 if hasattr(X, "count_nonzero") else bool(np.any(X))


def whirl_stations(system) -> tuple[np.ndarray, np.ndarray] | None:
    """Indices (into the unknowns) of the x and y displacements whose orbits classify whirl, or None
    (no whirl pair, or unknowns that are not a selection of nodal values). A lumped model may declare
    several pairs (Model.whirl_pair called again: ``metadata.whirl`` is then x1, y1, x2, y2, ...), one
    station each."""
    pair = system.metadata.whirl
    if not pair:
        return None
    if system.is_field:
        return system.nodal_indices(pair)
    names = system.coordinates
    return np.array([names.index(x) for x in pair[0::2]]), np.array([names.index(y) for y in pair[1::2]])


def run_damped_modes(system, mats: dict, options: dict) -> dict:
    """Damped modes about the operating point: frequencies (wd, rad/s), eigenvalues, log_dec, and (module
    docstring) a lumped model's complex ``shapes``, a rotor's ``whirl``, ``whirl_ratio`` and ``orbits``."""
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
    if system.metadata.whirl:
        out.update(rotor_outputs(system, res.shapes, res.wd))
    if not system.is_field and not system.is_lattice:
        out["shapes"] = complex_shapes(system.coordinates, out["_shapes"])
    return out


def rotor_outputs(system, shapes: np.ndarray, wd: np.ndarray) -> dict:
    """``whirl``, ``whirl_ratio`` and ``orbits`` of each mode at the rotor's whirl stations, and ``_shapes``
    with each double frequency's pair re-chosen as (backward, forward) circles (circular_pair)."""
    stations = whirl_stations(system)
    n = shapes.shape[0]
    if stations is None:  # unknowns are no selection of nodal values: observe them through x = Z q
        seen = system.nodal_rows(system.metadata.whirl) @ shapes
        half = seen.shape[0] // 2
        stations = (n + np.arange(half), n + half + np.arange(half))
        stacked = np.vstack([shapes, seen])
    else:
        stacked = np.array(shapes, dtype=complex)
    for i in repeated_pairs(wd):
        stacked[:, i:i + 2] = circular_pair(stacked[:, i:i + 2], *stations)
    axes = orbit_axes(stacked, *stations)
    orbits = [{"major": float(a), "minor": float(b), "angle": float(t)}
              for a, b, t in zip(axes["major"], axes["minor"], axes["angle"])]
    return {"whirl": _paired(whirl(stacked, *stations), wd), "whirl_ratio": [float(k) for k in axes["kappa"]],
            "orbits": orbits, "_shapes": stacked[:n]}


def repeated_pairs(wd: np.ndarray, rtol: float = 1e-6) -> list[int]:
    """The first index i of each pair of equal frequencies |wd[i+1] - wd[i]| <= rtol |wd[i]| (left to right)."""
    out, i = [], 0
    while i + 1 < len(wd):
        if abs(wd[i + 1] - wd[i]) <= rtol * abs(wd[i]):
            out.append(i)
            i += 2
        else:
            i += 1
    return out


#: an amplitude at most this (the largest is 1) has no meaningful phase: it is reported with phase 0
PHASE_FLOOR = 1e-12


def complex_shapes(names, Q: np.ndarray) -> list[dict]:
    """Complex mode shapes as [{coordinate: {"amplitude": |X_i|, "phase": arg X_i}}], one dict per column.

    The columns come normalised (damped.normalise_columns): the first largest |X_i| is 1 with phase 0,
    so q_i(t) = amplitude_i cos(wd t + phase_i) e^{Re(s) t} up to one common factor. Phases are in rad,
    in (-pi, pi] (a phase within 1e-9 of -pi is reported as pi); an amplitude below PHASE_FLOOR gets phase 0.
    """
    out = []
    for col in np.asarray(Q, dtype=complex).T:
        amp, phase = np.abs(col), np.angle(col)
        phase = np.where(phase <= -np.pi + 1e-9, np.pi, phase)
        phase = np.where(amp <= PHASE_FLOOR, 0.0, phase) + 0.0
        out.append({n: {"amplitude": float(a), "phase": float(p)} for n, a, p in zip(names, amp, phase)})
    return out


def _paired(labels: list[str], wd: np.ndarray, rtol: float = 1e-6) -> list[str]:
    """Whirl of repeated frequencies (an isotropic rotor at rest): the eigenvectors of a double frequency are
    an arbitrary basis of a plane that holds one backward and one forward circular whirl, so such a pair is
    labelled (backward, forward), the order a Campbell diagram gives as the spin grows from zero (the shapes
    are re-chosen as those circles: circular_pair). A pair that leaves the stations at rest keeps 'none'."""
    out = list(labels)
    for i in repeated_pairs(wd, rtol):
        if "none" not in out[i:i + 2]:
            out[i], out[i + 1] = "backward", "forward"
    return out
