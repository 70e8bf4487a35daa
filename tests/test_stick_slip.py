"""Stick-slip-separation contact (mechgen/models/stick_slip_contact.py) and the periodic analysis.

References: the Jenkins element (constant normal load N, u = U cos(theta), theta = omega t,
Delta = mu N / k_u < U) has the steady loop f = mu N - k_u (U - u) on [0, beta] and f = -mu N on
[beta, pi] (f(theta + pi) = -f(theta)), cos(beta) = 1 - 2 Delta / U. Its loop area is
W = 4 mu N (U - Delta), and its first harmonic (Griffin 1980, ASME J. Eng. Power 102, 329-333; Yang,
Chu & Menq 1998, J. Sound Vib. 210, eq. for the constant-normal-load case), derived by integrating the
two branches: k_eq = (1/(pi U)) int f cos = (k_u / pi) (beta - sin(2 beta) / 2) and
c_eq = -(1/(pi U omega)) int f sin = 4 mu N (1 - Delta / U) / (pi U omega) = W / (pi omega U^2).
Below the threshold (k_u U < mu N) the contact sticks: W = 0, k_eq = k_u, c_eq = 0.
With a variable normal load the loop area int f du equals the friction work int f dw (since
f du = f dw + d(f^2 / (2 k_u)) and the spring energy returns over a period).
"""
import math

import numpy as np
import pytest

import mechgen
from mechgen.analyses.public import analysis
from mechgen.errors import ConvergenceError

FREE = ["k_u", "k_v", "mu", "N", "amplitude", "normal_amplitude", "phase", "omega"]


@pytest.fixture(scope="module")
def system():
    return mechgen.compile("stick_slip_contact", {}, free=FREE)


def cycle(system, omega=1.0, displacement="tangential_displacement", **params):
    s = system.with_params(omega=omega, **params)
    return analysis("periodic", s, period=2 * math.pi / omega, force_output="friction_force",
                    displacement_output=displacement).outputs


def jenkins(k_u, mu, N, U, omega):
    d = mu * N / k_u
    beta = math.acos(1 - 2 * d / U)
    w = 4 * mu * N * (U - d)
    return w, k_u / math.pi * (beta - math.sin(2 * beta) / 2), w / (math.pi * omega * U**2)


@pytest.mark.parametrize("k_u, mu, N, U, omega", [(1.0, 0.3, 1.0, 1.0, 1.0), (50.0, 0.5, 2.0, 0.3, 3.0),
                                                  (1.0, 0.2, 1.0, 0.21, 1.0)])
def test_jenkins_closed_forms(system, k_u, mu, N, U, omega):
    out = cycle(system, omega, k_u=k_u, mu=mu, N=N, amplitude=U)
    w, k, c = jenkins(k_u, mu, N, U, omega)
    assert out["energy_per_cycle"] == pytest.approx(w, rel=1e-8)
    assert out["equivalent_stiffness"] == pytest.approx(k, rel=1e-8)
    assert out["equivalent_damping"] == pytest.approx(c, rel=1e-8)
    assert out["periodicity_error"] < 1e-9


def test_below_threshold_sticks(system):
    out = cycle(system, k_u=1.0, mu=0.3, N=1.0, amplitude=0.2)
    assert abs(out["energy_per_cycle"]) < 1e-12
    assert out["equivalent_stiffness"] == pytest.approx(1.0, rel=1e-10)
    assert abs(out["equivalent_damping"]) < 1e-12
    assert out["cycle_events"] == []


def test_separation_loop_area_is_friction_work(system):
    params = dict(k_u=1.0, k_v=1.0, mu=0.3, N=1.0, amplitude=1.0, normal_amplitude=1.5, phase=0.7)
    out = cycle(system, **params)
    work = cycle(system, displacement="slip", **params)["energy_per_cycle"]
    assert "separated" in {e["to"] for e in out["cycle_events"]}
    assert "stick" in {e["to"] for e in out["cycle_events"] if e["from"] == "separated"}
    assert out["energy_per_cycle"] > 0.1
    assert out["energy_per_cycle"] == pytest.approx(work, rel=1e-10)


