"""The closed forms of impact_reference.py against brute-force solve_ivp (rtol 1e-12) of the same ODEs
with release events, plus the limits (MKV across zeta = 1, SLS as epsilon -> 0, Hunt-Crossley small a)
and the hand-written baseline in benchmarks/impact_handwritten.py.

References: Butcher & Segalman, J. Appl. Mech. 67 (2000) 831 (eqs. 4, 9-11, 14-16, 19-21);
Hunt & Crossley, J. Appl. Mech. 42 (1975) 440; Forrestal et al., Int. J. Impact Eng. 15 (1994) 395
and Frew, Forrestal & Hanchak, J. Appl. Mech. 67 (2000) 841 (eqs. 1-3).  Derivations are in the
docstrings of impact_reference.py; symbolic steps in derive_impact_reference.py.
"""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import lambertw

import impact_reference as ref

RTOL, ATOL = 1e-12, 1e-14
M, WN, V = 2.0, 3.0, 1.5          # dimensional on purpose: e must not depend on them


def _release(rhs, y0, event, t_max, method="DOP853"):
    """Integrate to the first downward zero of event; (t_r, state) or (None, final state)."""
    event.terminal, event.direction = True, -1.0
    sol = solve_ivp(rhs, (0.0, t_max), y0, method=method, rtol=RTOL, atol=ATOL, events=event)
    if sol.t_events[0].size:
        return float(sol.t_events[0][0]), sol.y_events[0][0]
    return None, sol.y[:, -1]


# ------------------------------------------------------------------------------ KV and modified KV

def _kv_brute(zeta, release, t_max=60.0):
    k, c = ref.kv_parameters(M, WN, zeta)

    def rhs(t, s):  # x, v, dissipated energy int c v^2 dt
        return [s[1], -(k * s[0] + c * s[1]) / M, c * s[1] ** 2]
    ev = (lambda t, s: s[0]) if release == "x" else (lambda t, s: k * s[0] + c * s[1])
    return _release(rhs, [0.0, V, 0.0], ev, t_max / WN), k


@pytest.mark.parametrize("zeta", [0.05, 0.3, 0.7, 0.95])
def test_kv_half_period(zeta):
    (t_r, s), _ = _kv_brute(zeta, "x")
    e = ref.kv_restitution(zeta)
    assert -s[1] / V == pytest.approx(e, abs=1e-10)
    assert t_r == pytest.approx(ref.kv_contact_time(zeta, WN), rel=1e-10)
    E0 = 0.5 * M * V * V   # x = 0 at release: all lost kinetic energy went into the dashpot
    assert s[2] == pytest.approx(ref.energy_lost(e, E0), rel=1e-9)


@pytest.mark.parametrize("zeta", [1.0, 1.5])
def test_kv_overdamped_never_returns(zeta):
    (t_r, s), _ = _kv_brute(zeta, "x", t_max=30.0)
    assert t_r is None and s[0] > 0.0
    assert ref.kv_restitution(zeta) == 0.0 and ref.kv_contact_time(zeta) == math.inf


@pytest.mark.parametrize("zeta", [0.05, 0.3, 0.7, 0.999, 1.0, 1.001, 1.5, 4.0])
def test_modified_kv(zeta):
    (t_r, s), k = _kv_brute(zeta, "F")
    e = ref.mkv_restitution(zeta)
    assert -s[1] / V == pytest.approx(e, abs=1e-10)
    assert t_r == pytest.approx(ref.mkv_contact_time(zeta, WN), rel=1e-9)
    x_r = ref.mkv_release_penetration(zeta, V, WN)
    assert s[0] == pytest.approx(x_r, rel=1e-8, abs=1e-13) and x_r > 0
    # lost kinetic energy = dissipated during contact + still in the spring
    E0 = 0.5 * M * V * V
    assert s[2] + 0.5 * k * s[0] ** 2 == pytest.approx(ref.energy_lost(e, E0), rel=1e-9)


