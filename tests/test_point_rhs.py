"""System.rhs in one compiled call (issue 32 item 2: M, the bias and the solve in one call): equal to the Python
path (flow kernel, LAPACK's Cholesky) to round-off on the built-in smooth models, the n-link pendulum against its
closed form, a singular M and a NaN handled as the Python path handles them."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechgen
from mechgen.bench.multibody import closed_form_accelerations, pendulum_model
from mechgen.errors import KernelError
from mechgen.runtime.core.point_rhs import point_rhs
from mechgen.runtime.core.system import mass_solve


def python_rhs(system, t, x):
    """The Python path: the flow kernel's r and M, then LAPACK's Cholesky (mechgen.runtime.core.system)."""
    n = system.n
    out = system.bound("flow").evaluate(q=x[:n], v=x[n:], t=t)
    return np.concatenate([x[n:], mass_solve(out["M"].reshape(n, n), -out["r"])])


@pytest.mark.parametrize("model", ["spring_pendulum", "duffing", "van_der_pol", "laval_rotor"])
def test_equal_to_the_python_path(model):
    system = mechgen.compile(model, kernels=["flow", "residual", "tangent"])
    assert point_rhs(system) is not None
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = rng.standard_normal(2 * system.n)
        fast, slow = system.rhs(0.7, x), python_rhs(system, 0.7, x)
        assert np.allclose(fast, slow, rtol=1e-12, atol=1e-12 * np.max(np.abs(slow)))


def test_parameters_of_each_system_are_used():
    """Systems of other parameter values share the prepared call; each call reads its own system's values."""
    a = mechgen.compile("spring_pendulum", kernels=["flow"])
    b = a.with_params(k=2 * float(a.param_values()["k"]))
    x = np.array([0.3, 0.2, 0.1, -0.4])
    fa, fb = a.rhs(0.0, x), b.rhs(0.0, x)
    assert np.allclose(fa, python_rhs(a, 0.0, x), rtol=1e-13) and np.allclose(fb, python_rhs(b, 0.0, x), rtol=1e-13)
    assert not np.allclose(fa, fb)


@pytest.mark.parametrize("n", [3, 12])
def test_pendulum_against_its_closed_form(n):
    """n = 12 is derived by AD (>= 8 coordinates): the closed-form accelerations to 1e-11."""
    system = mechgen.compile(pendulum_model(n), kernels=["flow"])
    rng = np.random.default_rng(n)
    for _ in range(3):
        x = 0.5 * rng.standard_normal(2 * n)
        exact = closed_form_accelerations(x[:n], x[n:])
        assert np.max(np.abs(system.rhs(0.0, x)[n:] - exact)) < 1e-11 * np.max(np.abs(exact))


def test_singular_mass_and_nan_as_the_python_path():
    from mechgen import Model, Param

    model = Model("massless_at_zero")
    model.params(Param("k", 1.0, "N/m", "stiffness"))
    model.coordinates("x", "y")
    model.kinetic(lambda q, v: (q.x**2 * v.x**2 + v.y**2) / 2)  # M = diag(x^2, 1): singular at x = 0
    model.potential(lambda q, p: p.k * (q.x**2 + sp.sqrt(q.y) ** 3) / 2)  # dV/dy NaN for y < 0
    system = mechgen.compile(model, kernels=["flow"])
    assert point_rhs(system) is not None
    with pytest.raises(np.linalg.LinAlgError):
        system.rhs(0.0, np.array([0.0, 1.0, 0.1, 0.1]))
    with pytest.raises(KernelError, match="NaN/Inf"):
        system.rhs(0.0, np.array([1.0, -1.0, 0.1, 0.1]))
    x = np.array([0.5, 2.0, 0.1, -0.3])
    assert np.allclose(system.rhs(0.0, x), python_rhs(system, 0.0, x), rtol=1e-13)


def python_jacobian(system, t, x):
    """The Python path of System.jacobian (the compiled call switched off for this system)."""
    key = ("point_rhs",)
    kept = system.patterns.get(key)
    system.patterns[key] = None
    try:
        return system.jacobian(t, x)
    finally:
        system.patterns[key] = kept


