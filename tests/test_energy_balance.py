"""The energy balance of simulate (issue 25, item 5; mechgen.analyses.energy_balance): work and dissipated energy
integrated with the state, against references independent of mechgen:

* a forced, damped Duffing oscillator m x'' + c x' + k x + k3 x^3 = F cos(w t): scipy's DOP853 at rtol 1e-12 on
  the hand-derived equation augmented with W' = F cos(w t) x' and D' = c x'^2;
* a free, underdamped oscillator: D(t) = E(0) - E(t) with E from the closed-form x(t);
* a particle in a frame rotating at Omega, T = m/2 ((x' - Omega y)^2 + (y' + Omega x)^2), on springs fixed in
  that frame, V = (kx x^2 + ky y^2)/2: no work, no dissipation, T not quadratic in v (linear terms), so
  E = T + V varies (the rotating anisotropic springs do work in the inertial frame) while the Jacobi integral
  h = v.dT/dv - T + V is conserved (Goldstein, Classical Mechanics, 3rd ed., sec. 2.7 / 8.2);
* a parametrically pumped oscillator, V = k (1 + eps sin(nu t)) x^2 / 2: the work of the explicit time
  dependence W = int dV/dt dt against scipy on the hand-derived equation.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si
import sympy as sp

import mechgen
from mechgen import Model, Param

MODELS = Path(__file__).resolve().parent / "models"  # forced_duffing.py, bouncing_ball.py

ROTATING = '''\
"""A particle on an anisotropic spring that rotates with the frame (rate Omega)."""
from mechgen import Model, Param

model = Model("user_rotating_particle", doc=__doc__)
model.params(Param("m", 1.0), Param("kx", 3.0), Param("ky", 1.0), Param("Omega", 0.7))
model.coordinates("x", "y")


@model.kinetic
def kinetic(q, v, p):
    return p.m / 2 * ((v.x - p.Omega * q.y) ** 2 + (v.y + p.Omega * q.x) ** 2)


@model.potential
def potential(q, p):
    return (p.kx * q.x**2 + p.ky * q.y**2) / 2
'''

PUMPED = '''\
"""A parametrically pumped oscillator: V = k (1 + eps sin(nu t)) x^2 / 2."""
import sympy as sp
from mechgen import Model, Param

model = Model("user_pumped", doc=__doc__)
model.params(Param("k", 1.0), Param("eps", 0.2), Param("nu", 2.0))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q, p, t):
    return p.k * (1 + p.eps * sp.sin(p.nu * t)) * q.x**2 / 2
'''


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("balance_models")
    for name, text in {"rotating": ROTATING, "pumped": PUMPED}.items():
        (path / f"{name}.py").write_text(text)
    return path


def duffing_powers_reference(t_end: float, x0: float = 0.0) -> tuple[float, float]:
    """(work, dissipated) of the forced, damped Duffing oscillator (tests/models/forced_duffing.py) from x0 at
    rest: its hand-derived equation with the powers F cos(w t) v and c v^2 integrated by scipy at rtol 1e-12."""
    m, c, k, k3, F, w = 1.0, 0.05, 1.0, 0.5, 0.3, 1.2

    def rhs(t, y):
        x, v, _, _ = y
        return [v, (F * math.cos(w * t) - c * v - k * x - k3 * x**3) / m, F * math.cos(w * t) * v, c * v**2]

    ref = si.solve_ivp(rhs, (0, t_end), [x0, 0, 0, 0], method="DOP853", rtol=1e-12, atol=1e-14)
    return float(ref.y[2, -1]), float(ref.y[3, -1])


@pytest.mark.parametrize("loop", ["auto", "python"])
def test_forced_damped_duffing_work_and_dissipation(folder, loop):
    """work and dissipated against scipy's quadratures of the hand-derived powers (1e-8 relative: both runs'
    errors at rtol 1e-11 / 1e-12 over 60 s); the balance closes to 1e-9 of the energy scale; no energy_drift
    (a forced run from rest: E0 = 0, where the old figure divided by zero)."""
    system = mechgen.compile(str(MODELS / "forced_duffing.py"))
    r = mechgen.simulate(system, t_end=60.0, rtol=1e-11, atol=1e-13, loop=loop)
    assert "energy_drift" not in r
    work, dissipated = duffing_powers_reference(60.0)
    assert r["work"] == pytest.approx(work, rel=1e-8)
    assert r["dissipated"] == pytest.approx(dissipated, rel=1e-8)
    assert r["energy_balance_error"] < 1e-9
    traj = r["trajectory"]
    E = traj["energy"]
    np.testing.assert_allclose(E - E[0], traj["work"] - traj["dissipated"], atol=1e-9 * np.max(np.abs(E)))


def test_free_damped_oscillator_dissipates_its_energy(folder):
    """F = 0: the dissipated energy is E(0) - E(t) with E from the closed form x(t) = e^{-zeta wn t}(cos wd t +
    zeta wn / wd sin wd t), x(0) = 1 (k3 = 0, m = k = 1, c = 0.05)."""
    system = mechgen.compile(str(MODELS / "forced_duffing.py"), {"F": 0.0, "k3": 0.0})
    r = mechgen.simulate(system, t_end=30.0, q0={"x": 1.0}, rtol=1e-11, atol=1e-13, samples=31)
    zeta, wn = 0.025, 1.0
    wd = wn * math.sqrt(1 - zeta**2)
    t = r["t"]
    x = np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    v = -np.exp(-zeta * wn * t) * (wn**2 / wd) * np.sin(wd * t)
    E = (v**2 + x**2) / 2
    np.testing.assert_allclose(r["trajectory"]["dissipated"], E[0] - E, rtol=0, atol=1e-9)
    assert r["work"] == 0.0


def test_rotating_frame_balances_the_jacobi_integral(folder):
    """No work, no dissipation, but T has terms linear in v: E = T + V changes by O(1) while the balance on
    h = v.dT/dv - T + V closes to the integrator's accuracy."""
    system = mechgen.compile(str(folder / "rotating.py"))
    r = mechgen.simulate(system, t_end=20.0, q0={"x": 1.0}, v0={"y": 0.3}, rtol=1e-11, atol=1e-13)
    E = r["trajectory"]["energy"]
    assert np.max(np.abs(E - E[0])) > 0.1 * np.max(np.abs(E))
    assert r["work"] == 0.0 and r["dissipated"] == 0.0
    assert r["energy_balance_error"] < 1e-9


