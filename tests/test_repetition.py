"""Symbolic on the local piece, numeric over the repetition (DESIGN.md).

The chain's IR does not depend on N: N = 8 and N = 100 000 give the same kernel
signature and operation count, and derivation time does not grow with N. The
N = 100 000 kernel is checked against a vectorised numpy formula of the FPU force.
"""
import time

import numpy as np
import pytest

from mechgen import models
from mechgen.codegen.lower_model import lower_all
from mechgen.pipeline import compile_model, derive
from mechgen.symbolic.specialize import specialize

KERNELS = {"residual", "tangent", "linear", "force", "outputs"}


def _derive_and_lower(n):
    model = models.get("fpu_chain")
    spec = specialize(model, {"N": n, "alpha": 0.25, "beta": 0.5})
    start = time.perf_counter()
    irs = lower_all(model, derive(model, spec), KERNELS)
    return irs, time.perf_counter() - start


def test_ir_is_independent_of_chain_length():
    """The IR is the same for 8 and 100 000 sites, and so is the work of making it (the least of 3 runs each:
    a single run's wall time can absorb a descheduling under the parallel suite, which the least does not)."""
    _derive_and_lower(8)  # warm sympy caches
    small, t_small = min((_derive_and_lower(8) for _ in range(3)), key=lambda r: r[1])
    large, t_large = min((_derive_and_lower(100_000) for _ in range(3)), key=lambda r: r[1])
    assert [ir.signature() for ir in small] == [ir.signature() for ir in large]
    assert [ir.op_count() for ir in small] == [ir.op_count() for ir in large]
    assert t_large < 2 * t_small + 0.05


def _fpu_force(u, gamma, alpha, beta):
    """F_n = f(u_{n+1} - u_n) - f(u_n - u_{n-1}), f(r) = gamma r + alpha r^2 + beta r^3, u_0 = u_{N+1} = 0."""
    r = np.diff(np.concatenate([[0.0], u, [0.0]]))
    f = gamma * r + alpha * r**2 + beta * r**3
    return f[1:] - f[:-1]


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_large_chain_kernel_matches_vectorised_formula(backend):
    n = 100_000
    model = models.get("fpu_chain")
    system, report = compile_model(model, specialize(model, {"N": n, "alpha": 0.25, "beta": 0.5}),
                                   kernels={"force", "linear"}, backend=backend)
    u = np.random.default_rng(1).normal(scale=0.1, size=n)
    np.testing.assert_allclose(system.force(u), _fpu_force(u, 1.0, 0.25, 0.5), rtol=1e-12, atol=1e-14)
    K = system.linear(u)["K"]
    assert K.nnz == 3 * n - 2
    r = np.diff(np.concatenate([[0.0], u, [0.0]]))
    kb = 1.0 + 2 * 0.25 * r + 3 * 0.5 * r**2
    np.testing.assert_allclose(K.diagonal(), kb[:-1] + kb[1:], rtol=1e-12)
    np.testing.assert_allclose(K.diagonal(1), -kb[1:-1], rtol=1e-12)


def test_generated_c_loops_instead_of_unrolling():
    """The emitted C of a chain has the same length for any N (a loop, never unrolled text)."""
    from mechgen.pipeline import emit

    texts = {n: emit("c", _derive_and_lower(n)[0], model="fpu_chain", title="") for n in (8, 4096)}
    assert texts[8] == texts[4096]
    assert "for (long e = lo; e < hi; ++e)" in texts[8]
