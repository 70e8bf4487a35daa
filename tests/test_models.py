"""The proof models against closed forms (each reference cited in its test)."""
import numpy as np
import pytest

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.runtime.core.integrate import leapfrog
from mechgen.analyses.modes import run_modes
from mechgen.analyses.simulate import run_simulate
from mechgen.analyses.stability import run_stability
from mechgen.analyses.steady import run_steady
from mechgen.symbolic.specialize import specialize

LAVAL = {"m": 10.0, "Ip": 0.2, "Id": 0.1, "k_t": 4.0e5, "k_r": 2.0e4}


def laval_whirl(omega_spin, m, Ip, Id, k_t, k_r):
    """Jeffcott/Laval rotor whirl (Genta, Dynamics of Rotating Systems, 2005, sec. 4.3; Lalanne & Ferraris 1998):
    translations sqrt(k_t/m) (twice); tilts Id w^2 -+ Ip Omega w - k_r = 0, i.e.
    w_f,b = (+-Ip Omega + sqrt(Ip^2 Omega^2 + 4 Id k_r)) / (2 Id)."""
    root = np.sqrt((Ip * omega_spin) ** 2 + 4 * Id * k_r)
    w_t = np.sqrt(k_t / m)
    return np.sort([w_t, w_t, (root - Ip * omega_spin) / (2 * Id), (root + Ip * omega_spin) / (2 * Id)])


@pytest.fixture(scope="module")
def laval():
    model = models.get("laval_rotor")
    system, _ = compile_model(model, specialize(model, {**LAVAL, "c": 0.0, "c_r": 0.0}, free=("Omega",)),
                              kernels={"linear"}, backend="c")
    return system


@pytest.mark.parametrize("omega_spin", np.linspace(0.0, 3000.0, 13))
def test_laval_whirl_frequencies_match_closed_form(laval, omega_spin):
    out = run_stability(laval.with_params(Omega=omega_spin), {}, {})
    assert out["verdict"] == "stable"
    expected = laval_whirl(omega_spin, **LAVAL)
    found = np.sort(np.repeat(out["frequencies"], 1))
    # coincident translational pair appears once or twice depending on the eigen-solver's merging
    assert np.allclose(np.unique(np.round(found, 6)), np.unique(np.round(expected, 6)), rtol=1e-9)


def test_laval_gyroscopic_splitting_is_ip_omega_over_id(laval):
    """w_f - w_b = Ip Omega / Id exactly (the gyroscopic moment Ip Omega)."""
    w_t = np.sqrt(LAVAL["k_t"] / LAVAL["m"])
    for omega_spin in (100.0, 1000.0, 5000.0):
        tilt = [f for f in run_stability(laval.with_params(Omega=omega_spin), {}, {})["frequencies"] if abs(f - w_t) > 1e-6 * w_t]
        assert max(tilt) - min(tilt) == pytest.approx(LAVAL["Ip"] * omega_spin / LAVAL["Id"], rel=1e-10)


def test_laval_damped_rotor_is_stable_with_decaying_modes():
    model = models.get("laval_rotor")
    system, _ = compile_model(model, specialize(model, {**LAVAL, "c": 50.0, "c_r": 2.0, "Omega": 800.0}),
                              kernels={"linear"}, backend="c")
    out = run_stability(system, {}, {})
    assert out["verdict"] == "stable"
    assert max(re for re, _ in out["eigenvalues"]) < 0


@pytest.mark.parametrize("n", [8, 32])
def test_fpu_linear_frequencies(n):
    """omega_k = 2 sqrt(gamma) sin(k pi / (2 (N + 1))) for a fixed-end chain of unit masses (FPU 1955)."""
    model = models.get("fpu_chain")
    system, _ = compile_model(model, specialize(model, {"N": n, "gamma": 2.0}), kernels={"linear"}, backend="c")
    freqs = run_modes(system, {}, {})["frequencies"]
    k = np.arange(1, n + 1)
    np.testing.assert_allclose(freqs, 2 * np.sqrt(2.0) * np.sin(k * np.pi / (2 * (n + 1))), rtol=1e-10)


def test_fpu_leapfrog_energy_error_is_uniform_order_dt2_over_1e5_steps():
    """Backward error analysis of a symplectic integrator (Hairer, Lubich & Wanner, Geometric
    Numerical Integration, 2006, ch. IX.8): the energy error is bounded by C dt^2 uniformly over
    exponentially long times, without drift. Over the same horizon T = 5000 (10^5 steps at
    dt = 0.05), halving dt divides the maximum error by 4; a drifting method would not show it."""
    model = models.get("fpu_chain")
    n = 32
    system, _ = compile_model(model, specialize(model, {"N": n, "alpha": 0.25}),
                              kernels={"force", "outputs"}, backend="c")
    q0 = np.sin(np.arange(1, n + 1) * np.pi / (n + 1))
    t_end = 5000.0
    worst = []
    for dt in (0.05, 0.025):
        steps = int(round(t_end / dt))
        traj = leapfrog(system.force, q0, np.zeros(n), dt, steps, record_every=int(round(0.5 / dt)),
                        energy=lambda q, v: system.outputs(q, v)["energy"])
        e = np.asarray(traj.energy)
        worst.append(np.max(np.abs(e - e[0])) / e[0])
    assert worst[0] < 1e-4
    assert 3.5 < worst[0] / worst[1] < 4.5


def test_spring_pendulum_equilibrium_and_small_oscillations():
    """r_eq = l0 + m g / k; frequencies sqrt(k/m) (spring) and sqrt(g / r_eq) (pendulum)."""
    model = models.get("spring_pendulum")
    m, k, l0, g = 1.3, 40.0, 1.0, 9.81
    system, _ = compile_model(model, specialize(model, {"m": m, "k": k, "l0": l0, "g": g}),
                              kernels={"residual", "tangent", "outputs", "linear"}, backend="c")
    eq = run_steady(system, {"guess": {"r": 1.0}}, {})
    r_eq = l0 + m * g / k
    assert eq["coordinates"]["r"] == pytest.approx(r_eq, rel=1e-12)
    assert eq["coordinates"]["theta"] == pytest.approx(0.0, abs=1e-12)
    freqs = run_modes(system, {"about": "eq"}, {"eq": eq})["frequencies"]
    np.testing.assert_allclose(freqs, np.sort([np.sqrt(k / m), np.sqrt(g / r_eq)]), rtol=1e-10)


@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_spring_pendulum_conserves_energy(method):
    """Large swing (theta0 = 0.8 rad, stretched spring): T + V constant to the integrator tolerance."""
    model = models.get("spring_pendulum")
    system, _ = compile_model(model, specialize(model, {}), backend="c")
    out = run_simulate(system, {"method": method, "t_end": 10.0, "q0": {"r": 1.4, "theta": 0.8},
                                "rtol": 1e-10, "atol": 1e-12}, {})
    assert out["energy_drift"] < 1e-7
