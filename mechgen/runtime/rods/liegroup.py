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
"""
from __future__ import annotations

import math

import numpy as np

_SERIES_BELOW = 1.0   # rad: below this the angle functions are summed as series (12 terms: < 1e-20 truncation)
_TERMS = 12


def _fact(n: int) -> float:
    return float(math.factorial(n))


_BERNOULLI_ABS = (1 / 6, 1 / 30, 1 / 42, 1 / 30, 5 / 66, 691 / 2730, 7 / 6, 3617 / 510, 43867 / 798,
                  174611 / 330, 854513 / 138, 236364091 / 2730)    # |B_2| … |B_24|
_INV_SERIES = [b / _fact(2 * n + 2) for n, b in enumerate(_BERNOULLI_ABS)]


# a_j(theta) = sum_m (-1)^m c_jm theta^(2m): the angle functions of exp and its Jacobians, as series.
_SERIES = {
    "sinc": [(-1) ** m / _fact(2 * m + 1) for m in range(_TERMS)],           # sin t / t
    "a1": [(-1) ** m / _fact(2 * m + 2) for m in range(_TERMS)],             # (1 - cos t)/t^2
    "a2": [(-1) ** m / _fact(2 * m + 3) for m in range(_TERMS)],             # (t - sin t)/t^3
    "a3": [(-1) ** m / _fact(2 * m + 4) for m in range(_TERMS)],             # (t^2 + 2 cos t - 2)/(2 t^4)
    "a4": [(-1) ** m * (m + 1) / _fact(2 * m + 5) for m in range(_TERMS)],   # (2t - 3 sin t + t cos t)/(2 t^5)
}


def angle_series(name: str) -> tuple[float, ...]:
    """The Taylor coefficients c_m of an angle function (sinc, a1 … a4) in powers t^(2m), and ``"jl_inv"``:
    b(t) of :func:`jac_left_so3_inv` (Bernoulli numbers); 12 terms, for t < 1 (round-off there)."""
    if name == "jl_inv":
        return tuple(_INV_SERIES)
    return tuple(_SERIES[name])


def _closed(name: str, t: np.ndarray) -> np.ndarray:
    if name == "sinc":
        return np.sin(t) / t
    if name == "a1":
        return (1.0 - np.cos(t)) / t**2
    if name == "a2":
        return (t - np.sin(t)) / t**3
    if name == "a3":
        return (t**2 + 2.0 * np.cos(t) - 2.0) / (2.0 * t**4)
    return (2.0 * t - 3.0 * np.sin(t) + t * np.cos(t)) / (2.0 * t**5)


def _limits(name: str) -> list[float]:
    """For m = 1 … 12 terms, the largest angle whose first neglected term c_m t^(2m) is below 1e-18 of the
    function's value at 0 (|c_0|; the functions stay within a factor 2 of it for t < 1)."""
    coeffs = _SERIES[name]
    return [(1e-18 * abs(coeffs[0]) / abs(coeffs[m])) ** (1.0 / (2 * m)) if m < len(coeffs) else math.inf
            for m in range(1, len(coeffs) + 1)]


_LIMITS = {name: _limits(name) for name in _SERIES}


def _terms(name: str, t_max: float) -> int:
    """How many series terms reach round-off for every angle up to t_max (< 1)."""
    for m, limit in enumerate(_LIMITS[name], 1):
        if t_max <= limit:
            return m
    return len(_SERIES[name])


def _series(name: str, t: np.ndarray) -> np.ndarray:
    """The series of an angle function by Horner's rule in t^2, with only the terms the batch's largest angle
    needs."""
    coeffs = _SERIES[name][:_terms(name, float(np.max(t)) if t.size else 0.0)]
    t2 = t * t
    acc = np.full_like(t2, coeffs[-1])
    for c in reversed(coeffs[:-1]):
        acc *= t2
        acc += c
    return acc


def angle_function(name: str, theta) -> np.ndarray:
    """One of sinc, a1 … a4 (module docstring) at theta >= 0, accurate to round-off at every angle."""
    t = np.asarray(theta, dtype=float)
    small = t < _SERIES_BELOW
    if small.all():
        return _series(name, t)
    if not small.any():
        return _closed(name, t)
    safe = np.where(small, 1.0, t)
    return np.where(small, _series(name, np.where(small, t, 0.0)), _closed(name, safe))


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
    """Rodrigues: exp(hat3 w) = I + sinc(t) hat3 w + a1(t) hat3(w)^2 = cos t I + sinc(t) hat3 w + a1(t) w w^T,
    t = |w| (hat3(w)^2 = w w^T - t^2 I; cos t = 1 - a1 t^2)."""
    w = np.asarray(w, dtype=float)
    t = _theta(w)
    a1 = angle_function("a1", t)
    out = (a1[..., None, None] * w[..., :, None]) * w[..., None, :]
    out += angle_function("sinc", t)[..., None, None] * hat3(w)
    c = np.cos(t)
    for i in range(3):
        out[..., i, i] += c
    return out


