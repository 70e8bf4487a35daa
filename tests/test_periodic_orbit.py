"""``periodic_orbit`` (issue 27, item 1): periodic orbits of smooth lumped models by harmonic balance and shooting.

References, each independent of mechgen:
* the forced Duffing oscillator x'' + c x' + x + k3 x^3 = F cos(w t): first-order harmonic balance is the
  frequency-amplitude equation ((1 - w^2 + 3/4 k3 A^2)^2 + (c w)^2) A^2 = F^2 (closed form, a cubic in A^2);
  the converged orbit by scipy's DOP853 shooting with fsolve on the hand-written right-hand side, its harmonics by
  numpy's FFT; its monodromy by central differences of scipy's flow; Liouville's formula det Phi(T) = exp(-c T);
* the van der Pol oscillator x'' - mu (1 - x^2) x' + x = 0: the small-mu expansion T = 2 pi (1 + mu^2/16 - 5 mu^4 /
  3072 + ...) and amplitude 2 + O(mu^2) (Andersen & Geer, SIAM J. Appl. Math. 42 (1982)); for mu = 1 scipy shooting
  in the test and the known period 6.6632868593231 (same source); its non-trivial multiplier
  exp(mu int_0^T (1 - x^2) dt) (Liouville: the trace of the Jacobian), the integral carried by scipy beside the
  state.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si
import scipy.optimize as so

import mechgen
from mechgen.errors import ConvergenceError, InputError

DUFFING = '''\
"""Forced Duffing: x'' + c x' + x + k3 x^3 = F cos(w t)."""
import sympy as sp

from mechgen import Model, Param

model = Model("user_orbit_duffing", doc=__doc__)
model.params(Param("c", 0.05), Param("k3", 0.5), Param("F", 0.3), Param("w", 1.2))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q, p):
    return q.x**2 / 2 + p.k3 * q.x**4 / 4


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def forces(p, t):
    return {"x": p.F * sp.cos(p.w * t)}
'''

VAN_DER_POL = '''\
"""van der Pol: x'' - mu (1 - x^2) x' + x = 0."""
from mechgen import Model, Param

model = Model("user_orbit_van_der_pol", doc=__doc__)
model.params(Param("mu", 1.0))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q):
    return q.x**2 / 2


@model.forces
def forces(q, v, p):
    return {"x": p.mu * (1 - q.x**2) * v.x}
