"""Periodic orbits by first-order collocation of models with internal variables (issue 27, items 1, 6, 7): the
stick-slip limit cycle of the inertial rate-and-state slider, and smooth models declared with internal variables.

References, each independent of mechgen:
* the stick-slip cycle: a long run of the slider's equations written by hand in the test (the model doc's
  phi' = sigma (f - a phi - b psi) / (m V_ref e^phi), f' = k (V2 - V_ref e^phi) / sigma, psi' of the aging or slip
  law) by scipy's LSODA (ODEPACK's Adams/BDF, rtol 1e-13) from the step V1 -> V2, its period the distance between
  successive upward crossings of phi through ln(V2 / V_ref) (each located by brentq on the dense output) after the
  transient has died out; the transient itself measures the non-trivial multiplier: the deviations of the crossing
  periods from the limit shrink by mu_2 per cycle (the third multiplier is ~0);
* the first-order van der Pol oscillator x' = y, y' = mu (1 - x^2) y - x at mu = 1: the period 6.6632868593231
  (Andersen & Geer, SIAM J. Appl. Math. 42 (1982)), its non-trivial multiplier exp(mu int_0^T (1 - x^2) dt)
  (Liouville: the trace of the Jacobian) carried by scipy beside the state;
* the van der Pol oscillator with a lagged coupling (a coordinate and an internal variable): scipy's shooting of the
  three equations written by hand, and its monodromy by central differences;
* a forced linear oscillator written with internal variables, x' = y, y' = -x - c y + F cos(w t): the closed form
  x = Re(X e^{i w t}), X = F / (1 - w^2 + i c w), and its multipliers' modulus exp(-c T / 2).
"""
from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si
import scipy.optimize as so

import mechgen
from mechgen.errors import InputError

#: the slider of scenes/rate_state_stick_slip.toml
SLIDER = {"a": 0.01, "b": 0.015, "D_c": 1e-5, "k": 4e9, "sigma": 1e7, "V1": 1e-6, "V2": 1e-5, "V_ref": 1e-6,
          "m": 1e8}
#: a rough state near the cycle (no reference data): the collocation's guess re-integrates one period from it
ROUGH = {"phi": 2.0, "psi": -2.0, "f": 0.0}

VAN_DER_POL = '''"""First-order van der Pol, x' = y, y' = mu (1 - x^2) y - x, declared with internal variables only."""
from mechgen import Model, Param

model = Model("van_der_pol_first_order", doc=__doc__)
model.params(Param("mu", 1.0))
model.internal("x", lambda z: z.y)
model.internal("y", lambda z, p: p.mu * (1 - z.x**2) * z.y - z.x)
'''

FORCED = '''"""A forced damped oscillator declared with internal variables: x' = y, y' = -x - c y + F cos(w t)."""
import sympy as sp

from mechgen import Model, Param

model = Model("forced_first_order", doc=__doc__)
model.params(Param("c", 0.1), Param("F", 1.0), Param("w", 1.5))
model.internal("x", lambda z: z.y)
model.internal("y", lambda z, p, t: -z.x - p.c * z.y + p.F * sp.cos(p.w * t))
'''

LAGGED = '''"""van der Pol coupled to a lag: x'' - mu (1 - x^2) x' + x = eps (z - x), z' = (x - z) / tau."""
from mechgen import Model, Param

model = Model("van_der_pol_with_lag", doc=__doc__)
model.params(Param("mu", 1.0), Param("eps", 0.5), Param("tau", 0.7))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q):
    return q.x**2 / 2


@model.forces
def forces(q, v, z, p):
    return {"x": p.mu * (1 - q.x**2) * v.x + p.eps * (z.z - q.x)}


model.internal("z", lambda q, z, p: (q.x - z.z) / p.tau)
'''

VDP_PERIOD_MU1 = 6.6632868593231


