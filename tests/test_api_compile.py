"""mechgen.compile: matrices, residual, Jacobians and outputs against closed forms; with_params against a fresh
compile; recompiling for folded names; bad input."""
import math

import numpy as np
import pytest
import scipy.linalg as sla

import mechgen
from mechgen.errors import InputError
from mechgen.runtime.fields.mesh import Part, Segment

M_, K_, L0, G = 2.0, 50.0, 0.8, 9.81


@pytest.fixture(scope="module")
def pendulum():
    return mechgen.compile("spring_pendulum", {"m": M_, "k": K_, "l0": L0, "g": G})


def hanging(m=M_, k=K_, l0=L0, g=G):
    """The hanging equilibrium r = l0 + m g / k, theta = 0."""
    return np.array([l0 + m * g / k, 0.0])


def test_spring_pendulum_matrices_at_the_hanging_equilibrium(pendulum):
    q = hanging()
    r = q[0]
    mats = pendulum.linear(q, np.zeros(2))
    np.testing.assert_allclose(mats["M"], np.diag([M_, M_ * r**2]), rtol=1e-14)
    np.testing.assert_allclose(mats["K"], np.diag([K_, M_ * G * r]), rtol=1e-14)
    np.testing.assert_allclose(mats["D"], 0.0, atol=0)
    np.testing.assert_allclose(mats["G"], 0.0, atol=0)
    # the equilibrium: r(q, 0, 0) = dV/dq = 0
    np.testing.assert_allclose(pendulum.residual(q), 0.0, atol=1e-13)
    tan = pendulum.tangent(q)
    np.testing.assert_allclose(tan["r_q"], np.diag([K_, M_ * G * r]), rtol=1e-14)
    np.testing.assert_allclose(tan["r_a"], np.diag([M_, M_ * r**2]), rtol=1e-14)
    out = pendulum.outputs(q)
    assert out["x"] == pytest.approx(0.0, abs=1e-15) and out["y"] == pytest.approx(-r, rel=1e-15)
    assert isinstance(mats["M"], np.ndarray) and isinstance(pendulum.residual(q), np.ndarray)


def test_spring_pendulum_residual_off_equilibrium(pendulum):
    """r = M a - f with the Lagrange equations of T = m/2 (r'^2 + r^2 th'^2), V = k/2 (r - l0)^2 - m g r cos th."""
    r, th, vr, vth, ar, ath = 1.3, 0.4, 0.7, -1.1, 0.2, 0.5
    expected = [M_ * ar - M_ * r * vth**2 + K_ * (r - L0) - M_ * G * math.cos(th),
                M_ * r**2 * ath + 2 * M_ * r * vr * vth + M_ * G * r * math.sin(th)]
    np.testing.assert_allclose(pendulum.residual([r, th], [vr, vth], [ar, ath]), expected, rtol=1e-13)


def test_with_params_equals_a_fresh_compile_and_leaves_the_old_system(pendulum):
    before = pendulum.params.copy()
    stiffer = pendulum.with_params(k=80.0, m=3.0)
    fresh = mechgen.compile("spring_pendulum", {"m": 3.0, "k": 80.0, "l0": L0, "g": G})
    q = hanging(m=3.0, k=80.0)
    for name in ("M", "K"):
        np.testing.assert_allclose(stiffer.linear(q)[name], fresh.linear(q)[name], rtol=1e-15)
    np.testing.assert_allclose(stiffer.linear(q)["K"], np.diag([80.0, 3.0 * G * q[0]]), rtol=1e-14)
    np.testing.assert_array_equal(pendulum.params, before)
    np.testing.assert_allclose(pendulum.linear(hanging())["K"], np.diag([K_, M_ * G * hanging()[0]]), rtol=1e-14)
    assert stiffer is not pendulum and stiffer.kernels is pendulum.kernels  # a new vector, the same kernels


def test_a_folded_parameter_recompiles():
    """With ``free`` narrower than all, m is folded into the kernels: with_params recompiles for it."""
    narrow = mechgen.compile("spring_pendulum", {"m": M_, "k": K_, "l0": L0, "g": G}, free=["k"])
    assert narrow.meta["params"] == ["k"] and "m" in narrow.folded
    heavier = narrow.with_params(m=3.0, k=60.0)
    q = hanging(m=3.0, k=60.0)
    np.testing.assert_allclose(heavier.linear(q)["K"], np.diag([60.0, 3.0 * G * q[0]]), rtol=1e-14)
    assert heavier.meta["params"] == ["k"] and narrow.linear(hanging())["M"][0, 0] == M_


def test_folded_parameter_without_rebuild_and_unknown_names_raise():
    from mechgen import models
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.specialize import specialize

    model = models.get("spring_pendulum")
    system, _ = compile_model(model, specialize(model, {}, free=("k",)), kernels={"linear"}, backend="numpy")
    bare = type(system)(system.kernels, system.meta, system.params, folded=("m", "l0", "g"))
    with pytest.raises(InputError, match="'m'.*folded"):
        bare.with_params(m=2.0)
    with pytest.raises(InputError, match="unknown parameter 'mass'.*one of: g, k, l0, m"):
        bare.with_params(mass=2.0)
    with pytest.raises(InputError, match="not a number"):
        bare.with_params(k="stiff")


