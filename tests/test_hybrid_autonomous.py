"""Periodic orbits of nonsmooth models with stick-slip (issue 27, item 6): the autonomous stick-slip cycle of a mass
on a moving belt (shooting on the return map to a Poincare section at an event), and the forced Jenkins orbit of
the stick-slip contact (an event at the period's boundary).

References, independent of mechgen:

* Coulomb friction with a static coefficient mu_s above the kinetic mu_k, m x'' + k x = F, w = sqrt(k / m): the
  cycle sticks from x = (2 mu_k - mu_s) N / k to mu_s N / k at the belt's speed v_b (time 2 D / v_b,
  D = (mu_s - mu_k) N / k), then slips on the harmonic arc x = x_k + R sin(w t + theta0) about x_k = mu_k N / k,
  R = sqrt(D^2 + (v_b / w)^2), theta0 = atan2(D, v_b / w), from x' = v_b back to x' = v_b at x = x_k - D (time
  (2 pi - 2 theta0) / w). Period, largest |x| = x_k + R and the event times in closed form.
  (With mu_s = mu_k the stick phase has zero length and the cycle grazes v_rel = 0: a family of slip orbits
  about x_k, not an isolated cycle; hence mu_s > mu_k here.)
* A Stribeck curve: a hand-written event-driven integration (scipy's solve_ivp, the slip arc from the breakaway
  point to the catch, the stick phase at v_b by hand).
* The return map's Jacobian and the monodromy against central differences of that hand-written flow.
* The Jenkins element under u = U cos(omega t) (Griffin 1980; Yang, Chu & Menq 1998): energy per cycle
  4 mu N (U - mu N / k_u), slip starting where cos(omega t) = 1 - 2 mu N / (k_u U).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError
from mechgen.runtime.integration.hybrid_autonomous import return_map

#: m, k, N, mu_s, mu_k, v_belt (no round numbers, so that no term cancels by accident)
P = dict(m=0.7, k=1.9, N=1.3, mu_s=0.45, mu_k=0.25, v_belt=0.35)


@pytest.fixture(scope="module")
def belt():
    return mechgen.compile("belt_stick_slip", backend="c").with_params(**P)


def coulomb_cycle(m, k, N, mu_s, mu_k, v_belt):
    """(period, largest |x|, stick time) of the Coulomb stick-slip cycle (module doc)."""
    w = math.sqrt(k / m)
    D, xk = (mu_s - mu_k) * N / k, mu_k * N / k
    R, theta0 = math.hypot(D, v_belt / w), math.atan2(D, v_belt / w)
    stick = 2 * D / v_belt
    return (2 * math.pi - 2 * theta0) / w + stick, max(xk + R, abs(xk - R)), stick


def test_coulomb_cycle_closed_form(belt):
    out = mechgen.periodic_orbit(belt, period=5.0, section="breakaway")
    T, peak, stick = coulomb_cycle(**P)
    # shooting at Newton rtol 1e-9 (DOP853 at 1e-11): the period is an event time, found to ~1e-12
    assert out["period"] == pytest.approx(T, rel=1e-8, abs=0)
    # the amplitude's parabola through the largest of 4096 samples: error O(h^3) ~ 1e-11
    assert out["amplitude"]["x"] == pytest.approx(peak, rel=1e-8, abs=0)
    events = out["events"]
    assert [e["guard"] for e in events] == ["catch", "breakaway"]
    assert events[1]["t"] - events[0]["t"] == pytest.approx(stick, rel=1e-8, abs=0)
    assert out["section"] == "breakaway" and out["start_mode"] == "slip"
    mu = np.array(out["multipliers"])
    # the trivial multiplier along the cycle, and 0: the stick phase forgets the state (the catch's reset x' = v_b)
    assert mu[0] == pytest.approx([1.0, 0.0], abs=1e-9)
    assert mu[1] == pytest.approx([0.0, 0.0], abs=1e-9)
    assert out["stability"] == "stable"
    assert out["trajectory"]["x"][0] == pytest.approx(P["mu_s"] * P["N"] / P["k"], rel=1e-12)


STRIBECK = dict(stribeck=1.0, v_s=0.08)


def friction(v_rel, p):
    return p["N"] * (p["mu_k"] + p["stribeck"] * (p["mu_s"] - p["mu_k"]) * math.exp(-abs(v_rel) / p["v_s"]))


def hand_slip(x0, v0, p):
    """The hand-written slip arc from (x0, v0) until v_rel = v_b - x' falls through 0: (t, x, v) at the catch."""
    def rhs(t, y):
        return [y[1], (friction(p["v_belt"] - y[1], p) - p["k"] * y[0]) / p["m"]]

    def catch(t, y):
        return p["v_belt"] - y[1] if t > 0 else 1.0  # (the start sits on v_rel = 0)

    catch.terminal, catch.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 100.0), [x0, v0], method="DOP853", rtol=1e-13, atol=1e-15, events=catch)
    assert sol.status == 1
    return sol.t_events[0][0], sol.y_events[0][0][0], sol.y_events[0][0][1]