def test_modified_kv_forms_and_continuity():
    for z in (0.1, 0.5, 0.9):  # paper eq. 10 with the atan2 branch
        b = math.sqrt(1 - z * z)
        assert ref.mkv_restitution(z) == pytest.approx(math.exp(-(z / b) * math.atan2(2 * z * b, 2 * z * z - 1)), rel=1e-14)
        assert ref.mkv_contact_time(z) == pytest.approx(math.atan2(2 * z * b, 2 * z * z - 1) / b, rel=1e-14)
    for z in (1.2, 3.0, 50.0):  # paper eq. 11
        g = math.sqrt(z * z - 1)
        assert ref.mkv_restitution(z) == pytest.approx(((z - g) / (z + g)) ** (z / g), rel=1e-12)
        assert ref.mkv_contact_time(z) == pytest.approx(math.log((z + g) / (z - g)) / g, rel=1e-12)
    assert ref.mkv_restitution(1.0) == pytest.approx(math.exp(-2), rel=1e-15)
    for dz in (1e-4, 1e-8, 1e-12):  # both branches meet at zeta = 1 (analytic: slope d e/d zeta finite)
        for side in (-1, 1):
            assert ref.mkv_restitution(1 + side * dz) == pytest.approx(math.exp(-2), abs=2 * dz)
            assert ref.mkv_contact_time(1 + side * dz) == pytest.approx(2.0, abs=2 * dz)
    assert ref.mkv_restitution(1e3) == pytest.approx(1 / (2e3) ** 2, rel=0.02)  # e ~ (2 zeta)^-2


# ------------------------------------------------------------------------------ Maxwell

def _maxwell_brute(zeta, t_max):
    k, c = ref.maxwell_parameters(M, WN, zeta)
    assert zeta == pytest.approx(math.sqrt(k * M) / (2 * c), rel=1e-15)   # paper eq. 14

    def rhs(t, s):  # x, v, y
        F = k * (s[0] - s[2])
        return [s[1], -F / M, F / c]
    return _release(rhs, [0.0, V, 0.0], lambda t, s: k * (s[0] - s[2]), t_max / WN), c


@pytest.mark.parametrize("zeta", [0.1, 0.5, 0.9])
def test_maxwell(zeta):
    (t_r, s), c = _maxwell_brute(zeta, 60.0)
    e = ref.maxwell_restitution(zeta)
    assert -s[1] / V == pytest.approx(e, abs=1e-10)
    assert e == ref.kv_restitution(zeta)
    assert t_r == pytest.approx(ref.maxwell_contact_time(zeta, WN), rel=1e-10)
    assert s[0] == pytest.approx(M * V * (1 + e) / c, rel=1e-9)      # permanent set of the dashpot


@pytest.mark.parametrize("zeta", [1.0, 2.0])
def test_maxwell_overdamped_comes_to_rest(zeta):
    sigma = zeta - math.sqrt(zeta * zeta - 1)          # slowest decay rate / omega_n
    (t_r, s), c = _maxwell_brute(zeta, 25.0 / sigma)    # F ~ e^-25: stop before F is rounding noise
    assert t_r is None and abs(s[1]) < 1e-8 * V
    assert s[0] == pytest.approx(M * V / c, rel=1e-7)               # int F dt = m v_in
    assert ref.maxwell_restitution(zeta) == 0.0 and ref.maxwell_contact_time(zeta) == math.inf


# ------------------------------------------------------------------------------ standard linear solid

def test_sls_parameters_round_trip():
    k1, k2, c = ref.sls_parameters(M, WN, 0.4, 0.15)
    assert ref.sls_dimensionless(M, k1, k2, c) == pytest.approx((WN, 0.4, 0.15), rel=1e-14)
    k1, k2, c = ref.sls_parameters(M, WN, 0.4, 1e-9)   # KV limit: k2 -> m wn^2, c -> 2 zeta m wn
    assert (k2, c) == pytest.approx((M * WN ** 2, 2 * 0.4 * M * WN), rel=1e-8)


