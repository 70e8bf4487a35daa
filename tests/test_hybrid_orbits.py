"""Periodic orbits of hybrid models through their events (issue 27, item 6): saltation matrices from the generated
guard and reset derivatives, the monodromy of an impact oscillator's orbit, shooting, grazing.

The impact oscillator (Shaw & Holmes, J. Appl. Mech. 50, 1983): x'' + c x' + x = F cos(w t) for x < d; at x = d
the velocity resets to -e x'. References:

* the saltation matrix of this impact in closed form: with g = x - d, g_x = (1, 0), R_x = diag(1, -e) and
  f- = (v, a-), f+ = (-e v, a+), S = R_x + (f+ - R_x f-) g_x^T / v = [[-e, 0], [(a+ + e a-) / v, -e]];
* det S = e^2, so the monodromy of an orbit with k impacts per period has det = e^(2k) exp(-c T) (Liouville's
  formula between the impacts) - a closed form;
* the monodromy against central differences of an independent event-driven flow written here by hand (scipy's
  solve_ivp, DOP853 at rtol 1e-12, a terminal event at x = d, the reset applied by hand).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechgen
from mechgen.runtime.integration.hybrid_monodromy import flow_jacobian, periodic_orbit

C, F, W, D, E = 0.05, 0.6, 0.8, 0.5, 0.7
T = 2 * math.pi / W

MODEL = f'''"""Impact oscillator: x'' + c x' + x = F cos(w t) for x < d; at x = d, x' -> -e x'."""
import sympy as sp
from mechgen import Model, Param

model = Model("impact_orbit", doc=__doc__)
model.params(Param("c", {C}), Param("F", {F}), Param("w", {W}), Param("d", {D}), Param("cor", {E}))
model.coordinates("x")
free = model.mode("free")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q: q.x**2 / 2)
model.dissipation(lambda v, p: p.c * v.x**2 / 2)


@model.forces
def drive(p, t):
    return {{"x": p.F * sp.cos(p.w * t)}}


@free.guard(to="free", direction="rising", reset=lambda v, p: {{"x_dot": -p.cor * v.x}})
def stop(q, p):
    return q.x - p.d
