"""The ballooning string's branch on the fast path: Gauss collocation, parameter derivatives of the steady
form by the implicit function theorem, stability along the branch.

Independent reference: ``benchmarks/balloon_handwritten.py`` (hand-written scipy, tension-vector form; its
``pe_minimum`` locates p_e,min = 14.70509 at lambda0 = -0.08853, balloon_notes.md section 4) and central
differences of the generated right-hand side.
"""
from __future__ import annotations

import numpy as np
import pytest

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.runtime.steady.branch_stability import stability_along
from mechgen.runtime.steady.continuation import continue_bvp, minimize_along_branch, point_at
from mechgen.runtime.steady.steady_bvp import solve_steady, steady_bvp
from mechgen.symbolic.specialize import specialize
from test_balloon import H, balloon, l0_of, reference, tension_vector


def test_parameter_derivatives_of_the_steady_form_match_central_differences():
    """d f / d p at a batch of points (d u_ss / d p = -H^-1 d r / d p at the actual u_ss, plus f / L for the
    domain length L, which also moves the points s = L sigma) against central differences of f in p, for
    all parameters (lambda0, beta and L free) and for a requested column."""
    model = models.get("balloon_string")
    spec = specialize(model, {"law": "neo_hookean", "h": H}, free=("lambda0", "beta", "L"))
    system = compile_model(model, spec, kernels={"bvp_residual", "bvp_tangent", "bvp_outputs"}, backend="c")[0]
    system = system.with_params(lambda0=-0.2, beta=100.0, L=1.3)
    bvp = steady_bvp(system)
    assert bvp.length_index == bvp.params.index("L")
    prob, p = bvp.problem, bvp.start
    rng = np.random.default_rng(3)
    sigma = np.linspace(0.0, 1.0, 9)
    y = np.vstack([rng.random((3, 9)), rng.random((3, 9)) + np.array([[1.0], [0.1], [11.0]])])
    fd = []
    for j in range(len(p)):
        step = 1e-6 * max(abs(p[j]), 1e-3)
        e = np.zeros(len(p))
        e[j] = step
        fd.append((prob.f(sigma, y, p + e) - prob.f(sigma, y, p - e)) / (2 * step))
    fd = np.stack(fd, axis=1)
    scale = np.abs(fd).max()
    assert np.abs(prob.f_pv(sigma, y, p) - fd).max() < 1e-7 * scale
    for name in ("beta", "L"):
        j = bvp.params.index(name)
        assert np.abs(prob.f_pv(sigma, y, p, cols=[j])[:, 0] - fd[:, j]).max() < 1e-7 * scale


def test_gauss_branch_minimum_eyelet_tension_and_stability_against_the_reference():
    """4-stage Gauss collocation on 20 intervals from lambda0 = -0.3 past the minimum: p_e,min and its lambda0
    against the hand-written reference's pe_minimum (DOP853, rtol 1e-12); the single loops are stable
    (the paper's finding) and the Galerkin frequencies at lambda0 = -0.2 equal the reference's."""
    system = balloon("neo_hookean", -0.3)
    bvp = steady_bvp(system)
    start = solve_steady(bvp, method="collocation", modes={"x": [2.0]})
    branch = continue_bvp(bvp.problem, start, bvp.params.index("lambda0"), method="gauss", stages=4, mesh=20,
                          ds=0.05, ds_max=0.5, lam_max=0.0, max_points=100)
    assert branch.status == "lam_max"

    def p_e(u, lam):
        return bvp.outputs(branch.system.to_result(u, lam), np.array([0.0]))["tension"][0]

    best = minimize_along_branch(branch, p_e, kind="min")
    law = reference.Law("neo", 100.0)
    guess = reference.shoot(law, H, l0_of(-0.09), (7.2, 12.8))
    X = reference.pe_minimum(law, H, [guess[0], guess[1], l0_of(-0.09)])
    assert best.value == pytest.approx(np.hypot(X[0], X[1]), rel=1e-10)
    assert best.lam == pytest.approx(reference.lam0_of(X[2], H), abs=1e-6)
    verdicts = stability_along(system, bvp, branch)
    assert len(verdicts) == len(branch.lam) and {v.verdict for v in verdicts} == {"stable"}
    res = branch.system.to_result(point_at(branch, -0.2), -0.2)
    system = system.with_params(lambda0=-0.2)
    ours = stability_along(system, bvp, None, results=[res])[0]
    _, _, freqs = reference.stability(law, *tension_vector(bvp, res, -0.2), l0_of(-0.2), N=10)
    np.testing.assert_allclose(ours.frequencies[:20], freqs[:20], rtol=1e-9)
