"""Two-phase equilibria of a bar with a non-monotone stress-strain law (Abeyaratne & Knowles).

A law is given numerically: ``stress(g)`` sigma(gamma) and ``energy(g)`` W(gamma) (Pa), vectorised over strains
(the ``phase_boundary`` analysis passes a model's outputs kernel). The numerics here:

* :func:`spinodal`: the first rise-fall-rise of sigma on a sampled strain interval, its peak gamma_a and valley
  gamma_b (sigma' = 0, refined by Brent's method on the modulus, or on the stress's slope between samples);
* :func:`maxwell`: the Maxwell stress sigma_M in (sigma(gamma_b), sigma(gamma_a)) where the driving traction of
  the two phase strains at equal stress vanishes, i.e. the equal areas
  int_{gamma_1}^{gamma_2} sigma dgamma = sigma_M (gamma_2 - gamma_1); F(sigma) = W(gamma_2) - W(gamma_1)
  - sigma (gamma_2 - gamma_1) decreases strictly in sigma (dF/dsigma = -(gamma_2 - gamma_1)), so Brent's method
  on the bracket finds the only root;
* :func:`equilibria`: under a mean strain e = delta/L, the two-phase equilibria at stresses sigma of the bracket,
  phase-2 fraction nu = (e - gamma_1)/(gamma_2 - gamma_1) in [0, 1], and the driving traction
  f = W(gamma_1) - W(gamma_2) - sigma (gamma_1 - gamma_2) of their interface (phase 2 on the left).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

Law = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Spinodal:
    """The peak (gamma_a, sigma_a) ending phase 1 and the valley (gamma_b, sigma_b) starting phase 2."""

    gamma_a: float
    sigma_a: float
    gamma_b: float
    sigma_b: float


def _scalar(f: Law) -> Callable[[float], float]:
    return lambda g: float(np.asarray(f(np.array([g], float))).ravel()[0])


def _turn(slope: Callable[[float], float], a: float, b: float) -> float:
    """The strain in [a, b] where the slope changes sign (Brent; a jump of a piecewise-linear law's slope too)."""
    from scipy.optimize import brentq  # loaded on use (startup)

    return brentq(slope, a, b, xtol=1e-14 * max(1.0, abs(a), abs(b)), rtol=4 * np.finfo(float).eps)


def spinodal(stress: Law, modulus: Law | None, grid: np.ndarray) -> Spinodal | None:
    """The first peak and the following valley of sigma on the strain samples ``grid``, or None when sigma
    increases over them (a convex W there: no phase boundary). The turning points are refined between the samples
    on either side of them with the ``modulus`` sigma'(gamma) (or, without one, the samples' slopes)."""
    sig = np.asarray(stress(grid), float).ravel()
    d = np.diff(sig)
    falling = np.nonzero(d < 0)[0]
    if falling.size == 0:
        return None
    i = int(falling[0])
    rising = np.nonzero(d[i:] > 0)[0]
    if rising.size == 0:
        return None
    j = i + int(rising[0])
    ga = _refine(stress, modulus, grid, i)
    gb = _refine(stress, modulus, grid, j)
    s = _scalar(stress)
    return Spinodal(ga, s(ga), gb, s(gb))


def _refine(stress: Law, modulus: Law | None, grid: np.ndarray, i: int) -> float:
    """The turning point between grid[i - 1] and grid[i + 1] (the slope changes sign at sample i)."""
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    slope = _scalar(modulus) if modulus is not None else None
    if slope is not None and slope(a) * slope(b) < 0:
        return _turn(slope, a, b)
    return float(grid[i])


def branch_strain(stress: Law, sigma: float, a: float, b: float) -> float:
    """The strain in [a, b] of a rising branch where sigma(gamma) = sigma."""
    from scipy.optimize import brentq  # loaded on use (startup)

    s = _scalar(stress)
    return brentq(lambda g: s(g) - sigma, a, b, xtol=1e-15 * max(1.0, abs(a), abs(b)), rtol=4 * np.finfo(float).eps)


def traction(energy: Law, sigma: float, g1: float, g2: float) -> float:
    """f = W(gamma_1) - W(gamma_2) - sigma (gamma_1 - gamma_2) (Pa): phase 2 (gamma_2) left of the boundary."""
    w = np.asarray(energy(np.array([g1, g2], float)), float).ravel()
    return float(w[0] - w[1] - sigma * (g1 - g2))


@dataclass(frozen=True)
class Maxwell:
    """The Maxwell stress and the two phase strains at it (equal areas)."""

    stress: float
    gamma_1: float
    gamma_2: float


def maxwell(stress: Law, energy: Law, sp_: Spinodal, low: float, high: float) -> Maxwell:
    """sigma_M: the root of f(sigma) = 0 over (sigma_b, sigma_a), phase 1 on [low, gamma_a], phase 2 on
    [gamma_b, high] (the caller checks that both branches span the bracket)."""
    from scipy.optimize import brentq  # loaded on use (startup)

    def strains(sigma: float) -> tuple[float, float]:
        return branch_strain(stress, sigma, low, sp_.gamma_a), branch_strain(stress, sigma, sp_.gamma_b, high)

    def f(sigma: float) -> float:
        return traction(energy, sigma, *strains(sigma))

    scale = max(abs(sp_.sigma_a), abs(sp_.sigma_b), sp_.sigma_a - sp_.sigma_b)
    sigma_m = brentq(f, sp_.sigma_b, sp_.sigma_a, xtol=1e-15 * scale, rtol=4 * np.finfo(float).eps)
    g1, g2 = strains(sigma_m)
    return Maxwell(float(sigma_m), g1, g2)


def equilibria(stress: Law, energy: Law, sp_: Spinodal, low: float, high: float, mean_strain: float,
               samples: int) -> dict:
    """The two-phase equilibria under ``mean_strain`` e: at ``samples`` stresses strictly inside (sigma_b,
    sigma_a), those with a phase-2 fraction nu in [0, 1]: ``stress`` (Pa), ``phase_fraction`` nu,
    ``driving_traction`` f (Pa) of their interface."""
    out: dict = {"stress": [], "phase_fraction": [], "driving_traction": []}
    span = sp_.sigma_a - sp_.sigma_b
    for sigma in sp_.sigma_b + span * (np.arange(1, samples + 1) / (samples + 1)):
        g1 = branch_strain(stress, sigma, low, sp_.gamma_a)
        g2 = branch_strain(stress, sigma, sp_.gamma_b, high)
        nu = (mean_strain - g1) / (g2 - g1)
        if 0.0 <= nu <= 1.0:
            out["stress"].append(float(sigma))
            out["phase_fraction"].append(float(nu))
            out["driving_traction"].append(traction(energy, sigma, g1, g2))
    return out
