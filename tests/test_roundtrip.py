"""Codegen round trips: every backend, with and without CSE, against sympy's own evaluation.

Lumped models: the kernels' outputs equal the derived sympy matrices evaluated at
random states. Chains: the kernels equal derivatives of the *whole-chain* energy
built directly in sympy for a small N (an independent assembly).
"""
import numpy as np
import pytest
import sympy as sp

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.symbolic.derive import derive_lumped
from mechgen.symbolic.specialize import all_free, specialize

BACKENDS = ["numpy", "c", "casadi"]


def _random_state(n, rng):
    return rng.uniform(-0.7, 0.7, n), rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)


def _lumped_reference(eqs, q, v, a, pvals):
    values = dict(zip(eqs.q, q)) | dict(zip(eqs.v, v)) | dict(zip(eqs.a, a)) | dict(zip(eqs.params, pvals))
    values[eqs.t] = 0.0

    def ev(mat):
        return np.array(sp.Matrix(mat).subs(values).evalf(), dtype=float)

    lin_values = {k: ev(m) for k, m in eqs.linear_matrices().items()}
    tangent = {f"r_{w}": ev(eqs.jacobian(eqs.residual, w)) for w in ("q", "v", "a")}
    return {"residual": ev(eqs.residual).ravel(), "force": ev(eqs.force()).ravel(), **lin_values, **tangent,
            "energy": float(ev(sp.Matrix([eqs.outputs["energy"]]))[0, 0])}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("cse", [True, False])
@pytest.mark.parametrize("name", ["laval_rotor", "spring_pendulum"])
def test_lumped_kernels_match_sympy(name, backend, cse):
    model = models.get(name)
    spec = all_free(model)
    spec = specialize(model, {}, free=spec.free)
    system, _ = compile_model(model, spec, backend=backend, cse=cse)
    eqs = derive_lumped(model, spec)
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, v, a = _random_state(system.n, rng)
        if name == "spring_pendulum":
            q[0] = abs(q[0]) + 0.5
        system = system.with_param_vector(rng.uniform(0.5, 2.0, len(eqs.params)))
        ref = _lumped_reference(eqs, q, v, a, system.params)
        np.testing.assert_allclose(system.residual(q, v, a), ref["residual"], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(system.force(q), ref["force"], rtol=1e-12, atol=1e-12)
        lin = system.linear(q, v)
        tan = system.call("tangent", q=q, v=v, a=a)
        for key in ("M", "D", "G", "K"):
            np.testing.assert_allclose(lin[key], ref[key], rtol=1e-12, atol=1e-12, err_msg=key)
        for key in ("r_q", "r_v", "r_a"):
            np.testing.assert_allclose(tan[key], ref[key], rtol=1e-12, atol=1e-12, err_msg=key)
        assert system.outputs(q, v)["energy"] == pytest.approx(ref["energy"], rel=1e-12)


def _whole_chain(n, gamma, alpha, beta, ends):
    u = sp.symbols(f"u1:{n + 1}", real=True)
    ext = (0,) + u + (0,) if ends == "fixed" else u + (u[0],)
    V = sum(gamma * r**2 / 2 + alpha * r**3 / 3 + beta * r**4 / 4
            for r in (ext[i + 1] - ext[i] for i in range(len(ext) - 1)))
    grad = sp.Matrix([V]).jacobian(sp.Matrix(u))
    return u, V, grad, sp.hessian(V, u)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("cse", [True, False])
def test_chain_kernels_match_whole_chain_sympy(backend, cse):
    model = models.get("fpu_chain")
    n, gamma, alpha, beta = 6, 1.3, 0.4, 0.7
    spec = specialize(model, {"N": n, "gamma": gamma, "alpha": alpha, "beta": beta})
    system, _ = compile_model(model, spec, backend=backend, cse=cse)
    u, V, grad, hess = _whole_chain(n, gamma, alpha, beta, "fixed")
    rng = np.random.default_rng(3)
    q, v, a = _random_state(n, rng)
    values = dict(zip(u, q))
    np.testing.assert_allclose(system.force(q), -np.array(grad.subs(values).evalf(), float).ravel(), rtol=1e-12)
    np.testing.assert_allclose(system.residual(q, v, a),
                               a + np.array(grad.subs(values).evalf(), float).ravel(), rtol=1e-12)
    K = system.linear(q)["K"].toarray()
    np.testing.assert_allclose(K, np.array(hess.subs(values).evalf(), float), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(system.linear(q)["M"].toarray(), np.eye(n))
    energy = float(V.subs(values)) + 0.5 * float(v @ v)
    assert system.outputs(q, v)["energy"] == pytest.approx(energy, rel=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_batched_evaluation_matches_single_states(backend):
    model = models.get("spring_pendulum")
    system, _ = compile_model(model, all_free(model), backend=backend)
    rng = np.random.default_rng(11)
    Q = rng.uniform(0.5, 1.5, (50, 2))
    k = system.kernels["force"]
    batch = k.evaluate({"q": Q, "t": np.zeros((50, 1)), "p": system.params})["f"]
    single = np.array([system.force(q) for q in Q])
    np.testing.assert_allclose(batch, single, rtol=0, atol=0)
