"""Compliant impacts and rigid-projectile penetration, hand-written scipy baseline (no code generation).

What a user would write without mechgen: a plain-numpy right-hand side per contact model and
`scipy.integrate.solve_ivp` with a terminal release event.  The hybrid (event-driven) engine is
benchmarked against this file; the closed forms it should reproduce live in
tests/impact_reference.py (same parameterisation, derivations there).

    python benchmarks/impact_handwritten.py          # prints a short accuracy table

Impact models (mass m [kg] meets the contact at x = 0 with speed v_in > 0; x = penetration):
    "kv"       Kelvin-Voigt F = k x + c xdot, released when x returns to 0 (half period);
               k = m omega_n^2, c = 2 zeta m omega_n.
    "mkv"      the same force, released when F = k x + c xdot falls to 0.
    "maxwell"  spring k in series with dashpot c; internal dashpot stretch y:
               F = k (x - y) = c ydot; k = m omega_n^2, c = m omega_n/(2 zeta); released when F falls to 0.
    "sls"      standard linear solid, k1 in series with (k2 || c); internal y = K-V deflection:
               F = k1 (x - y) = k2 y + c ydot; (k1, k2, c) from (omega_n, zeta, epsilon) as in
               impact_reference.sls_parameters; released when F falls to 0.  Stiff for small
               epsilon (fast mode -omega_n/(2 zeta epsilon)): use method="Radau" or "LSODA".
    "hunt_crossley"  F = k x^n (1 + alpha xdot), released when x returns to 0; the sweep
               parameter is a = alpha v_in (e depends on a only).
In every model m xddot = -F while in contact.  Each call returns (e, t_c): the restitution
coefficient -xdot(t_r)/v_in and the contact duration t_r [s]; (0.0, inf) if no release occurs
before t_max (K-V and Maxwell with zeta >= 1 come to rest in contact).

Penetration ([FFH] Frew, Forrestal & Hanchak 2000 eqs. 1-2; Forrestal et al. 1994): crater
0 <= x <= 4a with force c x, c = pi a (R + N rho V1^2)/4 (V1 := 0 if m Vs^2 < 4 pi a^3 R),
then tunnel with force pi a^2 (R + N rho V^2), until V = 0.  `penetration(...)` returns
(P, t_rest, t_crater).
"""
from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp

MODELS = ("kv", "mkv", "maxwell", "sls", "hunt_crossley")


# ----------------------------------------------------------------------------- right-hand sides

def _rhs_kv(t, s, m, k, c):
    x, v = s
    return np.array([v, -(k * x + c * v) / m])


def _rhs_maxwell(t, s, m, k, c):
    x, v, y = s
    F = k * (x - y)
    return np.array([v, -F / m, F / c])


def _rhs_sls(t, s, m, k1, k2, c):
    x, v, y = s
    F = k1 * (x - y)
    return np.array([v, -F / m, (F - k2 * y) / c])


def _rhs_hc(t, s, m, k, alpha, n):
    x, v = s
    return np.array([v, -k * max(x, 0.0) ** n * (1.0 + alpha * v) / m])


def _terminal(fun):
    fun.terminal = True
    fun.direction = -1.0
    return fun


# ----------------------------------------------------------------------------- one impact

class ImpactResult(NamedTuple):
    e: float      #: restitution coefficient -xdot(t_r)/v_in
    t_c: float    #: contact duration [s] (inf: no release before t_max)
    nfev: int     #: right-hand-side evaluations


def impact(model: str, zeta: float, *, m: float = 1.0, omega_n: float = 1.0, v_in: float = 1.0,
           epsilon: float = 0.1, n: float = 1.5, k: float = 1.0, rtol: float = 1e-10,
           atol: float = 1e-12, method: str = "DOP853", t_max: float | None = None) -> ImpactResult:
    """Simulate one impact from x = 0, xdot = v_in to the release event.

    zeta: damping ratio for the linear models; for "hunt_crossley" it is a = alpha v_in
    (then k [N/m^n], n and m set the time scale, omega_n is unused).  epsilon: SLS stiffness
    ratio k2/(k1+k2).  t_max [s] defaults to 200/omega_n (linear) or 200 HC time scales.
    """
    if model in ("kv", "mkv"):
        kk, c = m * omega_n ** 2, 2.0 * zeta * m * omega_n
        args, y0, fun = (m, kk, c), [0.0, v_in], _rhs_kv
        if model == "kv":
            ev = _terminal(lambda t, s, *p: s[0])
        else:
            ev = _terminal(lambda t, s, *p: p[1] * s[0] + p[2] * s[1])
    elif model == "maxwell":
        kk, c = m * omega_n ** 2, m * omega_n / (2.0 * zeta)
        args, y0, fun = (m, kk, c), [0.0, v_in, 0.0], _rhs_maxwell
        ev = _terminal(lambda t, s, *p: p[1] * (s[0] - s[2]))
    elif model == "sls":
        K = m * omega_n ** 2
        k1, k2, c = K / epsilon, K / (1.0 - epsilon), 2.0 * zeta * m * omega_n / (1.0 - epsilon)
        args, y0, fun = (m, k1, k2, c), [0.0, v_in, 0.0], _rhs_sls
        ev = _terminal(lambda t, s, *p: p[1] * (s[0] - s[2]))
    elif model == "hunt_crossley":
        alpha = zeta / v_in
        args, y0, fun = (m, k, alpha, n), [0.0, v_in], _rhs_hc
        ev = _terminal(lambda t, s, *p: s[0])
    else:
        raise ValueError(f"unknown model {model!r}; one of {MODELS}")
    if t_max is None:
        if model == "hunt_crossley":
            t_max = 200.0 * (m / (k * v_in ** (n - 1.0))) ** (1.0 / (n + 1.0))
        else:
            t_max = 200.0 / omega_n
    sol = solve_ivp(fun, (0.0, t_max), y0, method=method, rtol=rtol, atol=atol, events=ev, args=args)
    if sol.t_events[0].size == 0:
        return ImpactResult(0.0, math.inf, int(sol.nfev))
    return ImpactResult(-float(sol.y_events[0][0][1]) / v_in, float(sol.t_events[0][0]), int(sol.nfev))


