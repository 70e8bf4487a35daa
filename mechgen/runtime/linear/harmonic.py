"""Steady harmonic response of a linear system, and the orbits it traces.

About an operating point, M q'' + (D + G) q' + K q = Re(f exp(i omega t)) responds in steady state with
q(t) = Re(X exp(i omega t)),

    (K - omega^2 M + i omega C) X = f,   C = D + G,

(units: X in the coordinates' units when f is in generalized force units). The matrices may depend on the
frequency's own parameter (a rotor's spin speed Omega, which is also the frequency of an unbalance): each
frequency takes the matrices ``matrices_at(omega)`` gives. A pair (x, y) of coordinates traces the ellipse
x = Re(X_x exp(i omega t)), y = Re(X_y exp(i omega t)): its semi-axes, orientation and whirl direction are
those of a mode's orbit (mechgen.runtime.linear.damped.orbit_axes, whirl), since a damped mode's shape and a
harmonic response are both complex amplitudes of exp(i w t), w > 0.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.linear.damped import orbit_axes, whirl

#: a pivot of the LU below this times the largest is a singular system (a resonance without damping)
SINGULAR_RTOL = 1e3 * np.finfo(float).eps


def harmonic_solve(M, C, K, omega: float, f: np.ndarray) -> np.ndarray:
    """X = (K - omega^2 M + i omega C)^-1 f (dense LU, or a sparse LU for sparse matrices); ConvergenceError
    naming omega (rad/s) where the dynamic stiffness is singular (an undamped resonance)."""
    import scipy.linalg as sla
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    w = np.float64(omega)
    with np.errstate(over="ignore", invalid="ignore"):  # a huge omega: inf entries, refused below
        A = K - w**2 * M + 1j * w * C
    values = A.data if sps.issparse(A) else np.asarray(A)
    if not np.all(np.isfinite(values)) or not np.all(np.isfinite(f)):
        raise ConvergenceError(f"response: the dynamic stiffness or the force is not finite at omega = {omega:g} "
                               "rad/s (overflow); drive at smaller frequencies or scale the model")
    if sps.issparse(A):
        x = spla.spsolve(sps.csc_matrix(A, dtype=complex), f)
    else:
        lu, piv = sla.lu_factor(np.asarray(A, dtype=complex), check_finite=False)
        pivots = np.abs(np.diag(lu))
        if np.min(pivots) <= SINGULAR_RTOL * np.max(pivots):
            raise ConvergenceError(f"response: the system is singular at omega = {omega:g} rad/s (a resonance "
                                   "without damping); drive off it or add damping")
        x = sla.lu_solve((lu, piv), f, check_finite=False)
    if not np.all(np.isfinite(x)):
        raise ConvergenceError(f"response: no finite response at omega = {omega:g} rad/s (a resonance without "
                               "damping); drive off it or add damping")
    return np.asarray(x, dtype=complex)


def harmonic_responses(matrices_at: Callable[[float], dict], omegas, force_at: Callable[[float], np.ndarray],
                       budget=None) -> np.ndarray:
    """The responses X (n x frequencies) to f = force_at(omega) with the matrices {M, C, K} = matrices_at(omega),
    omega in rad/s; ``budget`` (a mechgen.runtime.core.budget.Budget, or None) projects the time of all."""
    columns = []
    count = len(omegas)
    for i, w in enumerate(omegas):
        if budget is not None:
            budget.project(i, count, lambda: f"{i:,} of {count:,} frequencies (omega = {w:g} rad/s)")
        mats = matrices_at(float(w))
        columns.append(harmonic_solve(mats["M"], mats["C"], mats["K"], float(w), force_at(float(w))))
    return np.array(columns).T


def orbits(X: np.ndarray, Y: np.ndarray) -> dict[str, list]:
    """The orbit x = Re(X_j e^{i w t}), y = Re(Y_j e^{i w t}) at each frequency j: ``major`` and ``minor``
    semi-axes (a >= b >= 0; a^2 + b^2 = |X|^2 + |Y|^2, a b = |Im(X conj Y)|), ``angle`` (the major axis from x
    towards y, rad), ``whirl`` (forward: the angular momentum x y' - y x', mean w Im(X conj Y), positive;
    backward: negative; linear: a straight line, |b / a| <= 1e-6; none: no motion) and ``whirl_ratio`` (b / a
    signed as the angular momentum)."""
    shapes = np.vstack([np.asarray(X, dtype=complex), np.asarray(Y, dtype=complex)])
    axes = orbit_axes(shapes, 0, 1)
    return {"major": [float(a) for a in axes["major"]], "minor": [float(b) for b in axes["minor"]],
            "angle": [float(t) for t in axes["angle"]], "whirl": whirl(shapes, 0, 1),
            "whirl_ratio": [float(k) for k in axes["kappa"]]}
