"""Gauss-Legendre collocation for continuation (mechgen.runtime.steady.collocation), the continuation's own-solver
protocol, and the fast stability path for conservative gyroscopic systems.

References: the Bratu closed form and its turning point lam_c = 3.513830719 (J. P. Boyd, Appl. Math. Comput.
143 (2003) 189-200), the Dirichlet eigenvalue pi^2 (see test_bvp.py); the order 2s of s-stage Gauss
collocation at the nodes (E. Hairer, G. Wanner, Solving ODEs II, section IV.5) as a convergence study;
central differences for the Jacobians; dense linear algebra (numpy) for the condensed bordered solver and
scipy's QZ-free eig of the first-order companion matrix for the gyroscopic eigenvalues.
"""
import numpy as np
import pytest

from mechgen.runtime.steady.bvp import collocate
from mechgen.runtime.steady.collocation import DiscreteBVP
from mechgen.runtime.steady.continuation import continue_bvp, point_at
from mechgen.runtime.linear.stability import conservative_gyroscopic, stability
from test_bvp import MESH, S, _bratu_guess, bratu, bratu_exact, bratu_theta
from test_continuation import LAM_C


def _gauss(M, stages, lam=1.0):
    return DiscreteBVP(bratu(), 0, [lam], M, method="gauss", stages=stages)


@pytest.mark.parametrize("stages", [2, 3, 4])
def test_gauss_jacobian_and_bordered_solver(stages):
    """F_u and F_lam against central differences of F; the condensed bordered solve against a dense solve of
    the uncondensed matrix (stages included)."""
    disc = _gauss(6, stages)
    u = disc.pack(bratu_exact(disc.mesh, bratu_theta(1.0, False)))
    rng = np.random.default_rng(stages)
    u1, lam1 = u + 0.01 * rng.standard_normal(u.size), 1.1
    J = disc.F_u(u1, lam1).toarray()
    h = 1e-6
    cols = np.array([(disc.F(u1 + h * e, lam1) - disc.F(u1 - h * e, lam1)) / (2 * h) for e in np.eye(u.size)]).T
    assert np.max(np.abs(J - cols)) < 1e-7 * max(1.0, np.abs(J).max())
    Fl = (disc.F(u1, lam1 + h) - disc.F(u1, lam1 - h)) / (2 * h)
    assert np.max(np.abs(disc.F_lam(u1, lam1) - Fl)) < 1e-7
    _, blocks, F_lam = disc.evaluate(u1, lam1)
    row, rhs = rng.standard_normal(u.size + 1), rng.standard_normal(u.size + 1)
    x = disc.bordered(blocks, F_lam, row)(rhs)
    dense = np.block([[J, F_lam[:, None]], [row[None, :]]])
    np.testing.assert_allclose(x, np.linalg.solve(dense, rhs), rtol=0, atol=1e-10 * np.abs(x).max())


@pytest.mark.parametrize("stages", [2, 3])
def test_gauss_collocation_has_order_2s_at_the_nodes(stages):
    """Convergence study on the lower Bratu solution at lam = 1: the node error falls by 2^(2s) when M doubles,
    and the collocation polynomial between the nodes is accurate to order s + 1."""
    theta = bratu_theta(1.0, False)
    start = collocate(bratu(), MESH, _bratu_guess(False), p=[1.0], tol=1e-10)
    node_err, dense_err = [], []
    for M in (4, 8):
        br = continue_bvp(bratu(), start, 0, method="gauss", stages=stages, mesh=M, ds=0.1, max_points=2,
                          lam_max=1.5)
        res = br.system.to_result(br.u[0], br.lam[0])
        assert res.p[0] == 1.0
        node_err.append(np.max(np.abs(res.y - bratu_exact(res.s, theta))))
        dense_err.append(np.max(np.abs(res(S) - bratu_exact(S, theta))))
    assert 2 ** (2 * stages) / 1.5 < node_err[0] / node_err[1] < 2 ** (2 * stages) * 1.5
    assert dense_err[1] < dense_err[0] / 2 ** stages


def test_gauss_continuation_passes_the_bratu_fold():
    """Round the turning point with 4-stage Gauss collocation on 20 intervals (S holds nodes only: the
    superconvergent values): the fold at lam_c, the upper solution at lam = 2 (closed form); point_at
    reads the lower solution at lam = 3 off the branch (the first segment through 3)."""
    start = collocate(bratu(), MESH, _bratu_guess(False), p=[3.0], tol=1e-9)
    br = continue_bvp(bratu(), start, 0, method="gauss", stages=4, mesh=20, ds=0.5, ds_max=2.0, lam_min=2.0,
                      lam_max=4.0, max_points=80)
    assert br.status == "lam_min" and br.lam[-1] == 2.0
    assert len(br.folds) == 1 and abs(br.folds[0].lam - LAM_C) < 1e-10
    lower = br.system.to_result(point_at(br, 3.0), 3.0)
    assert np.max(np.abs(lower(S) - bratu_exact(S, bratu_theta(3.0, upper=False)))) < 1e-10
    end = br.system.to_result(br.u[-1], br.lam[-1])
    assert np.max(np.abs(end(S) - bratu_exact(S, bratu_theta(2.0, upper=True)))) < 1e-8


def test_f_p_columns_on_request():
    """A problem whose f_p takes ``cols`` is asked for the continuation's columns only; the values equal the
    full f_p's columns."""
    full = bratu()
    asked = []

    def f_p(s, y, p, cols=None):
        asked.append(cols)
        out = full.f_p(s, y, p)
        return out if cols is None else out[:, list(cols)]

    prob = type(full)(full.f, full.f_y, full.g, full.g_ya, full.g_yb, (0.0, 1.0), 2, 1, f_p, full.g_p,
                      vectorized=True)
    s, Y = np.linspace(0, 1, 5), np.ones((2, 5))
    np.testing.assert_array_equal(prob.f_pv(s, Y, [2.0], cols=[0]), full.f_pv(s, Y, [2.0]))
    assert asked == [[0]]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_conservative_gyroscopic_spectrum_equals_the_general_eigenproblem(seed):
    """M, K > 0 and C skew: the Hermitian path's eigenvalues (purely imaginary) equal those of the first-order
    companion matrix (numpy eig) to rounding; verdict stable. Damping (C not skew) or K indefinite take the
    general path."""
    rng = np.random.default_rng(seed)
    n = 12
    A, B, G = rng.random((3, n, n))
    M, K, C = A @ A.T + n * np.eye(n), B @ B.T + 0.1 * np.eye(n), 5 * (G - G.T)
    fast = conservative_gyroscopic(M, C, K)
    Minv = np.linalg.inv(M)
    general = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]]))
    np.testing.assert_allclose(np.sort(fast.imag), np.sort(general.imag), atol=1e-10 * np.abs(general).max())
    assert np.max(np.abs(general.real)) < 1e-9 * np.abs(general).max() and np.all(fast.real == 0)
    assert stability(M, C, K).verdict == "stable"
    assert conservative_gyroscopic(M, C + 0.01 * np.eye(n), K) is None
    assert conservative_gyroscopic(M, C, K - 2 * np.abs(np.linalg.eigvalsh(K)).max() * np.eye(n)) is None