'''


@pytest.fixture(scope="module")
def oscillator(tmp_path_factory):
    path = tmp_path_factory.mktemp("impact") / "impact_orbit.py"
    path.write_text(MODEL)
    return mechgen.compile(str(path))


def hand_flow(x0, t_end: float, *, c=C, f=F, w=W, d=D, e=E) -> np.ndarray:
    """The independent event-driven flow map: solve_ivp from impact to impact, the reset applied by hand."""
    def rhs(t, y):
        return [y[1], f * math.cos(w * t) - c * y[1] - y[0]]

    def hit(t, y):
        return y[0] - d

    hit.terminal, hit.direction = True, 1
    t, y = 0.0, np.asarray(x0, float)
    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-14, events=hit)
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1:
            y[1] = -e * y[1]
            y[0] = d - 1e-13  # just below the stop: the event is not found again at once
    return y


def settled(oscillator) -> np.ndarray:
    """The state at t = 60 T (a guess of the period-1 orbit at phase 0)."""
    run = mechgen.simulate(oscillator, t_end=60 * T, samples=2, q0={"x": 0.0})
    return np.array([run["trajectory"]["x"][-1], run["trajectory"]["x_dot"][-1]], float)


def test_saltation_matrix_of_an_impact(oscillator):
    """S at an impact against its closed form [[-e, 0], [(a+ + e a-) / v, -e]] (to 1e-12)."""
    t, v = 1.3, 0.8
    x = np.array([D, v])
    a_minus = F * math.cos(W * t) - C * v - D
    a_plus = F * math.cos(W * t) + C * E * v - D
    S = oscillator.saltation(0, 0, t, x)
    assert S == pytest.approx(np.array([[-E, 0.0], [(a_plus + E * a_minus) / v, -E]]), abs=1e-12)


def test_periodic_orbit_and_its_monodromy(oscillator):
    """Shooting converges to the period-1 orbit (the hand flow maps it onto itself to 1e-9); its monodromy equals
    central differences of the hand flow (to 1e-6: difference step 1e-6, flows at rtol 1e-12) and its determinant
    is e^2 exp(-c T) (one impact per period; to 1e-9)."""
    orbit = periodic_orbit(oscillator, settled(oscillator), T)
    assert len(orbit.events) == 1 and not orbit.grazing
    assert np.max(np.abs(hand_flow(orbit.x0, T) - orbit.x0)) < 1e-9
    h = 1e-6
    columns = [(hand_flow(orbit.x0 + h * e, T) - hand_flow(orbit.x0 - h * e, T)) / (2 * h) for e in np.eye(2)]
    assert orbit.monodromy == pytest.approx(np.column_stack(columns), abs=1e-6)
    assert np.linalg.det(orbit.monodromy) == pytest.approx(E**2 * math.exp(-C * T), rel=1e-9)
    assert np.prod(orbit.multipliers).real == pytest.approx(E**2 * math.exp(-C * T), rel=1e-9)
    assert np.max(np.abs(orbit.multipliers)) < 1  # a stable orbit (the run settled onto it)


def test_flow_jacobian_over_several_impacts(oscillator):
    """From a start off the orbit, over 3 periods (several impacts): the Jacobian equals central differences of the
    hand flow (to 1e-5) and its determinant is e^(2k) exp(-3 c T) with k the impacts met."""
    x0 = np.array([0.1, 0.3])
    fj = flow_jacobian(oscillator, x0, 3 * T)
    k = len(fj.events)
    assert k >= 2
    h = 1e-6
    columns = [(hand_flow(x0 + h * e, 3 * T) - hand_flow(x0 - h * e, 3 * T)) / (2 * h) for e in np.eye(2)]
    assert fj.phi == pytest.approx(np.column_stack(columns), abs=1e-5, rel=1e-5)
    assert np.linalg.det(fj.phi) == pytest.approx(E ** (2 * k) * math.exp(-3 * C * T), rel=1e-8)


def test_a_grazing_impact_is_reported(tmp_path):
    """Unforced and undamped, x = A cos t with A = d (1 + 1e-8) reaches the stop at t ~ 2 pi with
    v = A sin(theta), cos(theta) = d / A: v ~ d sqrt(2e-8) = 7e-5, so |dg/dt| / (|g_x| |f|) ~ v / d = 1.4e-4 <
    1e-3, a grazing event (the saltation matrix grows like 1/v there); the orbit of the forced oscillator, which
    hits the stop at |v| ~ 0.85, is not."""
    path = tmp_path / "graze.py"
    path.write_text(MODEL.replace('"impact_orbit"', '"graze"'))
    system = mechgen.compile(str(path), {"F": 0.0, "c": 0.0})
    fj = flow_jacobian(system, np.array([D * (1 + 1e-8), 0.0]), 7.0)
    assert fj.grazing == (0,)


def test_shooting_that_cannot_converge_says_so(oscillator):
    """Newton limited to one step from a poor guess: a ConvergenceError naming the residual and what to try."""
    from mechgen.errors import ConvergenceError

    with pytest.raises(ConvergenceError) as err:
        periodic_orbit(oscillator, np.array([-2.0, 0.0]), T, max_iter=1)
    assert "|x(T) - x0|" in str(err.value) and "guess" in str(err.value)


# the period-doubling of the one-impact orbit: stop at the equilibrium (d = 0), e = 0.8, F = 1, c = 0.05; the
# orbit's multiplier passes -1 between w = 2.6 and 2.7 (Shaw & Holmes 1983: the flip of the 1-impact orbit)
PD = {"c": 0.05, "f": 1.0, "d": 0.0, "e": 0.8}


def hand_multipliers(w: float, guess: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x0, multipliers) of the 1-impact orbit at w, all by hand: fsolve on the hand flow's x(T) - x0 and the
    eigenvalues of its central-difference Jacobian (step 1e-6)."""
    from scipy.optimize import fsolve

    T = 2 * math.pi / w
    x0 = fsolve(lambda x: hand_flow(x, T, w=w, **PD) - x, guess, xtol=1e-12)
    h = 1e-6
    J = np.column_stack([(hand_flow(x0 + h * u, T, w=w, **PD) - hand_flow(x0 - h * u, T, w=w, **PD)) / (2 * h)
                         for u in np.eye(2)])
    return x0, np.linalg.eigvals(J)


def test_period_doubling_of_the_impact_oscillator_and_its_doubled_orbit(tmp_path):
    """The branch of 1-impact orbits in w from 2.5 to 2.8 meets a PD point; its w against an independent
    computation in the test (the hand flow's orbit and multipliers, Brent on min mu + 1 = 0) to 1e-6 (the
    multipliers by differences: ~1e-7), its multiplier -1 (to 1e-8); just past it the doubled orbit has period 2T,
    is a fixed point of the hand flow over 2T (to 1e-8) and not over T."""
    from scipy.optimize import brentq

    from mechgen.runtime.integration.hybrid_orbit_branch import OrbitFamily, doubled_orbit
    from mechgen.runtime.steady.continuation import continuation
    from mechgen.runtime.steady.cycle_points import cycle_points

    path = tmp_path / "flip.py"
    path.write_text(MODEL.replace('"impact_orbit"', '"flip"'))
    system = mechgen.compile(str(path), {"d": 0.0, "F": 1.0, "c": 0.05, "cor": 0.8, "w": 2.5})
    family = OrbitFamily(system, "w", lambda w: 2 * math.pi / w)
    run = mechgen.simulate(system, t_end=80 * 2 * math.pi / 2.5, samples=2, q0={"x": -0.5})
    start = family.orbit(np.array([run["trajectory"]["x"][-1], run["trajectory"]["x_dot"][-1]]), 2.5)
    eqs = family.equations()
    branch = continuation(eqs, start.x0, 2.5, ds=0.02, ds_max=0.05, lam_max=2.8, max_points=40, progress=False)
    (pd,) = cycle_points(eqs, np.hstack([branch.u, branch.lam[:, None]]), family.multipliers)
    assert pd.type == "PD" and np.min(pd.data["multipliers"].real) == pytest.approx(-1.0, abs=1e-8)

    guess = {"x": start.x0}

    def flip(w):
        guess["x"], mu = hand_multipliers(w, guess["x"])
        return float(np.min(mu.real)) + 1.0

    w_hand = brentq(flip, 2.6, 2.7, xtol=1e-10)
    assert pd.x[-1] == pytest.approx(w_hand, abs=1e-6)

    doubled = doubled_orbit(family, pd.x, 0.02)
    w = pd.x[-1] + 0.02
    assert doubled.period == pytest.approx(2 * 2 * math.pi / w, rel=1e-14)
    assert np.max(np.abs(hand_flow(doubled.x0, doubled.period, w=w, **PD) - doubled.x0)) < 1e-8
    assert np.max(np.abs(hand_flow(doubled.x0, doubled.period / 2, w=w, **PD) - doubled.x0)) > 1e-3


def test_cycle_test_functions():
    """psi_PD = prod (1 + mu) changes sign as a real multiplier passes -1; psi_NS = prod_{i<j} (mu_i mu_j - 1) as a
    complex pair crosses the unit circle, and is_ns tells that from a real pair mu, 1/mu (both vanish there)."""
    from mechgen.runtime.steady.cycle_points import is_ns, ns_value, pd_value, without_trivial

    assert pd_value([-0.9, 0.3]) * pd_value([-1.1, 0.3]) < 0
    inside, outside = 0.99 * np.exp(1j * np.array([0.7, -0.7])), 1.01 * np.exp(1j * np.array([0.7, -0.7]))
    assert ns_value(np.append(inside, 0.2)) * ns_value(np.append(outside, 0.2)) < 0
    assert is_ns(np.exp(1j * np.array([0.7, -0.7]))) and not is_ns(np.array([2.0, 0.5]))
    assert list(without_trivial(np.array([0.3, 1.0 + 1e-9, -0.2]), True)) == [0.3, -0.2]


def test_hybrid_orbit_outputs_and_branch_with_the_doubled_orbit(tmp_path):
    """The analysis layer (mechgen.analyses.hybrid_orbit): the forced orbit's outputs (one impact per period, the
    multipliers' product e^2 exp(-c T), no grazing), and the branch in w through the PD point (multiplier -1 to
    1e-9) with the doubled orbit past it (period 2 T at its own w, two impacts, stable)."""
    from mechgen.analyses.hybrid_orbit import run_hybrid_orbit
    from mechgen.analyses.orbit_branch import run_orbit_branch
    from mechgen.analyses.schema import ParamExpression

    path = tmp_path / "flip.py"
    path.write_text(MODEL.replace('"impact_orbit"', '"flip_kind"'))
    system = mechgen.compile(str(path), {"d": 0.0, "F": 1.0, "c": 0.05, "cor": 0.8, "w": 2.5})
    run = mechgen.simulate(system, t_end=80 * 2 * math.pi / 2.5, samples=2, q0={"x": -0.5})
    guess = np.array([run["trajectory"]["x"][-1], run["trajectory"]["x_dot"][-1]])
    options = {"frequency": ParamExpression(2.5, "w"), "rtol": 1e-9, "atol": 1e-12, "max_iterations": 50,
               "samples": 201}
    out = run_hybrid_orbit(system, options, guess)
    T = 2 * math.pi / 2.5
    assert out["period"] == pytest.approx(T, rel=1e-15) and len(out["events"]) == 1 and out["grazing"] == []
    product = np.prod([complex(*mu) for mu in out["multipliers"]]).real
    assert product == pytest.approx(0.8**2 * math.exp(-0.05 * T), rel=1e-9)
    assert set(out["trajectory"]["mode_series"]) == {0}
    branch = run_orbit_branch(system, {"parameter": "w", "stop": 2.8, "max_step": 0.05, "switch_branches": True,
                                       "progress": False}, {"_orbit": out["_orbit"]})
    (pd,) = [s for s in branch["special_points"] if s["type"] == "PD"]
    assert min(mu[0] for mu in pd["multipliers"]) == pytest.approx(-1.0, abs=1e-9)
    (doubled,) = branch["doubled"]
    assert doubled["period"] == pytest.approx(2 * 2 * math.pi / doubled["w"], rel=1e-14)
    assert doubled["events_per_period"] == 2 and doubled["stability"] == "stable"


def test_impact_oscillator_scene_through_the_period_doubling():
    """scenes/impact_oscillator_bifurcation.toml (the built-in impact_oscillator, the kinds periodic_orbit and
    continuation): the PD point at the w the branch test above checks against the hand-written computation (to
    1e-6), its multiplier -1 (to 1e-9), the two-impact orbit of period 2T past it."""
    from pathlib import Path

    scene = Path(__file__).resolve().parents[1] / "scenes" / "impact_oscillator_bifurcation.toml"
    orbit, flip = (a["outputs"] for a in mechgen.run(str(scene))["analyses"])
    assert len(orbit["events"]) == 1 and orbit["grazing"] == [] and orbit["stability"] == "stable"
    (pd,) = [s for s in flip["special_points"] if s["type"] == "PD"]
    assert pd["w"] == pytest.approx(2.6561773, abs=1e-6)
    assert min(mu[0] for mu in pd["multipliers"]) == pytest.approx(-1.0, abs=1e-9)
    (doubled,) = flip["doubled"]
    assert doubled["events_per_period"] == 2 and doubled["period"] == pytest.approx(4 * math.pi / doubled["w"])


@pytest.mark.parametrize("extra, key", [('method = "harmonic_balance"', "method"), ("segments = 2", "segments"),
                                        (None, "frequency")])
def test_hybrid_orbit_refuses_what_it_cannot_do(tmp_path, capsys, extra, key):
    """A hybrid model's orbit by harmonic balance, multiple shooting, or a forced model's without its forcing
    frequency (an autonomous orbit of equations that depend on t): exit 2 naming the key, no traceback."""
    from pathlib import Path

    from mechgen.cli import main

    text = (Path(__file__).resolve().parents[1] / "scenes" / "impact_oscillator_bifurcation.toml").read_text()
    text = text.split("[[analysis]]\nname = \"flip\"")[0]
    if extra is None:
        text = text.replace('frequency = "w"\n', "period = 2.5\n")
    else:
        text = text.replace('frequency = "w"\n', f'frequency = "w"\n{extra}\n')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    # at load (the analysis's key path) or, for the forcing, at run time (the run compares the equations at two t)
    assert (f".{key}" in err or f"key '{key}'" in err) and "Traceback" not in err