def slider_rhs(law: str):
    """The slider's equations (mechgen/models/rate_state_inertial.py's doc), by hand."""
    p = SLIDER

    def rhs(t, x):
        phi, psi, f = x
        V = p["V_ref"] * math.exp(phi)
        if law == "aging":
            dpsi = p["V_ref"] / p["D_c"] * (math.exp(-psi) - math.exp(phi))
        else:
            dpsi = -p["V_ref"] / p["D_c"] * math.exp(phi) * (phi + psi)
        return [p["sigma"] * (f - p["a"] * phi - p["b"] * psi) / (p["m"] * V), dpsi,
                p["k"] * (p["V2"] - V) / p["sigma"]]

    return rhs


@functools.cache
def reference_periods(law: str, t_end: float = 330.0) -> np.ndarray:
    """The distances between successive upward crossings of phi = ln(V2/V_ref) in a run from the step by scipy's
    LSODA at rtol 1e-13 (ODEPACK, compiled: 2 s where scipy's Radau at rtol 1e-11 takes 20 s for the same periods,
    measured to agree within 5e-11 relative)."""
    before = math.log(SLIDER["V1"] / SLIDER["V_ref"])
    sol = si.solve_ivp(slider_rhs(law), (0.0, t_end), [before, -before, (SLIDER["a"] - SLIDER["b"]) * before],
                       method="LSODA", rtol=1e-13, atol=1e-14, dense_output=True)
    assert sol.status == 0
    level = math.log(SLIDER["V2"] / SLIDER["V_ref"])
    t = np.linspace(0.0, t_end, 200_001)
    phi = sol.sol(t)[0] - level
    up = np.flatnonzero((phi[:-1] < 0) & (phi[1:] >= 0))
    crossings = [so.brentq(lambda s: sol.sol(s)[0] - level, t[i], t[i + 1], xtol=1e-14) for i in up]
    return np.diff(crossings)


@pytest.fixture(scope="module")
def aging():
    return mechgen.compile("rate_state_inertial", {**SLIDER, "law": "aging"}, backend="c")


@pytest.mark.slow
@pytest.mark.parametrize("law", ["aging", "slip"])
def test_stick_slip_period_and_multiplier_against_a_long_lsoda_run(law):
    """The cycle by collocation (100 intervals, adapted twice, from a rough state) against the hand-written LSODA
    run from the step (15 cycles). The run's periods approach the cycle's geometrically, by mu_2 per cycle (the
    third multiplier is ~0): the ratio of successive differences of its periods is mu_2, and Aitken's extrapolation
    of three successive periods T_inf = T_3 - (T_3 - T_2)^2 / ((T_3 - T_2) - (T_2 - T_1)) the cycle's period. The period
    to 1e-9 relative (measured 5e-11 aging, 2.5e-11 slip: what is left is the run's rtol 1e-13 over 15 cycles and
    the next order of the transient); the trivial multiplier 1 to 1e-6; mu_2 against the median ratio of the last
    five differences (5e-3: their scatter, measured +-1e-4, from the run's error on differences of 1e-6 s; mu_2
    measured 0.3525 aging, 0.164 slip). Differences below 1e-8 T (the slip law's transient is gone within 10
    cycles) are the run's noise and left out of both."""
    periods = reference_periods(law)
    d = np.diff(periods)
    T_ref = aitken_period(periods)
    system = mechgen.compile("rate_state_inertial", {**SLIDER, "law": law}, backend="c")
    r = mechgen.periodic_orbit(system, method="collocation", period=21.0, z0=ROUGH, mesh=100, adapt=2)
    assert r["method"] == "collocation" and r["stability"] == "stable"
    assert abs(r["period"] - T_ref) < 1e-9 * T_ref
    mu = np.array([complex(*m) for m in r["multipliers"]])
    trivial = int(np.argmin(np.abs(mu - 1)))
    assert abs(mu[trivial] - 1) < 1e-6
    mu2 = np.delete(mu, trivial)[0].real
    significant = np.abs(d) > 1e-7 * T_ref  # differences far above the run's noise
    ratios = d[1:][significant[1:]] / d[:-1][significant[1:]]
    assert mu2 == pytest.approx(float(np.median(ratios[-5:])), abs=5e-3)


def aitken_period(periods: np.ndarray) -> float:
    """Aitken's extrapolation of the run's periods (above): the cycle's period."""
    d = np.diff(periods)
    k = int(np.flatnonzero(np.abs(d) > 1e-8 * periods[-1])[-1])  # the last difference above the run's noise
    return float(periods[k + 1] - d[k] ** 2 / (d[k] - d[k - 1]))