@pytest.mark.parametrize("k_u", [1e6, 1e10])
def test_stiff_contact(system, k_u):
    """k_u = 1e10 N/m (Delta = mu N / k_u = 3e-11 m against U = 1 m): the Jenkins closed forms to 1e-8. The
    state is the friction force f, not the slip w: f = k_u (u - w) from a slip state would carry k_u rtol U
    (3e-2 of mu N at rtol 1e-12), and k_u ulp(U) even at round-off. The stick phases last 2 Delta / U rad
    (6e-11 rad) between slips of pi rad: two events 6e-11 rad apart every half period, located apart."""
    out = cycle(system, k_u=k_u, mu=0.3, N=1.0, amplitude=1.0)
    w, k, c = jenkins(k_u, 0.3, 1.0, 1.0, 1.0)
    assert out["energy_per_cycle"] == pytest.approx(w, rel=1e-8)
    assert out["equivalent_damping"] == pytest.approx(c, rel=1e-8)
    # k_eq ~ (k_u / pi)(4/3) beta^3 (Delta / U)^(3/2) -> small: compare on the scale of mu N / U
    assert out["equivalent_stiffness"] == pytest.approx(k, abs=1e-8 * 0.3)
    # the period starts at a reversal (t = 0, stick): leaves it, reverses at pi, leaves again; no chatter
    assert [e["to"] for e in out["cycle_events"]] == ["slip_negative", "stick", "slip_positive"]


@pytest.mark.parametrize("loop", ["c", "python"])
@pytest.mark.parametrize("eps", [1e-6, 1e-8, 1e-10, 2.5e-13])
def test_long_stick_short_slip(system, eps, loop):
    """U = Delta (1 + eps): the slip lasts pi - beta ~ 2 sqrt(eps) rad of each half period (2e-5 rad at
    1e-10; 1e-6 rad at 2.5e-13, a stick 3e6 times longer than the slip, its guard past zero by 1.5e-13 N
    against mu N = 0.3 N). Both event loops find every slip (split at the cubic's dip: events.py, "Missed
    events"; before, slips under 2^-12 of a step were missed). W = 4 mu N Delta eps against the closed form
    to 5e-13 of mu N U: the loop area's floor at rtol 1e-12 (1.2e-13 of mu N U seen at every eps), so its
    relative error grows as 1/eps (0.12 at 2.5e-13, where W itself is 1e-12 of mu N U)."""
    U = 0.3 * (1 + eps)
    s = system.with_params(omega=1.0, k_u=1.0, mu=0.3, N=1.0, amplitude=U)
    out = analysis("periodic", s, period=2 * math.pi, force_output="friction_force",
                   displacement_output="tangential_displacement", loop=loop).outputs
    w, k, c = jenkins(1.0, 0.3, 1.0, U, 1.0)
    assert [e["to"] for e in out["cycle_events"]] == ["slip_negative", "stick", "slip_positive"]
    assert out["energy_per_cycle"] == pytest.approx(w, abs=5e-13 * 0.3 * U)
    assert out["equivalent_stiffness"] == pytest.approx(k, rel=1e-8)


def test_grazing_slip_threshold(system):
    """k_u U = mu N exactly: f reaches mu n with zero rate at the reversal; no slip, W = 0."""
    out = cycle(system, k_u=1.0, mu=0.3, N=1.0, amplitude=0.3)
    assert abs(out["energy_per_cycle"]) < 1e-10
    assert out["equivalent_stiffness"] == pytest.approx(1.0, rel=1e-8)


def test_no_steady_state_names_time_and_mode(system):
    """A drive period that is not the drive's (T = 2 pi / 1.37) never repeats: clear error, bounded."""
    s = system.with_params(k_u=1.0, mu=0.3, N=1.0, amplitude=1.0)
    with pytest.raises(ConvergenceError, match=r"no periodic steady state within 8 periods: at t = .* \(mode "):
        analysis("periodic", s, period=2 * math.pi / 1.37, force_output="friction_force",
                 displacement_output="tangential_displacement", max_periods=8)