'''

#: the van der Pol period at mu = 1 (Andersen & Geer 1982; also the scipy shooting below)
VDP_PERIOD_MU1 = 6.6632868593231
BOUNCING = Path(__file__).resolve().parent / "models" / "bouncing_ball.py"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("periodic_orbit_models")
    (path / "duffing.py").write_text(DUFFING)
    (path / "vdp.py").write_text(VAN_DER_POL)
    return path


@pytest.fixture(scope="module")
def duffing(folder):
    return mechgen.compile(str(folder / "duffing.py"))


@pytest.fixture(scope="module")
def vdp(folder):
    return mechgen.compile(str(folder / "vdp.py"))


# ----------------------------------------------------------------------------------------- independent references

def duffing_rhs(c, k3, F, w):
    return lambda t, x: [x[1], F * math.cos(w * t) - c * x[1] - x[0] - k3 * x[0] ** 3]


def scipy_flow(rhs, x0, T, t_eval=None):
    sol = si.solve_ivp(rhs, (0.0, T), x0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t_eval)
    assert sol.success
    return sol


def duffing_reference(c, k3, F, w, x0):
    """The forced orbit by scipy shooting: fsolve on phi_T(x0) - x0, T = 2 pi / w."""
    rhs, T = duffing_rhs(c, k3, F, w), 2 * math.pi / w
    x0 = so.fsolve(lambda x: scipy_flow(rhs, x, T).y[:, -1] - x, x0, xtol=1e-13)
    return x0, T, rhs


def fft_harmonics(samples):
    """(a_k, b_k), k = 0.., of q = a_0 + sum a_k cos + b_k sin from N equally spaced samples over [0, T)."""
    N = len(samples)
    spec = np.fft.rfft(samples) / N
    return 2 * spec.real, -2 * spec.imag


def vdp_reference(mu, x0, T):
    """The limit cycle by scipy shooting on (x(0), T) with v(0) = 0, and int_0^T (1 - x^2) dt carried as a third
    state."""
    def rhs(t, y):
        return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0], 1 - y[0] ** 2]

    def residual(u):
        end = scipy_flow(rhs, [u[0], 0.0, 0.0], u[1]).y[:, -1]
        return [end[0] - u[0], end[1]]

    a, T = so.fsolve(residual, [x0, T], xtol=1e-13)
    trace = scipy_flow(rhs, [a, 0.0, 0.0], T).y[2, -1]
    return a, T, math.exp(mu * trace)


def nontrivial(result):
    """The multiplier of an autonomous orbit that is not the trivial 1."""
    mu = np.array([complex(*m) for m in result["multipliers"]])
    return np.delete(mu, np.argmin(np.abs(mu - 1)))


# ----------------------------------------------------------------------------------------------- forced Duffing

def test_first_order_harmonic_balance_is_the_frequency_amplitude_equation(duffing):
    """H = 1 projects k3 x^3 onto the first harmonic exactly (3/4 k3 A^3; the 16 phases alias nothing below the
    third harmonic), so its amplitude is the closed form's root to Newton's tolerance (1e-10 on A ~ 0.3); in the
    weak-nonlinearity limit (k3 = 0.01) the converged orbit (H = 7) differs from it by the third harmonic only,
    O(k3 A^3 / 32) ~ 1e-5."""
    c, k3, F, w = 0.1, 0.01, 0.1, 1.1
    system = duffing.with_params(c=c, k3=k3, F=F, w=w)
    first = mechgen.periodic_orbit(system, frequency="w", harmonics=1, q0={"x": 0.3})
    s = np.roots([(0.75 * k3) ** 2, 2 * (1 - w**2) * 0.75 * k3, (1 - w**2) ** 2 + (c * w) ** 2, -F**2])
    A2 = [r.real for r in s if abs(r.imag) < 1e-12 and r.real > 0]
    assert len(A2) == 1  # one orbit at these values (below the fold of the resonance curve)
    A = math.sqrt(A2[0])
    assert first["method"] == "harmonic_balance"
    assert first["harmonics"]["x"]["amplitude"][0] == pytest.approx(A, rel=0, abs=1e-10)
    converged = mechgen.periodic_orbit(system, frequency="w", harmonics=7, q0={"x": 0.3})
    assert converged["amplitude"]["x"] == pytest.approx(A, rel=0, abs=k3 * A**3 / 32 * 2)


def test_multi_harmonic_orbit_by_both_methods_against_scipy_shooting(duffing):
    """A strongly nonlinear forced orbit (k3 = 0.5, A ~ 1.3): mechgen's shooting matches scipy's to the two
    integrations' errors (1e-8 on the start state); harmonic balance with H = 7 matches it to within ten times the
    first harmonic it leaves out (the 9th, |c_9| from the reference's FFT: the truncation error's size)."""
    c, k3, F, w = 0.05, 0.5, 0.3, 1.2
    x0, T, rhs = duffing_reference(c, k3, F, w, [1.3, 0.5])
    N = 256
    ref = scipy_flow(rhs, x0, T, t_eval=T * np.arange(N) / N).y[0]
    a, b = fft_harmonics(ref)
    truncation = 10 * math.hypot(a[9], b[9])
    assert 1e-12 < truncation < 1e-4  # the bound is meaningful: small, and above round-off
    for loop in ("auto", "python"):  # the compiled loop's flow (Newton's Jacobian by its differences), scipy's
        shot = mechgen.periodic_orbit(duffing, frequency="w", method="shooting", q0={"x": 1.3}, v0={"x": 0.5},
                                      loop=loop)
        assert shot["loop"] == ("python" if loop == "python" or duffing.backend != "c" else "c")
        assert shot["period"] == pytest.approx(T, rel=1e-15)
        np.testing.assert_allclose([shot["trajectory"]["x"][0], shot["trajectory"]["x_dot"][0]], x0, rtol=0,
                                   atol=1e-8)
    hb = mechgen.periodic_orbit(duffing, frequency="w", harmonics=7, q0={"x": 1.3}, v0={"x": 0.5})
    h = hb["harmonics"]["x"]
    np.testing.assert_allclose(h["cos"], a[1:8], rtol=0, atol=truncation)
    np.testing.assert_allclose(h["sin"], b[1:8], rtol=0, atol=truncation)
    assert h["mean"] == pytest.approx(a[0] / 2, abs=truncation)
    # the orbit itself, at the reported times
    t = np.array(hb["t"])
    exact = scipy_flow(rhs, x0, T, t_eval=t).y[0]
    np.testing.assert_allclose(hb["trajectory"]["x"], exact, rtol=0, atol=2 * truncation)
    assert hb["amplitude"]["x"] == pytest.approx(shot["amplitude"]["x"], abs=2 * truncation)


def test_floquet_multipliers_of_a_stable_forced_orbit(duffing):
    """The multipliers against the eigenvalues of scipy's monodromy by central differences of its flow (step 1e-5:
    truncation ~1e-10, rounding 1e-13 / 1e-5 = 1e-8 -> 1e-7 allowed); their product is exp(-c T) (Liouville:
    trace J = -c), which mechgen's variational equations hold to the integrator's error (1e-9). Harmonic balance with
    H = 15, whose truncation leaves ~1e-13 in the start state (H = 7 leaves 1e-6 there, and so in the multipliers of
    the monodromy integrated from it)."""
    c, k3, F, w = 0.05, 0.5, 0.3, 1.2
    x0, T, rhs = duffing_reference(c, k3, F, w, [1.3, 0.5])
    h = 1e-5
    columns = []
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        columns.append((scipy_flow(rhs, x0 + e, T).y[:, -1] - scipy_flow(rhs, x0 - e, T).y[:, -1]) / (2 * h))
    expected = np.sort_complex(np.linalg.eigvals(np.array(columns).T))
    for method in ("shooting", "harmonic_balance"):
        r = mechgen.periodic_orbit(duffing, frequency="w", method=method, q0={"x": 1.3}, v0={"x": 0.5}, harmonics=15)
        mu = np.array([complex(*m) for m in r["multipliers"]])
        np.testing.assert_allclose(np.sort_complex(mu), expected, rtol=0, atol=1e-7)
        assert np.prod(mu).real == pytest.approx(math.exp(-c * T), rel=1e-9)
        assert abs(np.prod(mu).imag) < 1e-12
        assert r["stability"] == "stable" and max(abs(mu)) < 1


# ------------------------------------------------------------------------------------------------- van der Pol

@pytest.mark.parametrize("method", ["shooting", "harmonic_balance"])
def test_van_der_pol_small_mu_expansion(vdp, method):
    """mu = 0.1: T = 2 pi (1 + mu^2/16) to the next term, 2 pi 5 mu^4 / 3072 = 1.0e-6 (allowed 3e-6); amplitude
    2 to O(mu^2) = 0.01 (the expansion's next term; the coefficient is below 1)."""
    mu = 0.1
    r = mechgen.periodic_orbit(vdp.with_params(mu=mu), method=method, period=6.3, q0={"x": 2.0}, harmonics=9)
    assert r["method"] == method
    assert r["period"] == pytest.approx(2 * math.pi * (1 + mu**2 / 16), rel=0, abs=3e-6)
    assert abs(r["period"] - 2 * math.pi * (1 + mu**2 / 16)) > 1e-8  # the mu^4 term is there: not the expansion itself
    assert r["amplitude"]["x"] == pytest.approx(2.0, abs=mu**2)


def test_van_der_pol_limit_cycle_against_scipy_shooting(vdp):
    """mu = 1: shooting's period and amplitude against scipy's shooting (1e-9: two integrations at 1e-11 / 1e-13)
    and the cited period; harmonic balance with H = 30 against the same (1e-8: its truncation, the 31st harmonic of
    a relaxation-like cycle); the non-trivial multiplier against exp(mu int (1 - x^2) dt) (1e-7 relative: the
    variational equations' error on a multiplier of 1e-3), the trivial one 1."""
    a, T, expected = vdp_reference(1.0, 2.0, 6.6)
    assert T == pytest.approx(VDP_PERIOD_MU1, abs=1e-10)
    assert expected < 1
    shot = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0})
    assert shot["method"] == "shooting" and shot["stability"] == "stable"
    assert shot["period"] == pytest.approx(T, abs=1e-9)
    assert shot["amplitude"]["x"] == pytest.approx(a, abs=1e-9)
    hb = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0}, harmonics=30)
    assert hb["period"] == pytest.approx(T, abs=1e-8)
    assert hb["amplitude"]["x"] == pytest.approx(a, abs=1e-8)
    for r in (shot, hb):
        mu = np.array([complex(*m) for m in r["multipliers"]])
        assert np.min(np.abs(mu - 1)) < 1e-6
        assert nontrivial(r)[0].real == pytest.approx(expected, rel=1e-7)


# ------------------------------------------------------------------------------------------------------ bad input

def test_bad_input_names_the_key(duffing, vdp):
    """Each mistake is an InputError naming its key."""
    cases = [(vdp, dict(period=-1.0, q0={"x": 2.0}), "period"),
             (vdp, dict(period=6.0, q0={"x": 2.0}, harmonics=0), "harmonics"),
             (vdp, dict(q0={"x": 2.0}), "period"),
             (duffing, dict(frequency="w", period=5.0), "period"),
             (duffing, dict(frequency=0.0), "frequency"),
             (duffing, dict(period=5.0, q0={"x": 1.0}), "frequency"),
             (vdp, dict(period=6.0), "q0"),
             (vdp, dict(period=6.0, q0={"x": 2.0}, harmonics=5, mesh=10), "method"),
             (vdp, dict(period=6.0, q0={"x": 2.0}, mesh=1), "mesh"),
             (vdp, dict(period=6.0, q0={"y": 2.0}), "q0.y")]
    for system, options, key in cases:
        with pytest.raises(InputError) as err:
            mechgen.periodic_orbit(system, **options)
        assert err.value.key is not None and err.value.key.endswith(key), (options, err.value)


def test_hybrid_model_is_refused_naming_method():
    """A hybrid model's orbit is found by shooting through its events (tests/test_hybrid_orbits.py): harmonic
    balance is refused at method."""
    ball = mechgen.compile(str(BOUNCING))
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(ball, frequency=1.0, method="harmonic_balance")
    assert err.value.key.endswith("method") and "hybrid" in str(err.value)


def test_non_convergence_names_the_residual_and_what_to_try(duffing):
    """Two Newton steps from far away: a ConvergenceError (exit 1) naming the residual and what to try."""
    with pytest.raises(ConvergenceError) as err:
        mechgen.periodic_orbit(duffing, frequency="w", method="harmonic_balance", q0={"x": 20.0}, max_iterations=2)
    text = str(err.value)
    assert "residual" in text and "try" in text and "max_iterations" in text


def test_a_start_from_an_earlier_simulate(duffing, vdp):
    """``from`` a simulate that settled onto the orbit: the same orbit as from a guess (the forced start state to
    1e-8, the limit cycle's period to 1e-9: Newton's and the integrators' tolerances), the autonomous period's
    guess taken from the run."""
    settle = mechgen.simulate(vdp, t_end=40.0, q0={"x": 0.5}, samples=801, name="settle")
    cycle = mechgen.periodic_orbit(vdp, **{"from": settle})
    assert cycle["period"] == pytest.approx(VDP_PERIOD_MU1, abs=1e-9)
    forced = mechgen.simulate(duffing, t_end=300.0, q0={"x": 1.0}, samples=3001, name="forced")
    orbit = mechgen.periodic_orbit(duffing, frequency="w", **{"from": forced})
    x0, _, _ = duffing_reference(0.05, 0.5, 0.3, 1.2, [1.3, 0.5])
    np.testing.assert_allclose([orbit["trajectory"]["x"][0], orbit["trajectory"]["x_dot"][0]], x0, atol=1e-8)


def test_from_needs_a_simulate_with_its_trajectory(duffing):
    short = mechgen.simulate(duffing, t_end=3.0, series=False, name="short")
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(duffing, frequency="w", **{"from": short})
    assert err.value.key == "from" and "series = true" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(duffing, frequency="w", q0={"x": 1.0}, **{"from": short})
    assert err.value.key.endswith("from")
    steady = mechgen.steady(duffing, name="rest")
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(duffing, frequency="w", **{"from": steady})
    assert err.value.key.endswith("from") and "not simulate" in str(err.value)


TWO_DOF = '''\
"""Two forced masses, a cubic spring and a mass that depends on q: M = diag(1, 1 + b x1^2)."""
import sympy as sp

