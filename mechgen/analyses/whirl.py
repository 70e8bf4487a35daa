"""Damped (gyroscopic) modes and their whirl: shared by ``modes`` and ``campbell``.

A system with gyroscopic or damping terms (or a non-symmetric stiffness) has the modes of
M q'' + (D + G) q' + K q = 0 instead of the symmetric problem: damped natural frequencies
wd = Im s (ascending), the eigenvalues s, logarithmic decrements and, for a model that declares
a whirl pair (Model.whirl_pair), each mode's whirl (forward / backward).
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.linear.damped import damped_modes, whirl

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
    (no whirl pair, or unknowns that are not a selection of nodal values)."""
    pair = system.metadata.whirl
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
    pair = system.metadata.whirl
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
