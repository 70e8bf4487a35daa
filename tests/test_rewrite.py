"""Rewrites ahead of CSE (mechgen.codegen.rewrite): writes shared up to sign, Horner form in a linear form.

Each rewrite must leave the value unchanged (checked at random points against
the expression as derived), cost fewer operations, and be deterministic. The
accuracy of the rewritten FPU kernels is checked against 50-digit arithmetic.
"""
import mpmath as mp
import numpy as np
import pytest
import sympy as sp

from mechgen import models
from mechgen.codegen.rewrite import operation_count, horner, optimise, share_writes
from mechgen.pipeline import compile_model
from mechgen.symbolic.specialize import specialize

g0, g1, g2, g3, g4 = G = sp.symbols("g0:5", real=True)
LOCAL = set(G)
V_BOND = g2 * (g1 - g0) ** 2 / 2 + g3 * (g1 - g0) ** 3 / 3 + g4 * (g1 - g0) ** 4 / 4


def _values(assignments, exprs, point):
    """Numbers of ``exprs`` after evaluating the assignments in order at ``point``."""
    env = dict(point)
    for s, e in assignments:
        env[s] = float(e.xreplace(env))
    return [float(e.xreplace(env)) for e in exprs]


def _check_same(exprs, rng):
    assignments, reduced = optimise(exprs, LOCAL)
    for _ in range(5):
        point = {s: sp.Float(rng.uniform(-2, 2)) for s in G}
        np.testing.assert_allclose(_values(assignments, reduced, point), [float(e.xreplace(point)) for e in exprs],
                                   rtol=1e-12, atol=1e-12)
    return assignments, reduced


def test_writes_equal_up_to_sign_share_one_temporary():
    grad = [sp.diff(V_BOND, g) for g in (g0, g1)]
    reps, refs = share_writes(grad + [sp.expand(grad[0]), -grad[1]])
    assert len(reps) == 1 and refs == [(0, 1), (0, -1), (0, 1), (0, 1)]
    assignments, reduced = _check_same(grad, np.random.default_rng(0))
    assert reduced[0] == -reduced[1] and reduced[0].is_Symbol


def test_bond_hessian_is_one_value_and_its_negation():
    hess = [sp.diff(V_BOND, a, b) for a in (g0, g1) for b in (g0, g1)]
    assignments, reduced = _check_same(hess, np.random.default_rng(1))
    assert reduced[0].is_Symbol and reduced == [reduced[0], -reduced[0], -reduced[0], reduced[0]]
    assert len(assignments) == 2                    # r = g1 - g0 and k(r)


def test_polynomial_of_a_bond_strain_becomes_horner():
    force = -sp.diff(V_BOND, g0)
    rewritten = horner(force, LOCAL, forms := {})
    assert list(forms) == [g1 - g0]
    z = forms[g1 - g0]
    assert sp.expand(rewritten.xreplace({z: g1 - g0}) - force) == 0
    assert rewritten == z * (g2 + z * (g3 + g4 * z))
    assert operation_count(rewritten) < operation_count(force)


def test_numeric_coefficients_and_single_locals():
    expr = sp.Float(0.25) * g0 ** 3 + sp.Float(1.5) * g0
    assert horner(expr, LOCAL, {}) == g0 * (sp.Float(1.5) + sp.Float(0.25) * g0 ** 2)
    _check_same([expr, -0.5 * g0 + 0.5 * g1 + 0.3 * (g1 - g0) ** 2 + 1.0], np.random.default_rng(2))


def test_non_polynomials_and_mixed_forms_are_left_alone():
    for expr in (sp.sin(g1 - g0) * g2, (g1 - g0) ** 2 * g0, 1 / (g1 - g0)):
        assert horner(expr, LOCAL, {}) == expr
        _check_same([expr], np.random.default_rng(3))


def test_optimise_is_deterministic():
    exprs = [sp.diff(V_BOND, a, b) for a in (g0, g1) for b in (g0, g1)] + [V_BOND, -sp.diff(V_BOND, g1)]
    runs = [optimise(exprs, LOCAL) for _ in range(2)]
    assert sp.srepr(runs[0]) == sp.srepr(runs[1])
    assert [s.name for s, _ in runs[0][0]] == [f"t{k}" for k in range(len(runs[0][0]))]


@pytest.mark.parametrize("cse", [True, False])
def test_fpu_kernels_are_accurate_to_a_few_ulps(cse):
    """Force and stiffness of the generated C, against the same formulas in 50-digit arithmetic."""
    mp.mp.dps = 50
    n, (gamma, alpha, beta) = 40, (1.0, 0.25, 0.1)
    model = models.get("fpu_chain")
    spec = specialize(model, {"N": n, "gamma": gamma, "alpha": alpha, "beta": beta})
    system, _ = compile_model(model, spec, kernels={"force", "stiffness"}, backend="c", cse=cse)
    rng = np.random.default_rng(8)
    for scale in (1e-6, 1e-2, 1.0, 10.0):
        u = rng.normal(scale=scale, size=n)
        ext = [mp.mpf(0)] + [mp.mpf(x) for x in u] + [mp.mpf(0)]
        r = [ext[i + 1] - ext[i] for i in range(n + 1)]
        f = [x * (gamma + x * (mp.mpf(alpha) + x * mp.mpf(beta))) for x in r]
        k = [gamma + x * (2 * mp.mpf(alpha) + 3 * mp.mpf(beta) * x) for x in r]
        F = np.array([float(f[i + 1] - f[i]) for i in range(n)])
        K = system.call("stiffness", q=u)["K"].toarray()
        eps = np.finfo(float).eps
        assert np.max(np.abs(system.force(u) - F)) <= 4 * eps * np.max(np.abs(F))
        diag = np.array([float(k[i] + k[i + 1]) for i in range(n)])
        assert np.max(np.abs(np.diag(K) - diag)) <= 4 * eps * np.max(np.abs(diag))
        off = np.array([float(-k[i + 1]) for i in range(n - 1)])
        assert np.max(np.abs(np.diag(K, 1) - off)) <= 4 * eps * np.max(np.abs(off))