from mechgen import Model, Param

model = Model("user_orbit_two_dof", doc=__doc__)
model.params(Param("c", 0.1), Param("k3", 0.3), Param("b", 0.2), Param("F", 1.0), Param("w", 0.8))
model.coordinates("x1", "x2")


@model.kinetic
def kinetic(q, v, p):
    return v.x1**2 / 2 + (1 + p.b * q.x1**2) * v.x2**2 / 2


@model.potential
def potential(q, p):
    return q.x1**2 / 2 + (q.x2 - q.x1) ** 2 / 2 + p.k3 * q.x1**4 / 4


@model.dissipation
def dissipation(v, p):
    return p.c * (v.x1**2 + v.x2**2) / 2


@model.forces
def forces(p, t):
    return {"x1": p.F * sp.cos(p.w * t)}
'''


@pytest.fixture(scope="module")
def two_dof(folder):
    (folder / "two_dof.py").write_text(TWO_DOF)
    return mechgen.compile(str(folder / "two_dof.py"))


def central_jacobian(fun, u, h=1e-6):
    """dR/du by central differences (step h: error ~h^2 R''' + eps R / h ~ 1e-10 here)."""
    cols = []
    for j in range(u.size):
        e = np.zeros(u.size)
        e[j] = h
        cols.append((fun(u + e) - fun(u - e)) / (2 * h))
    return np.array(cols).T


def test_harmonic_balance_jacobian_is_the_derivative_of_its_residual(two_dof, vdp):
    """The assembled Galerkin Jacobian (two coordinates, a mass that depends on q; and the autonomous one with its
    frequency column and phase row) against central differences of the residual at a random point (1e-7)."""
    from mechgen.runtime.periodic.fourier import basis
    from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance

    rng = np.random.default_rng(7)
    for system, omega in ((two_dof, 0.8), (vdp, None)):
        problem = HarmonicBalance(system, basis(4), omega, 0)
        u = 0.5 * rng.standard_normal(9 * system.n + (omega is None))
        if omega is None:
            u[-1] = 0.9
        R, J = problem.residual_jacobian(u)
        np.testing.assert_allclose(J, central_jacobian(problem.residual, u), rtol=0, atol=1e-7)


def test_two_coordinates_and_a_configuration_dependent_mass(two_dof):
    """Both methods on a two-mass forced orbit with M(q): shooting against scipy's shooting of the hand-written
    equations (1e-8); harmonic balance (H = 15) against shooting within 10 times its first left-out harmonic (from
    the reference's FFT) plus shooting's own 1e-8; the multipliers' product against Liouville, exp(int trace J dt):
    trace J = -c (1 + 1/m2) - 2 b x1 v1 / m2 (m2 = 1 + b x1^2), whose last term is -d/dt ln(m2) and integrates to
    zero over a period, so the first term is integrated by scipy beside the state (1e-8)."""
    c, k3, b, F, w = 0.1, 0.3, 0.2, 1.0, 0.8
    T = 2 * math.pi / w

    def rhs(t, y):
        x1, x2, v1, v2, _ = y
        m2 = 1 + b * x1**2
        a1 = F * math.cos(w * t) - c * v1 - x1 + (x2 - x1) - k3 * x1**3 + b * x1 * v2**2
        a2 = (-c * v2 - (x2 - x1) - 2 * b * x1 * v1 * v2) / m2
        return [v1, v2, a1, a2, -c * (1 + 1 / m2)]

    def end(x):
        return si.solve_ivp(rhs, (0, T), [*x, 0.0], method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]

    x0 = so.fsolve(lambda x: end(x)[:4] - x, [0.5, 0.5, 0.0, 0.0], xtol=1e-13)
    liouville = math.exp(end(x0)[4])
    shot = mechgen.periodic_orbit(two_dof, frequency="w", method="shooting", q0={"x1": 0.5, "x2": 0.5})
    got = [shot["trajectory"][k][0] for k in ("x1", "x2", "x1_dot", "x2_dot")]
    np.testing.assert_allclose(got, x0, rtol=0, atol=1e-8)
    mu = np.array([complex(*m) for m in shot["multipliers"]])
    assert np.prod(mu).real == pytest.approx(liouville, rel=1e-8)
    N = 256
    ref = si.solve_ivp(rhs, (0, T), [*x0, 0.0], method="DOP853", rtol=1e-13, atol=1e-14,
                       t_eval=T * np.arange(N) / N).y
    truncation = 10 * max(math.hypot(*(c[16] for c in fft_harmonics(ref[i]))) for i in range(2))
    assert truncation < 1e-5
    hb = mechgen.periodic_orbit(two_dof, frequency="w", harmonics=15, q0={"x1": 0.5, "x2": 0.5})
    for k in ("x1", "x2"):
        np.testing.assert_allclose(hb["trajectory"][k], shot["trajectory"][k], rtol=0, atol=truncation + 1e-8)


def test_the_continuation_interface_derivatives(duffing):
    """What a continuation of orbits builds on (mechgen.runtime.periodic): dR/dF of harmonic balance is exactly
    -1 on the first cosine coefficient and 0 elsewhere (r = x'' + ... - F cos(w t)), to the central differences'
    rounding (1e-9); shooting's dR/domega at fixed parameters against central differences of its residual in omega
    (1e-6: differences of a flow integrated at rtol 1e-11 with step 1e-4)."""
    from mechgen.runtime.periodic.fourier import basis
    from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance
    from mechgen.runtime.periodic.parameters import parameter_derivative
    from mechgen.runtime.periodic.shooting import Shooting

    u = np.array([0.1, 1.3, 0.0, 0.02, 0.5, 0.0, 0.01])
    dF = parameter_derivative(lambda s: HarmonicBalance(s, basis(3), 1.2), duffing, u, "F")
    expected = np.zeros(7)
    expected[1] = -1.0
    np.testing.assert_allclose(dF, expected, rtol=0, atol=1e-9)
    x0 = np.array([1.3, 0.5])
    shooting = Shooting(duffing, 1.2, 0, 1e-13, 1e-14)
    h = 1e-4
    differences = (Shooting(duffing, 1.2 + h, 0, 1e-13, 1e-14).residual_jacobian(x0)[0]
                   - Shooting(duffing, 1.2 - h, 0, 1e-13, 1e-14).residual_jacobian(x0)[0]) / (2 * h)
    np.testing.assert_allclose(shooting.frequency_derivative(x0), differences, rtol=0, atol=1e-6)


def test_frequency_as_a_parameter_expression(duffing):
    """``frequency = "w"`` is the parameter's value: the same orbit as the number 1.2."""
    by_name = mechgen.periodic_orbit(duffing, frequency="w", harmonics=5, q0={"x": 1.3})
    by_value = mechgen.periodic_orbit(duffing, frequency=1.2, harmonics=5, q0={"x": 1.3})
    assert by_name["period"] == by_value["period"] == 2 * math.pi / 1.2
    for part in ("cos", "sin"):
        np.testing.assert_array_equal(by_name["harmonics"]["x"][part], by_value["harmonics"]["x"][part])


def test_collocation_converges_at_order_eight(vdp, duffing):
    """Orthogonal collocation (degree 4, Gauss points): the van der Pol period's error against the cited value falls
    by about 2^8 = 256 from mesh 20 to mesh 40 (order 2m = 8 at the mesh points; measured 4.1e-7 -> 1.3e-9, ratio
    in [100, 600]: the asymptotic rate with room for the next term), and mesh 80 is within 1e-10; the forced Duffing
    start state against scipy's shooting (1e-9 at mesh 40); the multipliers as shooting's (1e-7)."""
    errors = []
    for mesh in (20, 40, 80):
        r = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0}, mesh=mesh)
        assert r["method"] == "collocation"
        errors.append(abs(r["period"] - VDP_PERIOD_MU1))
    assert 100 < errors[0] / errors[1] < 600
    assert errors[2] < 1e-10
    x0, T, _ = duffing_reference(0.05, 0.5, 0.3, 1.2, [1.3, 0.5])
    col = mechgen.periodic_orbit(duffing, frequency="w", method="collocation", q0={"x": 1.3}, v0={"x": 0.5})
    np.testing.assert_allclose([col["trajectory"]["x"][0], col["trajectory"]["x_dot"][0]], x0, rtol=0, atol=1e-9)
    assert col["trajectory"]["x"][-1] == pytest.approx(x0[0], abs=1e-9)  # periodic: the last sample is t = T
    shot = mechgen.periodic_orbit(duffing, frequency="w", q0={"x": 1.3}, v0={"x": 0.5})
    np.testing.assert_allclose(col["multipliers"], shot["multipliers"], rtol=0, atol=1e-7)


