"""The symbolic so(3)/se(3) maps and Frenet-Serret frames (mechgen.symbolic.liegroup, issue 15 item 1).

References: the defining series exp(X) = sum X^k/k! (scipy.linalg.expm) and J_l(xi) = sum ad_xi^k/(k+1)!
summed numerically; the numeric module mechgen.runtime.rods.liegroup (an independent implementation);
the helix u0 = (r cos a, r sin a, c a) with kappa = r/(r^2 + c^2), tau = c/(r^2 + c^2) and the circle
with kappa = 1/r, tau = 0 (do Carmo, Differential Geometry of Curves and Surfaces, sec. 1-5); the
Frenet-Serret equations R' = R hat3(|u0'| (tau, 0, kappa)) (seed 001, slide 6).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import sympy as sp

from mechgen.codegen.printing import c_code, numpy_code
from mechgen.runtime.rods import liegroup as num
from mechgen.symbolic import liegroup as L
from mechgen.symbolic.safe import closed_form

W = sp.symbols("w0:3", real=True)
V = sp.symbols("v0:3", real=True)
XI = V + W
MATS = {"exp_so3": L.exp_so3(W), "exp_se3": L.exp_se3(XI), "jac_left_se3": L.jac_left_se3(XI),
        "jac_right_se3": L.jac_right_se3(XI), "jac_left_so3_inv": L.jac_left_so3_inv(W),
        "jac_left_se3_inv": L.jac_left_se3_inv(XI), "jac_right_so3": L.jac_right_so3(W)}
ANGLES = (0.0, 1e-12, 1e-7, 1e-3, 0.3, 0.999999, 1.0, 1.000001, 2.5, 3.1)


_TEXTS: dict = {}


def _lowered_numpy(matrix: sp.Matrix, syms, values) -> np.ndarray:
    """The matrix evaluated through mechgen's numpy printer (the text a generated kernel holds), after one
    CSE pass as in a kernel (mechgen.codegen.lower)."""
    key = (sp.srepr(matrix), tuple(syms))
    if key not in _TEXTS:
        subs, (reduced,) = sp.cse([matrix], symbols=sp.numbered_symbols("t"))
        lines = [compile(f"{s} = {numpy_code(e)}", "<cse>", "exec") for s, e in subs]
        _TEXTS[key] = (lines, [[compile(numpy_code(e), "<out>", "eval") for e in row] for row in reduced.tolist()])
    lines, outs = _TEXTS[key]
    env = {"np": np, **{s.name: np.float64(x) for s, x in zip(syms, values)}}
    with np.errstate(divide="raise", invalid="raise", over="raise"):   # no 0/0 in either branch
        for line in lines:
            exec(line, env)
        return np.array([[float(eval(e, env)) for e in row] for row in outs])


def _point(theta: float, seed: int, n: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    w = rng.normal(size=3)
    w *= theta / np.linalg.norm(w)
    return np.concatenate([rng.normal(size=3), w]) if n == 6 else w


def _series_jl(xi: np.ndarray) -> np.ndarray:
    ad = num.ad6(xi)
    out, term = np.eye(6), np.eye(6)
    for k in range(1, 40):
        term = term @ ad / (k + 1)
        out = out + term
    return out


def test_hat_vee_ad_identities_hold_exactly():
    eta = sp.symbols("e0:6", real=True)
    assert L.vee3(L.hat3(W)) == sp.Matrix(W)
    assert L.vee6(L.hat6(XI)) == sp.Matrix(XI)
    bracket = L.hat6(XI) * L.hat6(eta) - L.hat6(eta) * L.hat6(XI)
    assert sp.expand(L.ad6(XI) * sp.Matrix(eta) - L.vee6(bracket)) == sp.zeros(6, 1)
    assert L.coad6(XI) == L.ad6(XI).T
    R = L.exp_so3(sp.Matrix([0, 0, sp.Symbol("q")]))
    H = L.pose(closed_form(R), sp.Matrix(sp.symbols("p0:3")))
    lhs = L.hat6(L.Ad(H) * sp.Matrix(XI))
    rhs = H * L.hat6(XI) * L.inverse(H)
    assert sp.simplify(lhs - rhs) == sp.zeros(4, 4)
    assert sp.simplify(L.inverse(H) * H) == sp.eye(4)


@pytest.mark.parametrize("theta", ANGLES)
def test_exponentials_and_jacobians_agree_with_expm_the_series_and_the_numeric_module(theta):
    xi = _point(theta, seed=int(theta * 1e6) % 97 + 1, n=6)
    w = xi[3:]
    R = _lowered_numpy(MATS["exp_so3"], W, w)
    # expm (scaling and squaring, Pade 13) is itself accurate to a few eps times |X|: 1e-14 up to pi
    np.testing.assert_allclose(R, scipy.linalg.expm(num.hat3(w)), rtol=0, atol=1e-14)
    np.testing.assert_allclose(R, num.exp_so3(w), rtol=0, atol=2e-15)   # a few ulp of entries up to 1
    H = _lowered_numpy(MATS["exp_se3"], XI, xi)
    np.testing.assert_allclose(H, scipy.linalg.expm(num.hat6(xi)), rtol=0, atol=1e-14)
    Jl = _lowered_numpy(MATS["jac_left_se3"], XI, xi)
    np.testing.assert_allclose(Jl, _series_jl(xi), rtol=0, atol=1e-14)
    np.testing.assert_allclose(Jl, num.jac_left_se3(xi), rtol=0, atol=2e-15)
    np.testing.assert_allclose(_lowered_numpy(MATS["jac_right_se3"], XI, xi), num.jac_right_se3(xi), rtol=0,
                               atol=2e-15)
    np.testing.assert_allclose(_lowered_numpy(MATS["jac_left_so3_inv"], W, w), num.jac_left_so3_inv(w), rtol=0,
                               atol=1e-15)
    Jinv = _lowered_numpy(MATS["jac_left_se3_inv"], XI, xi)
    np.testing.assert_allclose(Jinv @ Jl, np.eye(6), rtol=0, atol=5e-15)
    np.testing.assert_allclose(_lowered_numpy(MATS["jac_right_so3"], W, w), num.jac_left_so3(w).T, rtol=0,
                               atol=1e-15)


def test_ad_and_adjoint_of_a_pose_agree_with_the_numeric_module():
    xi = _point(0.7, seed=3, n=6)
    np.testing.assert_allclose(_lowered_numpy(L.ad6(XI), XI, xi), num.ad6(xi), atol=1e-15)
    np.testing.assert_allclose(_lowered_numpy(L.coad6(XI), XI, xi), num.coad6(xi), atol=1e-15)
    H = num.exp_se3(xi)
    np.testing.assert_allclose(np.array(L.Ad(sp.Matrix(H)), dtype=float), num.Ad(H), atol=1e-15)
    # Ad(exp(hat xi)) = expm(ad_xi): the adjoint representation of the exponential
    np.testing.assert_allclose(num.Ad(_lowered_numpy(L.exp_se3(XI), XI, xi)), scipy.linalg.expm(num.ad6(xi)),
                               atol=2e-15)


@pytest.mark.parametrize("theta", (0.0, 1e-9, 0.5, 2.0))
def test_identities_at_forty_digits_exp_orthonormal_jacobian_inverse(theta):
    w = _point(theta, seed=11)
    sub = {s: sp.Float(x, 40) for s, x in zip(W, w)}
    R = L.exp_so3(W).xreplace(sub).evalf(40)
    assert float(max(abs(x) for x in (R.T * R - sp.eye(3)))) < 1e-30
    J = (L.jac_left_so3(W) * L.jac_left_so3_inv(W)).xreplace(sub).evalf(40)
    assert float(max(abs(x) for x in (J - sp.eye(3)))) < 1e-30
    # J_r(w) = J_l(w)^T and exp(hat w) = J_l(w) J_r(w)^-1 (Barfoot & Furgale 2014, eq. (97))
    Jr = L.jac_right_so3(W).xreplace(sub).evalf(40)
    assert float(max(abs(x) for x in (Jr - L.jac_left_so3(W).T.xreplace(sub).evalf(40)))) < 1e-30
    E = (L.jac_left_so3(W) * L.jac_right_so3_inv(W)).xreplace(sub).evalf(40)
    assert float(max(abs(x) for x in (E - R))) < 1e-30


def test_derivatives_stay_finite_and_exact_at_zero_angle():
    # d/dw_i exp(hat w) at w = 0 is hat3(e_i); d2/dw_i dw_j exp(hat w) at 0 is (E_i E_j + E_j E_i)/2
    R = L.exp_so3(W)
    for i in range(3):
        Ri = R.diff(W[i])
        np.testing.assert_allclose(_lowered_numpy(Ri, W, [0.0, 0.0, 0.0]), num.hat3(np.eye(3)[i]), atol=0)
        for j in range(3):
            Rij = _lowered_numpy(Ri.diff(W[j]), W, [1e-300, 0.0, 0.0])
            Ei, Ej = num.hat3(np.eye(3)[i]), num.hat3(np.eye(3)[j])
            np.testing.assert_allclose(Rij, (Ei @ Ej + Ej @ Ei) / 2, atol=1e-16)
    # the second derivative of exp_se3 by finite differences of the lowered first derivative, at 1e-5 rad
    xi = _point(1e-5, seed=5, n=6)
    D = L.exp_se3(XI).diff(XI[4])
    h = 1e-6
    plus, minus = xi.copy(), xi.copy()
    plus[4] += h
    minus[4] -= h
    fd = (num.exp_se3(plus) - num.exp_se3(minus)) / (2 * h)
    np.testing.assert_allclose(_lowered_numpy(D, XI, xi), fd, atol=1e-9)


def test_c_text_of_an_angle_function_is_a_branch_between_series_and_closed_form():
    text = c_code(L.a2_sq(sp.Symbol("s", positive=True)))
    assert "?" in text and "sin(" in text and "s < 1.0" in text


def test_closed_forms_are_the_stated_ones():
    s = sp.Symbol("s", positive=True)
    t = sp.Symbol("t", positive=True)
    expect = {L.sinc_sq: sp.sin(t) / t, L.a1_sq: (1 - sp.cos(t)) / t**2, L.a2_sq: (t - sp.sin(t)) / t**3,
              L.a3_sq: (t**2 + 2 * sp.cos(t) - 2) / (2 * t**4),
              L.a4_sq: (2 * t - 3 * sp.sin(t) + t * sp.cos(t)) / (2 * t**5)}
    for fn, closed in expect.items():
        assert sp.simplify(fn(s).closed().subs(s, t**2) - closed) == 0
        # the series is the Taylor expansion of the closed form (first 8 terms)
        taylor = sp.series(closed, t, 0, 16).removeO()
        assert sp.expand(fn(s).series().subs(s, t**2) - taylor).as_poly(t).degree() >= 16
        for x in (0.2, 0.9, 1.5):
            exact = closed.subs(t, sp.sqrt(sp.nsimplify(x))).evalf(40)   # the closed form cancels: 40 digits
            assert math.isclose(float(fn(sp.Float(x))), float(exact), rel_tol=1e-15)


def test_frenet_frame_of_a_helix():
    a = sp.Symbol("a", real=True)
    r, c = sp.symbols("r c", positive=True)
    curve = sp.Matrix([r * sp.cos(a), r * sp.sin(a), c * a])
    fr = L.frenet_serret(curve, a)
    assert sp.simplify(fr.curvature - r / (r**2 + c**2)) == 0
    assert sp.simplify(fr.torsion - c / (r**2 + c**2)) == 0
    assert sp.simplify(fr.speed - sp.sqrt(r**2 + c**2)) == 0
    assert sp.simplify(fr.R.T * fr.R - sp.eye(3)) == sp.zeros(3, 3)
    assert sp.simplify(fr.R.det()) == 1
    # R' = R hat3(f0_w), u0' = R f0_u (seed 001, slides 6 and 9)
    assert sp.simplify(fr.R.diff(a) - fr.R * L.hat3(fr.twist[3:, 0])) == sp.zeros(3, 3)
    assert sp.simplify(curve.diff(a) - fr.R * fr.twist[:3, 0]) == sp.zeros(3, 1)


def test_frenet_frame_of_a_circle_and_a_straight_line():
    a = sp.Symbol("a", real=True)
    r = sp.Symbol("r", positive=True)
    circle = sp.Matrix([r * sp.cos(a / r), r * sp.sin(a / r), 0])   # seed 001, slide 21: arc length a
    fr = L.frenet_serret(circle, a)
    assert sp.simplify(fr.curvature - 1 / r) == 0 and fr.torsion == 0 and fr.speed == 1
    assert sp.simplify(fr.n + circle / r) == sp.zeros(3, 1)           # towards the centre
    assert fr.b == sp.Matrix([0, 0, 1])
    assert fr.twist == sp.Matrix([1, 0, 0, 0, 0, 1 / r])              # f0 = [e1; e3/r] (slide 22)
    with pytest.raises(ValueError, match="straight"):
        L.frenet_serret(sp.Matrix([a, 2 * a, 0]), a)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_a_compiled_kernel_of_the_exponential_and_its_jacobian_is_exact_at_and_near_zero(backend):
    # a lumped model whose outputs are entries of exp(hat w) and J_l(w) and whose potential holds them
    # (so the residual differentiates the angle functions): C through the real pipeline (lower, CSE, print)
    from mechgen import Model, Param, compile as build

    model = Model("exp_probe", file=None)
    model.params(Param("k", 1.0, "N m"))
    model.coordinates("w0", "w1", "w2")

    @model.potential
    def potential(q, p):
        return p.k * (3 - L.exp_so3([q.w0, q.w1, q.w2]).trace())   # tr R = 1 + 2 cos t: V = 2 k (1 - cos t)

    def entry(fn, i, j):
        return lambda q: fn([q.w0, q.w1, q.w2])[i, j]

    for i in range(3):
        for j in range(3):
            model.output(f"R{i}{j}", entry(L.exp_so3, i, j))
            model.output(f"J{i}{j}", entry(L.jac_left_so3, i, j))
    system = build(model, backend=backend, kernels={"outputs", "linear", "residual"})
    for theta in (0.0, 1e-300, 1e-9, 0.3, 0.999999, 1.000001, 2.0):
        w = _point(theta, seed=7)
        out = system.outputs(w)
        R = np.array([[out[f"R{i}{j}"] for j in range(3)] for i in range(3)])
        J = np.array([[out[f"J{i}{j}"] for j in range(3)] for i in range(3)])
        np.testing.assert_allclose(R, num.exp_so3(w), rtol=0, atol=2e-15)
        np.testing.assert_allclose(J, num.jac_left_so3(w), rtol=0, atol=2e-15)
        # V = 2 k (1 - cos t), t = |w|: its Hessian is 2 k I at w = 0 (k = 1), finite everywhere
        K = system.linear(w)["K"]
        assert np.all(np.isfinite(K))
        if theta < 1e-8:
            np.testing.assert_allclose(K, 2.0 * np.eye(3), rtol=0, atol=1e-15)
        elif theta > 0.1:   # grad V = 2 k sinc(t) w: Hessian 2 k (sinc I + (t cos t - sin t)/t^3 w w^T)
            t = theta
            ref = 2.0 * (math.sin(t) / t * np.eye(3) + (t * math.cos(t) - math.sin(t)) / t**3 * np.outer(w, w))
            np.testing.assert_allclose(K, ref, rtol=0, atol=1e-14)
