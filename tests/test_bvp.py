"""Two-point BVP solvers (mechgen.runtime.steady.bvp) against closed forms and literature values.

References:
* Bratu problem y'' + lam e^y = 0, y(0) = y(1) = 0: the closed form
  y = -2 ln(cosh((x - 1/2) theta/2) / cosh(theta/4)), theta = sqrt(2 lam) cosh(theta/4)
  (two solutions for lam < lam_c = 3.513830719, where (theta/4) tanh(theta/4) = 1);
  J. P. Boyd, Appl. Math. Comput. 143 (2003) 189-200; A. Mohsen, Comput. Math. Appl. 68
  (2014) 1121-1125 (lam_c = 3.513830719).
* y'' + p y = 0, y(0) = y(1) = 0, y'(0) = 1: the first Dirichlet eigenvalue p = pi^2,
  y = sin(pi s)/pi.
* Troesch's problem y'' = lam sinh(lam y), y(0) = 0, y(1) = 1: y'(0) = 4.575046140e-2 at
  lam = 5 (M. R. Scott, in Numerical Solutions of Boundary Value Problems for ODEs,
  Academic Press 1975; tabulated again by S.-H. Chang, J. Comput. Appl. Math. 234 (2010)
  3043-3047). Single shooting from the straight line blows up before s = 1.
* y'' = mu^2 y, y(0) = y(1) = 1: y = cosh(mu (s - 1/2)) / cosh(mu/2); for mu = 40 the
  shooting sensitivity is e^40 and single shooting cannot reach the tolerance.
"""
import time

import numpy as np
import pytest
from scipy.optimize import brentq

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.steady.bvp import BVP, check_jacobians, collocate, multiple_shoot, on_unit_interval, shoot
from mechgen.runtime.steady.collocation import DiscreteBVP


# ----------------------------------------------------------------------------- problems
def bratu(vectorized=True):
    z = np.zeros_like

    def f(s, y, p):
        return np.array([y[1], -p[0] * np.exp(y[0])])

    def f_y(s, y, p):
        return np.array([[z(y[0]), 1 + z(y[0])], [-p[0] * np.exp(y[0]), z(y[0])]])

    def f_p(s, y, p):
        return np.array([[z(y[0])], [-np.exp(y[0])]])

    return BVP(f, f_y, lambda ya, yb, p: np.array([ya[0], yb[0]]),
               lambda ya, yb, p: np.array([[1.0, 0.0], [0.0, 0.0]]),
               lambda ya, yb, p: np.array([[0.0, 0.0], [1.0, 0.0]]), (0.0, 1.0), 2, 1, f_p,
               lambda ya, yb, p: np.zeros((2, 1)), vectorized=vectorized, name="bratu")


def bratu_theta(lam, upper):
    """theta = sqrt(2 lam) cosh(theta/4) on the lower or upper branch (closed form)."""
    theta_c = 4 * brentq(lambda z: z * np.tanh(z) - 1, 0.5, 2.0, xtol=1e-15)
    eq = lambda th: th - np.sqrt(2 * lam) * np.cosh(th / 4)
    return brentq(eq, theta_c, 60.0, xtol=1e-15) if upper else brentq(eq, 1e-12, theta_c, xtol=1e-15)


def bratu_exact(s, theta):
    return np.vstack([-2 * np.log(np.cosh((s - 0.5) * theta / 2) / np.cosh(theta / 4)),
                      -theta * np.tanh((s - 0.5) * theta / 2)])


def eigen_problem():
    z = np.zeros_like
    return BVP(lambda s, y, p: np.array([y[1], -p[0] * y[0]]),
               lambda s, y, p: np.array([[z(y[0]), 1 + z(y[0])], [-p[0] + z(y[0]), z(y[0])]]),
               lambda ya, yb, p: np.array([ya[0], yb[0], ya[1] - 1.0]),
               lambda ya, yb, p: np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0]]),
               lambda ya, yb, p: np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]]), (0.0, 1.0), 2, 1,
               lambda s, y, p: np.array([[z(y[0])], [-y[0]]]), lambda ya, yb, p: np.zeros((3, 1)),
               unknown=(0,), vectorized=True, name="eigen")