def test_three_coexisting_orbits_and_the_unstable_one(duffing):
    """Above resonance (w = 1.4) the hardening Duffing oscillator has three orbits; started from the first-order
    closed form's amplitude and phase (a1 = A cos phi, b1 = A sin phi from (1 - w^2 + 3/4 k3 A^2) A = F cos phi,
    c w A = F sin phi), each method finds each orbit: the start state against scipy's shooting from the same guess
    (1e-7: harmonic balance's H = 11 truncation, collocation's mesh-40 error and shooting's 1e-9 are below it), the
    outer two stable and the middle one a saddle, its real multiplier > 1 against the eigenvalues of scipy's
    monodromy by central differences (1e-6: step 1e-5)."""
    c, k3, F, w = 0.05, 0.5, 0.3, 1.4
    system = duffing.with_params(w=w)
    roots = np.roots([(0.75 * k3) ** 2, 2 * (1 - w**2) * 0.75 * k3, (1 - w**2) ** 2 + (c * w) ** 2, -F**2])
    amplitudes = sorted(math.sqrt(r.real) for r in roots if abs(r.imag) < 1e-12)
    assert len(amplitudes) == 3
    for A, verdict in zip(amplitudes, ("stable", "unstable", "stable")):
        cos_phi, sin_phi = (1 - w**2 + 0.75 * k3 * A**2) * A / F, c * w * A / F
        guess = [A * cos_phi, w * A * sin_phi]
        x0, T, rhs = duffing_reference(c, k3, F, w, guess)
        for method, extra in (("harmonic_balance", {"harmonics": 11}), ("shooting", {}), ("collocation", {})):
            r = mechgen.periodic_orbit(system, frequency="w", method=method, q0={"x": guess[0]},
                                       v0={"x": guess[1]}, **extra)
            start = [r["trajectory"]["x"][0], r["trajectory"]["x_dot"][0]]
            np.testing.assert_allclose(start, x0, rtol=0, atol=1e-7, err_msg=f"{method} at A = {A}")
            assert r["stability"] == verdict, (method, A)
        if verdict == "unstable":
            h = 1e-5
            Phi = np.array([(scipy_flow(rhs, x0 + e, T).y[:, -1] - scipy_flow(rhs, x0 - e, T).y[:, -1]) / (2 * h)
                            for e in h * np.eye(2)]).T
            expected = np.sort(np.linalg.eigvals(Phi).real)
            mu = np.sort([m[0] for m in r["multipliers"]])
            assert expected[1] > 1
            np.testing.assert_allclose(mu, expected, rtol=0, atol=1e-6)


