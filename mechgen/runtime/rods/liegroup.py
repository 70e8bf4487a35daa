"""Numeric so(3)/se(3) maps, batched over leading axes, safe at zero angle and near pi.

Conventions (those of seed 001, Grazioso, "Modeling of a soft link"): a twist is xi = (v, w) in R^6,
translational part first, so that the 6x6 blocks read [uu, uw; wu, ww]. A pose is the 4x4 matrix

    H = [[R, p], [0, 1]],   hat6(xi) = [[hat3(w), v], [0, 0]],

and the deformation twist of a rod is f = vee6(H^-1 H'). The adjoint maps are

    Ad_H = [[R, hat3(p) R], [0, R]],   ad_xi = [[hat3(w), hat3(v)], [0, hat3(w)]],

with ad_xi eta = vee6([hat6(xi), hat6(eta)]) and the co-adjoint ad*_xi = ad_xi^T. The exponential and its
left Jacobian (tangent operator) are the series

    exp(hat6(xi)) = sum_k hat6(xi)^k / k!,    J_l(xi) = sum_k ad_xi^k / (k+1)!,
    exp(hat(xi + d)) = exp(hat(J_l(xi) d)) exp(hat(xi)) + O(d^2),   J_r(xi) = J_l(-xi),

summed in closed form (Rodrigues; Barfoot & Furgale 2014, eq. (102) for the Q block) with the angle
functions switched to their Taylor series for theta < 1, where the closed forms lose digits to cancellation
(the last coefficient of Q loses eps/theta^4). Angles are radians, lengths in the caller's units.

The formulas of exp_so3, jac_left_so3(_inv), q_block, exp_se3 and jac_left/right_se3, the angle functions'
closed forms and series coefficients are generated from their sympy source, mechgen.symbolic.liegroup, into
mechgen/generated/liegroup/numpy_maps.py (``mechgen regen``; mechgen.codegen.lower_liegroup); this module
holds the batching glue (the series/closed-form switch, :func:`angle_of_square`) and the hand-written maps
that are not formula copies: hat/vee, the adjoints, the logarithms with their branch near pi.
"""
from __future__ import annotations

import math

import numpy as np

from mechgen.generated.liegroup import numpy_maps as maps

#: below this squared angle s = t^2 the angle functions are summed as series (generated from the sympy source)
SERIES_BELOW = maps.SERIES_BELOW
_CLOSED = {"sinc": maps.closed_sinc, "a1": maps.closed_a1, "a2": maps.closed_a2, "a3": maps.closed_a3,
           "a4": maps.closed_a4, "b": maps.closed_b}
_ALIASES = {"jl_inv": "b"}


def angle_series(name: str) -> tuple[float, ...]:
    """The Taylor coefficients c_m of an angle function (sinc, a1 … a4) in powers t^(2m), and ``"jl_inv"`` (or
    ``"b"``): b(t) of :func:`jac_left_so3_inv` (Bernoulli numbers); those of mechgen.symbolic.liegroup (16 terms,
    generated), for t < 1."""
    return maps.COEFFS[_ALIASES.get(name, name)]


def _limits(coeffs) -> list[float]:
    """For m = 1 … M terms, the largest angle whose first neglected term c_m t^(2m) is below 1e-18 of the
    function's value at 0 (|c_0|; the functions stay within a factor 2 of it for t < 1)."""
    return [(1e-18 * abs(coeffs[0]) / abs(coeffs[m])) ** (1.0 / (2 * m)) if m < len(coeffs) else math.inf
            for m in range(1, len(coeffs) + 1)]


_LIMITS = {name: _limits(coeffs) for name, coeffs in maps.COEFFS.items()}


def _terms(name: str, t_max: float) -> int:
    """How many series terms reach round-off for every angle up to t_max (< 1)."""
    for m, limit in enumerate(_LIMITS[name], 1):
        if t_max <= limit:
            return m
    return len(_LIMITS[name])


def _series(name: str, s: np.ndarray) -> np.ndarray:
    """The series of an angle function by Horner's rule in s = t^2, with only the terms the batch's largest
    angle needs."""
    coeffs = maps.COEFFS[name][:_terms(name, math.sqrt(float(np.max(s))) if s.size else 0.0)]
    acc = np.full_like(s, coeffs[-1])
    for c in reversed(coeffs[:-1]):
        acc *= s
        acc += c
    return acc