def k_critical() -> float:
    """k_c = sigma (b - a) / D_c (1 + m V2^2 / (sigma a D_c)) (Rice & Ruina 1983; tests/test_rate_state_inertial.py)."""
    p = SLIDER
    return p["sigma"] * (p["b"] - p["a"]) / p["D_c"] * (1 + p["m"] * p["V2"] ** 2 / (p["sigma"] * p["a"] * p["D_c"]))


@pytest.mark.slow
def test_the_scene_finds_the_cycle_from_its_simulate_and_follows_it_in_k():
    """scenes/rate_state_stick_slip.toml: "cycle" starts from the last cycle of the simulate "cycles" (601 samples
    over 300 s: the slip falls between samples, so the guess is re-integrated over one period from its state) and
    finds the aging-law period of the hand-written LSODA run (1e-9 relative, as above). "cycle_in_k" follows it in
    k: stable, its period falling, up to one cyclic fold (LPC) just above k_c (a subcritical Hopf point: measured
    k = 5.0746e9 = 1.0049 k_c), then unstable, shrinking onto steady sliding, where the branch ends (status
    ``equilibrium``) at the Hopf point of the linear theory: k_c (1e-4 relative, measured 1.4e-5) with the neutral
    period 2 pi / ((V2 / D_c) sqrt((b - a) / a)) (1e-3 relative, measured 2.8e-4: the last orbit keeps 2 % of the
    first's size, whose period differs by O(size^2))."""
    scene = Path(__file__).resolve().parents[1] / "scenes" / "rate_state_stick_slip.toml"
    analyses = {a["name"]: a["outputs"] for a in mechgen.run(str(scene))["analyses"]}
    cycle, branch = analyses["cycle"], analyses["cycle_in_k"]
    T_ref = aitken_period(reference_periods("aging"))
    assert abs(cycle["period"] - T_ref) < 1e-9 * T_ref and cycle["stability"] == "stable"
    points = branch["branch"]
    assert points[0]["period"] == pytest.approx(cycle["period"], rel=1e-9)
    assert [s["type"] for s in branch["special_points"]] == ["LPC"]
    fold = branch["special_points"][0]["k"]
    assert k_critical() < fold < 1.01 * k_critical()
    before = [p for p in points if p["period"] > branch["special_points"][0]["period"]]
    after = points[len(before) + 1:]
    assert all(p["stability"] == "stable" for p in before) and all(p["stability"] == "unstable" for p in after)
    assert np.all(np.diff([p["period"] for p in points]) < 0)
    assert branch["status"] == "equilibrium"
    omega = SLIDER["V2"] / SLIDER["D_c"] * math.sqrt((SLIDER["b"] - SLIDER["a"]) / SLIDER["a"])
    assert points[-1]["k"] == pytest.approx(k_critical(), rel=1e-4)
    assert points[-1]["period"] == pytest.approx(2 * math.pi / omega, rel=1e-3)


def test_stick_slip_mesh_convergence_and_trivial_multiplier(aging):
    """The aging-law cycle's period on 50 and 100 adapted intervals against 200: the error falls by about 2^8 per
    halving (order 2m = 8 at the mesh points; measured 3.6e-8 at 50 and 1.5e-10 at 100, ratio ~240, checked in
    [100, 1000]); the trivial multiplier's distance from 1, the collocation monodromy's own error, falls at the same
    order (measured 1.1e-6, 2.7e-9, 6.9e-12 at 50, 100, 200: checked below 1e-5, 1e-8, 1e-10 and a ratio > 100)."""
    found = {mesh: mechgen.periodic_orbit(aging, method="collocation", period=21.0, z0=ROUGH, mesh=mesh, adapt=2)
             for mesh in (50, 100, 200)}
    best = found[200]["period"]
    errors = [abs(found[mesh]["period"] - best) for mesh in (50, 100)]
    assert 100 < errors[0] / errors[1] < 1000
    assert errors[1] < 1e-9 * best

    def trivial_gap(r):
        return float(np.min(np.abs(np.array([complex(*m) for m in r["multipliers"]]) - 1)))

    gaps = [trivial_gap(found[mesh]) for mesh in (50, 100, 200)]
    assert gaps[0] < 1e-5 and gaps[1] < 1e-8 and gaps[2] < 1e-10 and gaps[0] / gaps[1] > 100