class Sweep(NamedTuple):
    param: np.ndarray   #: the swept zetas (or a = alpha v_in for Hunt-Crossley)
    e: np.ndarray       #: restitution coefficients
    t_c: np.ndarray     #: contact durations [s]
    nfev: np.ndarray    #: right-hand-side evaluations per impact


def restitution_sweep(model: str, zetas, rtol: float = 1e-10, atol: float = 1e-12,
                      method: str = "DOP853", **params) -> Sweep:
    """One `impact` per value of zetas (keyword params as in `impact`); times nothing itself."""
    zs = np.asarray(zetas, dtype=float)
    res = [impact(model, float(z), rtol=rtol, atol=atol, method=method, **params) for z in zs]
    return Sweep(zs, np.array([r.e for r in res]), np.array([r.t_c for r in res]),
                 np.array([r.nfev for r in res]))


# ----------------------------------------------------------------------------- penetration

class PenetrationResult(NamedTuple):
    P: float          #: final depth [m]
    t_rest: float     #: time to rest [s]
    t_crater: float   #: time at x = 4a [s] (inf if it stops in the crater)
    nfev: int


def penetration(m: float, a: float, psi: float, rho: float, R: float, Vs: float, *,
                rtol: float = 1e-10, atol: float = 1e-14, method: str = "DOP853") -> PenetrationResult:
    """Rigid ogive-nose projectile (mass m [kg], shank radius a [m], caliber-radius-head psi) into a
    target of density rho [kg/m^3] and strength R [Pa] at striking speed Vs [m/s]: crater phase
    with events (x = 4a rising, V = 0), then tunnel phase to V = 0."""
    N = (8.0 * psi - 1.0) / (24.0 * psi * psi)
    V1sq = (m * Vs ** 2 - 4.0 * math.pi * a ** 3 * R) / (m + 4.0 * math.pi * a ** 3 * N * rho)
    c = math.pi * a * (R + N * rho * max(V1sq, 0.0)) / 4.0
    T = math.pi / 2.0 * math.sqrt(m / c)  # quarter period of the crater spring: the latest possible stop

    def crater(t, s):
        return np.array([s[1], -c * s[0] / m])

    def tunnel(t, s):
        return np.array([s[1], -math.pi * a * a * (R + N * rho * s[1] ** 2) / m])

    def at_4a(t, s):
        return s[0] - 4.0 * a
    at_4a.terminal, at_4a.direction = True, 1.0
    stop = _terminal(lambda t, s: s[1])

    s1 = solve_ivp(crater, (0.0, 2.0 * T), [0.0, Vs], method=method, rtol=rtol, atol=atol, events=(at_4a, stop))
    nfev = int(s1.nfev)
    if s1.t_events[1].size:  # stopped in the crater
        return PenetrationResult(float(s1.y_events[1][0][0]), float(s1.t_events[1][0]), math.inf, nfev)
    t1, (x1, V1) = float(s1.t_events[0][0]), s1.y_events[0][0]
    t_stop = t1 + m / (math.pi * a * a * math.sqrt(R * N * rho)) * math.pi / 2 * 1.5  # > any atan bound
    s2 = solve_ivp(tunnel, (t1, t_stop), [x1, V1], method=method, rtol=rtol, atol=atol, events=stop)
    nfev += int(s2.nfev)
    return PenetrationResult(float(s2.y_events[0][0][0]), float(s2.t_events[0][0]), t1, nfev)


# ----------------------------------------------------------------------------- script

def _main() -> None:  # pragma: no cover - manual run
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    import impact_reference as ref

    zetas = np.array([0.05, 0.2, 0.5, 0.9, 1.5])
    refs = {"kv": ref.kv_restitution, "mkv": ref.mkv_restitution, "maxwell": ref.maxwell_restitution,
            "sls": lambda z: ref.sls_restitution(z, 0.1)}
    for model, fe in refs.items():
        t0 = time.perf_counter()
        sw = restitution_sweep(model, zetas, method="Radau" if model == "sls" else "DOP853")
        dt = time.perf_counter() - t0
        err = max(abs(e - fe(z)) for z, e in zip(zetas, sw.e))
        print(f"{model:8s} max |e - ref| = {err:.2e}  ({dt * 1e3:.1f} ms, {sw.nfev.sum()} f-evals)")
    a_s = np.array([0.01, 0.1, 0.5, 1.0])
    sw = restitution_sweep("hunt_crossley", a_s)
    print(f"hunt_crossley max |e - ref| = {max(abs(e - ref.hc_restitution(a)) for a, e in zip(a_s, sw.e)):.2e}")
    p = ref.FREW_2001_PROJECTILES["12.7mm"]
    for Vs in (400.0, 1000.0):
        r = penetration(p["m"], p["two_a"] / 2, p["psi"], ref.LIMESTONE_DENSITY, p["R"], Vs)
        P = ref.penetration_depth(p["m"], p["two_a"] / 2, p["psi"], ref.LIMESTONE_DENSITY, p["R"], Vs)
        print(f"penetration Vs = {Vs:.0f} m/s: P = {r.P:.6f} m (closed form {P:.6f}), t_rest = {r.t_rest * 1e3:.4f} ms")


if __name__ == "__main__":  # pragma: no cover
    _main()
