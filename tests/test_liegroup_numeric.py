"""Numeric so(3)/se(3) maps (mechgen.runtime.rods.liegroup) against their defining series.

References: exp(X) = sum X^k/k! (scipy.linalg.expm, Higham's scaling and squaring); J_l(xi) = sum ad^k/(k+1)!,
summed here to convergence; ad_xi eta = vee([hat xi, hat eta]); Ad_H = vee(H hat(xi) H^-1). Angles from 1e-9
(series branch) through 1 (the switch) to pi - 1e-7 (log near pi) and 20 rad (many turns)."""
import numpy as np
import pytest
from scipy.linalg import expm

from mechgen.runtime.rods import liegroup as lg

ANGLES = [0.0, 1e-9, 1e-4, 0.3, 0.999999, 1.000001, 2.5, np.pi - 1e-7, 20.0]


def _twist(rng, angle):
    w = rng.normal(size=3)
    w *= angle / np.linalg.norm(w)
    return np.concatenate([rng.normal(size=3), w])



def _jac_reference(xi):
    ad = lg.ad6(xi)
    out, term, fact = np.zeros((6, 6)), np.eye(6), 1.0
    for k in range(80):
        fact *= k + 1
        out += term / fact
        term = term @ ad
    return out


@pytest.mark.parametrize("angle", ANGLES)
def test_exp_se3_matches_expm(angle):
    rng = np.random.default_rng(1)
    xi = _twist(rng, angle)
    H = lg.exp_se3(xi)
    assert np.allclose(H, expm(lg.hat6(xi)), rtol=0, atol=1e-13 * max(1.0, angle))
    assert lg.orthonormality_error(H[:3, :3]) < 5e-15


@pytest.mark.parametrize("angle", [a for a in ANGLES if a < 8])
def test_left_jacobian_matches_series(angle):
    rng = np.random.default_rng(2)
    xi = _twist(rng, angle)
    ref = _jac_reference(xi)
    assert np.allclose(lg.jac_left_se3(xi), ref, rtol=0, atol=2e-14)
    assert np.allclose(lg.jac_right_se3(xi), _jac_reference(-xi), rtol=0, atol=2e-14)


@pytest.mark.parametrize("angle", [0.0, 1e-8, 0.5, 2.0, 3.0, np.pi - 1e-7])
def test_log_inverts_exp(angle):
    rng = np.random.default_rng(3)
    xi = _twist(rng, angle)
    back = lg.log_se3(lg.exp_se3(xi))
    assert np.allclose(back, xi, rtol=0, atol=1e-8 if angle > 3.1 else 1e-13)


def test_so3_jacobian_inverse():
    rng = np.random.default_rng(4)
    for angle in [0.0, 1e-6, 0.9, 1.1, 3.0, 6.0]:
        w = _twist(rng, angle)[3:]
        assert np.allclose(lg.jac_left_so3_inv(w) @ lg.jac_left_so3(w), np.eye(3), atol=1e-13)


def test_adjoint_identities():
    rng = np.random.default_rng(5)
    xi, eta = rng.normal(size=6), rng.normal(size=6)
    A, B = lg.hat6(xi), lg.hat6(eta)
    assert np.allclose(lg.ad6(xi) @ eta, lg.vee6(A @ B - B @ A), atol=1e-14)
    H = lg.exp_se3(rng.normal(size=6))
    assert np.allclose(lg.Ad(H) @ eta, lg.vee6(H @ B @ lg.inverse(H)), atol=1e-13)
    assert np.allclose(lg.inverse(H) @ H, np.eye(4), atol=1e-14)
    assert np.allclose(lg.coad6(xi), lg.ad6(xi).T)
    # d/dt exp(t xi) = exp(t xi) hat(xi) and the Jacobian definition by a finite difference
    d = 1e-7 * rng.normal(size=6)
    lhs = lg.exp_se3(xi + d)
    rhs = lg.exp_se3(lg.jac_left_se3(xi) @ d) @ lg.exp_se3(xi)
    assert np.abs(lhs - rhs).max() < 1e-12


def test_batched_shapes():
    rng = np.random.default_rng(6)
    xi = rng.normal(size=(5, 4, 6))
    H = lg.exp_se3(xi)
    assert H.shape == (5, 4, 4, 4)
    assert np.allclose(H[2, 3], lg.exp_se3(xi[2, 3]))
    assert lg.jac_left_se3(xi).shape == (5, 4, 6, 6)