def test_adapted_mesh_puts_its_intervals_in_the_slip(aging):
    """100 uniform intervals miss the slip (a few hundredths of the period): the period is off by 3 % (measured
    21.50 s); the mesh that equidistributes AUTO's monitor, adapted twice after the uniform solve, is within 1e-5
    (measured 1e-6 relative); its smallest interval (1/25 of its largest) within two intervals of where phi changes
    fastest (the slip's arrest, |dphi/dt| up to 66/s), and where |dphi/dt| > 1/s (the slip, 29 of the 100 intervals)
    the median interval is below half the mesh's median (measured 0.36).
    The converged value is the 200-interval orbit (a convergence study: the test above)."""
    from mechgen.runtime.periodic.collocation import Collocation
    from mechgen.runtime.periodic.cycle_guess import closed_cycle
    from mechgen.runtime.periodic.newton import NewtonSettings, newton

    best = mechgen.periodic_orbit(aging, method="collocation", period=21.0, z0=ROUGH, mesh=200, adapt=2)["period"]
    x0, T, curve = closed_cycle(aging, np.array(list(ROUGH.values())), 21.0)
    problem = Collocation(aging, 100, None)
    X = curve(T * problem.node_tau())
    problem = Collocation(aging, 100, None, 0, None, X)
    settings = NewtonSettings(rtol=1e-9, atol=1e-12, max_iterations=50)
    u = newton(problem.residual_jacobian, problem.unknowns(X, T), settings).u
    assert abs(u[-1] - best) > 1e-2 * best
    for _ in range(2):
        problem, u = problem.adapted(u)
        u = newton(problem.residual_jacobian, u, settings).u
    assert abs(u[-1] - best) < 1e-5 * best
    widths = problem.widths
    nodes, _ = problem.split(u)
    rates = np.abs([slider_rhs("aging")(0.0, x)[0] for x in nodes[::4]])  # |dphi/dt| at each interval's start
    assert widths.min() < widths.max() / 10
    assert abs(int(np.argmin(widths)) - int(np.argmax(rates))) <= 2
    assert np.median(widths[rates > 1.0]) < np.median(widths) / 2


