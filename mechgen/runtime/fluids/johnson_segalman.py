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
    from scipy.optimize import brentq  # loaded on use (startup)

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


def stress_square_integral(rate: float, epsilon: float, xi: float) -> float:
    """I(g) = int_0^g T(s)^2 ds in closed form (k = xi (2 - xi) > 0):
    eps^2 g^3/3 + 2 eps (g/k - atan(sqrt(k) g)/k^(3/2)) + (atan(sqrt(k) g)/sqrt(k) - g/(1 + k g^2))/(2 k);
    for k = 0, (1 + eps)^2 g^3 / 3."""
    k = slip_factor(xi)
    if k <= 0.0:
        return (1.0 + epsilon) ** 2 * rate**3 / 3.0
    r = math.sqrt(k)
    x = r * rate
    return (epsilon**2 * rate**3 / 3.0 + 2.0 * epsilon * atan_remainder(x) / k**1.5
            + atan_pair(x) / (2.0 * k * r))


#: below this x the atan differences are summed as series (their closed forms cancel: relative error eps / x^2)
SERIES_BELOW = 1e-2


def atan_remainder(x: float) -> float:
    """x - atan(x) (= x^3/3 - x^5/5 + x^7/7 - x^9/9 + ... for small x)."""
    if x < SERIES_BELOW:
        return x**3 * (1.0 / 3.0 - x**2 * (1.0 / 5.0 - x**2 * (1.0 / 7.0 - x**2 / 9.0)))
    return x - math.atan(x)


def atan_pair(x: float) -> float:
    """atan(x) - x / (1 + x^2) (= 2x^3/3 - 4x^5/5 + 6x^7/7 - 8x^9/9 + ... for small x)."""
    if x < SERIES_BELOW:
        return x**3 * (2.0 / 3.0 - x**2 * (4.0 / 5.0 - x**2 * (6.0 / 7.0 - x**2 * 8.0 / 9.0)))
    return math.atan(x) - x / (1.0 + x**2)


def branch_flux(g1: float, g2: float, epsilon: float, xi: float) -> float:
    """int T g dT along a monotone piece of the curve from rate g1 to g2 (by parts in g:
    [g T^2/2] - int T^2/2 dg), the contribution of that piece to G^2 Q / 2."""
    T1, T2 = float(total_stress(g1, epsilon, xi)), float(total_stress(g2, epsilon, xi))
    return 0.5 * (g2 * T2**2 - g1 * T1**2) - 0.5 * (stress_square_integral(g2, epsilon, xi)
                                                     - stress_square_integral(g1, epsilon, xi))


def high_rate(stress: float, epsilon: float, xi: float) -> float:
    """The root g >= g_min of T(g) = stress on the high-rate branch (stress >= T_min), by Brent's method."""
    from scipy.optimize import brentq  # loaded on use (startup)

    (_, _), (g_min, T_min) = extrema(epsilon, xi)
    if stress <= T_min:
        return g_min
    high = 2.0 * g_min
    while total_stress(high, epsilon, xi) < stress:
        high *= 2.0
    return brentq(lambda g: total_stress(g, epsilon, xi) - stress, g_min, high, xtol=1e-14, rtol=1e-14)


def flow_rate(G: float, epsilon: float, xi: float, jump: str | None = None) -> tuple[float, float]:
    """(Q, y_jump): the flux per unit width through the channel -1 < y < 1 at pressure gradient G (wall stress
    G), Q = 2 int_0^1 y g(G y) dy = (2/G^2) int_0^G T g(T) dT, and the position of the jump in shear rate
    (1 where there is none). ``jump`` None: the classical branch (G <= T_max); "top": the rate jumps to the
    high branch where G y = T_max; "bottom": where G y = T_min (G >= T_max resp. T_min)."""
    if G <= 0.0:
        return 0.0, 1.0
    if jump is None:
        return 2.0 * branch_flux(0.0, classical_rate(G, epsilon, xi), epsilon, xi) / G**2, 1.0
    top = extrema(epsilon, xi)
    if top is None:
        raise ValueError("a jumping solution needs a non-monotone curve (epsilon < 1/8, 0 < xi < 2)")
    T_jump = top[0][1] if jump == "top" else top[1][1]
    if G < T_jump:
        raise ValueError(f"no {jump}-jumping solution below G = {T_jump!r}")
    g_low = top[0][0] if jump == "top" else classical_rate(T_jump, epsilon, xi)
    g_high = high_rate(T_jump, epsilon, xi)
    flux = branch_flux(0.0, g_low, epsilon, xi) + branch_flux(g_high, high_rate(G, epsilon, xi), epsilon, xi)
    return 2.0 * flux / G**2, T_jump / G


def latched_flow_rate(G: float, y_jump: float, epsilon: float, xi: float) -> float:
    """The flux with the low branch for |y| < y_jump and the high branch beyond (needs T_min <= G y_jump <= T_max)."""
    T_jump = G * y_jump
    flux = (branch_flux(0.0, classical_rate(T_jump, epsilon, xi), epsilon, xi)
            + branch_flux(high_rate(T_jump, epsilon, xi), high_rate(G, epsilon, xi), epsilon, xi))
    return 2.0 * flux / G**2


def hysteresis_loop(G_max: float, epsilon: float, xi: float, samples: int) -> dict:
    """The quasi-static loop of a ramp 0 -> G_max -> 0 without inertia (each y follows its local S-curve, jumping up
    at T_max and down at T_min): loading, the classical branch up to T_max then top-jumping (interface T_max / G);
    unloading, the interface latched at y_l = T_max / G_max while G y_l >= T_min, then bottom-jumping (T_min / G)
    until G = T_min, then classical. Returns G_up, flow_rate_up, G_down, flow_rate_down, jump_down (the interface,
    1 where none)."""
    (_, T_max), (_, T_min) = extrema(epsilon, xi)
    if G_max <= T_max:
        raise ValueError(f"a hysteresis loop needs G_max above the spurt gradient {T_max!r}")
    up = np.linspace(0.0, G_max, samples)
    q_up = [float(flow_rate(G, epsilon, xi, None if G <= T_max else "top")[0]) for G in up]
    down = up[::-1]
    y_latched = T_max / G_max
    q_down, jump = [], []
    for G in down:
        if G * y_latched >= T_min:
            q_down.append(float(latched_flow_rate(G, y_latched, epsilon, xi)))
            jump.append(float(y_latched))
        elif G >= T_min:
            q_down.append(float(flow_rate(G, epsilon, xi, "bottom")[0]))
            jump.append(float(T_min / G))
        else:
            q_down.append(float(flow_rate(G, epsilon, xi)[0]))
            jump.append(1.0)
    return {"G_up": up.tolist(), "flow_rate_up": q_up, "G_down": down.tolist(), "flow_rate_down": q_down,
            "jump_down": jump}