@pytest.mark.parametrize("zeta,eps", [(0.2, 0.05), (0.6, 0.2), (1.0, 0.1), (1.5, 0.1), (3.0, 0.3)])
def test_sls_exact_against_brute_force(zeta, eps):
    k1, k2, c = ref.sls_parameters(M, WN, zeta, eps)

    def rhs(t, s):  # x, v, y, dissipated int c ydot^2 dt
        F = k1 * (s[0] - s[2])
        yd = (F - k2 * s[2]) / c
        return [s[1], -F / M, yd, c * yd * yd]
    t_r, s = _release(rhs, [0.0, V, 0.0, 0.0], lambda t, s: k1 * (s[0] - s[2]), 60.0 / WN)
    r = ref.sls_release(zeta, eps)
    assert -s[1] / V == pytest.approx(r.e, abs=1e-10)
    assert t_r * WN == pytest.approx(r.tau_r, rel=1e-9)
    assert s[0] * WN / V == pytest.approx(r.x_r, rel=1e-8)
    assert s[3] / (0.5 * M * V * V) == pytest.approx(r.dissipated, rel=1e-8, abs=1e-12)
    assert r.e * r.e + r.stored + r.dissipated == pytest.approx(1.0, abs=1e-15)


def test_sls_limits():
    for z in (0.3, 0.9, 2.0):     # epsilon -> 0: modified K-V
        assert ref.sls_restitution(z, 1e-7) == pytest.approx(ref.mkv_restitution(z), rel=1e-5)
        assert ref.sls_contact_time(z, 1e-7) == pytest.approx(ref.mkv_contact_time(z), rel=1e-5)
    # large zeta at fixed epsilon: the dashpot locks, only k1 is left (elastic, half period of k1)
    r = ref.sls_release(1e4, 0.25)
    assert r.e == pytest.approx(1.0, abs=1e-3) and r.tau_r == pytest.approx(math.pi * math.sqrt(0.25), rel=1e-3)


@pytest.mark.parametrize("zeta", [0.2, 0.6, 0.95, 1.0, 1.3])
def test_sls_first_order_is_second_order_accurate(zeta):
    def residuals(eps):
        r = ref.sls_release(zeta, eps)
        return (r.e - ref.sls_restitution_first_order(zeta, eps),
                r.tau_r - ref.sls_contact_time_first_order(zeta, eps))
    e_res, t_res = zip(*(residuals(eps) for eps in (4e-3, 2e-3, 1e-3)))
    for res in (e_res, t_res):
        c2 = [res[i] / eps ** 2 for i, eps in enumerate((4e-3, 2e-3, 1e-3))]
        assert abs(c2[1] - c2[2]) < 0.03 * abs(c2[2]) + 1e-3       # residual / eps^2 -> constant
        assert abs(c2[2]) < 100.0
    # while the zeroth order alone misses by O(epsilon)
    assert abs(ref.sls_restitution(zeta, 1e-3) - ref.mkv_restitution(zeta)) > 100 * abs(e_res[2])


def test_sls_e1_closed_form_pieces():
    assert ref.sls_e1(1.0) == pytest.approx(8 / 3, rel=1e-15) and ref.sls_tau1(1.0) == pytest.approx(-14 / 3, rel=1e-15)
    for z0 in (1 - 2e-3, 1 + 2e-3):   # series and closed form agree where sls_e1 switches
        for f in (ref.sls_e1, ref.sls_tau1):
            assert f(z0 * (1 - 1e-12)) == pytest.approx(f(z0 * (1 + 1e-12)), rel=1e-11)
    for z in (0.1, 0.5, 0.8):
        f1, f2 = ref.sls_paper_f1_f2(z)
        assert f1 * 2 * math.acos(z) + f2 == pytest.approx(ref.sls_e1(z), rel=1e-13)
    z = 1e-3                           # small zeta: f1 = zeta - zeta^3/2 + O(zeta^5), e1 ~ pi zeta
    assert ref.sls_paper_f1_f2(z)[0] == pytest.approx(z - z ** 3 / 2, rel=1e-11)
    assert ref.sls_e1(z) == pytest.approx(math.pi * z - math.pi * z ** 3 / 2 + 8 * z ** 4 / 3, rel=1e-12)
    assert ref.sls_tau1(0.0) == 0.0


