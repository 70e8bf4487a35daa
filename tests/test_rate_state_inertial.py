"""Spring-slider with inertia and rate-and-state friction (mechgen/models/rate_state_inertial.py).

m V' = F - sigma mu, F' = k (V2 - V), mu = mu0 + a ln(V/V*) + b ln(V* theta/D_c), aging or slip law. With
u = phi - ln(V2/V*), w = psi + ln(V2/V*), g = f - (a - b) ln(V2/V*), M = m V2/sigma, w0 = V2/D_c and
kappa = k V2/sigma, both laws linearise about steady sliding at V2 to

    w' = -w0 (u + w),   g' = -kappa u,   M u' = g - a u - b w,

whose characteristic polynomial (eliminate w = -w0 u/(s + w0), g = -kappa u/s) is

    M s^3 + (M w0 + a) s^2 + (kappa - (b - a) w0) s + kappa w0 = 0.

At s = i Omega: Omega^2 = kappa w0/(M w0 + a) = (kappa - (b - a) w0)/M, so kappa_c = (b - a) w0 (1 + M w0/a):
k_c = sigma (b - a)/D_c (1 + m V2^2/(sigma a D_c)) and Omega = w0 sqrt((b - a)/a) (Rice & Ruina 1983, J. Appl.
Mech. 50, 343, the spring-slider with inertia; Ruina 1983, J. Geophys. Res. 88, 10359). m -> 0 recovers the
quasi-static slider (tests/test_rate_state.py).
"""
import math

import numpy as np
import pytest

import mechgen

BASE = {"a": 0.01, "b": 0.015, "D_c": 1e-5, "sigma": 1e7, "mu0": 0.6, "V1": 1e-6, "V2": 1e-5, "V_ref": 1e-6}


def k_critical(p: dict) -> float:
    return p["sigma"] * (p["b"] - p["a"]) / p["D_c"] * (1 + p["m"] * p["V2"] ** 2 / (p["sigma"] * p["a"] * p["D_c"]))


def cubic_roots(p: dict) -> np.ndarray:
    M, w0, kappa = p["m"] * p["V2"] / p["sigma"], p["V2"] / p["D_c"], p["k"] * p["V2"] / p["sigma"]
    return np.roots([M, M * w0 + p["a"], kappa - (p["b"] - p["a"]) * w0, kappa * w0])


@pytest.mark.parametrize("law", ["aging", "slip"])
@pytest.mark.parametrize("m", [1e8, 1e10])
def test_critical_stiffness_with_inertia(law, m):
    """k_c = sigma (b - a)/D_c (1 + m V2^2/(sigma a D_c)) and Omega = (V2/D_c) sqrt((b - a)/a) to 1e-10 (module
    doc); the eigenvalues at 0.8 k_c are the roots of the cubic."""
    p = {**BASE, "m": m}
    k_c = k_critical(p)
    system = mechgen.compile("rate_state_inertial", {**p, "law": law, "k": 0.8 * k_c}, backend="c")
    steady = mechgen.steady(system)
    out = mechgen.analysis("stability_boundary", system, about=steady, parameter="k", bracket=[1e-2 * k_c, 1e2 * k_c],
                           labels={"flutter": "stick_slip"})
    assert abs(out["k_critical"] / k_c - 1) < 1e-10
    assert abs(out["frequency_critical"] / (p["V2"] / p["D_c"] * math.sqrt((p["b"] - p["a"]) / p["a"])) - 1) < 1e-10
    assert out["verdict"] == "stick_slip"
    expected = np.sort_complex(cubic_roots({**p, "k": 0.8 * k_c}))
    found = np.sort_complex(np.array([complex(*e) for e in out["eigenvalues"]]))
    assert np.max(np.abs(found - expected)) < 1e-10 * np.max(np.abs(expected))


def test_small_mass_tends_to_the_quasi_static_slider():
    """mu(30 s) after the step V1 -> 10 V1 at k = 2 k_c: the inertial slider's differs from the quasi-static one's
    by O(m) (a convergence study: the difference falls tenfold with m, to 1 %)."""
    def mu_at(model: str, **params) -> float:
        system = mechgen.compile(model, {**BASE, "k": 1e10, **params}, backend="c")
        return mechgen.simulate(system, t_end=30.0, method="Radau", rtol=1e-11, atol=1e-13)["mu"]

    quasi_static = mu_at("rate_state_slider")
    gaps = [mu_at("rate_state_inertial", m=m) - quasi_static for m in (1e5, 1e4)]
    assert abs(gaps[0] / gaps[1] / 10 - 1) < 1e-2 and abs(gaps[1]) < 1e-10


def _run(law: str, factor: float, t_end: float):
    p = {**BASE, "m": 1e8}
    system = mechgen.compile("rate_state_inertial", {**p, "law": law, "k": factor * k_critical(p)}, backend="c")
    run = mechgen.simulate(system, t_end=t_end, method="Radau", rtol=1e-8, atol=1e-12, samples=int(20 * t_end) + 1)
    return np.asarray(run["t"]), np.column_stack([run["trajectory"][name] for name in ("phi", "psi", "f")])


@pytest.mark.parametrize("law", ["aging", "slip"])
def test_stick_slip_limit_cycle_below_k_c(law):
    """At k = 0.8 k_c the step V1 -> V2 grows into stick-slip that settles on a limit cycle: the spring's
    stress crosses its steady value with periods that converge (the last three within 1e-5), the block
    nearly sticks (V < V2/5) and slips fast (V > 20 V2) on every cycle, and stays bounded."""
    t, x = _run(law, 0.8, 300.0)
    f_steady = (BASE["a"] - BASE["b"]) * math.log(BASE["V2"] / BASE["V_ref"])
    f = x[:, 2]
    up = np.flatnonzero((f[:-1] < f_steady) & (f[1:] >= f_steady))
    crossings = t[up] + (f_steady - f[up]) / (f[up + 1] - f[up]) * (t[up + 1] - t[up])
    periods = np.diff(crossings)
    assert len(periods) >= 10
    assert np.ptp(periods[-3:]) < 1e-5 * periods[-1]
    last = t >= crossings[-2]
    V = BASE["V_ref"] * np.exp(x[last, 0])
    assert V.min() < BASE["V2"] / 5 and 20 * BASE["V2"] < V.max() < 1.0


def test_steady_sliding_returns_above_k_c():
    """At k = 1.25 k_c the same step decays back to steady sliding at V2 (aging law)."""
    t, x = _run("aging", 1.25, 300.0)
    assert abs(math.exp(x[-1, 0]) * BASE["V_ref"] / BASE["V2"] - 1) < 1e-6