SCENE = """model = "van_der_pol"
[params]
mu = 1.0
[[analysis]]
name = "cycle"
kind = "periodic_orbit"
{body}
"""


@pytest.mark.parametrize("body, code, words", [
    ('period = -1.0\nq0 = { x = 2.0 }', 2, ["analysis[1].period", "not positive"]),
    ('period = 6.5\nq0 = { x = 2.0 }\nharmonics = 0', 2, ["analysis[1].harmonics", "below 1"]),
    ('period = 6.5\nq0 = { x = 2.0 }\nmethod = "spline"', 2, ["analysis[1].method", "harmonic_balance"]),
    ('period = 6.5\nq0 = { x = 20.0 }\nharmonics = 5\nmax_iterations = 1', 1, ["residual", "try"]),
    ('period = 6.5\nq0 = { x = 2.0 }\nmesh = 20', 0, []),
])
def test_the_command_line_exit_codes(body, code, words, tmp_path, capsys):
    """A scene's mistakes exit 2 naming the file and the key; a starting guess that does not converge exits 1
    naming the residual and what to try; a good one runs."""
    from mechgen.cli import main

    path = tmp_path / "orbit.toml"
    path.write_text(SCENE.format(body=body))
    assert main(["run", str(path)]) == code
    err = capsys.readouterr().err
    for word in words:
        assert word in err, err
    if code == 2:
        assert str(path) in err or "orbit.toml" in err


