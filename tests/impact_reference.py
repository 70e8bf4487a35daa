"""Closed-form and exact reference results for compliant impacts and rigid-projectile penetration.

Pure numpy/scipy (no mechgen imports): these are the independent references that the hybrid
(event-driven) engine is tested and benchmarked against.

Sources
-------
[BS]  E. A. Butcher and D. J. Segalman, "Characterizing Damping and Restitution in Compliant
      Impacts via Modified K-V and Higher-Order Linear Viscoelastic Models", ASME J. Appl.
      Mech. 67 (2000) 831-834.  Eq. numbers below are the paper's; its symbols were lost in
      the text extraction, so every formula here was re-derived (steps in each docstring) and
      checked against a brute-force solve_ivp (tests/test_impact_reference.py).
[HC]  K. H. Hunt and F. R. E. Crossley, "Coefficient of Restitution Interpreted as Damping
      in Vibroimpact", ASME J. Appl. Mech. 42 (1975) 440-445.
[F94] M. J. Forrestal, B. S. Altman, J. D. Cargile and S. J. Hanchak, "An empirical equation
      for penetration depth of ogive-nose projectiles into concrete targets", Int. J. Impact
      Eng. 15 (1994) 395-405.
[FFH] D. J. Frew, M. J. Forrestal and S. J. Hanchak, "Penetration Experiments With Limestone
      Targets and Ogive-Nose Steel Projectiles", ASME J. Appl. Mech. 67 (2000) 841-845
      (eqs. 1-3).

Common setting (impact models 1-5)
----------------------------------
A point mass m [kg] meets a compliant contact at speed v_in [m/s] > 0.  x [m] is the
penetration (x >= 0 in contact), contact starts at t = 0 with x(0) = 0, xdot(0) = v_in.
The contact force F [N] pushes the mass back: m xddot = -F.  Release ("exit") happens at the
first t_r > 0 at which the model's release condition holds; the restitution coefficient is
e = -xdot(t_r)/v_in and the kinetic energy lost is E0 (1 - e^2), E0 = m v_in^2/2 [J].
omega_n = sqrt(k/m) [rad/s], zeta [-] the damping ratio; the linear models are scale-free:
e depends only on the dimensionless parameters and the contact duration is tau_r/omega_n with
tau = omega_n t.

Helper used throughout (analytic in zeta, one formula for all branches):
    q(zeta) = acos(zeta)/sqrt(1 - zeta^2)      zeta < 1
            = 1                                zeta = 1
            = acosh(zeta)/sqrt(zeta^2 - 1)     zeta > 1   (acos z = i acosh z, sqrt(1-z^2) = i sqrt(z^2-1)).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.integrate import quad
from scipy.linalg import expm
from scipy.optimize import brentq

__all__ = [
    "LIMESTONE_DENSITY", "FREW_2001_PROJECTILES", "FREW_2001_K", "FREW_2001_k", "FREW_2001_2A0",
    "q_zeta", "energy_lost",
    "kv_parameters", "kv_restitution", "kv_contact_time",
    "mkv_restitution", "mkv_contact_time", "mkv_release_penetration",
    "maxwell_parameters", "maxwell_restitution", "maxwell_contact_time",
    "sls_parameters", "sls_dimensionless", "SLSRelease", "sls_release", "sls_restitution",
    "sls_contact_time", "sls_e1", "sls_tau1", "sls_restitution_first_order",
    "sls_contact_time_first_order", "sls_paper_f1_f2",
    "hc_restitution", "hc_restitution_series", "hc_contact_time",
    "forrestal_N", "crater_exit_speed_sq", "crater_stiffness", "penetration_depth",
    "penetration_time", "strength_from_depth", "frew_strength",
]

# ---------------------------------------------------------------------------------------------
# Data
# ---------------------------------------------------------------------------------------------

#: Bulk density of dry Indiana (Salem, "Bedford") limestone [kg/m^3].
#: 144 lb/ft^3 = 2306.7 kg/m^3, rounded to 2300: "The average weight of dry (seasoned) Indiana
#: limestone is 144 pounds per cubic foot" (Indiana Limestone Institute data as printed in
#: Masonry Magazine, June 1963, p. 15, "Characteristics of Limestone",
#: https://masonrymagazine.com/?pageID=15674).  [FFH]'s Table 1 (the nominal density of the
#: target batches, Elliot Stone Co., Bedford IN) was lost in the text extraction and could not
#: be recovered; the authors state their properties match Fossum et al. (1995) for the same
#: stone, whose porosity (~13-15 %) with calcite (2710 kg/m^3) also gives about 2300 kg/m^3.
LIMESTONE_DENSITY = 2300.0

#: [FFH] projectiles (4340 / AerMet 100 steel, 3.0 CRH ogive nose, L/D = 10):
#: shank diameter 2a [m], mass m [kg], caliber-radius-head psi [-], fitted R [Pa] from eq. 2.
FREW_2001_PROJECTILES = {
    "7.1mm": {"two_a": 7.1e-3, "m": 0.020, "psi": 3.0, "R": 913e6},
    "12.7mm": {"two_a": 12.7e-3, "m": 0.117, "psi": 3.0, "R": 787e6},
    "25.4mm": {"two_a": 25.4e-3, "m": 0.931, "psi": 3.0, "R": 693e6},
}
#: [FFH] eq. 3, R = K + k (2 a0)/(2 a): K [Pa], k [Pa], 2 a0 [m].
FREW_2001_K = 607e6
FREW_2001_k = 86e6
FREW_2001_2A0 = 25.4e-3


# ---------------------------------------------------------------------------------------------
# Shared helpers
# ---------------------------------------------------------------------------------------------

def q_zeta(zeta: float) -> float:
    """q(zeta) = acos(zeta)/sqrt(1-zeta^2) (zeta<1), 1 (zeta=1), acosh(zeta)/sqrt(zeta^2-1) (zeta>1).

    Computed without cancellation: 1 -/+ zeta is exact near zeta = 1 (Sterbenz), acos as
    atan2(beta, zeta), acosh as log1p((zeta-1) + g).  Series at zeta = 1 (d = 1 - zeta):
    q = 1 + d/3 + 2 d^2/15 + 2 d^3/35 + ...
    """
    z = float(zeta)
    if z < 0.0:
        raise ValueError("zeta must be >= 0")
    if z < 1.0:
        b = math.sqrt((1.0 - z) * (1.0 + z))
        return math.atan2(b, z) / b
    if z == 1.0:
        return 1.0
    g = math.sqrt((z - 1.0) * (z + 1.0))
    return math.log1p((z - 1.0) + g) / g


def energy_lost(e: float, E0: float) -> float:
    """Kinetic energy lost in the impact, E0 (1 - e^2) [J] (E0 = m v_in^2/2 the incoming energy)."""
    return E0 * (1.0 - e * e)


# ---------------------------------------------------------------------------------------------
# 1. Kelvin-Voigt, released at the half period ([BS] eqs. 1-6)
# ---------------------------------------------------------------------------------------------

def kv_parameters(m: float, omega_n: float, zeta: float) -> tuple[float, float]:
    """Kelvin-Voigt F = k x + c xdot: k = m omega_n^2 [N/m], c = 2 zeta m omega_n [N s/m]."""
    return m * omega_n ** 2, 2.0 * zeta * m * omega_n


def kv_restitution(zeta: float) -> float:
    """Half-period K-V restitution e = exp(-zeta pi/sqrt(1-zeta^2)) for zeta < 1, 0 for zeta >= 1.

    Derivation: m xddot + c xdot + k x = 0 -> xddot + 2 zeta omega_n xdot + omega_n^2 x = 0
    ([BS] eq. 2).  With x(0)=0, xdot(0)=v_in: x = (v_in/omega_d) exp(-zeta omega_n t)
    sin(omega_d t), omega_d = omega_n sqrt(1-zeta^2) (eq. 3).  x returns to 0 at
    t_r = pi/omega_d where xdot = -v_in exp(-zeta omega_n pi/omega_d) (cos pi = -1), so
    e = exp(-zeta pi/sqrt(1-zeta^2)) (eq. 4).  For zeta >= 1 the solution
    (v_in t e^{-omega_n t}, or a difference of decaying exponentials) stays > 0 for all t > 0:
    x never returns to 0 and the impact is perfectly plastic, e = 0.
    """
    z = float(zeta)
    if z >= 1.0:
        return 0.0
    return math.exp(-z * math.pi / math.sqrt((1.0 - z) * (1.0 + z)))


def kv_contact_time(zeta: float, omega_n: float = 1.0) -> float:
    """Half-period K-V contact duration t_r = pi/omega_d = pi/(omega_n sqrt(1-zeta^2)) [s]; inf for zeta >= 1."""
    z = float(zeta)
    if z >= 1.0:
        return math.inf
    return math.pi / (omega_n * math.sqrt((1.0 - z) * (1.0 + z)))


# ---------------------------------------------------------------------------------------------
# 2. Modified K-V: release when k x + c xdot falls to 0 ([BS] eqs. 9-11)
# ---------------------------------------------------------------------------------------------

def mkv_restitution(zeta: float) -> float:
    """Modified K-V restitution e = exp(-2 zeta q(zeta)), valid for every zeta >= 0.

    Derivation (zeta < 1, write zeta = sin(alpha), beta = sqrt(1-zeta^2) = cos(alpha),
    theta = omega_d t, x and xdot from kv_restitution):
        xdot = v_in e^{-zeta omega_n t} [cos theta - (zeta/beta) sin theta]
             = v_in e^{-zeta omega_n t} cos(theta + alpha)/cos(alpha),
        F/m  = omega_n^2 x + 2 zeta omega_n xdot
             = (v_in omega_n/beta) e^{-zeta omega_n t} [(1 - 2 zeta^2) sin theta + 2 zeta beta cos theta]
             = (v_in omega_n/beta) e^{-zeta omega_n t} sin(theta + 2 alpha)
    (since 1 - 2 zeta^2 = cos 2alpha, 2 zeta beta = sin 2alpha).  F(0) = 2 zeta m omega_n v_in > 0
    and F first vanishes at theta_r = pi - 2 alpha = 2 acos(zeta) = atan2(2 zeta beta, 2 zeta^2 - 1)
    ([BS] eq. 9 with the branch of tan^-1 in (0, pi)).  There cos(theta_r + alpha)/cos(alpha)
    = cos(pi - alpha)/cos(alpha) = -1, so xdot(t_r) = -v_in e^{-zeta omega_n t_r} and
        e = exp(-(zeta/beta) theta_r) = exp(-(zeta/beta) atan2(2 zeta beta, 2 zeta^2 - 1))
          = exp(-2 zeta acos(zeta)/sqrt(1 - zeta^2))                           ([BS] eq. 10).
    Every step is analytic in zeta, so zeta > 1 follows by continuation (acos -> i acosh):
        e = exp(-2 zeta acosh(zeta)/g) = ((zeta - g)/(zeta + g))^(zeta/g),  g = sqrt(zeta^2 - 1)
    ([BS] eq. 11; (zeta+g)(zeta-g) = 1 so ln((zeta+g)/(zeta-g)) = 2 acosh zeta), and zeta = 1 gives
    e = exp(-2) ~ 0.135.  e -> 0 only as zeta -> inf (e ~ (2 zeta)^-2).  x(t_r) > 0 on every
    branch (release happens before x returns to 0) and after release the massless K-V surface
    relaxes as xdot = -(k/c) x, slower than the departing mass: no re-contact.
    """
    return math.exp(-2.0 * float(zeta) * q_zeta(zeta))


def mkv_contact_time(zeta: float, omega_n: float = 1.0) -> float:
    """Modified K-V contact duration t_r = 2 q(zeta)/omega_n [s].

    zeta < 1: 2 acos(zeta)/omega_d ([BS] eq. 9); zeta = 1: 2/omega_n; zeta > 1:
    ln((zeta+g)/(zeta-g))/(omega_n g) = 2 acosh(zeta)/(omega_n g), g = sqrt(zeta^2-1).
    """
    return 2.0 * q_zeta(zeta) / omega_n


def mkv_release_penetration(zeta: float, v_in: float = 1.0, omega_n: float = 1.0) -> float:
    """Penetration at release x_r = 2 zeta e v_in/omega_n [m] (k x_r + c xdot_r = 0 with xdot_r = -e v_in).

    The spring still holds k x_r^2/2 = 4 zeta^2 e^2 E0 at release (dissipated afterwards by the
    relaxing massless element); the energy dissipated during contact is E0 (1 - e^2 - 4 zeta^2 e^2).
    """
    return 2.0 * zeta * mkv_restitution(zeta) * v_in / omega_n


# ---------------------------------------------------------------------------------------------
# 3. Maxwell: spring k in series with dashpot c ([BS] eqs. 13-17)
# ---------------------------------------------------------------------------------------------

def maxwell_parameters(m: float, omega_n: float, zeta: float) -> tuple[float, float]:
    """Maxwell element: k = m omega_n^2 [N/m], c = sqrt(k m)/(2 zeta) = m omega_n/(2 zeta) [N s/m] ([BS] eq. 14)."""
    return m * omega_n ** 2, m * omega_n / (2.0 * zeta)


def maxwell_restitution(zeta: float) -> float:
    """Maxwell restitution e = exp(-zeta pi/sqrt(1-zeta^2)) (zeta < 1), 0 (zeta >= 1, no release).

    Model: dashpot stretch y (internal), F = k (x - y) = c ydot, m xddot = -F, release when F
    falls to 0.  Derivation: Fdot = k (xdot - ydot) = k xdot - (k/c) F, so
    Fddot = k xddot - (k/c) Fdot = -(k/m) F - (k/c) Fdot, i.e. Fddot + 2 zeta omega_n Fdot
    + omega_n^2 F = 0 with 2 zeta omega_n = k/c -> zeta = sqrt(k m)/(2 c) ([BS] eq. 14; the
    paper writes the same equation for x).  F(0) = 0 (x = y = 0), Fdot(0) = k v_in, so
    F = (k v_in/omega_d) e^{-zeta omega_n t} sin(omega_d t) > 0 until t_r = pi/omega_d.  Momentum:
    m xdot(t_r) = m v_in - int_0^t_r F dt, and int_0^{pi/omega_d} e^{-s t} sin(omega_d t) dt
    = omega_d (1 + E)/(s^2 + omega_d^2) with s = zeta omega_n, E = e^{-s pi/omega_d},
    s^2 + omega_d^2 = omega_n^2, so m xdot(t_r) = m v_in - m v_in (1 + E) = -m v_in E: e = E, the
    half-period K-V value ([BS] section 3).  For zeta >= 1, F > 0 for all t and
    int_0^inf F dt = k v_in/omega_n^2 = m v_in (Laplace transform at s = 0): the mass comes to rest
    in contact (xdot -> 0, x -> m v_in/c), e = 0.  During contact x > y > 0 (F > 0, ydot > 0).
    """
    return kv_restitution(zeta)


def maxwell_contact_time(zeta: float, omega_n: float = 1.0) -> float:
    """Maxwell contact duration pi/omega_d [s] (zeta < 1); inf for zeta >= 1.

    At release the spring is unstretched and x_r = y_r = m v_in (1 + e)/c = 2 zeta (1+e) v_in/omega_n
    (permanent set of the dashpot); all of E0 (1 - e^2) is dissipated during contact.
    """
    return kv_contact_time(zeta, omega_n)


# ---------------------------------------------------------------------------------------------
# 4. Standard linear solid: k1 in series with (k2 || c) ([BS] eqs. 18-21)
# ---------------------------------------------------------------------------------------------

def sls_parameters(m: float, omega_n: float, zeta: float, epsilon: float) -> tuple[float, float, float]:
    """(k1, k2, c) from the paper's parameters, 0 < epsilon < 1.

    [BS] after eq. 19: omega_n^2 = k1 k2/((k1+k2) m), zeta = k1 c/(2 (k1+k2) m omega_n),
    epsilon = k2/(k1+k2).  With K = m omega_n^2 (the series stiffness): 1 - epsilon = k1/(k1+k2),
    K = k1 epsilon = k2 (1 - epsilon), hence
        k1 = m omega_n^2/epsilon,  k2 = m omega_n^2/(1 - epsilon),  c = 2 zeta m omega_n/(1 - epsilon)
    [N/m, N/m, N s/m].  epsilon -> 0 (k1 -> inf) is K-V with k = k2 -> m omega_n^2, c -> 2 zeta m omega_n.
    """
    if not 0.0 < epsilon < 1.0:
        raise ValueError("epsilon must lie in (0, 1)")
    K = m * omega_n ** 2
    return K / epsilon, K / (1.0 - epsilon), 2.0 * zeta * m * omega_n / (1.0 - epsilon)


def sls_dimensionless(m: float, k1: float, k2: float, c: float) -> tuple[float, float, float]:
    """Inverse of sls_parameters: (omega_n [rad/s], zeta, epsilon) from (m, k1, k2, c)."""
    wn = math.sqrt(k1 * k2 / ((k1 + k2) * m))
    return wn, k1 * c / (2.0 * (k1 + k2) * m * wn), k2 / (k1 + k2)


class SLSRelease(NamedTuple):
    """Exact SLS release (dimensionless: tau = omega_n t, x scaled by v_in/omega_n, energies by E0)."""
    e: float            #: restitution coefficient
    tau_r: float        #: omega_n t_r (inf when the mass never leaves)
    x_r: float          #: omega_n x(t_r)/v_in; at F = 0, x = y (spring k1 unstretched)
    stored: float       #: k2 y_r^2/2 / E0 = x_r^2/(1 - epsilon), still in k2 at release
    dissipated: float   #: energy dissipated in c during contact / E0 = 1 - e^2 - stored


def _sls_matrix(zeta: float, eps: float) -> np.ndarray:
    a = 1.0 / (2.0 * zeta * eps)
    return np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [a, 1.0 / eps, -a]])


def sls_release(zeta: float, epsilon: float) -> SLSRelease:
    """Exact release of the standard linear solid (linear 3-state system, matrix exponential).

    Model: y = deflection of the K-V element, F = k1 (x - y) = k2 y + c ydot, m xddot = -F,
    release when F falls to 0.  Eliminating y (y = x - F/k1) gives
        (c/(k1+k2)) Fdot + F = (k1 k2/(k1+k2)) x + (k1 c/(k1+k2)) xdot,
    i.e. with F = -m xddot ([BS] eq. 19): (2 zeta epsilon/omega_n) x''' + x'' + 2 zeta omega_n x'
    + omega_n^2 x = 0.  Dimensionless (tau = omega_n t, xi = omega_n x/v_in, u = xdot/v_in,
    f = F/(m omega_n v_in)):
        xi' = u,  u' = -f,  2 zeta epsilon f' = xi + 2 zeta u - f,   (xi, u, f)(0) = (0, 1, 0),
    z(tau) = expm(A tau) z(0).  f rises with slope 1/epsilon; the first sign change of f is
    bracketed on a grid (geometric near 0 for the fast mode -1/(2 zeta epsilon), then at most
    0.05/|lambda_slow| apart) and refined with brentq (xtol 1e-15); e = -u(tau_r), which is
    insensitive to tau_r at first order because u' = -f = 0 there.  If f stays positive until
    the state has decayed by e^-80 the mass never leaves (e = 0, tau_r = inf).  After release the
    K-V element relaxes as ydot = -(k2/c) y, slower than the mass (f' <= 0 at release gives
    xi + 2 zeta u <= 0): no re-contact.
    """
    z, eps = float(zeta), float(epsilon)
    if z <= 0.0:
        raise ValueError("zeta must be > 0 (zeta = 0 is elastic, e = 1)")
    if not 0.0 < eps < 1.0:
        raise ValueError("epsilon must lie in (0, 1)")
    A = _sls_matrix(z, eps)
    z0 = np.array([0.0, 1.0, 0.0])
    lam, V = np.linalg.eig(A)
    coef = np.linalg.solve(V, z0.astype(complex)) * V[2, :]  # f(tau) = Re sum coef_j exp(lam_j tau)
    mods = np.sort(np.abs(lam))
    h_max = 0.05 / mods[1]
    oscillatory = bool(np.any(np.abs(lam.imag) > 1e-12 * mods[2]))
    tau_end = 80.0 / np.min(np.abs(lam.real))

    def f_exact(t: float) -> float:
        return float((expm(A * t) @ z0)[2])

    def f_eig(ts: np.ndarray) -> np.ndarray:
        return np.real(np.exp(np.outer(ts, lam)) @ coef)

    t_prev = 1e-3 * min(1.0 / mods[2], h_max)
    f_prev = f_exact(t_prev)
    bracket = None
    while t_prev < tau_end and bracket is None:
        ts = [t_prev]
        for _ in range(256):
            step = 0.02 * ts[-1]
            if oscillatory:
                step = min(step, h_max)
            ts.append(ts[-1] + step)
        ts = np.array(ts[1:])
        fs = f_eig(ts)
        neg = np.nonzero(fs < 0.0)[0]
        if neg.size:
            i = int(neg[0])
            lo = ts[i - 1] if i > 0 else t_prev
            hi = ts[i]
            if f_exact(lo) > 0.0 and f_exact(hi) < 0.0:
                bracket = (lo, hi)
            else:  # eigen-basis rounding near a repeated root: rescan this chunk exactly
                grid = np.concatenate(([t_prev], ts))
                fe = np.array([f_exact(t) for t in grid])
                j = np.nonzero(fe < 0.0)[0]
                if j.size:
                    bracket = (grid[j[0] - 1], grid[j[0]])
        t_prev = ts[-1]
    if bracket is None:
        return SLSRelease(0.0, math.inf, float("nan"), float("nan"), float("nan"))
    tau_r = brentq(f_exact, bracket[0], bracket[1], xtol=1e-15, rtol=4.0 * np.finfo(float).eps, maxiter=200)
    s = expm(A * tau_r) @ z0
    e = -float(s[1])
    xr = float(s[0])
    stored = xr * xr / (1.0 - eps)
    return SLSRelease(e, tau_r, xr, stored, 1.0 - e * e - stored)


def sls_restitution(zeta: float, epsilon: float) -> float:
    """Exact SLS restitution coefficient e(zeta, epsilon) (see sls_release)."""
    return sls_release(zeta, epsilon).e


def sls_contact_time(zeta: float, epsilon: float, omega_n: float = 1.0) -> float:
    """Exact SLS contact duration t_r = tau_r/omega_n [s] (see sls_release)."""
    return sls_release(zeta, epsilon).tau_r / omega_n


# Taylor coefficients at zeta = 1 in d = 1 - zeta (sympy, tests/derive_impact_reference.py),
# used where the closed forms below cancel (|d| < 2e-3); both are analytic through zeta = 1.
_E1_AT_1 = (8 / 3, -32 / 15, -16 / 35, -32 / 315, -8 / 693, 128 / 15015, 64 / 6435)
_TAU1_AT_1 = (-14 / 3, 142 / 15, -124 / 35, -268 / 315, -928 / 3465, -1376 / 15015, -32 / 1001)


def _poly(cs, d):
    return sum(c * d ** i for i, c in enumerate(cs))


def sls_e1(zeta: float) -> float:
    """First-order SLS correction: e = e_MKV(zeta) (1 + epsilon e1(zeta) + O(epsilon^2)).

        e1(zeta) = (2 zeta/(1 - zeta^2)) [zeta + (1 - 2 zeta^2) q(zeta)]
                 = 2 zeta^2/beta^2 + zeta (1 - 2 zeta^2) theta0/beta^3,   theta0 = 2 acos zeta, beta = sqrt(1-zeta^2)
    (one formula for all zeta; e1(1) = 8/3; small zeta: pi zeta - pi zeta^3/2 + 8 zeta^4/3 + ...;
    large zeta: ~ 4 ln(2 zeta), the expansion needs epsilon zeta^2 << 1).

    Derivation.  Laplace transform of the dimensionless system (sls_release):
    f(s) = (1 + 2 zeta s)/p(s), u(s) = s (1 + 2 zeta epsilon s)/p(s), p(s) = 2 zeta epsilon s^3
    + s^2 + 2 zeta s + 1.  The fast root s_f ~ -1/(2 zeta epsilon) gives a boundary layer at
    tau = O(epsilon) that is exponentially small at release, so to all orders in epsilon
    u(tau) = 2 Re[R_u(lam, epsilon) e^{lam tau}], R_u = lam (1 + 2 zeta epsilon lam)/p'(lam),
    with the slow root lam = s0 + epsilon s1, s0 = -zeta + i beta = i e^{i alpha} (zeta = sin alpha),
    s1 = -zeta s0^3/(s0 + zeta) (from p(s0 + epsilon s1) = O(epsilon^2)).  Release:
    tau_r = tau0 + epsilon tau1 with f0(tau0) = 0, and since u' = -f vanishes at tau0,
    e = -u0(tau0) - epsilon u1(tau0) + O(epsilon^2): the release-time shift drops out and
    e1 = -u1(tau0)/e0.  With dR_u/d epsilon = zeta lam^2 (2 zeta - lam)/(2 (lam+zeta)^2)
    - zeta^2 lam^3/(2 (lam+zeta)^3) + R_u0 s1 tau, e^{s0 tau0} = -e0 e^{-2 i alpha}, lam + zeta = i beta:
    e1 = 2 Re[zeta (3 zeta - i beta)/(2 beta^2) - zeta^2 e^{i alpha}/(2 beta^3) + zeta e^{2 i alpha} tau0/(2 beta^2)]
       = [2 zeta^2 + zeta (1 - 2 zeta^2) tau0]/beta^2.
    Checked against sls_release: (e - e_MKV (1 + epsilon e1))/epsilon^2 tends to a constant.
    """
    z = float(zeta)
    d = 1.0 - z
    if abs(d) < 2e-3:
        return _poly(_E1_AT_1, d)
    b2 = (1.0 - z) * (1.0 + z)
    return (2.0 * z / b2) * (z + (1.0 - 2.0 * z * z) * q_zeta(z))


def sls_tau1(zeta: float) -> float:
    """First-order shift of the SLS release time: omega_n t_r = 2 q(zeta) + epsilon tau1(zeta) + O(epsilon^2).

        tau1 = zeta [2 (1 - 2 zeta^2) - zeta (3 - 4 zeta^2) tau0]/(1 - zeta^2),  tau0 = 2 q(zeta)
    (tau1(0) = 0: undamped, the series springs have stiffness m omega_n^2 exactly; tau1(1) = -14/3).
    Derivation as sls_e1 with R_f = (1 + 2 zeta lam)/p'(lam): f1(tau0) = 2 Re[(dR_f/d epsilon
    + R_f0 s1 tau0) e^{s0 tau0}], tau1 = -f1(tau0)/f0'(tau0) = f1(tau0)/e0 (f0'(tau0) = -e0), with
    dR_f/d epsilon = -3 zeta e^{4 i alpha}/(2 beta^2) + zeta cos(2 alpha) e^{3 i alpha}/(2 beta^3),
    R_f0 s1 = -i zeta e^{5 i alpha}/(2 beta^2), sin 3 alpha = zeta (3 - 4 zeta^2).
    """
    z = float(zeta)
    d = 1.0 - z
    if abs(d) < 2e-3:
        return _poly(_TAU1_AT_1, d)
    b2 = (1.0 - z) * (1.0 + z)
    t0 = 2.0 * q_zeta(z)
    return z * (2.0 * (1.0 - 2.0 * z * z) - z * (3.0 - 4.0 * z * z) * t0) / b2


def sls_restitution_first_order(zeta: float, epsilon: float) -> float:
    """e_MKV(zeta) (1 + epsilon e1(zeta)); differs from the exact e by O(epsilon^2)."""
    return mkv_restitution(zeta) * (1.0 + epsilon * sls_e1(zeta))


def sls_contact_time_first_order(zeta: float, epsilon: float, omega_n: float = 1.0) -> float:
    """(2 q(zeta) + epsilon tau1(zeta))/omega_n [s]; differs from the exact t_r by O(epsilon^2)/omega_n."""
    return (2.0 * q_zeta(zeta) + epsilon * sls_tau1(zeta)) / omega_n


def sls_paper_f1_f2(zeta: float) -> tuple[float, float]:
    """(f1, f2) of [BS] eq. 21 as reconstructed here, zeta < 1.

    Reading eq. 21 as e = exp{-(zeta/beta - epsilon f1) tan^-1[2 zeta beta/(2 zeta^2 - 1)] + epsilon f2}
    (signs are lost in the extraction), the first-order result above gives
        f1 = zeta (1 - 2 zeta^2)/beta^3 = zeta - zeta^3/2 - 9 zeta^5/8 + ...   (paper: "... 3/2 ... O(zeta^5)": agrees)
        f2 = 2 zeta^2/beta^2 = 2 zeta^2 + 2 zeta^4 + ...                       (paper: digits "2 3 3", O(zeta^5): not recovered)
    Each of f1 theta0 and f2 diverges like 2/beta^2 as zeta -> 1 while their sum e1 stays 8/3, which
    is why the paper's truncated series "break down for zeta near unity".
    """
    z = float(zeta)
    b2 = (1.0 - z) * (1.0 + z)
    return z * (1.0 - 2.0 * z * z) / b2 ** 1.5, 2.0 * z * z / b2


# ---------------------------------------------------------------------------------------------
# 5. Hunt-Crossley F = k x^n (1 + alpha xdot)
# ---------------------------------------------------------------------------------------------

_HC_SERIES = (1.0, -2 / 3, 4 / 9, -44 / 135, 104 / 405, -40 / 189, 7648 / 42525)


def _x_minus_log1p(q: float) -> float:
    """q - log(1 + q) without cancellation for small |q|."""
    if abs(q) < 0.1:
        s, term, k = 0.0, -q, 1  # sum_{k>=2} (-1)^k q^k / k
        while True:
            k += 1
            term = -term * q
            add = term / k
            s += add
            if abs(add) <= 1e-18 * abs(s):
                return s
    return q - math.log1p(q)


def hc_restitution_series(a: float, order: int = 6) -> float:
    """Small-a series e = 1 - 2a/3 + 4a^2/9 - 44a^3/135 + 104a^4/405 - 40a^5/189 + 7648a^6/42525 + O(a^7).

    Obtained by substituting e = 1 + sum c_j a^j into ln((1+a)/(1-a e)) = a (1+e) (sympy,
    tests/derive_impact_reference.py).  The first two terms are Hunt & Crossley's
    alpha = 3 (1 - e)/(2 v_in).
    """
    return sum(c * a ** j for j, c in enumerate(_HC_SERIES[: order + 1]))


def hc_restitution(a: float) -> float:
    """Hunt-Crossley restitution from a = alpha v_in >= 0, independent of k, m and n.

    Derivation: in contact m xddot = -k x^n (1 + alpha xdot).  With v = xdot as a function of x,
    xddot = v dv/dx, separate: m v dv/(1 + alpha v) = -k x^n dx.  Integrate along the whole
    contact from (x, v) = (0, v_in) to the exit (0, -e v_in): the right side is
    -k [int_0^xmax + int_xmax^0] x^n dx = 0, so int_{v_in}^{-e v_in} v dv/(1 + alpha v) = 0.
    With int v/(1 + alpha v) dv = v/alpha - ln(1 + alpha v)/alpha^2 and multiplying by alpha^2:
        -a (1 + e) + ln((1 + a)/(1 - a e)) = 0,   i.e.   ln((1 + a)/(1 - a e)) = a (1 + e).
    (Requires 1 + alpha v > 0 on the way out, i.e. a e < 1, which the root satisfies.)  The
    function h(e) = ln((1+a)/(1-a e)) - a(1+e) is convex with h(-1) = 0 (trivial root) and
    h(0) = ln(1+a) - a < 0, so there is exactly one root in (0, min(1, 1/a)).  Solved in
    w = 1 - a e (w - ln w = 1 + a - ln(1+a), w in (0, 1); closed form w = -W0(-(1+a) e^-(1+a))):
    for a >= 0.3 by brentq on w; for a < 0.3 by brentq on e in the divided form
    sum_{n>=2} a^{n-2} (e^n - (-1)^n)/(n (1+e)) = 0, which avoids the O(a^2) cancellation.
    """
    a = float(a)
    if a < 0.0:
        raise ValueError("a = alpha v_in must be >= 0")
    if a == 0.0:
        return 1.0
    if a >= 0.3:
        rhs = 1.0 + a - math.log1p(a)
        if rhs > 700.0:  # w < 1e-300: w = (1+a) e^-(1+a) e^w to double precision, e = (1-w)/a = 1/a
            return 1.0 / a
        w = brentq(lambda w: w - math.log(w) - rhs, 1e-300, 1.0 - 1e-16,
                   xtol=1e-300, rtol=4 * np.finfo(float).eps, maxiter=500)
        return (1.0 - w) / a

    def H(e: float) -> float:
        # sum_{n>=2} a^(n-2) Q_n/n with Q_n = (e^n - (-1)^n)/(1+e): Q_1 = 1, Q_n = e Q_(n-1) + (-1)^(n-1)
        total, an, quot = 0.0, 1.0, 1.0
        for n in range(2, 200):
            quot = e * quot + (-1.0) ** (n - 1)
            total += an * quot / n
            an *= a
            if an < 1e-20:
                break
        return total

    return brentq(H, 0.0, 1.0, xtol=1e-16, rtol=4 * np.finfo(float).eps, maxiter=200)


def _hc_I(a: float, w0: float, w1: float) -> float:
    """int_{w0}^{w1} s/(1 + a s) ds, stable for small a (q = a (w1-w0)/(1 + a w0))."""
    if a == 0.0:
        return 0.5 * (w1 * w1 - w0 * w0)
    q = a * (w1 - w0) / (1.0 + a * w0)
    return _x_minus_log1p(q) / (a * a) + q * w0 / a


def hc_contact_time(a: float, n: float = 1.5, m: float = 1.0, k: float = 1.0, v_in: float = 1.0) -> float:
    """Hunt-Crossley contact duration [s] by quadrature.

    From the energy integral of hc_restitution, with v = v_in w:
        x^(n+1) = ((n+1) m v_in^2/k) s(w),   s(w) = int_w^1 s'/(1 + a s') ds'   (compression, w from 1 to 0)
                                             s(w) = -int_{-e}^w s'/(1 + a s') ds' (restitution, w from 0 to -e)
    and dt = dv/vdot = -m dv/(k x^n (1 + alpha v)), so
        t_c = T int_{-e}^{1} dw/(s(w)^p (1 + a w)),   p = n/(n+1),  T = (m v_in/k) ((n+1) m v_in^2/k)^(-p).
    s vanishes linearly at both ends (s ~ (1-w)/(1+a) and s ~ e (w+e)/(1-a e)), so each half is
    integrated with the algebraic weight (end distance)^(-p) (QUADPACK QAWS).  Check: n = 1,
    a = 0 gives pi sqrt(m/k).
    """
    a = float(a)
    e = hc_restitution(a)
    p = n / (n + 1.0)
    T = (m * v_in / k) * ((n + 1.0) * m * v_in ** 2 / k) ** (-p)

    def upper(w):  # (1-w)^p / (s^p (1 + a w)) on [0, 1]
        d = 1.0 - w
        if d < 1e-13:
            return (1.0 + a) ** p / (1.0 + a)
        return (d / _hc_I(a, w, 1.0)) ** p / (1.0 + a * w)

    def lower(w):  # (w+e)^p / (s^p (1 + a w)) on [-e, 0]
        d = w + e
        if d < 1e-13:
            return ((1.0 - a * e) / e) ** p / (1.0 - a * e)
        return (d / -_hc_I(a, -e, w)) ** p / (1.0 + a * w)

    opts = dict(epsabs=0.0, epsrel=1e-13, limit=200)
    i_up = quad(upper, 0.0, 1.0, weight="alg", wvar=(0.0, -p), **opts)[0]
    i_lo = quad(lower, -e, 0.0, weight="alg", wvar=(-p, 0.0), **opts)[0]
    return T * (i_up + i_lo)


# ---------------------------------------------------------------------------------------------
# 6. Rigid ogive-nose projectile into a concrete/limestone target ([F94], [FFH] eqs. 1-3)
# ---------------------------------------------------------------------------------------------

def forrestal_N(psi: float) -> float:
    """Nose factor of a tangent ogive with caliber-radius-head psi: N = (8 psi - 1)/(24 psi^2) [-] ([FFH] eq. 1b)."""
    return (8.0 * psi - 1.0) / (24.0 * psi * psi)


def crater_exit_speed_sq(m: float, a: float, psi: float, rho: float, R: float, Vs: float) -> float:
    """V1^2 = (m Vs^2 - 4 pi a^3 R)/(m + 4 pi a^3 N rho) [m^2/s^2], the speed^2 at the end of the crater x = 4a.

    Derivation: crater force F = c x on 0 <= x <= 4a, c fixed by continuity with the tunnel force
    at x = 4a: 4 a c = pi a^2 (R + N rho V1^2) -> c = pi a (R + N rho V1^2)/4.  Energy over the
    crater: m (Vs^2 - V1^2)/2 = c (4a)^2/2 -> V1^2 = Vs^2 - 4 pi a^3 (R + N rho V1^2)/m, solved
    for V1^2.  Negative when m Vs^2 < 4 pi a^3 R (the projectile stops inside the crater).
    m [kg], a shank radius [m], rho target density [kg/m^3], R target strength [Pa], Vs [m/s].
    """
    N = forrestal_N(psi)
    return (m * Vs * Vs - 4.0 * math.pi * a ** 3 * R) / (m + 4.0 * math.pi * a ** 3 * N * rho)


def crater_stiffness(m: float, a: float, psi: float, rho: float, R: float, Vs: float) -> float:
    """Crater-phase stiffness c = pi a (R + N rho V1^2)/4 [N/m], with V1 := 0 when the projectile stops in the crater.

    Rule for m Vs^2 < 4 pi a^3 R: the crater force keeps the form c x with the continuity
    constant evaluated at zero exit speed, c = pi a R/4 (the force it would meet at x = 4a is
    the quasi-static tunnel resistance pi a^2 R).  Then m Vs^2/2 = c P^2/2 gives P = Vs sqrt(m/c)
    < 4a, and at m Vs^2 = 4 pi a^3 R both branches give P = 4a (continuous).
    """
    V1sq = max(crater_exit_speed_sq(m, a, psi, rho, R, Vs), 0.0)
    return math.pi * a * (R + forrestal_N(psi) * rho * V1sq) / 4.0


def penetration_depth(m: float, a: float, psi: float, rho: float, R: float, Vs: float) -> float:
    """Final penetration depth P [m] ([FFH] eq. 1a, [F94]).

    Tunnel phase x >= 4a: m V dV/dx = -pi a^2 (R + N rho V^2) -> d(V^2)/dx = -(2 pi a^2/m)(R + N rho V^2)
    -> ln((R + N rho V1^2)/R) = (2 pi a^2 N rho/m)(P - 4a):
        P = (m/(2 pi a^2 rho N)) ln(1 + N rho V1^2/R) + 4a            (m Vs^2 >= 4 pi a^3 R)
        P = Vs sqrt(m/c),  c = pi a R/4                                  (m Vs^2 <  4 pi a^3 R)
    """
    V1sq = crater_exit_speed_sq(m, a, psi, rho, R, Vs)
    if V1sq <= 0.0:
        return Vs * math.sqrt(m / crater_stiffness(m, a, psi, rho, R, Vs))
    N = forrestal_N(psi)
    return m / (2.0 * math.pi * a * a * rho * N) * math.log1p(N * rho * V1sq / R) + 4.0 * a


def penetration_time(m: float, a: float, psi: float, rho: float, R: float, Vs: float) -> tuple[float, float]:
    """(t_crater, t_total) [s]: time to reach x = 4a (inf if it stops in the crater) and time to rest.

    Crater: m xddot = -c x, x = (Vs/W) sin(W t), W = sqrt(c/m): reaches 4a at asin(4 a W/Vs)/W,
    or stops at pi/(2 W).  Tunnel: m Vdot = -pi a^2 (R + N rho V^2) ->
    t = (m/(pi a^2 sqrt(R N rho))) atan(V1 sqrt(N rho/R)).
    """
    c = crater_stiffness(m, a, psi, rho, R, Vs)
    W = math.sqrt(c / m)
    V1sq = crater_exit_speed_sq(m, a, psi, rho, R, Vs)
    if V1sq <= 0.0:
        return math.inf, math.pi / (2.0 * W)
    t1 = math.asin(min(4.0 * a * W / Vs, 1.0)) / W
    N = forrestal_N(psi)
    t2 = m / (math.pi * a * a * math.sqrt(R * N * rho)) * math.atan(math.sqrt(V1sq * N * rho / R))
    return t1, t1 + t2


def strength_from_depth(m: float, a: float, psi: float, rho: float, Vs: float, P: float) -> float:
    """Target strength R [Pa] from one measured (Vs, P) ([FFH] eq. 2, the inverse of penetration_depth).

    P > 4a: let E = exp(2 pi a^2 (P - 4a) N rho/m) = 1 + N rho V1^2/R; substituting V1^2 from
    crater_exit_speed_sq: N rho (m Vs^2 - 4 pi a^3 R) = R (E - 1)(m + 4 pi a^3 N rho), so
        R = N rho Vs^2 / [(1 + 4 pi a^3 N rho/m) E - 1].
    P <= 4a (stopped in the crater): P = Vs sqrt(m/c), c = pi a R/4 -> R = 4 m Vs^2/(pi a P^2).
    """
    if P <= 4.0 * a:
        return 4.0 * m * Vs * Vs / (math.pi * a * P * P)
    N = forrestal_N(psi)
    E = math.exp(2.0 * math.pi * a * a * (P - 4.0 * a) * N * rho / m)
    return N * rho * Vs * Vs / ((1.0 + 4.0 * math.pi * a ** 3 * N * rho / m) * E - 1.0)


def frew_strength(two_a: float, K: float = FREW_2001_K, k: float = FREW_2001_k, two_a0: float = FREW_2001_2A0) -> float:
    """[FFH] eq. 3: limestone strength R = K + k (2 a0)/(2 a) [Pa] (913, 787, 693 MPa fitted for 7.1, 12.7, 25.4 mm)."""
    return K + k * two_a0 / two_a