def test_stribeck_cycle_against_hand_integration(belt):
    p = {**P, **STRIBECK}
    out = mechgen.periodic_orbit(belt.with_params(**STRIBECK), period=5.0, section="breakaway")
    x_break = p["mu_s"] * p["N"] / p["k"]
    t_slip, x_catch, _ = hand_slip(x_break, p["v_belt"], p)
    assert abs(p["k"] * x_catch) < p["mu_s"] * p["N"]  # the catch sticks
    T = t_slip + (x_break - x_catch) / p["v_belt"]
    # both integrate the same arc at rtol <= 1e-11: the event times agree to ~1e-11
    assert out["period"] == pytest.approx(T, rel=1e-8, abs=0)
    assert out["events"][0]["t"] == pytest.approx(t_slip, rel=1e-8, abs=0)


def hand_return(x0, v0, p):
    """From (x0, v0) just after a catch (stick at speed v0: x'' = 0) to just after the next catch: (x, v, time)."""
    x_break = p["mu_s"] * p["N"] / p["k"]
    t_stick = (x_break - x0) / v0
    t_slip, x, _ = hand_slip(x_break, v0 * (1 - 64 * 2.0**-52), p)  # the model's breakaway nudge (its doc)
    return np.array([x, p["v_belt"]]), t_stick + t_slip


def test_return_map_jacobian_against_differences(belt):
    """The section at the catch: P(x0, v0) depends on v0 (the slip starts at the stick's speed), so P_x is not 0;
    P_x and the monodromy M = P_x - f+ (d tau / d x0) against central differences of the hand-written flow."""
    p = {**P, **STRIBECK}
    system = belt.with_params(**STRIBECK)
    x0 = np.array([0.1, p["v_belt"] * 0.98])
    rm = return_map(system, x0, system.modes.index("stick"), "catch", 50.0)
    x_hand, tau = hand_return(x0[0], x0[1], p)
    assert rm.x == pytest.approx(x_hand, rel=1e-9, abs=1e-12)
    assert rm.period == pytest.approx(tau, rel=1e-9)
    h = 1e-5
    cols, dtau = [], []
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        (xp, tp), (xm, tm) = hand_return(*(x0 + e), p), hand_return(*(x0 - e), p)
        cols.append((xp - xm) / (2 * h))
        dtau.append((tp - tm) / (2 * h))
    P_fd = np.column_stack(cols)
    # central differences of h = 1e-5 on an integration at rtol 1e-13: truncation h^2 ~ 1e-10, noise 1e-13 / h
    assert rm.jacobian == pytest.approx(P_fd, abs=1e-7)
    assert abs(P_fd[0, 1]) > 0.1  # not a trivial check
    f_plus = np.array([p["v_belt"], 0.0])  # dx/dt just after the catch: stick, x' = v_b, x'' = 0
    assert rm.monodromy == pytest.approx(P_fd - np.outer(f_plus, dtau), abs=1e-7)