def test_multiple_shooting_on_an_unstable_cycle_and_a_forced_orbit(vdp, duffing):
    """mu = -1 reverses time: the van der Pol cycle becomes unstable, same period, its non-trivial multiplier the
    reciprocal of mu = +1's (about 1163), exp(-int (1 - x^2) dt) from scipy's reference at mu = 1 (1e-6 relative:
    the multiplier's sensitivity is ~1e3 times the integrations' 1e-11). Multiple shooting (8 segments, in both loops)
    and single shooting agree; a forced orbit by 3 segments matches scipy's start state (1e-8)."""
    _, T, decay = vdp_reference(1.0, 2.0, 6.6)
    unstable = vdp.with_params(mu=-1.0)
    for segments, loop in ((1, "auto"), (8, "auto"), (8, "python")):
        r = mechgen.periodic_orbit(unstable, period=6.5, q0={"x": 2.0}, segments=segments, loop=loop)
        assert r["period"] == pytest.approx(T, abs=1e-9)
        assert r["stability"] == "unstable"
        assert nontrivial(r)[0].real == pytest.approx(1 / decay, rel=1e-6)
    x0, _, _ = duffing_reference(0.05, 0.5, 0.3, 1.2, [1.3, 0.5])
    r = mechgen.periodic_orbit(duffing, frequency="w", q0={"x": 1.3}, v0={"x": 0.5}, segments=3)
    np.testing.assert_allclose([r["trajectory"]["x"][0], r["trajectory"]["x_dot"][0]], x0, rtol=0, atol=1e-8)


