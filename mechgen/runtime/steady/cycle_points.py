"""Special points of a branch of periodic orbits, from the Floquet multipliers mu_i of each orbit.

Along a branch of orbits continued in a parameter p (the orbit's state x0 at phase 0 with F(x0, p) = x(T; x0, p)
- x0 = 0), each point is the zero of a test function of the multipliers, located along the branch by Brent's method
(mechgen.runtime.steady.branch_scan.crossing; Kuznetsov, *Elements of Applied Bifurcation Theory*, sec. 10.3):

* **LPC** (cyclic fold): the branch turns in p (the continuation's folds; a multiplier 1 there);
* **PD** (period doubling, flip): psi_PD = prod_i (1 + mu_i) = det(I + Phi), real, changes sign where a real
  multiplier passes through -1; a doubled orbit, of period 2T, branches off there;
* **NS** (Neimark-Sacker, torus): psi_NS = prod_{i<j} (mu_i mu_j - 1) changes sign where a complex pair crosses
  the unit circle (mu mu* = 1); it also vanishes at a real pair mu, 1/mu (a neutral saddle of the map), which the
  located point's multipliers tell apart.

The trivial multiplier 1 of an autonomous orbit is left out of psi_NS by the caller (``trivial``); a forced
orbit has none.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from mechgen.runtime.steady import branch_scan
from mechgen.runtime.steady.special_points import SpecialPoint

#: a located NS point is kept when its critical pair has |Im| above this (else a neutral saddle of the map)
NS_IMAG = 1e-7


def pd_value(multipliers: np.ndarray) -> float:
    """prod (1 + mu_i), real (the factors of a complex pair are conjugate)."""
    return float(np.real(np.prod(1.0 + np.asarray(multipliers, complex))))


def ns_value(multipliers: np.ndarray) -> float:
    """prod_{i<j} (mu_i mu_j - 1), real."""
    mu = np.asarray(multipliers, complex).ravel()
    i, j = np.triu_indices(mu.size, 1)
    return float(np.real(np.prod(mu[i] * mu[j] - 1.0)))


def without_trivial(multipliers: np.ndarray, trivial: bool) -> np.ndarray:
    """The multipliers less the one nearest 1 (an autonomous orbit's, along its flow) when ``trivial``."""
    mu = np.asarray(multipliers, complex).ravel()
    if not trivial or mu.size == 0:
        return mu
    return np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))


def is_ns(multipliers: np.ndarray) -> bool:
    """Whether the multipliers hold a complex pair on the unit circle (not a real pair mu, 1/mu)."""
    mu = np.asarray(multipliers, complex)
    on_circle = mu[np.abs(np.abs(mu) - 1.0) < 1e-4]
    return bool(np.any(np.abs(on_circle.imag) > NS_IMAG))


def cycle_points(eqs, X: np.ndarray, multipliers: Callable[[np.ndarray], np.ndarray], *,
                 trivial: bool = False, kinds: tuple = ("PD", "NS")) -> list[SpecialPoint]:
    """PD and NS points between consecutive rows of X (branch points (x0, p)); ``multipliers(x)``: the Floquet
    multipliers of the orbit at the branch point x. A PD point carries the eigenvector of -1 (``direction``, the
    doubled orbit leaves along it); an NS point the pair's angle (``angle``, rad: the torus's rotation number
    times 2 pi). ``kinds``: the points sought (a conservative orbit's NS test function vanishes identically)."""
    mus = [without_trivial(multipliers(x), trivial) for x in X]
    found = []
    for kind, value in [(k, v) for k, v in (("PD", pd_value), ("NS", ns_value)) if k in kinds]:
        values = [value(mu) for mu in mus]
        for i in range(len(X) - 1):
            if values[i] * values[i + 1] >= 0:
                continue
            x = branch_scan.crossing(eqs, X[i], X[i + 1], lambda z: value(without_trivial(multipliers(z), trivial)))
            mu = without_trivial(multipliers(x), trivial)
            if kind == "NS" and not is_ns(mu):
                continue
            if kind == "PD":
                found.append(SpecialPoint("PD", x, i, {"multipliers": mu}))
            else:
                pair = mu[np.argmin(np.abs(np.abs(mu) - 1.0) + (np.abs(mu.imag) <= NS_IMAG))]
                found.append(SpecialPoint("NS", x, i, {"multipliers": mu, "angle": float(abs(np.angle(pair)))}))
    return sorted(found, key=lambda s: s.index)
