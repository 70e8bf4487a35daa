"""The Johnson-Segalman fluid in steady simple shear: closed forms (seed 002, Khayat & Ashrafi, eq. 4).

Scales: stress in eta_p / lambda (polymer viscosity over relaxation time), shear rate in 1 / lambda;
epsilon = eta_s / eta_p (solvent over polymer viscosity), xi in [0, 2] the slip parameter of the
Gordon-Schowalter derivative, k = xi (2 - xi). In steady shear at rate g the polymer stresses are

    tau_xy = g / (1 + k g^2),   tau_xx = (2 - xi) g tau_xy,   tau_yy = -xi g tau_xy,

and the total shear stress T(g) = epsilon g + g / (1 + k g^2). With x = sqrt(k) g, dT/dg = epsilon +
(1 - x^2)/(1 + x^2)^2, whose minimum over x is -1/8 (at x^2 = 3): T is monotone for epsilon >= 1/8 and
otherwise has a local maximum and minimum at x^2 = s_-+ = ((1 - 2 epsilon) -+ sqrt(1 - 8 epsilon)) / (2 epsilon).

Stress-controlled local dynamics (imposed T, so g = (T - tau_xy) / epsilon): at an equilibrium the Jacobian
in (tau_xx, tau_yy, tau_xy) has the eigenvalue -1 of W = xi tau_xx + (2 - xi) tau_yy (dW/dt = -W exactly),
and trace -3 - 1 / (epsilon (1 + k g^2)); the other pair therefore sums to -2 - 1/(epsilon (1 + k g^2)) < 0,
so no pair crosses the imaginary axis: no Hopf point, only folds (where det = 0, at the extrema of T).

Channel (half-width 1, pressure gradient G in stress units per half-width): T = G y, so the wall stress is
G; the classical (low-rate) branch exists up to G = T_max (``spurt_gradient``), and its flow rate per unit
width over the half-channel is Q = int_0^1 u dy = int_0^1 y g(G y) dy (by parts, u(1) = 0, u' = -g for y > 0)
with g(T) the low-rate root of T(g) = T.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

#: epsilon at and above which T(g) is monotone (no extrema, no spurt)
MONOTONE_EPSILON = 0.125


def slip_factor(xi: float) -> float:
    """k = xi (2 - xi)."""
    return xi * (2.0 - xi)


def total_stress(rate, epsilon: float, xi: float):
    """T(g) = epsilon g + g / (1 + k g^2) (stress units eta_p / lambda)."""
    rate = np.asarray(rate, dtype=float)
    return epsilon * rate + rate / (1.0 + slip_factor(xi) * rate**2)


def polymer_stresses(rate, xi: float) -> tuple:
    """(tau_xx, tau_yy, tau_xy) in steady shear at rate g."""
    rate = np.asarray(rate, dtype=float)
    txy = rate / (1.0 + slip_factor(xi) * rate**2)
    return (2.0 - xi) * rate * txy, -xi * rate * txy, txy


def extrema(epsilon: float, xi: float) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """((g_max, T_max), (g_min, T_min)) of the local maximum and minimum of T(g), or None where T is
    monotone (epsilon >= 1/8, or k = 0: xi = 0 or 2)."""
    k = slip_factor(xi)
    if epsilon >= MONOTONE_EPSILON or k <= 0.0 or epsilon <= 0.0:
        return None
    root = math.sqrt(1.0 - 8.0 * epsilon)
    points = []
    for s in ((1.0 - 2.0 * epsilon - root) / (2.0 * epsilon), (1.0 - 2.0 * epsilon + root) / (2.0 * epsilon)):
        g = math.sqrt(s / k)
        points.append((g, float(total_stress(g, epsilon, xi))))
    return points[0], points[1]


def pair_trace(rate, epsilon: float, xi: float):
    """The sum of the two eigenvalues of the local stress-controlled Jacobian other than -1, at the equilibrium
    of shear rate g: -2 - 1 / (epsilon (1 + k g^2)) (always < -2)."""
    rate = np.asarray(rate, dtype=float)
    return -2.0 - 1.0 / (epsilon * (1.0 + slip_factor(xi) * rate**2))


def classical_rate(stress: float, epsilon: float, xi: float) -> float:
    """The low-rate root g of T(g) = stress on the classical branch (0 <= stress <= T_max; any stress >= 0 when T
    is monotone), by Brent's method on [0, g_max]."""
    if stress <= 0.0:
        return 0.0
    top = extrema(epsilon, xi)
    if top is None:
        high = 1.0
        while total_stress(high, epsilon, xi) < stress:
            high *= 2.0
        return brentq(lambda g: total_stress(g, epsilon, xi) - stress, 0.0, high, xtol=1e-14, rtol=1e-14)
    g_max, T_max = top[0]
    if stress > T_max * (1.0 + 1e-14):
        raise ValueError(f"stress {stress!r} is above the classical branch's maximum {T_max!r}")
    if stress >= T_max:
        return g_max
    return brentq(lambda g: total_stress(g, epsilon, xi) - stress, 0.0, g_max, xtol=1e-14, rtol=1e-14)
