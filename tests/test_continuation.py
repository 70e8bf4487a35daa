"""Pseudo-arclength continuation (mechgen.runtime.steady.continuation) against exact folds.

References:
* u^2 + lam^2 = 1: folds at lam = +-1, u = 0 (a circle).
* u^3 - u - lam = 0: folds where 3u^2 = 1, at u = -+1/sqrt(3), lam = +-2/(3 sqrt(3)).
* Bratu y'' + lam e^y = 0, y(0) = y(1) = 0: closed form y = -2 ln(cosh((x - 1/2) theta/2) /
  cosh(theta/4)), theta = sqrt(2 lam) cosh(theta/4); the turning point lam_c = 8 z^2/cosh^2 z
  with z tanh z = 1, lam_c = 3.513830719 (J. P. Boyd, Appl. Math. Comput. 143 (2003) 189-200;
  A. Mohsen, Comput. Math. Appl. 68 (2014) 1121-1125). Along the branch lam = theta^2 /
  (2 cosh^2(theta/4)) and y'(0) = theta tanh(theta/4).
"""
import numpy as np
import pytest
import scipy.sparse as sps
from scipy.optimize import brentq, minimize_scalar

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.steady.bvp import collocate
from mechgen.runtime.steady.continuation import ParametricEquations, continuation, continue_bvp, minimize_along_branch
from test_bvp import MESH, S, _bratu_guess, bratu, bratu_exact, bratu_theta

Z_C = brentq(lambda z: z * np.tanh(z) - 1, 0.5, 2.0, xtol=1e-15)
LAM_C = 8 * Z_C ** 2 / np.cosh(Z_C) ** 2


def test_closed_form_turning_point():
    assert abs(LAM_C - 3.513830719) < 1e-9


# ----------------------------------------------------------------------------- algebraic folds
CIRCLE = ParametricEquations(lambda u, lam: np.array([u[0] ** 2 + lam ** 2 - 1.0]),
                lambda u, lam: np.array([[2 * u[0]]]),
                lambda u, lam: np.array([2 * lam]), name="circle")


def test_circle_passes_both_folds():
    br = continuation(CIRCLE, [-1.0], 0.0, ds=0.1, ds_max=0.3, max_points=40)
    # the circle is a closed branch: it ends where it comes back to its start (arclength 2 pi), before max_points
    assert br.status == "closed" and len(br.lam) < 40 and br.arclength[-1] == pytest.approx(2 * np.pi, abs=0.3)
    assert np.max(np.abs(br.u[:, 0] ** 2 + br.lam ** 2 - 1)) < 1e-10
    assert len(br.folds) >= 2
    first, second = br.folds[:2]
    assert first.located and second.located
    assert abs(first.lam - 1.0) < 1e-12 and abs(first.u[0]) < 1e-7
    assert abs(second.lam + 1.0) < 1e-12 and abs(second.u[0]) < 1e-7
    assert np.all(np.abs(np.linalg.norm(br.tangents, axis=1) - 1) < 1e-12)
    assert np.all(np.diff(br.arclength) > 0)


def _cubic(sparse):
    """u = (a, b) with a = b and a^3 - a - lam = 0 (sparse Jacobian optional)."""
    def F_u(u, lam):
        J = np.array([[1.0, -1.0], [3 * u[0] ** 2 - 1, 0.0]])
        return sps.csc_matrix(J) if sparse else J
    return ParametricEquations(lambda u, lam: np.array([u[0] - u[1], u[0] ** 3 - u[0] - lam]), F_u,
                  lambda u, lam: np.array([0.0, -1.0]), name="cubic")