def test_scene_names_and_values(tmp_path):
    """scenes/stick_slip_element.toml: the issue's output names, the Jenkins closed forms at its parameters."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    scene = Path(__file__).resolve().parents[1] / "scenes" / "stick_slip_element.toml"
    out = tmp_path / "r.json"
    proc = subprocess.run([sys.executable, "-m", "mechgen", "run", str(scene), "--json", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(out.read_text())["analyses"][0]["outputs"]
    w, k, c = jenkins(1.0, 0.3, 1.0, 1.0, 1.0)
    assert result["energy_per_cycle"] == pytest.approx(w, rel=1e-8)
    assert result["equivalent_stiffness"] == pytest.approx(k, rel=1e-8)
    assert result["equivalent_damping"] == pytest.approx(c, rel=1e-8)


def stop_operator(k_u, k_v, mu, N, U, V, phase, per, periods=3):
    """Independent reference for a variable normal load: the contact as a stop operator sampled on a grid.

    Quasi-static Jenkins element = the stop operator (Krasnosel'skii & Pokrovskii 1989, "Systems with
    Hysteresis", ch. 1; Visintin 1994): f_{k+1} = clamp(f_k + k_u (u_{k+1} - u_k), -mu n+_{k+1}, mu n+_{k+1}),
    n+ = max(N + k_v v, 0), exact in stick and in slip; at a reversal between samples it errs by O(dt^2)
    (the slip rate vanishes there), and at re-contact the step restarts from f = 0 at the exact root of n.
    Over the last of ``periods`` periods (theta = omega t, u = U cos theta): W = int f du, and the first
    harmonic k_eq = int f cos / (pi U), c_eq = -int f sin / (pi U omega) (omega = 1), by the trapezoid rule."""
    from scipy.optimize import brentq
    th = np.linspace(0, 2 * np.pi * periods, per * periods + 1)
    u = U * np.cos(th)
    n = N + k_v * V * np.cos(th + phase)
    lim = mu * np.maximum(n, 0.0)
    f = np.empty_like(th)
    f[0] = lim[0]
    for k in range(th.size - 1):
        if n[k] <= 0 < n[k + 1]:
            tc = brentq(lambda x: N + k_v * V * np.cos(x + phase), th[k], th[k + 1], xtol=1e-15)
            fk = k_u * (u[k + 1] - U * np.cos(tc))
        else:
            fk = f[k] + k_u * (u[k + 1] - u[k])
        f[k + 1] = min(max(fk, -lim[k + 1]), lim[k + 1])
    last = slice(per * (periods - 1), per * periods + 1)
    t, fl = th[last], f[last]
    w = np.full(t.size, t[1] - t[0])
    w[0] = w[-1] = w[0] / 2
    return np.array([np.sum(w * fl * -U * np.sin(t)), np.sum(w * fl * np.cos(t)) / (np.pi * U),
                     -np.sum(w * fl * np.sin(t)) / (np.pi * U)])


@pytest.mark.parametrize("V", [0.5, 1.5])
def test_variable_normal_load_against_stop_operator(system, V):
    """Variable normal load n = N + k_v V cos(omega t + 0.7), with (V = 1.5) and without (V = 0.5) separation:
    W, k_eq and c_eq against the sampled stop operator, whose own convergence (2^16 -> 2^18 samples a period,
    second order) is checked first: its change bounds its error (< 1e-9; 1e-10 seen)."""
    params = dict(k_u=1.0, k_v=1.0, mu=0.3, N=1.0, amplitude=1.0, normal_amplitude=V, phase=0.7)
    out = cycle(system, **params)
    got = np.array([out["energy_per_cycle"], out["equivalent_stiffness"], out["equivalent_damping"]])
    coarse = stop_operator(1.0, 1.0, 0.3, 1.0, 1.0, V, 0.7, per=2**16)
    fine = stop_operator(1.0, 1.0, 0.3, 1.0, 1.0, V, 0.7, per=2**18)
    assert np.all(np.abs(fine - coarse) < 1e-9 * np.abs(fine))
    assert np.all(np.abs(got - fine) < 2e-9 * np.abs(fine))
    if V > 1:
        assert "separated" in {e["to"] for e in out["cycle_events"]}