def test_explicit_time_dependence_is_work(folder):
    """V = k (1 + eps sin(nu t)) x^2/2: W = int dV/dt dt = int k eps nu cos(nu t) x^2/2 dt (scipy reference)."""
    system = mechgen.compile(str(folder / "pumped.py"))
    r = mechgen.simulate(system, t_end=15.0, q0={"x": 1.0}, rtol=1e-11, atol=1e-13)
    k, eps, nu = 1.0, 0.2, 2.0

    def rhs(t, y):
        x, v, _ = y
        return [v, -k * (1 + eps * math.sin(nu * t)) * x, k * eps * nu * math.cos(nu * t) * x**2 / 2]

    ref = si.solve_ivp(rhs, (0, 15.0), [1.0, 0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14)
    assert r["work"] == pytest.approx(ref.y[2, -1], rel=1e-8, abs=1e-12)
    assert r["energy_balance_error"] < 1e-9


def test_a_conservative_run_keeps_energy_drift(folder):
    """c = F = 0: the powers are generated zeros, so the run reports energy_drift, not a balance."""
    system = mechgen.compile(str(MODELS / "forced_duffing.py"), {"F": 0.0, "c": 0.0})
    r = mechgen.simulate(system, t_end=10.0, q0={"x": 1.0}, rtol=1e-10, atol=1e-12)
    assert "energy_balance_error" not in r and r["energy_drift"] < 1e-8


@pytest.mark.parametrize("loop", ["c", "python"])
def test_bouncing_ball_resets_dissipate_the_closed_form(tmp_path, loop):
    """Dropped from h = 1 with e = 0.8: after k impacts the resets have taken m g h (1 - e^(2k)); the flights
    conserve E, so the balance E(t) - E(0) + D(t) closes to the integrator's accuracy; no energy_drift (the
    energy's drop is the resets', not an error)."""
    ball = mechgen.compile(str(MODELS / "bouncing_ball.py"))
    r = mechgen.simulate(ball, t_end=3.0, q0={"y": 1.0}, method="DOP853", rtol=1e-11, atol=1e-13, loop=loop)
    k = len(r["events"])
    assert k >= 5 and "energy_drift" not in r
    assert r["dissipated"] == pytest.approx(9.81 * (1 - 0.8 ** (2 * k)), rel=1e-9)
    assert r["work"] == 0.0 and r["energy_balance_error"] < 1e-9


@pytest.mark.parametrize("loop", ["c", "python"])
def test_a_dissipative_hybrid_run_balances_its_energy_across_events(loop):
    """Kelvin-Voigt contact (dissipative in contact): the dashpot's power is integrated through both modes and
    carried across the events. Reference: the closed-form restitution of a linear spring-dashpot released at
    x = 0, e = exp(-zeta pi / sqrt(1 - zeta^2)) (Butcher & Segalman 2000, eq. 4), so the energy dissipated is
    m v_in^2 (1 - e^2) / 2; the event location and rtol 1e-10 bound the difference (1e-8 relative)."""
    zeta = 0.1
    impact = mechgen.compile("viscoelastic_impact", {"law": "kelvin_voigt", "zeta": zeta})
    r = mechgen.simulate(impact, t_end=5.0, v0={"x": 1.0}, method="DOP853", rtol=1e-10, atol=1e-12, loop=loop)
    assert r["events"][0]["guard"] == "touch" and r["final_mode"] == "flight" and r["loop"] == loop
    e = math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    assert "energy_drift" not in r and r["work"] == 0.0
    assert r["dissipated"] == pytest.approx(0.5 * (1 - e**2), rel=1e-8)
    assert r["energy_balance_error"] < 1e-9
    assert r["trajectory"]["dissipated"][-1] == pytest.approx(r["dissipated"], rel=1e-12)


def forced_stop_reference(t_end: float, c=0.05, F=0.5, w=1.3, e=0.8):
    """(work, dissipated) of x'' + c x' + x = F cos(w t) with impacts on a stop at x = -0.2 (x' -> -e x'), by
    scipy's DOP853 with its own event location, the work and the flow's dissipation integrated with the state
    and each impact's loss (1 - e^2) x'^2 / 2 added at the impact."""
    def rhs(t, y):
        x, v = y[0], y[1]
        return [v, F * math.cos(w * t) - c * v - x, F * math.cos(w * t) * v, c * v * v]

    def stop(t, y):
        return y[0] + 0.2
    stop.terminal, stop.direction = True, -1
    t, y, lost = 0.0, np.zeros(4), 0.0
    while t < t_end:
        sol = si.solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-14, events=stop)
        t, y = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status == 1:
            lost += (1 - e**2) * y[1] ** 2 / 2
            y[1] = -e * y[1]
    return y[2], y[3] + lost