def troesch():
    z = np.zeros_like
    return BVP(lambda s, y, p: np.array([y[1], p[0] * np.sinh(p[0] * y[0])]),
               lambda s, y, p: np.array([[z(y[0]), 1 + z(y[0])], [p[0] ** 2 * np.cosh(p[0] * y[0]), z(y[0])]]),
               lambda ya, yb, p: np.array([ya[0], yb[0] - 1.0]),
               lambda ya, yb, p: np.array([[1.0, 0.0], [0.0, 0.0]]),
               lambda ya, yb, p: np.array([[0.0, 0.0], [1.0, 0.0]]), (0.0, 1.0), 2, 1,
               lambda s, y, p: np.array([[z(y[0])], [np.sinh(p[0] * y[0]) + p[0] * y[0] * np.cosh(p[0] * y[0])]]),
               lambda ya, yb, p: np.zeros((2, 1)), vectorized=True, name="troesch")


S = np.linspace(0.0, 1.0, 21)
MESH = np.linspace(0.0, 1.0, 11)


def _bratu_guess(upper):
    amp = 4.0 if upper else 0.1
    return np.vstack([amp * np.sin(np.pi * MESH), amp * np.pi * np.cos(np.pi * MESH)])


# ----------------------------------------------------------------------------- Bratu, both solutions
@pytest.mark.parametrize("upper", [False, True])
@pytest.mark.parametrize("method", ["shoot", "multiple_shoot", "collocate"])
def test_bratu_both_solutions_match_closed_form(method, upper):
    prob = bratu()
    theta = bratu_theta(1.0, upper)
    if method == "shoot":
        slope = theta * np.tanh(theta / 4) * (1.1 if upper else 0.5)   # a 10 % / 50 % wrong initial slope
        res = shoot(prob, [0.0, slope], p=[1.0])
    elif method == "multiple_shoot":
        res = multiple_shoot(prob, MESH, _bratu_guess(upper), p=[1.0], nodes=5)
    else:
        res = collocate(prob, MESH, _bratu_guess(upper), p=[1.0], tol=1e-9)
    err = np.max(np.abs(res(S) - bratu_exact(S, theta)))
    assert err < 1e-8, (method, upper, err)
    assert res.p[0] == 1.0 and res.residual_norm < 1e-8 and res.iterations >= 1
    assert res.y.shape == (2, res.s.size) and res(0.5).shape == (2,)


def test_bratu_non_vectorized_and_radau_agree():
    vec = bratu(vectorized=True)
    loop = bratu(vectorized=False)
    theta = bratu_theta(1.0, False)
    ref = bratu_exact(S, theta)
    for res in (shoot(loop, [0.0, 0.3], p=[1.0]),
                shoot(vec, [0.0, 0.3], p=[1.0], ivp_method="Radau", rtol_ivp=1e-11),
                multiple_shoot(loop, MESH, _bratu_guess(False), p=[1.0], nodes=[0.0, 0.3, 0.5, 1.0]),
                collocate(loop, MESH, _bratu_guess(False), p=[1.0], tol=1e-9)):
        assert np.max(np.abs(res(S) - ref)) < 1e-8, res.method


# ----------------------------------------------------------------------------- unknown parameter
@pytest.mark.parametrize("method", ["shoot", "multiple_shoot", "collocate"])
def test_eigenvalue_as_unknown_parameter(method):
    prob = eigen_problem()
    guess = np.vstack([np.sin(3 * MESH) / 3, np.cos(3 * MESH)])
    if method == "shoot":
        res = shoot(prob, [0.0, 1.0], p=[7.0], rtol_ivp=1e-12)
    elif method == "multiple_shoot":
        res = multiple_shoot(prob, MESH, guess, p=[7.0], nodes=4, rtol_ivp=1e-12)
    else:
        res = collocate(prob, MESH, guess, p=[7.0], tol=1e-10)
    assert abs(res.p[0] - np.pi ** 2) < 1e-10, res.p[0] - np.pi ** 2
    assert np.max(np.abs(res(S)[0] - np.sin(np.pi * S) / np.pi)) < 1e-9


