"""Friction-excited clamped beam (issue 14, part 3): scenes/friction_beam.toml and the ``spectrum`` analysis.

References:
* clamped-clamped Euler-Bernoulli beam, f_n = (beta_n L)^2 / (2 pi L^2) sqrt(E I / (rho A)) with beta_n L
  the roots of cos(x) cosh(x) = 1: 4.730040744862704, 7.853204624095838, 10.99560783800167,
  14.13716549125746 (Blevins, Formulas for Natural Frequency and Mode Shape, table 8-1); circular
  section of diameter d: I / A = d^2 / 16. Cubic Hermite elements converge as h^4 in the eigenvalue.
* a single impulse J on a mode with modal mass 1: q(t) = J exp(-zeta omega t) sin(omega_d t) / omega_d,
  q'(t) = J exp(-zeta omega t) (cos(omega_d t) - zeta omega / omega_d sin(omega_d t)), omega_d =
  omega sqrt(1 - zeta^2) (the damped oscillator's impulse response).
"""
from __future__ import annotations

import copy
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mechgen.runtime.linear.impulses import modal_train
from mechgen.scene.run import run_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "friction_beam.toml"
ROOTS = np.array([4.730040744862704, 7.853204624095838, 10.99560783800167, 14.13716549125746])


def _exact(L=0.28, d=0.03, E=70e9, rho=2700.0) -> np.ndarray:
    return ROOTS**2 / (2 * np.pi * L**2) * np.sqrt(E * d**2 / (16 * rho))


def _scene(**spectrum) -> dict:
    data = tomllib.loads(SCENE.read_text())
    data["analysis"] = [a for a in data["analysis"] if a["kind"] == "spectrum"]
    data["analysis"][0].update(spectrum)
    return data


def _spectrum(overrides=(), **spectrum) -> dict:
    return run_scene(_scene(**spectrum), overrides=overrides)["analyses"][0]["outputs"]


def test_natural_frequencies_converge_to_the_clamped_clamped_roots():
    exact = _exact()
    errors = []
    for n in (8, 16, 32):
        out = _spectrum((f"N={n}",), t_end=0.01, peaks=1, modes=4)
        errors.append(np.abs(np.array(out["natural_frequencies"][:4]) / exact - 1))
    errors = np.array(errors)
    assert np.all(errors[-1] < 3e-5)                   # N = 32: the scene's mesh
    rates = np.log2(errors[:-1] / errors[1:])          # h^4 for cubic Hermite elements
    assert np.all(rates[:, :3] > 3.7) and np.all(rates[:, :3] < 4.3)


def test_the_scene_prints_the_computed_frequencies_not_the_papers():
    out = _spectrum()
    f = np.array(out["natural_frequencies"][:4])
    assert np.allclose(f, _exact(), rtol=3e-5)
    paper = [19.0, 145.0, 360.0, 745.0]                # the paper's list: see the scene's comments
    assert out["reference_frequencies"] == paper
    assert np.allclose(out["frequency_ratio"], f / paper, rtol=1e-12)


@pytest.mark.parametrize("v_slide", [3.0, 5.0])
def test_spectrum_peaks_lie_within_one_bin_of_the_natural_frequencies(v_slide):
    out = _spectrum((f"v_slide={v_slide}",))
    peaks, df = np.array(out["spectrum_peaks"]), out["frequency_bin"]
    assert out["impulse_rate"] == pytest.approx(v_slide / 0.01)
    for f in _exact():
        assert np.min(np.abs(peaks - f)) <= df, (f, peaks)


@pytest.mark.parametrize("derivative", [0, 1])
def test_modal_impulse_train_is_the_damped_sine(derivative):
    omega, zeta, rate = 2 * np.pi * 150.0, 0.02, 4000.0
    t = np.arange(2000) / rate
    times, J = np.array([0.00113, 0.2371]), np.array([0.7, -1.3])   # off the sampling grid
    q = modal_train(omega, zeta, 1 / rate, len(t), times, J, derivative)
    wd, a = omega * np.sqrt(1 - zeta**2), zeta * omega
    expected = np.zeros_like(t)
    for tk, jk in zip(times, J):
        s = np.clip(t - tk, 0, None)
        h = np.sin(wd * s) / wd if derivative == 0 else np.cos(wd * s) - a / wd * np.sin(wd * s)
        expected += np.where(t >= tk, jk * np.exp(-a * s) * h, 0.0)
    assert np.max(np.abs(q - expected)) <= 1e-10 * np.max(np.abs(expected))


