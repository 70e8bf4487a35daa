"""Symbolic so(3)/se(3) maps and Frenet-Serret frames (the sympy counterpart of mechgen.runtime.rods.liegroup).

Conventions (seed 001, Grazioso, "Modeling of a soft link"; those of the numeric module): a twist is
xi = (v, w), translational part first; a pose H = [[R, p], [0, 1]], hat6(xi) = [[hat3(w), v], [0, 0]];

    Ad_H = [[R, hat3(p) R], [0, R]],   ad_xi = [[hat3(w), hat3(v)], [0, hat3(w)]],   ad*_xi = ad_xi^T,
    exp(hat3 w) = I + sinc W + a1 W^2,      J_l(w) = I + a1 W + a2 W^2,    J_r(w) = J_l(-w),
    J_l(w)^-1 = I - W/2 + b W^2,            exp(hat6 xi) = [[exp(hat3 w), J_l(w) v], [0, 1]],
    J_l(xi) = [[J_l(w), Q(v, w)], [0, J_l(w)]] (Barfoot & Furgale 2014, eq. (102)),  J_r(xi) = J_l(-xi),

with W = hat3(w), t = |w| and the angle functions of s = t^2 = w.w (not of t: sqrt(w.w) has no derivative
at w = 0, while each a(s) is analytic there)

    sinc = sin t/t,  a1 = (1 - cos t)/t^2,  a2 = (t - sin t)/t^3,  a3 = (t^2 + 2 cos t - 2)/(2 t^4),
    a4 = (2 t - 3 sin t + t cos t)/(2 t^5),  b = (1 - t sin t/(2 (1 - cos t)))/t^2.

They are :class:`~mechgen.symbolic.safe.SafeFunction`s: their Taylor series below t = 1 rad (s < 1), the
closed form above, as in the numeric module, so a lowered kernel is finite and accurate at w = 0.
Angles in radians; lengths in the caller's units.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from mechgen.symbolic.safe import safe_function

_TERMS = 16
_S = sp.Symbol("s", positive=True)
_T = sp.sqrt(_S)


def _angle(name: str, closed: sp.Expr, coeff) -> type:
    return safe_function(f"angle_{name}", sp.Lambda(_S, closed), [coeff(k) for k in range(_TERMS)], 1)


_F = sp.factorial
#: the angle functions of the squared angle s = w.w (module docstring)
sinc_sq = _angle("sinc", sp.sin(_T) / _T, lambda k: sp.Integer(-1) ** k / _F(2 * k + 1))
a1_sq = _angle("a1", (1 - sp.cos(_T)) / _S, lambda k: sp.Integer(-1) ** k / _F(2 * k + 2))
a2_sq = _angle("a2", (_T - sp.sin(_T)) / _T**3, lambda k: sp.Integer(-1) ** k / _F(2 * k + 3))
a3_sq = _angle("a3", (_S + 2 * sp.cos(_T) - 2) / (2 * _S**2), lambda k: sp.Integer(-1) ** k / _F(2 * k + 4))
a4_sq = _angle("a4", (2 * _T - 3 * sp.sin(_T) + _T * sp.cos(_T)) / (2 * _T**5),
               lambda k: sp.Integer(-1) ** k * (k + 1) / _F(2 * k + 5))
# (1 - (t/2) cot(t/2))/t^2 = sum_n |B_2n| t^(2n-2)/(2n)!: converges for t < 2 pi (singular at 2 pi k)
b_sq = _angle("b", (1 - _T * sp.sin(_T) / (2 * (1 - sp.cos(_T)))) / _S,
              lambda k: sp.Abs(sp.bernoulli(2 * k + 2)) / _F(2 * k + 2))


def _vec(x, n: int) -> sp.Matrix:
    m = sp.Matrix(x)
    if m.shape != (n, 1):
        m = m.reshape(n, 1)
    return m


def hat3(w) -> sp.Matrix:
    """hat3(w) x = w x x: the skew matrix of a 3-vector."""
    w = _vec(w, 3)
    return sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def vee3(W) -> sp.Matrix:
    """Inverse of hat3 on the skew part: (W32 - W23, W13 - W31, W21 - W12)/2."""
    W = sp.Matrix(W)
    return sp.Matrix([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]]) / 2


def hat6(xi) -> sp.Matrix:
    """hat6(v, w) = [[hat3(w), v], [0, 0]] (4x4)."""
    xi = _vec(xi, 6)
    out = sp.zeros(4, 4)
    out[:3, :3] = hat3(xi[3:, 0])
    out[:3, 3] = xi[:3, 0]
    return out


def vee6(X) -> sp.Matrix:
    """Inverse of hat6: (X[:3, 3], vee3(X[:3, :3]))."""
    X = sp.Matrix(X)
    return X[:3, 3].col_join(vee3(X[:3, :3]))


def ad6(xi) -> sp.Matrix:
    """ad_xi = [[hat3(w), hat3(v)], [0, hat3(w)]]: ad_xi eta = vee6([hat6 xi, hat6 eta])."""
    xi = _vec(xi, 6)
    W, V = hat3(xi[3:, 0]), hat3(xi[:3, 0])
    return sp.BlockMatrix([[W, V], [sp.zeros(3, 3), W]]).as_explicit()


def coad6(xi) -> sp.Matrix:
    """The co-adjoint ad*_xi = ad_xi^T, acting on wrenches (force, moment)."""
    return ad6(xi).T


def pose(R, p) -> sp.Matrix:
    """H = [[R, p], [0, 1]]."""
    H = sp.eye(4)
    H[:3, :3] = sp.Matrix(R)
    H[:3, 3] = _vec(p, 3)
    return H


def Ad(H) -> sp.Matrix:  # noqa: N802 - the usual name
    """Ad_H = [[R, hat3(p) R], [0, R]]: hat6(Ad_H xi) = H hat6(xi) H^-1."""
    H = sp.Matrix(H)
    R, p = H[:3, :3], H[:3, 3]
    return sp.BlockMatrix([[R, hat3(p) * R], [sp.zeros(3, 3), R]]).as_explicit()


def inverse(H) -> sp.Matrix:
    """H^-1 = [[R^T, -R^T p], [0, 1]]."""
    H = sp.Matrix(H)
    R, p = H[:3, :3], H[:3, 3]
    return pose(R.T, -R.T * p)


def _sq(w: sp.Matrix) -> sp.Expr:
    return (w.T * w)[0, 0]


def exp_so3(w) -> sp.Matrix:
    """Rodrigues: exp(hat3 w) = I + sinc W + a1 W^2."""
    w = _vec(w, 3)
    s, W = _sq(w), hat3(w)
    return sp.eye(3) + sinc_sq(s) * W + a1_sq(s) * W * W


def jac_left_so3(w) -> sp.Matrix:
    """Left Jacobian of SO(3): J_l(w) = I + a1 W + a2 W^2 = sum_k hat3(w)^k/(k+1)!."""
    w = _vec(w, 3)
    s, W = _sq(w), hat3(w)
    return sp.eye(3) + a1_sq(s) * W + a2_sq(s) * W * W


def jac_right_so3(w) -> sp.Matrix:
    """Right Jacobian J_r(w) = J_l(-w) = J_l(w)^T: exp(hat(w + d)) = exp(hat w) exp(hat(J_r d)) + O(d^2)."""
    return jac_left_so3(-_vec(w, 3))


def jac_left_so3_inv(w) -> sp.Matrix:
    """J_l(w)^-1 = I - W/2 + b W^2 (singular at |w| = 2 pi k, k >= 1)."""
    w = _vec(w, 3)
    s, W = _sq(w), hat3(w)
    return sp.eye(3) - W / 2 + b_sq(s) * W * W


def jac_right_so3_inv(w) -> sp.Matrix:
    """J_r(w)^-1 = J_l(-w)^-1."""
    return jac_left_so3_inv(-_vec(w, 3))


def q_block(v, w) -> sp.Matrix:
    """The upper-right block Q(v, w) of the SE(3) left Jacobian (Barfoot & Furgale 2014, eq. (102))."""
    v, w = _vec(v, 3), _vec(w, 3)
    s, V, W = _sq(w), hat3(v), hat3(w)
    WV, VW = W * V, V * W
    WVW = WV * W
    return (V / 2 + a2_sq(s) * (WV + VW + WVW) + a3_sq(s) * (W * WV + VW * W - 3 * WVW)
            + a4_sq(s) * (WVW * W + W * WVW))


def exp_se3(xi) -> sp.Matrix:
    """exp(hat6(v, w)) = [[exp_so3 w, J_l(w) v], [0, 1]]."""
    xi = _vec(xi, 6)
    v, w = xi[:3, 0], xi[3:, 0]
    return pose(exp_so3(w), jac_left_so3(w) * v)


def jac_left_se3(xi) -> sp.Matrix:
    """J_l(xi) = sum_k ad_xi^k/(k+1)! = [[J_l(w), Q(v, w)], [0, J_l(w)]]:
    exp(hat(xi + d)) = exp(hat(J_l(xi) d)) exp(hat xi) + O(d^2)."""
    xi = _vec(xi, 6)
    v, w = xi[:3, 0], xi[3:, 0]
    J = jac_left_so3(w)
    return sp.BlockMatrix([[J, q_block(v, w)], [sp.zeros(3, 3), J]]).as_explicit()


def jac_right_se3(xi) -> sp.Matrix:
    """J_r(xi) = J_l(-xi): exp(hat(xi + d)) = exp(hat xi) exp(hat(J_r(xi) d)) + O(d^2)."""
    return jac_left_se3(-_vec(xi, 6))


def jac_left_se3_inv(xi) -> sp.Matrix:
    """J_l(xi)^-1 = [[J^-1, -J^-1 Q J^-1], [0, J^-1]] with J = J_l(w) (block triangular inverse)."""
    xi = _vec(xi, 6)
    v, w = xi[:3, 0], xi[3:, 0]
    Ji = jac_left_so3_inv(w)
    return sp.BlockMatrix([[Ji, -Ji * q_block(v, w) * Ji], [sp.zeros(3, 3), Ji]]).as_explicit()


def jac_right_se3_inv(xi) -> sp.Matrix:
    """J_r(xi)^-1 = J_l(-xi)^-1."""
    return jac_left_se3_inv(-_vec(xi, 6))


# -- reference curves -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FrenetFrame:
    """The Frenet-Serret frame of a parametric curve u0(a) (seed 001, slides 4-6).

    Attributes:
        t, n, b: unit tangent, principal normal (towards the centre of curvature), binormal (3-vectors).
        R: the rotation [t n b] (columns).
        curvature: kappa0 = |u0' x u0''|/|u0'|^3 (1/length).
        torsion: tau0 = (u0' x u0'').u0'''/|u0' x u0''|^2 (1/length).
        speed: |u0'| (length per unit of the parameter; 1 for an arc-length parameter).
        twist: f0 = (|u0'| e1, |u0'| (tau0, 0, kappa0)): the reference deformation twist, R' = R hat3(f0_w),
            u0' = R f0_u.
    """

    t: sp.Matrix
    n: sp.Matrix
    b: sp.Matrix
    R: sp.Matrix
    curvature: sp.Expr
    torsion: sp.Expr
    speed: sp.Expr
    twist: sp.Matrix


def _simp(e):
    return sp.simplify(e)


def curvature(curve, a: sp.Symbol) -> sp.Expr:
    """kappa0 = |u0' x u0''| / |u0'|^3 of the curve u0(a) (a 3-vector of expressions in a)."""
    u = _vec(curve, 3)
    d1, d2 = u.diff(a), u.diff(a, 2)
    c = d1.cross(d2)
    return _simp(sp.sqrt(_simp(c.dot(c))) / sp.sqrt(_simp(d1.dot(d1))) ** 3)


def torsion(curve, a: sp.Symbol) -> sp.Expr:
    """tau0 = (u0' x u0'') . u0''' / |u0' x u0''|^2 (undefined where the curvature vanishes)."""
    u = _vec(curve, 3)
    d1, d2, d3 = u.diff(a), u.diff(a, 2), u.diff(a, 3)
    c = d1.cross(d2)
    return _simp(_simp(c.dot(d3)) / _simp(c.dot(c)))


def frenet_serret(curve, a: sp.Symbol) -> FrenetFrame:
    """The Frenet-Serret frame, curvature, torsion and reference twist of the curve u0(a).

    t = u0'/|u0'|, b = (u0' x u0'')/|u0' x u0''|, n = b x t; the frame obeys R' = R hat3(|u0'| (tau0, 0, kappa0))
    (seed 001, slide 6). Needs a curve with nonzero curvature (a straight line has no principal normal).
    """
    u = _vec(curve, 3)
    d1, d2 = u.diff(a), u.diff(a, 2)
    speed = _simp(sp.sqrt(_simp(d1.dot(d1))))
    c = d1.cross(d2)
    cn = _simp(sp.sqrt(_simp(c.dot(c))))
    if cn == 0:
        raise ValueError("a straight reference curve has no Frenet-Serret frame (zero curvature)")
    t = (d1 / speed).applyfunc(_simp)
    b = (c / cn).applyfunc(_simp)
    n = b.cross(t).applyfunc(_simp)
    R = t.row_join(n).row_join(b)
    kappa, tau = curvature(u, a), torsion(u, a)
    twist = sp.Matrix([speed, 0, 0, _simp(speed * tau), 0, _simp(speed * kappa)])
    return FrenetFrame(t, n, b, R, kappa, tau, speed, twist)
