"""Hand-written baseline for ``mechgen bench friction``: the quasi-static rate-and-state spring-slider.

The equations of mechgen/models/rate_state_slider.py (loading = "spring"), written out by hand in the same
log variables y = (phi, psi), phi = ln(V/V_ref), psi = ln(V_ref theta/D_c):

    aging: psi' = (V_ref/D_c) (exp(-psi) - exp(phi))        slip: psi' = -(V_ref/D_c) exp(phi) (phi + psi)
    phi'  = (k (V2 - V_ref exp(phi)) / sigma - b psi') / a,     mu = mu0 + a phi + b psi,

from steady sliding at V1 (phi = -psi = ln(V1/V_ref)), integrated by ``scipy.integrate.solve_ivp`` with
Radau and the analytic Jacobian, as a user would write it without mechgen. Plain numpy and math; nothing
from mechgen.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def slider(law: str, *, a: float, b: float, D_c: float, k: float, sigma: float, V2: float, V_ref: float):
    """(rhs, jac) of the slider in (phi, psi)."""
    c = V_ref / D_c

    def state(phi, psi):
        if law == "aging":
            return c * (math.exp(-psi) - math.exp(phi)), -c * math.exp(phi), -c * math.exp(-psi)
        e = math.exp(phi)
        return -c * e * (phi + psi), -c * e * (phi + psi) - c * e, -c * e

    def rhs(t, y):
        phi, psi = y
        g, _, _ = state(phi, psi)
        return np.array([(k * (V2 - V_ref * math.exp(phi)) / sigma - b * g) / a, g])

    def jac(t, y):
        phi, psi = y
        _, g_phi, g_psi = state(phi, psi)
        return np.array([[(-k * V_ref * math.exp(phi) / sigma - b * g_phi) / a, -b * g_psi / a], [g_phi, g_psi]])

    return rhs, jac


def mu_at_end(law: str, t_end: float, *, rtol: float, atol: float, a: float, b: float, D_c: float, k: float,
              sigma: float, mu0: float, V1: float, V2: float, V_ref: float, method: str = "Radau") -> float:
    """The friction coefficient at t_end after the load point's step V1 -> V2."""
    rhs, jac = slider(law, a=a, b=b, D_c=D_c, k=k, sigma=sigma, V2=V2, V_ref=V_ref)
    start = math.log(V1 / V_ref)
    sol = solve_ivp(rhs, (0.0, t_end), [start, -start], method=method, jac=jac, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(sol.message)
    phi, psi = sol.y[:, -1]
    return mu0 + a * phi + b * psi