@pytest.mark.parametrize("key, value, named", [
    ("damping", 1.5, "damping"),
    ("speed", -1.0, "speed"),
    ("impulse", "2*y", "impulse"),
    ("sample_rate", 8000.0, "sample_rate"),       # below twice the 6th mode's frequency: aliasing
    ("input", "w", "input"),                      # a continuum has no named coordinates
    ("wobble", 1, "wobble"),
    ("couple", "x*zz", "couple"),                 # unknown name in the couple's expression
    ("couple", [1.0], "couple"),                  # not a number or an expression
])
def test_bad_spectrum_keys_exit_2_naming_the_key(tmp_path, key, value, named):
    data = tomllib.loads(SCENE.read_text())
    data["analysis"][1][key] = value
    path = tmp_path / "bad.toml"
    path.write_text(_toml(data))
    run = subprocess.run([sys.executable, "-m", "mechgen", "run", str(path)], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 2, run.stderr
    assert named in run.stderr


def _toml(data: dict) -> str:
    """A tiny TOML writer for the scene's shapes (scalars, [params], [[analysis]])."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace('"', '\\"') + '"'
        return repr(v)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, (dict, list))]
    lines += ["[params]"] + [f"{k} = {value(v)}" for k, v in data["params"].items()]
    for a in copy.deepcopy(data["analysis"]):
        lines += ["[[analysis]]"] + [f"{k} = {value(v)}" for k, v in a.items()]
    return "\n".join(lines) + "\n"


def test_a_lumped_model_matches_direct_integration_with_velocity_jumps():
    """Two masses, blows on x1 every spacing / speed s, x2 recorded: the modal sum against scipy's DOP853 on
    M q'' + C q' + K q = 0 between blows (each blow a jump M^-1 e_1 J of q'), C = M Phi diag(2 zeta omega) Phi^T M
    the modal damping (Phi mass-normalised)."""
    import mechgen
    from mechgen.analyses.public import analysis
    from scipy.integrate import solve_ivp

    system = mechgen.compile(str(ROOT / "tests" / "models" / "two_masses.py"), backend="numpy")
    zeta, rate, t_end = 0.01, 2000.0, 0.3
    res = analysis("spectrum", system, speed=2.0, spacing=0.1, stop=0.5, t_end=t_end, sample_rate=rate,
                   input="x1", output="x2", modes=2, damping=zeta, impulse="0.5 + x", series=10**6).outputs
    M, K = np.diag([1.0, 2.0]), np.array([[6.0e4, -2.0e4], [-2.0e4, 8.0e4]])
    w2, phi = np.linalg.eigh(np.linalg.solve(np.sqrt(M), np.linalg.solve(np.sqrt(M), K).T))
    phi = np.linalg.solve(np.sqrt(M), phi)
    C = M @ phi @ np.diag(2 * zeta * np.sqrt(w2)) @ phi.T @ M
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    blows = [(0.05 * k, 0.5 + 0.1 * k) for k in range(6)]          # t_k = x_k / v, J = 0.5 + x_k
    t = np.arange(int(t_end * rate)) / rate
    state, x2 = np.zeros(4), np.zeros_like(t)
    edges = [b[0] for b in blows] + [t_end]
    for (tk, J), t_next in zip(blows, edges[1:]):
        state = state + np.r_[0.0, 0.0, J / 1.0, 0.0]
        inside = (t >= tk) & (t < t_next)
        sol = solve_ivp(lambda _, y: A @ y, (tk, t_next), state, method="DOP853", rtol=1e-11, atol=1e-14,
                        dense_output=True)
        x2[inside] = sol.sol(t[inside])[1]
        state = sol.y[:, -1]
    assert res["impulses"] == 6
    assert np.max(np.abs(np.array(res["response"]) - x2)) <= 1e-7 * np.max(np.abs(x2))
    assert np.allclose(res["natural_frequencies"], np.sqrt(w2) / (2 * np.pi), rtol=1e-12)


def test_couple_impulse_against_the_pinned_pinned_modal_sum():
    """A tangential impulse J_t on an interface at e from the neutral axis acts as the couple C = e J_t. One
    couple C at x0 on a pinned-pinned beam (modes phi_n = sqrt(2/(rho A L)) sin(n pi x/L), omega_n =
    (n pi/L)^2 sqrt(EI/(rho A)); Blevins table 8-1) gives w(x, t) = sum_n phi_n(x) C phi_n'(x0) sin(omega_n t)
    / omega_n (undamped), and a transverse impulse J adds sum_n phi_n(x) J phi_n(x0) sin(omega_n t)/omega_n.
    The FE record (6 modes, cubic Hermite) against the exact 6-mode shapes with the FE's own omega_n (their
    h^4 error, 8e-5 for mode 6 at N = 32, is tested above; over 0.01 s it would shift mode 6 by 0.14 rad):
    this checks the projection of the force and of the couple (the slope row) on the modes. Measured: 2.7e-5
    of the peak at N = 32, 8e-7 at N = 64 (the mode shapes' error)."""
    L, d, E, rho = 0.28, 0.03, 70e9, 2700.0
    A = np.pi * d**2 / 4
    x0, obs, C, J, rate, t_end = 0.07, 0.2, 0.3, 0.5, 400_000.0, 0.01
    errors = []
    for n_el in (32, 64):
        out = _spectrum(("bc=pinned-pinned", f"N={n_el}"), speed=1.0, spacing=1.0, start=x0, stop=x0,
                        t_end=t_end, sample_rate=rate, impulse=J, couple=C, observe=obs, damping=0.0, modes=6,
                        series=4000)
        t = np.asarray(out["t"])
        k = np.arange(1, 7)[:, None] * np.pi / L
        omega = 2 * np.pi * np.asarray(out["natural_frequencies"])[:, None]
        norm = np.sqrt(2 / (rho * A * L))
        drive = C * norm * k * np.cos(k * x0) + J * norm * np.sin(k * x0)
        exact = np.sum(norm * np.sin(k * obs) * drive * np.sin(omega * t) / omega, axis=0)
        assert out["impulses"] == 1
        errors.append(np.max(np.abs(np.asarray(out["response"]) - exact)) / np.max(np.abs(exact)))
    assert errors[1] < 2e-6 and errors[1] < errors[0] / 10