@pytest.mark.parametrize("model", ["spring_pendulum", "duffing", "van_der_pol", "laval_rotor"])
def test_jacobian_equal_to_the_python_path(model):
    """df/dx = ((0, I), -M^-1 (r_q, r_v)) in one compiled call: equal to the Python path (tangent kernel, LAPACK) to
    round-off."""
    system = mechgen.compile(model, kernels=["flow", "residual", "tangent"])
    assert point_rhs(system).J is not None
    rng = np.random.default_rng(4)
    for _ in range(3):
        x = rng.standard_normal(2 * system.n)
        fast, slow = system.jacobian(0.4, x), python_jacobian(system, 0.4, x)
        assert np.allclose(fast, slow, rtol=1e-12, atol=1e-12 * np.max(np.abs(slow)))


@pytest.mark.parametrize("n", [3, 12])
def test_pendulum_jacobian_against_differences_of_the_closed_form(n):
    """The lower block da/dx against central differences (h = 1e-5) of the closed-form accelerations: their
    truncation error, O(h^2 a''') ~ 1e-9 here, sets the tolerance."""
    system = mechgen.compile(pendulum_model(n), kernels=["flow", "tangent"])
    x = 0.5 * np.random.default_rng(n).standard_normal(2 * n)
    J = system.jacobian(0.0, x)
    h = 1e-5

    def accel(y):
        return closed_form_accelerations(y[:n], y[n:])
    fd = np.column_stack([(accel(x + h * e) - accel(x - h * e)) / (2 * h) for e in np.eye(2 * n)])
    assert np.array_equal(J[:n], np.hstack([np.zeros((n, n)), np.eye(n)]))
    assert np.max(np.abs(J[n:] - fd)) < 1e-7 * np.max(np.abs(fd))


def test_jacobian_at_a_singular_mass_as_the_python_path():
    from mechgen import Model

    model = Model("massless_at_zero_j")
    model.coordinates("x", "y")
    model.kinetic(lambda q, v: (q.x**2 * v.x**2 + v.y**2) / 2)
    model.potential(lambda q: (q.x**2 + q.y**4) / 2)
    system = mechgen.compile(model, kernels=["flow", "tangent"])
    assert point_rhs(system).J is not None
    with pytest.raises(np.linalg.LinAlgError):
        system.jacobian(0.0, np.array([0.0, 1.0, 0.1, 0.1]))
    x = np.array([0.5, 2.0, 0.1, -0.3])
    assert np.allclose(system.jacobian(0.0, x), python_jacobian(system, 0.0, x), rtol=1e-12, atol=1e-14)


def test_an_indefinite_mass_takes_the_lu_branch():
    """T = (v_x^2 + v_x v_y - v_y^2)/2 has M = ((1, 1/2), (1/2, -1)), indefinite: Cholesky fails and LU with partial
    pivoting solves, for dx/dt and for each column of the Jacobian (against numpy's solve on the same r and M)."""
    from mechgen import Model

    model = Model("indefinite_mass")
    model.coordinates("x", "y")
    model.kinetic(lambda q, v: (v.x**2 + v.x * v.y - v.y**2) / 2 + q.x**2 * v.y**2 / 8)
    model.potential(lambda q: (q.x**2 + 3 * q.y**2) / 2 + q.x * q.y**3)
    system = mechgen.compile(model, kernels=["flow", "tangent"])
    assert point_rhs(system).J is not None
    x = np.array([0.3, -0.2, 0.5, 0.1])
    assert np.allclose(system.rhs(0.0, x), python_rhs(system, 0.0, x), rtol=1e-13)
    assert np.allclose(system.jacobian(0.0, x), python_jacobian(system, 0.0, x), rtol=1e-12, atol=1e-14)


def test_runtime_sources_inline_their_shared_header():
    """point_rhs.c and radau_loop.c take LU and its solve from one header (runtime/csrc/dense_lu.h), inlined into
    the text each library is built from; no source of the folder keeps an include of a local header."""
    from mechgen.runtime import csrc

    header = csrc.path("dense_lu.h").read_text(encoding="utf-8")
    for name in ("point_rhs.c", "radau_loop.c"):
        text = csrc.source(name)
        assert header in text and '#include "dense_lu.h"' not in text and text.count("mg_lu_factor(long n") == 1
    for path in csrc.FOLDER.glob("*.c"):
        assert '#include "' not in csrc.source(path.name), path.name
