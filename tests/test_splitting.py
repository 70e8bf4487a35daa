"""Splitting methods (mechgen.runtime.core.splitting) on the linear chain, against its exact solution.

Linear chain of N unit masses, fixed ends (fpu_chain with alpha = beta = 0): mode k has
omega_k = 2 sin(k pi / (2 (N + 1))) and shape sin(n k pi / (N + 1)), so that
q(t) = S (Q0 cos(omega t) + P0 / omega sin(omega t)) exactly (S the orthonormal sine matrix).
Observed orders come from the error at t = 10 under halving dt; design orders 2, 4, 6 and 4 for
ABA864 (Blanes et al. 2013: order 4 in general).
"""
import numpy as np
import pytest

import mechgen
from mechgen.runtime.core.splitting import METHODS, evolve

N = 8


@pytest.fixture(scope="module")
def chain():
    return mechgen.compile("fpu_chain", {"N": N, "alpha": 0.0, "beta": 0.0}, kernels=["force", "outputs"])


def exact(q0, v0, t):
    n = np.arange(1, N + 1)
    S = np.sqrt(2.0 / (N + 1)) * np.sin(np.outer(n, n) * np.pi / (N + 1))
    w = 2 * np.sin(n * np.pi / (2 * (N + 1)))
    Q0, P0 = S @ q0, S @ v0
    return S @ (Q0 * np.cos(w * t) + P0 / w * np.sin(w * t)), S @ (-Q0 * w * np.sin(w * t) + P0 * np.cos(w * t))


@pytest.mark.parametrize("name", list(METHODS))
def test_coefficients_consistent_and_symmetric(name):
    m = METHODS[name]
    assert abs(sum(m.a) - 1) < 1e-14 and abs(sum(m.b) - 1) < 1e-14
    assert np.allclose(m.a, m.a[::-1], atol=0, rtol=0) and np.allclose(m.b, m.b[::-1], atol=0, rtol=0)


def test_frequencies_of_the_linear_chain(chain):
    """The force kernel's stiffness has eigenvalues omega_k^2 = 4 sin^2(k pi / (2 (N + 1)))."""
    K = -np.array([chain.force(e) for e in np.eye(N)]).T
    k = np.arange(1, N + 1)
    assert np.allclose(np.sort(np.linalg.eigvalsh(K)), 4 * np.sin(k * np.pi / (2 * (N + 1))) ** 2, atol=1e-14)