def test_jenkins_orbit_energy_and_reversal():
    """The forced stick-slip contact's orbit reverses at t = 0 = T (an event at the period's boundary)."""
    k_u, mu, N, U, omega = 1.7, 0.3, 1.1, 0.9, 1.3
    system = mechgen.compile("stick_slip_contact", backend="c").with_params(k_u=k_u, mu=mu, N=N, amplitude=U,
                                                                              omega=omega)
    samples = 100001
    out = mechgen.periodic_orbit(system, frequency=omega, samples=samples)
    delta = mu * N / k_u
    assert out["period"] == pytest.approx(2 * math.pi / omega, rel=1e-15)
    f = np.array(out["trajectory"]["friction_force"])
    t = np.array(out["t"])
    assert f[0] == pytest.approx(mu * N, rel=1e-9)
    # the flat slip phase meets the stick phase in a kink: the amplitude is not a parabola's overshoot across it
    assert out["amplitude"]["f"] == pytest.approx(mu * N, rel=1e-9)
    slip = math.acos(1 - 2 * delta / U) / omega
    assert out["events"][0]["t"] == pytest.approx(slip, rel=1e-9)
    assert [e["guard"] for e in out["events"]][-1] == "stop_forward"
    du = -U * omega * np.sin(omega * t)
    g = f * du
    W = float(np.sum((g[1:] + g[:-1]) * np.diff(t)) / 2)
    # the trapezoid rule on 1e5 intervals of a piecewise-smooth f du/dt: error ~ T h^2 max|g''| / 12 ~ 1e-9
    # (measured 1.2e-10)
    assert W == pytest.approx(4 * mu * N * (U - delta), rel=1e-8)
    assert np.array(out["multipliers"])[0] == pytest.approx([0.0, 0.0], abs=1e-9)  # a slip forgets f


def test_section_names_a_guard(belt):
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(belt, period=5.0, section="brakeaway")
    assert err.value.key.endswith("section") and "breakaway" in str(err.value)