def jac_left_so3(w) -> np.ndarray:
    """Left Jacobian of SO(3): J_l(w) = I + a1(t) hat3 w + a2(t) hat3(w)^2."""
    w = np.asarray(w, dtype=float)
    t = _theta(w)
    W = hat3(w)
    return (np.eye(3) + angle_function("a1", t)[..., None, None] * W
            + angle_function("a2", t)[..., None, None] * (W @ W))


def jac_left_so3_inv(w) -> np.ndarray:
    """J_l(w)^-1 = I - hat3(w)/2 + b(t) hat3(w)^2, b = (1 - t sin t/(2(1 - cos t)))/t^2 (1/12 + t^2/720 + …).

    Singular at t = 2 pi k (k >= 1), where the exponential map is not a local diffeomorphism."""
    w = np.asarray(w, dtype=float)
    t = _theta(w)
    W = hat3(w)
    small = t < _SERIES_BELOW
    ts = np.where(small, 1.0, t)
    closed = (1.0 - ts * np.sin(ts) / (2.0 * (1.0 - np.cos(ts)))) / ts**2
    t2 = t * t
    # (1 - (t/2) cot(t/2))/t^2 = sum_n |B_2n| t^(2n-2)/(2n)! (Bernoulli numbers; converges for t < 2 pi)
    series = np.polynomial.polynomial.polyval(t * t, _INV_SERIES)
    b = np.where(small, series, closed)
    return np.eye(3) - 0.5 * W + b[..., None, None] * (W @ W)


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


def _q_block(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The upper-right block of J_l(xi) (Barfoot & Furgale 2014, eq. (102))."""
    t = _theta(w)
    V, W = hat3(v), hat3(w)
    WV, VW = W @ V, V @ W
    WVW = WV @ W
    a2, a3, a4 = (angle_function(n, t)[..., None, None] for n in ("a2", "a3", "a4"))
    return 0.5 * V + a2 * (WV + VW + WVW) + a3 * (W @ WV + VW @ W - 3.0 * WVW) + a4 * (WVW @ W + W @ WVW)


def exp_se3(xi) -> np.ndarray:
    """exp(hat6(v, w)) = [[exp_so3 w, J_l(w) v], [0, 1]]."""
    xi = np.asarray(xi, dtype=float)
    out = np.zeros(xi.shape[:-1] + (4, 4))
    out[..., :3, :3] = exp_so3(xi[..., 3:])
    out[..., :3, 3] = np.einsum("...ij,...j->...i", jac_left_so3(xi[..., 3:]), xi[..., :3])
    out[..., 3, 3] = 1.0
    return out


def log_se3(H) -> np.ndarray:
    """xi with exp_se3(xi) = H, |w| <= pi: w = log_so3(R), v = J_l(w)^-1 p."""
    H = np.asarray(H, dtype=float)
    w = log_so3(H[..., :3, :3])
    v = np.einsum("...ij,...j->...i", jac_left_so3_inv(w), H[..., :3, 3])
    return np.concatenate([v, w], axis=-1)


def jac_left_se3(xi) -> np.ndarray:
    """J_l(xi) = sum_k ad_xi^k/(k+1)! = [[J_l(w), Q(v, w)], [0, J_l(w)]] (6x6)."""
    xi = np.asarray(xi, dtype=float)
    v, w = xi[..., :3], xi[..., 3:]
    J = jac_left_so3(w)
    out = np.zeros(xi.shape[:-1] + (6, 6))
    out[..., :3, :3] = J
    out[..., 3:, 3:] = J
    out[..., :3, 3:] = _q_block(v, w)
    return out


def jac_right_se3(xi) -> np.ndarray:
    """J_r(xi) = J_l(-xi) = sum_k (-ad_xi)^k/(k+1)!: exp(hat(xi + d)) = exp(hat xi) exp(hat(J_r d)) + O(d^2)."""
    return jac_left_se3(-np.asarray(xi, dtype=float))


def orthonormality_error(R) -> float:
    """max |R^T R - I| over a batch of rotations: the drift the Lie-group integrators must keep at round-off."""
    R = np.asarray(R, dtype=float)
    return float(np.max(np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3))))