def van_der_pol_multiplier(mu: float, x0: float, T_guess: float) -> tuple[float, float]:
    """(T, exp(mu int_0^T (1 - x^2) dt)) of the van der Pol cycle by scipy shooting from (x0, 0)."""
    def rhs(t, y):
        return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0], mu * (1 - y[0] ** 2)]

    def residual(u):
        end = si.solve_ivp(rhs, (0, u[1]), [u[0], 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
        return [end[0] - u[0], end[1]]

    a, T = so.fsolve(residual, [x0, T_guess], xtol=1e-13)
    end = si.solve_ivp(rhs, (0, T), [a, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    return T, math.exp(end[2])


def test_first_order_van_der_pol_declared_with_internal_variables(tmp_path):
    """The van der Pol cycle of a model with internal variables only, by collocation from z0: the period against
    the cited value (measured 5e-10 at mesh 40, 2.1e-7 at mesh 20: ratio ~400, checked in [100, 1000] for order 8),
    the trivial multiplier 1 (1e-8) and the non-trivial one against scipy's Liouville integral (1e-7 relative)."""
    path = tmp_path / "vdp_first_order.py"
    path.write_text(VAN_DER_POL)
    system = mechgen.compile(str(path))
    errors = []
    for mesh in (20, 40):
        r = mechgen.periodic_orbit(system, method="collocation", period=6.5, z0={"x": 2.0}, mesh=mesh)
        errors.append(abs(r["period"] - VDP_PERIOD_MU1))
    assert errors[1] < 2e-9 and 100 < errors[0] / errors[1] < 1000
    _, expected = van_der_pol_multiplier(1.0, 2.0, 6.6)
    mu = np.array([complex(*m) for m in r["multipliers"]])
    assert np.min(np.abs(mu - 1)) < 1e-8
    assert mu[np.argmax(np.abs(mu - 1))].real == pytest.approx(expected, rel=1e-7)
    assert r["amplitude"]["x"] == pytest.approx(2.00861986, abs=1e-7)  # Andersen & Geer's amplitude at mu = 1
    assert set(r["trajectory"]) >= {"x", "y"} and r["t"][-1] == pytest.approx(r["period"])


def test_coordinates_and_internal_variables_together(tmp_path):
    """A model with a coordinate and an internal variable (the implicit rows r = 0 with r_z, and dz/dtau = T g with
    g_q, g_v, g_z): the cycle against scipy's shooting of the hand-written three equations (period: 3e-9, measured
    1.2e-9 at mesh 40, 3.3e-7 at mesh 20: ratio ~280 for order 8) and the multipliers' moduli against the
    eigenvalues of scipy's monodromy by central differences (1e-8: step 1e-6 on rtol 1e-13 flows, measured 6e-10)."""
    path = tmp_path / "lagged.py"
    path.write_text(LAGGED)
    system = mechgen.compile(str(path))
    mu, eps, tau = 1.0, 0.5, 0.7

    def rhs(t, y):
        return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0] + eps * (y[2] - y[0]), (y[0] - y[2]) / tau]

    def flow(y0, T):
        return si.solve_ivp(rhs, (0, T), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]

    def residual(u):
        end = flow([u[0], 0.0, u[1]], u[2])
        return [end[0] - u[0], end[1], end[2] - u[1]]

    x0, z0, T = so.fsolve(residual, [2.0, 1.0, 6.5], xtol=1e-13)
    h = 1e-6
    Phi = np.array([(flow([x0, 0.0, z0] + h * e, T) - flow([x0, 0.0, z0] - h * e, T)) / (2 * h)
                    for e in np.eye(3)]).T
    errors = []
    for mesh in (20, 40):
        r = mechgen.periodic_orbit(system, method="collocation", period=6.5, q0={"x": 2.0}, z0={"z": 1.0}, mesh=mesh)
        errors.append(abs(r["period"] - T))
    assert errors[1] < 3e-9 and 100 < errors[0] / errors[1] < 1000
    moduli = np.sort(np.abs([complex(*m) for m in r["multipliers"]]))
    np.testing.assert_allclose(moduli, np.sort(np.abs(np.linalg.eigvals(Phi))), rtol=0, atol=1e-8)
    assert set(r["amplitude"]) == {"x", "z"} and r["stability"] == "stable"


def test_forced_orbit_of_a_model_with_internal_variables(tmp_path):
    """A forced orbit (frequency given) of a model with internal variables: x(0) and the amplitude against the
    closed form (1e-9 and 1e-7: the amplitude is the largest of 4096 phases refined by a parabola), the multipliers'
    modulus exp(-c T / 2) (1e-9)."""
    path = tmp_path / "forced_first_order.py"
    path.write_text(FORCED)
    system = mechgen.compile(str(path))
    c, F, w = 0.1, 1.0, 1.5
    X = F / complex(1 - w**2, c * w)
    r = mechgen.periodic_orbit(system, method="collocation", frequency="w", z0={"x": 0.5}, mesh=20)
    assert r["trajectory"]["x"][0] == pytest.approx(X.real, abs=1e-9)
    assert r["amplitude"]["x"] == pytest.approx(abs(X), abs=1e-7)
    moduli = np.abs([complex(*m) for m in r["multipliers"]])
    np.testing.assert_allclose(moduli, math.exp(-c * 2 * math.pi / w / 2), rtol=0, atol=1e-9)


def test_harmonic_balance_stays_refused_for_internal_variables(aging):
    """Harmonic balance's residual holds the coordinates only: refused at ``method``, naming collocation and
    shooting; a zero guess of a model of internal variables only is refused at ``z0``."""
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(aging, method="harmonic_balance", period=21.0, z0=ROUGH)
    assert err.value.key.endswith("method") and "collocation" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(aging, method="collocation", period=21.0, z0={"phi": 0.0, "psi": 0.0, "f": 0.0})
    assert err.value.key.endswith("z0")