def test_free_length_on_unit_interval():
    """y'' = -y, y(0) = 0, y'(0) = 1, y'(L) = 0 with L unknown: L = pi/2 (y = sin s)."""
    base = BVP(lambda s, y, p: np.array([y[1], -y[0]]),
               lambda s, y, p: np.array([[0.0, 1.0], [-1.0, 0.0]]),
               lambda ya, yb, p: np.array([ya[0], ya[1] - 1.0, yb[1]]),
               lambda ya, yb, p: np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]),
               lambda ya, yb, p: np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 1.0]]), (0.0, 1.0), 2, 1,
               lambda s, y, p: np.zeros((2, 1)), lambda ya, yb, p: np.zeros((3, 1)), unknown=(0,))
    with pytest.raises(InputError):
        on_unit_interval(base, 0)                     # s-dependence not declared
    prob = on_unit_interval(base, 0, autonomous=True)
    res = shoot(prob, [0.0, 1.0], p=[1.2], rtol_ivp=1e-12)
    assert abs(res.p[0] - np.pi / 2) < 1e-10
    sig = np.linspace(0, 1, 9)
    assert np.max(np.abs(res(sig)[0] - np.sin(res.p[0] * sig))) < 1e-10
    ms = multiple_shoot(prob, sig, np.vstack([sig, np.ones_like(sig)]), p=[1.2], nodes=3)
    assert abs(ms.p[0] - np.pi / 2) < 1e-10


# ----------------------------------------------------------------------------- hard cases
def test_troesch_single_shooting_fails_multiple_shooting_converges():
    prob = troesch()
    line = np.vstack([MESH, np.ones_like(MESH)])             # the straight line y = s
    t0 = time.perf_counter()
    with pytest.raises(ConvergenceError, match="single shooting.*initial guess.*multiple shooting"):
        shoot(prob, [0.0, 1.0], p=[5.0])
    with pytest.raises(ConvergenceError, match="single shooting"):
        shoot(prob, [0.0, 0.1], p=[5.0])
    assert time.perf_counter() - t0 < 5.0
    ms = multiple_shoot(prob, MESH, line, p=[5.0], nodes=20)
    col = collocate(prob, MESH, line, p=[5.0], tol=1e-9)
    assert np.max(np.abs(ms(S) - col(S))) < 1e-6
    assert abs(ms.y[1, 0] - 4.575046140e-2) < 1e-10          # literature value of y'(0)
    assert abs(col.y[1, 0] - 4.575046140e-2) < 1e-9


def test_ill_conditioned_linear_problem():
    mu = 40.0
    prob = BVP(lambda s, y, p: np.array([y[1], mu ** 2 * y[0]]),
               lambda s, y, p: np.array([[0.0, 1.0], [mu ** 2, 0.0]]),
               lambda ya, yb, p: np.array([ya[0] - 1.0, yb[0] - 1.0]),
               lambda ya, yb, p: np.array([[1.0, 0.0], [0.0, 0.0]]),
               lambda ya, yb, p: np.array([[0.0, 0.0], [1.0, 0.0]]), (0.0, 1.0), 2, name="linear")
    exact = np.cosh(mu * (S - 0.5)) / np.cosh(mu / 2)
    t0 = time.perf_counter()
    with pytest.raises(ConvergenceError, match="single shooting.*residual norm"):
        shoot(prob, [1.0, -mu * np.tanh(mu / 2)])          # even from the exact initial slope
    assert time.perf_counter() - t0 < 5.0
    ms = multiple_shoot(prob, MESH, np.vstack([np.ones_like(MESH), np.zeros_like(MESH)]), nodes=20)
    assert np.max(np.abs(ms(S)[0] - exact)) < 1e-8


def test_newton_iteration_limit_message():
    with pytest.raises(ConvergenceError, match=r"no convergence in 1 Newton iterations; residual norm"):
        shoot(bratu(), [0.0, 3.0], p=[1.0], max_iter=1)