# ------------------------------------------------------------------------------ Hunt-Crossley

@pytest.mark.parametrize("a", [1e-6, 1e-3, 0.05, 0.2999, 0.3, 1.0, 3.0, 10.0, 1e3])
def test_hunt_crossley_root(a):
    e = ref.hc_restitution(a)
    assert 0.0 < e <= min(1.0, 1.0 / a)
    if a > 700:   # 1 - a e = (1+a) exp(-(1+a)) e^(...) underflows: e = 1/a to double precision
        assert e == 1.0 / a
        return
    lhs, rhs = math.log1p(a) - math.log1p(-a * e), a * (1 + e)
    assert lhs == pytest.approx(rhs, rel=1e-13)
    if a < 1e2:  # Lambert-W closed form, e = (1 + W0(-(1+a) exp(-(1+a))))/a (loses digits as a -> 0)
        w = -lambertw(-(1 + a) * math.exp(-(1 + a)), 0).real
        assert e == pytest.approx((1 - w) / a, rel=1e-12 / min(a, 1.0) ** 2)


def test_hunt_crossley_small_a_series():
    for a in (1e-3, 0.01, 0.05, 0.1):
        assert abs(ref.hc_restitution(a) - ref.hc_restitution_series(a)) < 2 * a ** 7 + 1e-16
    assert ref.hc_restitution_series(0.01, 1) == pytest.approx(1 - 0.02 / 3, rel=1e-15)


@pytest.mark.parametrize("a,n", [(0.05, 1.5), (0.5, 1.0), (0.5, 2.5), (2.0, 1.5)])
def test_hunt_crossley_against_brute_force(a, n):
    k, m, v = 7.0, 0.3, 2.0
    alpha = a / v

    def rhs(t, s):
        return [s[1], -k * max(s[0], 0.0) ** n * (1 + alpha * s[1]) / m]
    T = ref.hc_contact_time(0.0, n, m, k, v)
    t_r, s = _release(rhs, [0.0, v], lambda t, s: s[0], 50 * T)
    assert -s[1] / v == pytest.approx(ref.hc_restitution(a), abs=1e-9)     # independent of k, m, n
    assert t_r == pytest.approx(ref.hc_contact_time(a, n, m, k, v), rel=1e-8)


def test_hunt_crossley_contact_time_linear_elastic():
    assert ref.hc_contact_time(0.0, 1.0, 2.0, 8.0, 3.0) == pytest.approx(math.pi * math.sqrt(2.0 / 8.0), rel=1e-12)
    assert ref.hc_contact_time(1e-9, 1.0, 2.0, 8.0, 3.0) == pytest.approx(math.pi * math.sqrt(2.0 / 8.0), rel=1e-8)


# ------------------------------------------------------------------------------ penetration

P127 = ref.FREW_2001_PROJECTILES["12.7mm"]
ARGS = (P127["m"], P127["two_a"] / 2, P127["psi"], ref.LIMESTONE_DENSITY, P127["R"])


def _penetration_brute(m, a, psi, rho, R, Vs):
    N = ref.forrestal_N(psi)
    c = ref.crater_stiffness(m, a, psi, rho, R, Vs)
    at4a = lambda t, s: s[0] - 4 * a
    at4a.terminal, at4a.direction = True, 1.0
    stop = lambda t, s: s[1]
    stop.terminal, stop.direction = True, -1.0
    s1 = solve_ivp(lambda t, s: [s[1], -c * s[0] / m], (0, 1.0), [0.0, Vs], method="DOP853",
                   rtol=RTOL, atol=1e-16, events=(at4a, stop))
    if s1.t_events[1].size:
        return s1.y_events[1][0][0], s1.t_events[1][0]
    t1, y1 = s1.t_events[0][0], s1.y_events[0][0]
    s2 = solve_ivp(lambda t, s: [s[1], -math.pi * a * a * (R + N * rho * s[1] ** 2) / m], (t1, 1.0), y1,
                   method="DOP853", rtol=RTOL, atol=1e-16, events=stop)
    return s2.y_events[0][0][0], s2.t_events[0][0]


