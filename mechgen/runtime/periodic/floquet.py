"""Floquet multipliers of a periodic orbit and its stability.

The multipliers mu are the eigenvalues of the monodromy matrix Phi(T) (mechgen.runtime.periodic.flow): a small
perturbation grows by mu per period along its eigenvector. An autonomous orbit always has the trivial multiplier
mu = 1 (a shift along the orbit); the one nearest 1 is set aside before judging (a free orbit of a conservative family
has two, along the orbit and along the family: ``trivial = 2``). The orbit is ``stable`` when
every other |mu| <= 1 + NEUTRAL (a neutral multiplier, |mu| = 1 of a conservative system, counts as stable: the
multipliers themselves say more), else ``unstable``. By Liouville's formula det Phi(T) = exp(int_0^T trace J dt),
the product of all multipliers (exp(-c T / m) for a linear dashpot c on a mass m).
"""
from __future__ import annotations

import numpy as np

#: |mu| up to 1 + NEUTRAL counts as neutral: the integration's relative accuracy on Phi is far below it
NEUTRAL = 1e-6


def ordered(mu: np.ndarray) -> np.ndarray:
    """Multipliers by decreasing modulus (equal to 1e-9 relative: a conjugate pair), then decreasing imaginary part."""
    mu = np.asarray(mu, complex)
    modulus = np.round(np.abs(mu) / max(float(np.max(np.abs(mu), initial=0.0)), 1e-300), 9)
    return mu[np.lexsort((-mu.imag, -modulus))]


def multipliers(monodromy: np.ndarray) -> np.ndarray:
    """The eigenvalues of the monodromy matrix, :func:`ordered`."""
    return ordered(np.linalg.eigvals(np.asarray(monodromy, float)))


def nontrivial(mu: np.ndarray, autonomous: bool, trivial: int | None = None) -> np.ndarray:
    """The multipliers without the trivial ones: the one nearest 1 of an autonomous orbit, or the ``trivial`` nearest
    1 (2 for a free orbit of a conservative family: along the orbit and along the family)."""
    count = int(autonomous) if trivial is None else int(trivial)
    mu = np.asarray(mu)
    for _ in range(min(count, mu.size)):
        mu = np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))
    return mu


def stability(mu: np.ndarray, autonomous: bool, trivial: int | None = None) -> str:
    """``stable`` or ``unstable`` (module doc; ``trivial``: :func:`nontrivial`)."""
    rest = nontrivial(mu, autonomous, trivial)
    return "stable" if float(np.max(np.abs(rest), initial=0.0)) <= 1.0 + NEUTRAL else "unstable"


def as_pairs(mu: np.ndarray) -> list[list[float]]:
    """[re, im] pairs, as mechgen reports eigenvalues."""
    return [[float(m.real), float(m.imag)] for m in mu]