@pytest.mark.parametrize("name, what, options", [("fpu_chain", "a chain", {}),
                                                  ("euler_bernoulli_beam", "a continuum", {}),
                                                  ("rate_state_slider", "internal variables",
                                                   {"method": "harmonic_balance"})])
def test_models_outside_the_methods_assumptions_are_refused(name, what, options):
    """A chain, a continuum, and a model with internal variables by harmonic balance (its residual holds the
    coordinates only; shooting carries them): exit 2 at ``method``, saying which."""
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(mechgen.compile(name), frequency=1.0, **options)
    assert err.value.key.endswith("method") and what in str(err.value)


def test_collocation_mesh_adaptation_on_a_relaxation_cycle(vdp):
    """mu = 5: a relaxation oscillation, slow drifts and fast jumps. From a simulate's motion, 40 uniform intervals
    leave a period error of about 4e-3 against scipy's shooting; two adaptations (AUTO's equidistributed monitor)
    bring the same 40 intervals below 1e-6 (measured 1e-7): more than a thousandfold."""
    mu = 5.0
    system = vdp.with_params(mu=mu)

    def rhs(t, y):
        return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]]

    def residual(u):
        end = scipy_flow(rhs, [u[0], 0.0], u[1]).y[:, -1]
        return [end[0] - u[0], end[1]]

    a, T = so.fsolve(residual, [2.0, 11.6], xtol=1e-13)
    settle = mechgen.simulate(system, t_end=60.0, q0={"x": 2.0}, samples=3001, name="settle")
    uniform = mechgen.periodic_orbit(system, mesh=40, **{"from": settle})
    adapted = mechgen.periodic_orbit(system, mesh=40, adapt=2, **{"from": settle})
    error_uniform, error_adapted = abs(uniform["period"] - T), abs(adapted["period"] - T)
    assert error_adapted < 1e-6 and error_adapted < error_uniform / 1000
    assert adapted["amplitude"]["x"] == pytest.approx(a, abs=1e-6)
    # harmonic balance may converge to the mirrored solution (omega < 0, b_k -> -b_k: the same autonomous orbit);
    # it reports the orbit with its positive frequency (H = 20 truncates this cycle: measured 1.0e-2 in T)
    hb = mechgen.periodic_orbit(system, harmonics=20, **{"from": settle})
    assert hb["frequency"] > 0 and hb["period"] == pytest.approx(T, abs=0.05)


