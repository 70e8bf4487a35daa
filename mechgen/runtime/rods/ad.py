"""CasADi SX forms of the Lie-group maps, for algorithmic derivatives of the rods' local residuals.

The rod solvers (statics collocation and shooting, the dynamics step) evaluate their residuals with the
batched numpy maps of :mod:`mechgen.runtime.rods.liegroup`; their Jacobians come from CasADi's algorithmic
differentiation of the same local pieces written here in SX (one element, one node, one integration step),
mapped over the repetition: the symbolic work is that of one piece whatever N is (DESIGN.md, "symbolic on
the local piece, numeric over the repetition"). Closed forms of these derivatives (second variations of a
log of a product of exponentials) swell; AD does not.

Conventions are liegroup's: twists (v, w) translation first, poses as (R, p), angles in radians. The angle
functions switch to their Taylor series in t^2 below t = 1 exactly as the numpy maps do (same coefficients,
:func:`liegroup.angle_series`), so the derivative at zero angle is the series' (no 0/0). The formulas
of exp_so3, jac_left_so3(_inv), q_block and exp_se3, and the angle functions' closed forms and coefficients, are
generated from mechgen.symbolic.liegroup into mechgen/generated/liegroup/casadi_maps.py (``mechgen regen``);
this module holds the series/closed-form switch (:func:`angle`) and the maps that are not formula copies.
CasADi's if_else on SX evaluates both branches and multiplies the unused one by zero without reading it (a NaN
of a closed form at t = 0 does not leak). The logarithm here is for rotations away from pi (|angle| < pi - 1e-3
keeps its derivative to about 1e-6; the Jacobians of element increments and node updates never come near it);
the residuals themselves keep liegroup's log with its branch near pi.
"""
from __future__ import annotations

import math

import casadi as ca

from mechgen.generated.liegroup import casadi_maps as maps
from mechgen.runtime.rods.liegroup import angle_series

#: below this t^2 the angle functions are their series (t < 1, as in liegroup; from the sympy source)
SERIES_BELOW = maps.SERIES_BELOW
#: below this |sin t|^2 (and cos t > 0) log's t/sin t is the series of asin(x)/x (10 terms: < 1e-19)
LOG_SERIES_BELOW = 0.01
_ASIN_OVER_X = tuple(math.factorial(2 * n) / (4**n * math.factorial(n) ** 2 * (2 * n + 1)) for n in range(10))


def horner(coeffs, x):
    """sum_m coeffs[m] x^m by Horner's rule (x an SX expression)."""
    acc = coeffs[-1]
    for c in reversed(coeffs[:-1]):
        acc = acc * x + c
    return acc


def hat3(w):
    """hat3(w) y = w x y (3 x 3 SX)."""
    return ca.vertcat(ca.horzcat(0, -w[2], w[1]), ca.horzcat(w[2], 0, -w[0]), ca.horzcat(-w[1], w[0], 0))


def vee3(W):
    """(W32 - W23, W13 - W31, W21 - W12)/2."""
    return 0.5 * ca.vertcat(W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1])


_CLOSED = {"sinc": maps.closed_sinc, "a1": maps.closed_a1, "a2": maps.closed_a2, "a3": maps.closed_a3,
           "a4": maps.closed_a4, "b": maps.closed_b, "jl_inv": maps.closed_b}


def angle(name: str, t2):
    """sinc, a1 … a4, b (liegroup's angle functions) of t = sqrt(t2): the series below t = 1, else the closed
    form."""
    closed = _CLOSED[name](ca.sqrt(t2))
    return ca.if_else(t2 < SERIES_BELOW, horner(angle_series(name), t2), closed)


def exp_so3(w):
    """exp(hat3 w) = I + sinc(t) hat3 w + a1(t) hat3(w)^2 (generated)."""
    return maps.exp_so3(w, angle)


def jac_left_so3(w):
    """J_l(w) = I + a1(t) hat3 w + a2(t) hat3(w)^2 (generated)."""
    return maps.jac_left_so3(w, angle)


def jac_left_so3_inv(w):
    """J_l(w)^-1 = I - hat3(w)/2 + b(t) hat3(w)^2, b = (1 - t sin t/(2(1 - cos t)))/t^2 (series below t = 1;
    generated)."""
    return maps.jac_left_so3_inv(w, angle)


def log_so3(R):
    """w with exp(hat3 w) = R, |w| < pi: w = (t / sin t) vee3(R), t = atan2(|vee3 R|, (tr R - 1)/2)."""
    s = vee3(R)
    x2 = ca.dot(s, s)
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1)
    x = ca.sqrt(x2)
    closed = ca.atan2(x, c) / x
    ratio = ca.if_else(ca.logic_and(x2 < LOG_SERIES_BELOW, c > 0), horner(_ASIN_OVER_X, x2), closed)
    return ratio * s


def q_block(v, w):
    """The upper-right block Q(v, w) of the SE(3) left Jacobian (Barfoot & Furgale 2014, eq. (102); generated)."""
    return maps.q_block(v, w, angle)


def dexp_inv_right(theta, xi):
    """J_r(theta)^-1 xi for twists: J_r(theta) = J_l(-theta) = [[A, Q], [0, A]] with A = J_l(-w),
    Q = Q(-v, -w), so J_r^-1 xi = (A^-1 (xi_v - Q A^-1 xi_w), A^-1 xi_w)."""
    v, w = theta[:3], theta[3:]
    Ainv = jac_left_so3_inv(-w)
    rot = Ainv @ xi[3:]
    return ca.vertcat(Ainv @ (xi[:3] - q_block(-v, -w) @ rot), rot)


def exp_se3(xi):
    """exp(hat6(v, w)) as (R, p) = (exp_so3 w, J_l(w) v) (generated)."""
    H = maps.exp_se3(xi, angle)
    return H[:3, :3], H[:3, 3]


def log_se3(R, p):
    """xi = (J_l(w)^-1 p, w), w = log_so3(R)."""
    w = log_so3(R)
    return ca.vertcat(jac_left_so3_inv(w) @ p, w)


def compose(a, b):
    """(R_a, p_a)(R_b, p_b) = (R_a R_b, R_a p_b + p_a)."""
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def inverse(a):
    """(R, p)^-1 = (R^T, -R^T p)."""
    return a[0].T, -(a[0].T @ a[1])


def coad6(f, sigma):
    """ad_f^T sigma = (n x w, n x v + m x w) for f = (v, w), sigma = (n, m)."""
    v, w, n, m = f[:3], f[3:], sigma[:3], sigma[3:]
    return ca.vertcat(ca.cross(n, w), ca.cross(n, v) + ca.cross(m, w))


def matrix(flat, rows: int, cols: int):
    """A row-major flat SX vector as a rows x cols matrix (numpy's C order)."""
    return ca.reshape(flat, cols, rows).T


def flat(M):
    """A matrix as its row-major flat column (numpy's C order)."""
    return ca.reshape(M.T, -1, 1)


__all__ = ["hat3", "vee3", "angle", "q_block", "dexp_inv_right", "exp_so3", "jac_left_so3", "jac_left_so3_inv", "log_so3", "exp_se3",
           "log_se3", "compose", "inverse", "coad6", "matrix", "flat", "horner"]