@pytest.mark.parametrize("sparse", [False, True])
def test_cubic_folds_end_on_bound_and_callback(sparse):
    seen = []
    br = continuation(_cubic(sparse), [-1.5, -1.5], -1.875, ds=0.05, ds_max=0.25, lam_max=2.0, max_points=500,
                      callback=lambda u, lam: seen.append(lam) or u[0] ** 3 - u[0] - lam)
    fold_lam = 2 / (3 * np.sqrt(3))
    assert [f.index < g.index for f, g in zip(br.folds, br.folds[1:])] == [True]
    (f1, f2) = br.folds
    assert abs(f1.lam - fold_lam) < 1e-12 and abs(f1.u[0] + 1 / np.sqrt(3)) < 1e-7
    assert abs(f2.lam + fold_lam) < 1e-12 and abs(f2.u[0] - 1 / np.sqrt(3)) < 1e-7
    assert br.status == "lam_max" and br.lam[-1] == 2.0
    root = brentq(lambda a: a ** 3 - a - 2, 1, 2, xtol=1e-15)
    assert abs(br.u[-1, 0] - root) < 1e-10
    assert len(br.data) == len(br.lam) == len(seen) and max(abs(v) for v in br.data) < 1e-10
    # decreasing direction: the branch leaves through lam_min with no fold
    down = continuation(_cubic(sparse), [-1.5, -1.5], -1.875, direction=-1, lam_min=-3.0)
    assert down.status == "lam_min" and down.lam[-1] == -3.0 and not down.folds


def test_stops_with_message_where_the_branch_ends():
    """u = sqrt(1 - lam) (NaN beyond lam = 1, singular F_lam at 1): stop below ds_min."""
    sqrt_sys = ParametricEquations(lambda u, lam: np.array([u[0] - np.sqrt(1 - lam)]), lambda u, lam: np.eye(1),
                      lambda u, lam: np.array([0.5 / np.sqrt(1 - lam)]))
    br = continuation(sqrt_sys, [1.0], 0.0, ds=0.1, ds_min=1e-6)
    assert br.status == "min_step" and "ds_min" in br.message
    assert 0.99 < br.lam[-1] <= 1.0


def test_start_off_branch_and_bad_input():
    with pytest.raises(ConvergenceError, match="start"):
        continuation(ParametricEquations(lambda u, lam: np.array([u[0] ** 2 + 1.0]),
                                         lambda u, lam: np.array([[2 * u[0]]]), lambda u, lam: np.array([0.0])),
                     [0.5], 0.0)
    with pytest.raises(InputError, match="F returned"):
        continuation(ParametricEquations(lambda u, lam: np.zeros(2), lambda u, lam: np.eye(1),
                                         lambda u, lam: np.zeros(1)), [0.0], 0.0)
    with pytest.raises(InputError, match="F_u"):
        continuation(ParametricEquations(CIRCLE.F, lambda u, lam: np.eye(2), CIRCLE.F_lam), [-1.0], 0.0)
    with pytest.raises(InputError):
        continuation(CIRCLE, [-1.0], 0.0, ds=-0.1)
    with pytest.raises(InputError):
        continuation(CIRCLE, [-1.0], 0.0, direction=0)
    with pytest.raises(InputError, match="outside"):
        continuation(CIRCLE, [-1.0], 0.0, lam_min=0.5)
    with pytest.raises(InputError, match="kind"):
        minimize_along_branch(continuation(CIRCLE, [-1.0], 0.0, max_points=5), lambda u, lam: lam, kind="both")


def test_extremum_of_an_output_along_the_circle():
    br = continuation(CIRCLE, [-1.0], 0.0, ds=0.1, ds_max=0.3, max_points=40)
    top = minimize_along_branch(br, lambda u, lam: u[0] + lam, gradient=lambda u, lam: (np.array([1.0]), 1.0),
                                kind="max")
    assert abs(top.value - np.sqrt(2)) < 1e-12 and abs(top.lam - 1 / np.sqrt(2)) < 1e-7
    low = minimize_along_branch(br, lambda u, lam: u[0] + lam)          # central differences along the branch
    assert abs(low.value + np.sqrt(2)) < 1e-10 and abs(low.lam + 1 / np.sqrt(2)) < 1e-5
    short = continuation(CIRCLE, [-1.0], 0.0, ds=0.1, max_points=5)       # lam increases monotonically
    with pytest.raises(ConvergenceError, match="end of the branch"):
        minimize_along_branch(short, lambda u, lam: lam)


# ----------------------------------------------------------------------------- Bratu
def _bratu_start(lam):
    return collocate(bratu(), MESH, _bratu_guess(False), p=[lam], tol=1e-9)


@pytest.mark.parametrize("method, mesh, fold_tol, point_tol", [("collocation", 100, 1e-6, 1e-6),
                                                                ("multiple_shooting", 4, 1e-8, 1e-8)])