def test_hills_method_gives_the_monodromy_multipliers(duffing, vdp):
    """Hill's method (floquet = "hill", no integration) against the monodromy matrix's multipliers: the stable forced
    orbit (complex pair) and the saddle above resonance (real, one > 1), 1e-7 with H = 11 (the truncation's effect
    on the multipliers, like the orbit's); the van der Pol cycle at H = 30: the trivial 1 and exp(mu int (1 - x^2)
    dt) from scipy (1e-7 relative). Asked of another method it is refused at ``floquet``."""
    A, c, k3, F, w = 1.42496445, 0.05, 0.5, 0.3, 1.4  # the saddle's first-order amplitude and phase (closed form)
    saddle = {"q0": {"x": (1 - w**2 + 0.75 * k3 * A**2) * A**2 / F}, "v0": {"x": c * w**2 * A**2 / F}}
    for w, guess in ((1.2, {"q0": {"x": 1.3}, "v0": {"x": 0.5}}), (1.4, saddle)):
        system = duffing.with_params(w=w)
        hill = mechgen.periodic_orbit(system, frequency="w", harmonics=11, floquet="hill", **guess)
        shot = mechgen.periodic_orbit(system, frequency="w", **guess)
        assert hill["amplitude"]["x"] == pytest.approx(shot["amplitude"]["x"], abs=1e-7)  # the same orbit
        np.testing.assert_allclose(hill["multipliers"], shot["multipliers"], rtol=0, atol=1e-7)
    assert hill["stability"] == "unstable"
    _, _, expected = vdp_reference(1.0, 2.0, 6.6)
    cycle = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0}, harmonics=30, floquet="hill")
    mu = np.array([complex(*m) for m in cycle["multipliers"]])
    assert np.min(np.abs(mu - 1)) < 1e-7
    assert nontrivial(cycle)[0].real == pytest.approx(expected, rel=1e-7)
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0}, floquet="hill")
    assert err.value.key.endswith("floquet")


HOPF_NORMAL_FORM = '''"""z1' = mu z1 - w z2 - z1 (z1^2 + z2^2), z2' = w z1 + mu z2 - z2 (z1^2 + z2^2): internal variables only."""
from mechgen import Model, Param

model = Model("hopf_normal_form", doc=__doc__)
model.params(Param("mu", 0.25), Param("w", 2.0))
model.internal("z1", lambda z, p: p.mu * z.z1 - p.w * z.z2 - z.z1 * (z.z1**2 + z.z2**2))
model.internal("z2", lambda z, p: p.w * z.z1 + p.mu * z.z2 - z.z2 * (z.z1**2 + z.z2**2))
'''


def test_limit_cycle_of_a_model_of_internal_variables(tmp_path):
    """Shooting carries the internal variables (x = (q, v, z)): the Hopf normal form's cycle is the circle
    r^2 = mu with period 2 pi / w (closed form) - the amplitude of z1 to 1e-8 and the period to 1e-9; harmonic
    balance is refused for it (its residual holds the coordinates only)."""
    path = tmp_path / "normal_form.py"
    path.write_text(HOPF_NORMAL_FORM)
    system = mechgen.compile(str(path))
    r = mechgen.periodic_orbit(system, method="shooting", period=3.0, z0={"z1": 0.4})
    assert r["period"] == pytest.approx(np.pi, abs=1e-9)
    assert r["amplitude"]["z1"] == pytest.approx(0.5, abs=1e-8) and r["amplitude"]["z2"] == pytest.approx(0.5, abs=1e-8)
    assert r["stability"] == "stable"


def test_internal_variables_guess_and_refusals(tmp_path):
    """z0 naming no internal variable: exit 2 at z0.<name>, listing the names; harmonic balance on a model of
    internal variables: exit 2 at method."""
    path = tmp_path / "normal_form.py"
    path.write_text(HOPF_NORMAL_FORM)
    system = mechgen.compile(str(path))
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(system, method="shooting", period=3.0, z0={"z3": 0.4})
    assert err.value.key.endswith("z0.z3") and "z1, z2" in str(err.value)
    with pytest.raises(InputError) as err:
        mechgen.periodic_orbit(system, method="harmonic_balance", period=3.0, z0={"z1": 0.4})
    assert err.value.key.endswith("method") and "internal variables" in str(err.value)


@pytest.mark.parametrize("block_bytes", [None, 3000, 1])
def test_interval_blocks_are_the_jacobians_rows_and_node_columns(monkeypatch, block_bytes):
    """Collocation.interval_blocks (the monodromy's input) against scipy's own indexing J[rows][:, cols] of a random
    sparse J, interval by interval: one interval (its last node its first), two, five and seven, gathered all at once
    and in chunks of two intervals and of one (BLOCK_BYTES)."""
    import scipy.sparse as sps

    from mechgen.runtime.periodic import collocation
    from mechgen.runtime.periodic.collocation import DEGREE, Collocation

    if block_bytes is not None:
        monkeypatch.setattr(collocation, "BLOCK_BYTES", block_bytes)

    class ThreeStates:  # x = (q, v, z): n = 1 coordinate, m = 1 internal variable
        n, m = 1, 1

    for mesh in (1, 2, 5, 7):
        problem = Collocation(ThreeStates(), mesh, None)
        d, size = problem.state_size, mesh * DEGREE * problem.state_size + 1
        J = sps.random(size, size, density=0.3, random_state=mesh, format="csr")
        blocks = list(problem.interval_blocks(J))
        assert len(blocks) == mesh
        for i, nodes in enumerate(problem.node_index()):
            cols = (nodes[:, None] * d + np.arange(d)[None, :]).ravel()
            expected = J[np.arange(i * DEGREE * d, (i + 1) * DEGREE * d)][:, cols].toarray()
            np.testing.assert_array_equal(blocks[i], expected)