def test_compile_rejects_bad_input():
    with pytest.raises(InputError, match="no parameter 'mass'"):
        mechgen.compile("spring_pendulum", {"mass": 1.0})
    with pytest.raises(InputError, match="free"):
        mechgen.compile("spring_pendulum", free=["r"])
    with pytest.raises(InputError, match="not one of its choices"):
        mechgen.compile("euler_bernoulli_beam", {"bc": "glued"})
    with pytest.raises(InputError, match="model"):
        mechgen.compile(42)
    with pytest.raises(InputError, match="not a continuum"):
        mechgen.compile("spring_pendulum", segments=[{"length": 1.0, "elements": 2}])
    with pytest.raises(InputError, match="part kind 'disk'"):
        mechgen.compile("euler_bernoulli_beam", parts=[Part("disk", 0.5, {})])


EI, RHOA, L = 2.0, 0.5, 1.5


@pytest.fixture(scope="module")
def beam():
    return mechgen.compile("euler_bernoulli_beam", {"EI": EI, "rhoA": RHOA, "L": L, "N": 32}, backend="numpy")


def lowest(system) -> float:
    mats = system.linear()
    M, K = (A.toarray() if hasattr(A, "toarray") else A for A in (mats["M"], mats["K"]))
    return math.sqrt(sla.eigh(K, M, eigvals_only=True)[0])


def test_pinned_pinned_beam_lowest_frequency(beam):
    """omega_1 = (pi / L)^2 sqrt(EI / rhoA); 32 cubic Hermite elements (the error falls as h^4: 6e-8 here)."""
    assert lowest(beam) == pytest.approx((math.pi / L) ** 2 * math.sqrt(EI / RHOA), rel=1e-7)


def test_beam_with_params_numbers_choices_and_folded_names(beam):
    longer = beam.with_params(L=3.0)
    assert lowest(longer) == pytest.approx((math.pi / 3.0) ** 2 * math.sqrt(EI / RHOA), rel=1e-7)
    coarse = beam.with_params(N=8)  # 16^-1 of the error per halving of h: 1.6e-5 at N = 8
    assert coarse.choices["N"] == 8 and beam.choices["N"] == 32
    assert lowest(coarse) == pytest.approx((math.pi / L) ** 2 * math.sqrt(EI / RHOA), rel=2e-5)
    assert abs(lowest(coarse) / lowest(beam) - 1) > 1e-5
    cantilever = beam.with_params(bc="clamped-free")  # folded into the kernels: recompiled
    beta1 = 1.8751040687119611  # first root of cos x cosh x = -1
    assert lowest(cantilever) == pytest.approx((beta1 / L) ** 2 * math.sqrt(EI / RHOA), rel=1e-7)
    assert lowest(beam) == pytest.approx((math.pi / L) ** 2 * math.sqrt(EI / RHOA), rel=1e-7)
    fresh = mechgen.compile("euler_bernoulli_beam", {"EI": EI, "rhoA": RHOA, "L": 3.0, "N": 32}, backend="numpy")
    np.testing.assert_allclose(longer.linear()["K"].toarray(), fresh.linear()["K"].toarray(), rtol=1e-14)
    with pytest.raises(InputError, match="N = 0"):
        beam.with_params(N=0)


def test_segments_of_one_material_give_the_uniform_beam():
    """Two segments of the same EI and rhoA (lengths 0.5 and 1.0): the uniform pinned-pinned beam of L = 1.5."""
    stepped = mechgen.compile("euler_bernoulli_beam", {"EI": EI, "rhoA": RHOA}, backend="numpy",
                              segments=[{"length": 0.5, "elements": 12}, Segment(1.0, 24, {"EI": EI})])
    assert stepped.layout.length == pytest.approx(L)
    assert lowest(stepped) == pytest.approx((math.pi / L) ** 2 * math.sqrt(EI / RHOA), rel=1e-7)


def test_chain_sites_are_a_runtime_size():
    """A fixed-fixed harmonic chain: omega_k = 2 sqrt(gamma) sin(k pi / (2 (N + 1))) for each N."""
    chain = mechgen.compile("fpu_chain", {"N": 8, "gamma": 1.5, "alpha": 0.0, "beta": 0.0}, backend="numpy")
    for system, n in ((chain, 8), (chain.with_params(N=13), 13)):
        mats = system.linear(np.zeros(system.n))
        w = np.sqrt(sla.eigh(mats["K"].toarray(), mats["M"].toarray(), eigvals_only=True))
        k = np.arange(1, n + 1)
        np.testing.assert_allclose(w, 2 * math.sqrt(1.5) * np.sin(k * math.pi / (2 * (n + 1))), rtol=1e-12)
    assert chain.n == 8