@pytest.mark.parametrize("Vs", [50.0, 400.0, 1000.0, 1800.0])
def test_penetration_against_brute_force(Vs):
    P, t = _penetration_brute(*ARGS, Vs)
    assert P == pytest.approx(ref.penetration_depth(*ARGS, Vs), rel=1e-10)
    assert t == pytest.approx(ref.penetration_time(*ARGS, Vs)[1], rel=1e-10)
    assert ref.strength_from_depth(*ARGS[:4], Vs, P) == pytest.approx(P127["R"], rel=1e-8)   # eq. 2 inverts eq. 1


def test_penetration_crater_rule_and_data():
    m, a, psi, rho, R = ARGS
    V_star = math.sqrt(4 * math.pi * a ** 3 * R / m)        # m Vs^2 = 4 pi a^3 R: stops exactly at x = 4a
    for Vs in (V_star * (1 - 1e-9), V_star * (1 + 1e-9)):
        assert ref.penetration_depth(*ARGS, Vs) == pytest.approx(4 * a, rel=1e-7)
    assert ref.penetration_depth(*ARGS, 0.5 * V_star) == pytest.approx(0.5 * V_star * math.sqrt(m / (math.pi * a * R / 4)), rel=1e-14)
    assert ref.forrestal_N(3.0) == pytest.approx(23 / 216, rel=1e-15)
    for p in ref.FREW_2001_PROJECTILES.values():            # eq. 3 recovers the fitted R within 1.2 %
        assert ref.frew_strength(p["two_a"]) == pytest.approx(p["R"], rel=0.012)
    assert 2000.0 < ref.LIMESTONE_DENSITY < 2700.0


# ------------------------------------------------------------------------------ hand-written baseline

def _baseline():
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "impact_handwritten.py"
    spec = importlib.util.spec_from_file_location("impact_handwritten", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_handwritten_baseline_matches_references():
    hw = _baseline()
    zetas = [0.3, 1.5]
    exact = {"kv": ref.kv_restitution, "mkv": ref.mkv_restitution, "maxwell": ref.maxwell_restitution,
             "sls": lambda z: ref.sls_restitution(z, 0.2)}
    times = {"kv": ref.kv_contact_time, "mkv": ref.mkv_contact_time, "maxwell": ref.maxwell_contact_time,
             "sls": lambda z: ref.sls_contact_time(z, 0.2)}
    for model in exact:
        sw = hw.restitution_sweep(model, zetas, rtol=1e-11, atol=1e-13, method="DOP853", epsilon=0.2, t_max=40.0)
        for z, e, t in zip(zetas, sw.e, sw.t_c):
            assert e == pytest.approx(exact[model](z), abs=1e-8)
            assert t == pytest.approx(times[model](z), rel=1e-8) if math.isfinite(times[model](z)) else t == math.inf
    sw = hw.restitution_sweep("hunt_crossley", [0.1, 1.0], rtol=1e-11, atol=1e-13, n=1.5)
    assert sw.e == pytest.approx([ref.hc_restitution(0.1), ref.hc_restitution(1.0)], abs=1e-8)
    assert sw.t_c == pytest.approx([ref.hc_contact_time(0.1, 1.5), ref.hc_contact_time(1.0, 1.5)], rel=1e-8)
    for Vs in (100.0, 1000.0):
        r = hw.penetration(*ARGS, Vs)
        assert r.P == pytest.approx(ref.penetration_depth(*ARGS, Vs), rel=1e-8)
        t_cr, t_rest = ref.penetration_time(*ARGS, Vs)
        assert r.t_rest == pytest.approx(t_rest, rel=1e-8)
        assert r.t_crater == pytest.approx(t_cr, rel=1e-8) if math.isfinite(t_cr) else r.t_crater == math.inf
