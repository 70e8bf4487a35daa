"""A hand-written frequency-response curve of the forced Duffing oscillator: shooting plus pseudo-arclength
continuation in plain scipy (the peer of ``mechgen bench orbits``), written as a user without mechgen would.

    x'' + c x' + x + k3 x^3 = F cos(w t),   c = 0.1, k3 = 1, F = 0.3,

the orbit's start x0 = (x(0), x'(0)) solving R(x0, w) = x(2 pi / w) - x0 = 0 (scipy's solve_ivp, DOP853); the
branch z = (x0, w) followed by pseudo-arclength: the tangent is the null vector of the forward-difference Jacobian
[R_x0, R_w], the predictor z + ds t, the corrector scipy.optimize.fsolve on (R(z), t . (z - z_pred)); a fold of
the curve is where t_w changes sign, located by the secant on t_w between the two points (one more corrected
point). Returns the branch and the folds' w.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

C, K3, F = 0.1, 1.0, 0.3


def residual(z: np.ndarray, rtol: float) -> np.ndarray:
    """x(T) - x0 for z = (x(0), x'(0), w), T = 2 pi / w."""
    w = z[2]

    def rhs(t, y):
        return [y[1], F * math.cos(w * t) - C * y[1] - y[0] - K3 * y[0] ** 3]

    sol = solve_ivp(rhs, (0.0, 2 * math.pi / w), z[:2], method="DOP853", rtol=rtol, atol=rtol * 1e-2)
    return sol.y[:, -1] - z[:2]


def tangent(z: np.ndarray, rtol: float, previous: np.ndarray | None) -> np.ndarray:
    """The unit null vector of [R_x0, R_w] (forward differences), oriented along ``previous``."""
    r0 = residual(z, rtol)
    h = 1e-7
    J = np.column_stack([(residual(z + h * e, rtol) - r0) / h for e in np.eye(3)])
    t = np.linalg.svd(J)[2][-1]
    if previous is not None and t @ previous < 0:
        t = -t
    elif previous is None and t[2] < 0:
        t = -t
    return t / np.linalg.norm(t)


def frequency_response(w_start: float, w_stop: float, rtol: float, ds: float = 0.05,
                       max_points: int = 400) -> tuple[np.ndarray, list[float]]:
    """(branch points z (rows), the folds' w) from w_start to w_stop."""
    x0 = fsolve(lambda x: residual(np.append(x, w_start), rtol), [0.3, 0.0], xtol=rtol)
    z = np.append(x0, w_start)
    t = tangent(z, rtol, None)
    points, folds = [z], []
    while z[2] < w_stop and len(points) < max_points:
        pred = z + ds * t
        z_new = fsolve(lambda y: np.append(residual(y, rtol), t @ (y - pred)), pred, xtol=rtol)
        t_new = tangent(z_new, rtol, t)
        if t[2] * t_new[2] < 0:  # a fold between z and z_new: the secant on t_w
            s = t[2] / (t[2] - t_new[2])
            guess = z + s * (z_new - z)
            chord = (z_new - z) / np.linalg.norm(z_new - z)
            fold = fsolve(lambda y: np.append(residual(y, rtol), chord @ (y - guess)), guess, xtol=rtol)
            folds.append(float(fold[2]))
        z, t = z_new, t_new
        points.append(z)
    return np.array(points), folds
