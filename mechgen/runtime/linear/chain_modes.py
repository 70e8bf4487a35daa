"""Normal modes of a fixed-end chain, modal energies by a sine transform, and recurrence detection.

For N unit masses between fixed walls with linear bond stiffness gamma, mode k = 1..N has

    omega_k = 2 sqrt(gamma) sin(k pi / (2 (N + 1))),   shape sqrt(2/(N+1)) sin(n k pi / (N + 1)),

and the normal coordinates Q_k = sqrt(2/(N+1)) sum_n q_n sin(n k pi / (N + 1)) (P_k likewise from v) are
the orthonormal type-I discrete sine transform of q (scipy.fft.dst(type=1, norm="ortho")): O(N log N)
per state, never a dense N x N projection. Harmonic (FPU) modal energies E_k = (P_k^2 + omega_k^2 Q_k^2)/2.

Recurrence (:func:`recurrence`): after the share of the harmonic energy in mode 1, E_1 / sum_k E_k, has
fallen below ``leave``, its first return above ``back``; the recurrence is the largest share in that
excursion (refined by a parabola through the three samples around it): the time in periods of mode 1,
T_1 = 2 pi / omega_1, and the share returned.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def frequencies(n: int, gamma: float = 1.0) -> np.ndarray:
    """omega_k = 2 sqrt(gamma) sin(k pi / (2 (n + 1))), k = 1..n (rad per unit time)."""
    k = np.arange(1, n + 1)
    return 2.0 * np.sqrt(gamma) * np.sin(k * np.pi / (2.0 * (n + 1)))


def mode_shape(n: int, k: int) -> np.ndarray:
    """The orthonormal shape of mode k: sqrt(2/(n+1)) sin(j k pi / (n + 1)), j = 1..n."""
    j = np.arange(1, n + 1)
    return np.sqrt(2.0 / (n + 1)) * np.sin(j * k * np.pi / (n + 1))


def normal_coordinates(x: np.ndarray) -> np.ndarray:
    """Q = S x along the last axis (S the orthonormal sine matrix, its own inverse), by scipy.fft.dst."""
    from scipy.fft import dst

    return dst(np.asarray(x, float), type=1, norm="ortho", axis=-1)


def modal_energies(q: np.ndarray, v: np.ndarray, gamma: float = 1.0) -> np.ndarray:
    """E_k = (P_k^2 + omega_k^2 Q_k^2) / 2 of states q, v (last axis: the sites)."""
    Q, P = normal_coordinates(q), normal_coordinates(v)
    w = frequencies(np.shape(q)[-1], gamma)
    return 0.5 * (P**2 + (w * Q) ** 2)


@dataclass(frozen=True)
class Recurrence:
    """The first recurrence: time (and in periods T_1 of mode 1) and the share of energy back in mode 1."""

    found: bool
    time: float
    periods: float
    fraction: float


def recurrence(t: np.ndarray, energies: np.ndarray, omega1: float, *, leave: float = 0.2,
               back: float = 0.8) -> Recurrence:
    """The first return of the energy to mode 1 (module doc); ``energies`` rows E_k at times ``t``."""
    t = np.asarray(t, float)
    share = energies[:, 0] / np.sum(energies, axis=1)
    period = 2.0 * np.pi / omega1
    gone = np.flatnonzero(share < leave)
    if not gone.size:
        return Recurrence(False, float("nan"), float("nan"), float("nan"))
    up = gone[0] + np.flatnonzero(share[gone[0]:] > back)
    if not up.size:
        return Recurrence(False, float("nan"), float("nan"), float("nan"))
    start = up[0]
    below = start + np.flatnonzero(share[start:] < back)
    stop = below[0] if below.size else share.size
    i = start + int(np.argmax(share[start:stop]))
    t_r, f_r = t[i], share[i]
    if 0 < i < share.size - 1:
        y0, y1, y2 = share[i - 1:i + 2]
        curv = y0 - 2 * y1 + y2
        if curv < 0:
            d = 0.5 * (y0 - y2) / curv
            h = t[i + 1] - t[i]
            t_r, f_r = t[i] + d * h, y1 - 0.25 * (y0 - y2) * d
    return Recurrence(True, float(t_r), float(t_r / period), float(f_r))


__all__ = ["Recurrence", "frequencies", "modal_energies", "mode_shape", "normal_coordinates", "recurrence"]