def test_bratu_continuation_passes_the_fold(method, mesh, fold_tol, point_tol):
    """From the lower solution at lam = 3 round the turning point to the upper one at lam = 3."""
    br = continue_bvp(bratu(), _bratu_start(3.0), 0, method=method, mesh=mesh, ds=0.5, ds_max=2.0,
                      lam_min=3.0, lam_max=4.0, max_points=60)
    assert br.status == "lam_min" and br.lam[-1] == 3.0
    assert len(br.folds) == 1 and br.folds[0].located
    assert abs(br.folds[0].lam - LAM_C) < fold_tol
    assert np.all(br.lam <= LAM_C + 1e-9)
    end = br.system.to_result(br.u[-1], br.lam[-1])
    err = np.max(np.abs(end(S) - bratu_exact(S, bratu_theta(3.0, upper=True))))
    assert err < point_tol, err
    start = br.system.to_result(br.u[0], br.lam[0])
    assert np.max(np.abs(start(S) - bratu_exact(S, bratu_theta(3.0, upper=False)))) < point_tol


def test_extremum_of_a_bvp_output_and_stability_callback():
    """Maximise phi = lam - y'(0)/10 along the Bratu branch; reference from the closed form."""
    c = 0.1
    lam_of = lambda th: th ** 2 / (2 * np.cosh(th / 4) ** 2)
    phi_of = lambda th: lam_of(th) - c * th * np.tanh(th / 4)
    ref = -minimize_scalar(lambda th: -phi_of(th), bounds=(1.0, 4 * Z_C), method="bounded",
                           options={"xatol": 1e-12}).fun
    sizes = []
    br = continue_bvp(bratu(), _bratu_start(1.0), 0, mesh=100, ds=0.5, ds_max=2.0, lam_min=1.0, max_points=40,
                      callback=lambda u, lam: sizes.append(u.size) or float(np.max(u[0::2])))
    assert len(br.data) == len(br.lam) and set(sizes) == {202}
    phi, grad = br.system.output(lambda ya, yb, p: p[0] - c * ya[1],
                                 lambda ya, yb, p: (np.array([0.0, -c]), np.zeros(2), np.array([1.0])))
    top = minimize_along_branch(br, phi, gradient=grad, kind="max")
    assert abs(top.value - ref) < 1e-7, top.value - ref
    fd = minimize_along_branch(br, phi, kind="max")
    assert abs(fd.value - ref) < 1e-7


@pytest.mark.parametrize("method, mesh, tol, shape_tol", [("collocation", 60, 1e-6, 1e-6),
                                                          ("multiple_shooting", 3, 1e-9, 1e-9),
                                                          ("gauss", 10, 1e-9, 1e-7)])
def test_bvp_continuation_with_an_unknown_parameter(method, mesh, tol, shape_tol):
    """y'' + p0 y = 0, y(0) = y(1) = 0, y'(0) = lam = p1 with p0 unknown: p0 = pi^2 and
    y = lam sin(pi s)/pi all along the branch."""
    from test_bvp import eigen_problem
    base = eigen_problem()
    prob = type(base)(base.f, base.f_y, lambda ya, yb, p: np.array([ya[0], yb[0], ya[1] - p[1]]), base.g_ya,
                      base.g_yb, (0.0, 1.0), 2, 2,
                      lambda s, y, p: np.concatenate([base.f_p(s, y, p), np.zeros((2, 1) + np.shape(s))], axis=1),
                      lambda ya, yb, p: np.array([[0.0, 0.0], [0.0, 0.0], [0.0, -1.0]]), unknown=(0,),
                      vectorized=True)
    start = collocate(prob, MESH, np.vstack([np.sin(3 * MESH) / 3, np.cos(3 * MESH)]), p=[7.0, 1.0], tol=1e-10)
    br = continue_bvp(prob, start, 1, method=method, mesh=mesh, ds=0.2, lam_max=3.0, max_points=30)
    assert br.status == "lam_max" and br.lam[-1] == 3.0 and not br.folds
    for u, lam in zip(br.u, br.lam):
        res = br.system.to_result(u, lam)
        assert abs(res.p[0] - np.pi ** 2) < tol and res.p[1] == lam
        assert np.max(np.abs(res(S)[0] - lam * np.sin(np.pi * S) / np.pi)) < shape_tol