def test_section_refused_for_forced_and_smooth(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text('model = "belt_stick_slip"\nbackend = "c"\n[[analysis]]\nname = "o"\nkind = "periodic_orbit"\n'
                     'frequency = 1.0\nsection = "breakaway"\n')
    with pytest.raises(InputError) as err:
        mechgen.run(str(scene))
    assert "section" in str(err.value)
    scene.write_text('model = "van_der_pol"\n[[analysis]]\nname = "o"\nkind = "periodic_orbit"\n'
                     'period = 6.0\nsection = "breakaway"\nq0 = { x = 2.0 }\n')
    with pytest.raises(InputError) as err:
        mechgen.run(str(scene))
    assert "section" in str(err.value)


def test_branch_in_belt_speed_closed_form(tmp_path):
    """continuation about the autonomous orbit: the Coulomb cycle's period along v_belt against the closed form."""
    scene = tmp_path / "belt.toml"
    scene.write_text('model = "belt_stick_slip"\nbackend = "c"\n[params]\n'
                     + "".join(f"{k} = {v}\n" for k, v in P.items())
                     + '[[analysis]]\nname = "cycle"\nkind = "periodic_orbit"\nperiod = 5.0\n'
                     '[[analysis]]\nname = "speed"\nkind = "continuation"\nabout = "cycle"\nparameter = "v_belt"\n'
                     'stop = 0.8\nmax_step = 0.1\n')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    assert out["status"] == "lam_max" and out["points"] >= 5
    for point in out["branch"]:
        T, peak, _ = coulomb_cycle(**{**P, "v_belt": point["v_belt"]})
        # each point a converged shooting orbit (Newton's corrector at 1e-9, DOP853 at 1e-11)
        assert point["period"] == pytest.approx(T, rel=1e-8, abs=0)
        assert point["amplitude"]["x"] == pytest.approx(peak, rel=1e-6)  # 1024 phases: parabola error O(h^3)
        assert point["multipliers"][1] == pytest.approx([0.0, 0.0], abs=1e-9)
    assert out["special_points"] == []


def test_switch_branches_refused_for_an_autonomous_hybrid_orbit(tmp_path):
    scene = tmp_path / "belt.toml"
    scene.write_text('model = "belt_stick_slip"\nbackend = "c"\n[[analysis]]\nname = "cycle"\nkind = "periodic_orbit"\n'
                     'period = 6.0\n[[analysis]]\nname = "speed"\nkind = "continuation"\nabout = "cycle"\n'
                     'parameter = "v_belt"\nstop = 0.6\nswitch_branches = true\n')
    with pytest.raises(InputError) as err:
        mechgen.run(str(scene))
    assert "switch_branches" in str(err.value)


def test_equal_coefficients_graze(belt):
    """mu_s = mu_k: the slip arc is the circle x = x_k + (v_b / w) sin(w t), back at x' = v_b tangentially after
    2 pi / w; the catch is reported as grazing (its saltation matrix and the multipliers are not to be trusted)."""
    system = belt.with_params(mu_k=P["mu_s"])
    out = mechgen.periodic_orbit(system, period=5.0, section="breakaway")
    w = math.sqrt(P["k"] / P["m"])
    assert out["grazing"] == ["catch"]
    # a tangential zero, v_rel ~ (t - T)^2, is located to about sqrt(round-off) ~ 1e-8 in time (measured 5e-13)
    assert out["period"] == pytest.approx(2 * math.pi / w, rel=1e-7)
    assert out["amplitude"]["x"] == pytest.approx(P["mu_s"] * P["N"] / P["k"] + P["v_belt"] / w, rel=1e-6)


def test_jenkins_orbit_branch_in_the_normal_load(tmp_path):
    """continuation of the forced stick-slip orbit (a boundary event at every point) in N: the reversal force
    f(0) = mu N and the largest |f| = mu N along the branch, while k_u U > mu N (slip every half period)."""
    scene = tmp_path / "jenkins.toml"
    scene.write_text('model = "stick_slip_contact"\nbackend = "c"\n[[analysis]]\nname = "orbit"\n'
                     'kind = "periodic_orbit"\nfrequency = "omega"\n[[analysis]]\nname = "load"\n'
                     'kind = "continuation"\nabout = "orbit"\nparameter = "N"\nstop = 2.5\nmax_step = 0.3\n')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    assert out["status"] == "lam_max" and out["points"] >= 4
    for point in out["branch"]:
        # Newton's corrector at rtol 1e-9 on f(0); the peak of 1024 phases on the flat slip part is exact
        assert point["start"]["f"] == pytest.approx(0.3 * point["N"], rel=1e-8)
        assert point["amplitude"]["f"] == pytest.approx(0.3 * point["N"], rel=1e-8)
        assert point["events_per_period"] == 4


def test_a_short_period_guess_is_corrected_by_the_settling_run(belt):
    """period = 1 (the cycle's is 3.9): the settling run's return time replaces the guess, so that the return map,
    bounded at 3 periods, runs past the real return."""
    out = mechgen.periodic_orbit(belt, period=1.0, section="breakaway")
    assert out["period"] == pytest.approx(coulomb_cycle(**P)[0], rel=1e-8, abs=0)  # as the closed-form test


def test_a_parameter_named_amplitude_keeps_the_orbit_amplitude(tmp_path):
    """Continued in the contact's forcing ``amplitude`` U (a model parameter whose name is also a branch output):
    each point carries U under ``amplitude`` and the orbit's max |f| under ``orbit_amplitude``, which stays
    mu N = 0.3 (the slider saturates while k_u U > mu N) as U grows; the figure draws it."""
    scene = tmp_path / "jenkins.toml"
    scene.write_text('model = "stick_slip_contact"\nbackend = "c"\n[[analysis]]\nname = "orbit"\n'
                     'kind = "periodic_orbit"\nfrequency = "omega"\n[[analysis]]\nname = "in_U"\n'
                     'kind = "continuation"\nabout = "orbit"\nparameter = "amplitude"\nstop = 2.0\n'
                     'max_step = 0.3\n')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    us = [point["amplitude"] for point in out["branch"]]
    assert us[0] == pytest.approx(1.0) and us[-1] == pytest.approx(2.0) and us == sorted(us)
    for point in out["branch"]:
        assert point["orbit_amplitude"]["f"] == pytest.approx(0.3, rel=1e-8)
    assert main(["run", str(scene), "--plot", str(tmp_path / "figures")]) == 0
    assert (tmp_path / "figures" / "jenkins_in_U.png").stat().st_size > 0