# ----------------------------------------------------------------------------- discretisation
@pytest.mark.parametrize("method", ["collocation", "multiple_shooting"])
def test_discretisation_residual_and_jacobian(method):
    """F vanishes at the (discretised) solution, and F_u, F_lam match differences of F."""
    prob = bratu()
    theta = bratu_theta(1.0, False)
    disc = DiscreteBVP(prob, 0, [1.0], 40 if method == "collocation" else 4, method=method)
    u = disc.pack(bratu_exact(disc.mesh, theta))
    assert np.linalg.norm(disc.F(u, 1.0)) < (1e-5 if method == "collocation" else 1e-9)
    rng = np.random.default_rng(1)
    u1, lam1 = u + 0.01 * rng.standard_normal(u.size), 1.1
    J = disc.F_u(u1, lam1).toarray()
    h = 1e-6
    cols = [(disc.F(u1 + h * e, lam1) - disc.F(u1 - h * e, lam1)) / (2 * h) for e in np.eye(u.size)]
    assert np.max(np.abs(J - np.array(cols).T)) < 1e-5 * max(1.0, np.abs(J).max())
    Fl = (disc.F(u1, lam1 + h) - disc.F(u1, lam1 - h)) / (2 * h)
    assert np.max(np.abs(disc.F_lam(u1, lam1) - Fl)) < 1e-5
    res = disc.to_result(u, 1.0)
    assert np.max(np.abs(res(S) - bratu_exact(S, theta))) < 1e-4


def test_check_jacobians_flags_a_wrong_jacobian():
    prob = bratu()
    assert max(check_jacobians(prob, 0.2, [0.3, 0.1], [1.0]).values()) < 1e-8
    bad = BVP(prob.f, lambda s, y, p: np.array([[0.0, 1.0], [-p[0], 0.0]]), prob.g, prob.g_ya, prob.g_yb,
              (0.0, 1.0), 2, 1, prob.f_p, prob.g_p)
    assert check_jacobians(bad, 0.2, [0.3, 0.1], [1.0])["f_y"] > 0.1


# ----------------------------------------------------------------------------- bad input
def test_bad_input_raises_input_error():
    prob = bratu()
    ok = dict(f=prob.f, f_y=prob.f_y, g=prob.g, g_ya=prob.g_ya, g_yb=prob.g_yb, interval=(0.0, 1.0), n=2, n_p=1,
              f_p=prob.f_p, g_p=prob.g_p, vectorized=True)
    with pytest.raises(InputError, match="interval"):
        BVP(**{**ok, "interval": (1.0, 0.0)})
    with pytest.raises(InputError, match="unknown"):
        BVP(**{**ok, "unknown": (3,)})
    with pytest.raises(InputError, match="f_p"):
        BVP(**{**ok, "f_p": None})
    with pytest.raises(InputError, match="n"):
        BVP(**{**ok, "n": 0})
    wrong_fy = BVP(**{**ok, "f_y": lambda s, y, p: np.zeros((3, 3, np.size(s)))})
    with pytest.raises(InputError, match="f_y returned shape"):
        shoot(wrong_fy, [0.0, 1.0], p=[1.0])
    three_bcs = BVP(**{**ok, "g": lambda ya, yb, p: np.array([ya[0], yb[0], ya[1]])})
    with pytest.raises(InputError, match="g returned shape"):
        collocate(three_bcs, MESH, _bratu_guess(False), p=[1.0])
    with pytest.raises(InputError, match="guess"):
        shoot(prob, [0.0, 1.0, 2.0], p=[1.0])
    with pytest.raises(InputError, match="p"):
        shoot(prob, [0.0, 1.0])
    with pytest.raises(InputError, match="nodes"):
        multiple_shoot(prob, MESH, _bratu_guess(False), p=[1.0], nodes=[0.0, 0.7, 0.5, 1.0])
    with pytest.raises(InputError, match="guess"):
        multiple_shoot(prob, MESH, _bratu_guess(False)[:, :5], p=[1.0])
    with pytest.raises(InputError, match="mesh"):
        collocate(prob, MESH * 0.5, _bratu_guess(False), p=[1.0])
    with pytest.raises(InputError, match="integrator"):
        shoot(prob, [0.0, 1.0], p=[1.0], ivp_method="Euler")
    with pytest.raises(InputError, match="lam_index"):
        DiscreteBVP(eigen_problem(), 0, [7.0], 10)              # the unknown parameter cannot be lam


def test_evaluation_budget_stops_a_costly_solve():
    with pytest.raises(ConvergenceError, match="budget of right-hand side evaluations"):
        multiple_shoot(troesch(), MESH, np.vstack([MESH, np.ones_like(MESH)]), p=[5.0], nodes=20, max_nfev=2000)