def test_a_forced_hybrid_run_balances_work_and_reset_losses():
    """A forced, damped oscillator whose impacts on a stop at x = -0.2 reverse the velocity with restitution
    0.8: the forcing's work and the damping (integrated through the events) and the impacts' losses, against
    scipy integrating the hand-written equations with its own event location (forced_stop_reference); the
    event times located to ~1e-12 and rtol 1e-10 bound the difference (1e-7 relative)."""
    model = Model("forced_stop", doc="forced, damped oscillator on a stop")
    model.params(Param("c", 0.05), Param("F", 0.5), Param("w", 1.3))
    model.coordinates("x")
    free = model.mode("free")

    @model.kinetic
    def kinetic(v):
        return v.x**2 / 2

    @model.potential
    def potential(q):
        return q.x**2 / 2

    @model.dissipation
    def dissipation(v, p):
        return p.c * v.x**2 / 2

    @model.forces
    def forces(p, t):
        return {"x": p.F * sp.cos(p.w * t)}

    @free.guard(to="free", direction="falling", reset=lambda v: {"x_dot": -0.8 * v.x})
    def stop(q):
        return q.x + 0.2

    system = mechgen.compile(model)
    work, dissipated = forced_stop_reference(40.0)
    for loop in ("c", "python"):
        r = mechgen.simulate(system, t_end=40.0, q0={"x": 0.0}, method="DOP853", rtol=1e-10, atol=1e-12, loop=loop)
        assert len(r["events"]) >= 3 and "energy_drift" not in r and r["loop"] == loop
        assert r["work"] == pytest.approx(work, rel=1e-7)
        assert r["dissipated"] == pytest.approx(dissipated, rel=1e-7)
        assert r["energy_balance_error"] < 1e-8


def test_cvodes_integrates_the_energy_balance_of_a_forced_run():
    """CVODES carries the balance's integrals in its CasADi expression (the energy_rates kernel's powers): work
    and dissipated against scipy on the hand-derived powers (duffing_powers_reference; 1e-7 relative: CVODES's
    BDF at rtol 1e-10 over 10 s, measured 1.4e-9); a conservative run keeps its energy_drift."""
    forced = mechgen.compile(str(MODELS / "forced_duffing.py"), backend="casadi")
    r = mechgen.simulate(forced, t_end=10.0, q0={"x": 0.5}, method="cvodes", rtol=1e-10, atol=1e-12)
    work, dissipated = duffing_powers_reference(10.0, x0=0.5)
    assert "energy_drift" not in r and "energy_note" not in r
    assert r["work"] == pytest.approx(work, rel=1e-7)
    assert r["dissipated"] == pytest.approx(dissipated, rel=1e-7)
    assert r["energy_balance_error"] < 1e-7
    free = mechgen.compile(str(MODELS / "forced_duffing.py"), {"F": 0.0, "c": 0.0}, backend="casadi")
    r = mechgen.simulate(free, t_end=5.0, q0={"x": 0.5}, method="cvodes", rtol=1e-10, atol=1e-12)
    assert "energy_balance_error" not in r and r["energy_drift"] < 1e-7