@pytest.mark.parametrize("name", list(METHODS))
def test_observed_order(chain, name):
    rng = np.random.default_rng(3)
    q0, v0 = rng.standard_normal(N) * 0.1, rng.standard_normal(N) * 0.1
    t_end = 10.0
    hs = [0.4, 0.2, 0.1] if name != "leapfrog" else [0.1, 0.05, 0.025]
    errors = []
    for h in hs:
        q, v, _ = evolve(chain.force, q0, v0, h, int(round(t_end / h)), name)
        qe, ve = exact(q0, v0, t_end)
        errors.append(np.hypot(np.linalg.norm(q - qe), np.linalg.norm(v - ve)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    design = METHODS[name].order
    assert orders[-1] > design - 0.3, (name, errors, orders)
    if name != "aba864":  # ABA864 is designed for order 4 at least; on a linear chain it may do better
        assert orders[-1] < design + 0.7, (name, errors, orders)


@pytest.mark.slow
def test_energy_bounded_no_drift_over_a_million_steps():
    """Leapfrog, 10^6 steps of a 4-mass linear chain: |E - E0|/E0 stays O(dt^2), with no secular growth."""
    n = 4
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    rng = np.random.default_rng(1)
    q0, v0 = rng.standard_normal(n), rng.standard_normal(n)
    energy = lambda q, v: 0.5 * (v @ v + q @ K @ q)  # noqa: E731
    dt, steps = 0.1, 1_000_000
    _, _, rec = evolve(lambda q: -(K @ q), q0, v0, dt, steps, "leapfrog", stride=1000, observe=energy)
    err = np.abs(np.array(rec) - rec[0]) / rec[0]
    w_max = 2 * np.sin(n * np.pi / (2 * (n + 1)))
    assert err.max() < (dt * w_max) ** 2  # the modified energy's distance, O((dt omega)^2 / 8)
    tenth = len(err) // 10
    assert abs(err[-tenth:].mean() - err[:tenth].mean()) < 0.2 * err.max()


@pytest.mark.parametrize("name", list(METHODS))
def test_c_loop_agrees_with_numpy_stepper(name):
    """The compiled loop (symplectic_loop.c) steps exactly as the numpy stepper does, on the FPU-alpha chain."""
    from mechgen.runtime.core.symplectic_c import evolve_system

    system = mechgen.compile("fpu_chain", {"N": 16, "alpha": 0.25}, kernels=["force", "outputs"])
    rng = np.random.default_rng(5)
    q0, v0 = rng.standard_normal(16) * 0.3, rng.standard_normal(16) * 0.3
    qc, vc, ec, used = evolve_system(system, q0, v0, 0.05, 400, name, stride=100)
    assert used == "c"
    qn, vn, en, used_n = evolve_system(system, q0, v0, 0.05, 400, name, stride=100, loop="numpy")
    assert used_n == "numpy"
    assert np.allclose(qc, qn, rtol=0, atol=1e-12) and np.allclose(vc, vn, rtol=0, atol=1e-12)
    assert ec.shape == (5,) and np.allclose(ec, en, rtol=1e-13, atol=0)


def test_c_loop_energy_bounded_over_a_million_steps():
    """10^6 steps in C of the 8-mass FPU-alpha chain (alpha = 0.25, generated kernels): the energy error of
    each method stays within its O(dt^order) bound and shows no drift (first and last tenth alike)."""
    from mechgen.runtime.core.symplectic_c import evolve_system

    system = mechgen.compile("fpu_chain", {"N": N, "alpha": 0.25}, kernels=["force", "outputs"])
    n = np.arange(1, N + 1)
    q0 = np.sin(n * np.pi / (N + 1))  # the lowest mode, unit amplitude
    dt = 0.1
    for name in ("leapfrog", "aba864"):
        _, _, e, used = evolve_system(system, q0, np.zeros(N), dt, 1_000_000, name, stride=1000)
        assert used == "c"
        err = np.abs(e - e[0]) / e[0]
        assert err.max() < dt ** METHODS[name].order, (name, err.max())
        tenth = len(err) // 10
        assert abs(err[-tenth:].mean() - err[:tenth].mean()) < 0.2 * err.max(), name


def test_without_a_compiler_the_numpy_stepper_runs(monkeypatch, tmp_path):
    from mechgen.codegen import build
    from mechgen.errors import CompilerUnavailable
    from mechgen.runtime.core import symplectic_c

    system = mechgen.compile("fpu_chain", {"N": 6, "alpha": 0.25}, kernels=["force", "outputs"])  # compiler works
    q0 = np.linspace(0.1, 0.6, 6)
    reference = evolve(system.force, q0, np.zeros(6), 0.1, 50, "yoshida4")[0]
    monkeypatch.setenv("CC", "/nonexistent/cc")
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path))  # an empty cache: the loop library is not there built
    build.reset_compiler_cache()
    symplectic_c.forget_library()
    try:
        assert "cannot be built" in symplectic_c.c_unavailable(system)
        q, _, _, used = symplectic_c.evolve_system(system, q0, np.zeros(6), 0.1, 50, "yoshida4")
        assert used == "numpy" and np.array_equal(q, reference)
        with pytest.raises(CompilerUnavailable):
            symplectic_c.evolve_system(system, q0, np.zeros(6), 0.1, 50, "yoshida4", loop="c")
    finally:
        monkeypatch.undo()
        build.reset_compiler_cache()
        symplectic_c.forget_library()
    assert symplectic_c.c_unavailable(system) is None


def test_the_diagonal_mass_is_read_off_the_kinetic_energy():
    """The splittings' fitness reads m_i of T = sum m_i v_i^2 / 2 off T's polynomial in v (no Hessian); a cross
    term, a cubic term or a non-polynomial T gives None and the Hessian path names what breaks the form, as it
    always did; a mass depending on q is caught by that path too."""
    import sympy as sp

    from mechgen.symbolic.separable import diagonal_masses, mass_obstacle

    q1, q2, v1, v2, m = sp.symbols("q1 q2 v1 v2 m", real=True)
    v, q = (v1, v2), (q1, q2)
    assert diagonal_masses(m * v1**2 / 2 + 3 * v2**2, v) == [m, 6]
    assert mass_obstacle(m * v1**2 / 2 + 3 * v2**2, q, v, (), ("x", "y")) is None
    assert diagonal_masses(v1 * v2 + v1**2, v) is None
    assert "not diagonal" in mass_obstacle(v1 * v2 + v1**2, q, v, (), ("x", "y"))
    assert diagonal_masses(v1**3 + v2**2, v) is None
    assert diagonal_masses(sp.cos(v1) + v2**2, v) is None
    assert "depends on v1" in mass_obstacle(v1**4 + v2**2, q, v, (), ("x", "y"))
    assert diagonal_masses(v1**2 + v1, v) is None
    assert "quadratic form" in mass_obstacle(v1**2 + v1, q, v, (), ("x", "y"))
    assert "depends on q1" in mass_obstacle((1 + q1**2) * v1**2 + v2**2, q, v, (), ("x", "y"))