def angle_of_square(name: str, s) -> np.ndarray:
    """An angle function (sinc, a1 … a4, b; module docstring) at the squared angle s = t^2 >= 0: its series
    below t = 1, its closed form above (both generated from mechgen.symbolic.liegroup); round-off everywhere."""
    name = _ALIASES.get(name, name)
    s = np.asarray(s, dtype=float)
    small = s < SERIES_BELOW
    if small.all():
        return _series(name, s)
    if not small.any():
        return _CLOSED[name](np.sqrt(s))
    closed = _CLOSED[name](np.sqrt(np.where(small, SERIES_BELOW, s)))
    return np.where(small, _series(name, np.where(small, s, 0.0)), closed)


def angle_function(name: str, theta) -> np.ndarray:
    """One of sinc, a1 … a4 (module docstring) at theta >= 0, accurate to round-off at every angle."""
    t = np.asarray(theta, dtype=float)
    return angle_of_square(name, t * t)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis, batched (numpy's cross costs 40 us a call in axis bookkeeping: this is the
    hot path of the rod step's residual)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def hat3(w) -> np.ndarray:
    """hat3(w) x = w x x: the skew matrix of w, shape (..., 3, 3)."""
    w = np.asarray(w, dtype=float)
    out = np.zeros(w.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def vee3(W) -> np.ndarray:
    """Inverse of hat3 on the skew part: vee3(W) = (W32 - W23, W13 - W31, W21 - W12)/2."""
    W = np.asarray(W, dtype=float)
    return 0.5 * np.stack([W[..., 2, 1] - W[..., 1, 2], W[..., 0, 2] - W[..., 2, 0],
                           W[..., 1, 0] - W[..., 0, 1]], axis=-1)


def hat6(xi) -> np.ndarray:
    """hat6(v, w) = [[hat3(w), v], [0, 0]], shape (..., 4, 4)."""
    xi = np.asarray(xi, dtype=float)
    out = np.zeros(xi.shape[:-1] + (4, 4))
    out[..., :3, :3] = hat3(xi[..., 3:])
    out[..., :3, 3] = xi[..., :3]
    return out


def vee6(X) -> np.ndarray:
    """Inverse of hat6: (X[:3, 3], vee3(X[:3, :3]))."""
    X = np.asarray(X, dtype=float)
    return np.concatenate([X[..., :3, 3], vee3(X[..., :3, :3])], axis=-1)


def ad6(xi) -> np.ndarray:
    """ad_xi = [[hat3(w), hat3(v)], [0, hat3(w)]]: ad_xi eta = vee6([hat6 xi, hat6 eta])."""
    xi = np.asarray(xi, dtype=float)
    W, V = hat3(xi[..., 3:]), hat3(xi[..., :3])
    out = np.zeros(xi.shape[:-1] + (6, 6))
    out[..., :3, :3] = W
    out[..., :3, 3:] = V
    out[..., 3:, 3:] = W
    return out


def coad6(xi) -> np.ndarray:
    """The co-adjoint ad*_xi = ad_xi^T, acting on wrenches (force, moment)."""
    return np.swapaxes(ad6(xi), -1, -2)


def Ad(H) -> np.ndarray:
    """Ad_H = [[R, hat3(p) R], [0, R]]: hat6(Ad_H xi) = H hat6(xi) H^-1."""
    H = np.asarray(H, dtype=float)
    R, p = H[..., :3, :3], H[..., :3, 3]
    out = np.zeros(H.shape[:-2] + (6, 6))
    out[..., :3, :3] = R
    out[..., :3, 3:] = hat3(p) @ R
    out[..., 3:, 3:] = R
    return out


def inverse(H) -> np.ndarray:
    """H^-1 = [[R^T, -R^T p], [0, 1]]."""
    H = np.asarray(H, dtype=float)
    out = np.zeros_like(H)
    Rt = np.swapaxes(H[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, H[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def _theta(w: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("...i,...i->...", w, w))


def exp_so3(w) -> np.ndarray:
    """Rodrigues: exp(hat3 w) = I + sinc(t) hat3 w + a1(t) hat3(w)^2, t = |w| (generated from
    mechgen.symbolic.liegroup.exp_so3)."""
    return maps.exp_so3(np.asarray(w, dtype=float), angle_of_square)


def jac_left_so3(w) -> np.ndarray:
    """Left Jacobian of SO(3): J_l(w) = I + a1(t) hat3 w + a2(t) hat3(w)^2 (generated)."""
    return maps.jac_left_so3(np.asarray(w, dtype=float), angle_of_square)


def jac_left_so3_inv(w) -> np.ndarray:
    """J_l(w)^-1 = I - hat3(w)/2 + b(t) hat3(w)^2, b = (1 - t sin t/(2(1 - cos t)))/t^2 (1/12 + t^2/720 + …;
    generated).

    Singular at t = 2 pi k (k >= 1), where the exponential map is not a local diffeomorphism."""
    return maps.jac_left_so3_inv(np.asarray(w, dtype=float), angle_of_square)


def log_so3(R) -> np.ndarray:
    """w with exp_so3(w) = R and |w| <= pi; accurate near 0 (series) and near pi (from R + R^T)."""
    R = np.asarray(R, dtype=float)
    s = vee3(R)                                        # sin(t) n
    c = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)  # cos(t)
    t = np.arctan2(np.linalg.norm(s, axis=-1), c)
    near_pi = c < -0.9
    sinc = angle_function("sinc", t)
    w = s / np.where(near_pi, 1.0, sinc)[..., None]
    if np.any(near_pi):
        # (R + R^T)/2 - c I = (1 - c) n n^T: the axis from its largest column, its sign from s
        B = 0.5 * (R + np.swapaxes(R, -1, -2)) - c[..., None, None] * np.eye(3)
        d = np.diagonal(B, axis1=-2, axis2=-1)
        k = np.argmax(d, axis=-1)
        col = np.take_along_axis(B, k[..., None, None], axis=-1)[..., 0]
        n = col / np.linalg.norm(col, axis=-1)[..., None]
        sign = np.where(np.einsum("...i,...i->...", n, s) < 0, -1.0, 1.0)
        w = np.where(near_pi[..., None], (sign * t)[..., None] * n, w)
    return w


def q_block(v, w) -> np.ndarray:
    """The upper-right block Q(v, w) of J_l(xi) (Barfoot & Furgale 2014, eq. (102); generated)."""
    return maps.q_block(np.asarray(v, dtype=float), np.asarray(w, dtype=float), angle_of_square)


def exp_se3(xi) -> np.ndarray:
    """exp(hat6(v, w)) = [[exp_so3 w, J_l(w) v], [0, 1]] (generated)."""
    return maps.exp_se3(np.asarray(xi, dtype=float), angle_of_square)


def log_se3(H) -> np.ndarray:
    """xi with exp_se3(xi) = H, |w| <= pi: w = log_so3(R), v = J_l(w)^-1 p."""
    H = np.asarray(H, dtype=float)
    w = log_so3(H[..., :3, :3])
    v = np.einsum("...ij,...j->...i", jac_left_so3_inv(w), H[..., :3, 3])
    return np.concatenate([v, w], axis=-1)


def jac_left_se3(xi) -> np.ndarray:
    """J_l(xi) = sum_k ad_xi^k/(k+1)! = [[J_l(w), Q(v, w)], [0, J_l(w)]] (6x6; generated)."""
    return maps.jac_left_se3(np.asarray(xi, dtype=float), angle_of_square)


def jac_right_se3(xi) -> np.ndarray:
    """J_r(xi) = J_l(-xi) = sum_k (-ad_xi)^k/(k+1)!: exp(hat(xi + d)) = exp(hat xi) exp(hat(J_r d)) + O(d^2)
    (generated)."""
    return maps.jac_right_se3(np.asarray(xi, dtype=float), angle_of_square)


def orthonormality_error(R) -> float:
    """max |R^T R - I| over a batch of rotations: the drift the Lie-group integrators must keep at round-off."""
    R = np.asarray(R, dtype=float)
    return float(np.max(np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3))))
