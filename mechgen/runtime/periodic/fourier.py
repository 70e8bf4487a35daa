"""Truncated Fourier series of a T-periodic coordinate, sampled at equally spaced phases.

A coordinate q_i(t) of an orbit of angular frequency omega = 2 pi / T (rad/s) is held as 2H + 1 real
coefficients, in this order (one column of the coefficient array U, shape (2H + 1, n)):

    q_i(t) = U[0, i] + sum_{k=1..H} ( U[k, i] cos(k theta) + U[H + k, i] sin(k theta) ),   theta = omega t.

The series is evaluated at N equally spaced phases theta_s = 2 pi s / N (s = 0 .. N-1) by the real matrix
``values`` (N x (2H + 1)); d/dtheta and d^2/dtheta^2 of it by ``slopes`` and ``curvatures``, so that
q = G0 U, dq/dt = omega G1 U, d^2q/dt^2 = omega^2 G2 U. ``projector`` P ((2H + 1) x N) is the discrete Fourier
transform back to coefficients, P G0 = I exactly when N > 2H (the discrete orthogonality of the samples). These
are the real DFT as matrices: for the harmonics counts here (tens) one matrix product is as cheap as numpy's rfft
called from Python, and the Jacobian needs the matrices anyway.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np


def sample_count(harmonics: int) -> int:
    """N = 8 (H + 1) phases: the Galerkin projection of a polynomial nonlinearity of degree up to 7 in q, v, a
    (harmonics up to 7H) is free of aliasing when N > 8H; more than the 2H + 1 the transform needs."""
    return 8 * (harmonics + 1)


@dataclass(frozen=True)
class FourierBasis:
    """The sampled series of H harmonics at N phases (module doc): ``theta`` (N,), ``values``, ``slopes``,
    ``curvatures`` (N x (2H + 1)) and ``projector`` ((2H + 1) x N)."""

    harmonics: int
    theta: np.ndarray
    values: np.ndarray
    slopes: np.ndarray
    curvatures: np.ndarray
    projector: np.ndarray

    @property
    def size(self) -> int:
        """2H + 1 coefficients per coordinate."""
        return 2 * self.harmonics + 1


def basis(harmonics: int, samples: int | None = None) -> FourierBasis:
    """The :class:`FourierBasis` of ``harmonics`` H at ``samples`` N phases (default :func:`sample_count`); one
    per (H, N), shared (its arrays are read-only): a continuation builds a problem at every parameter it tries."""
    H = int(harmonics)
    return _shared_basis(H, sample_count(H) if samples is None else int(samples))


@lru_cache(maxsize=64)
def _shared_basis(H: int, N: int) -> FourierBasis:
    if N <= 2 * H:
        raise ValueError(f"{N} samples cannot resolve {H} harmonics (need more than {2 * H})")
    theta = 2 * np.pi * np.arange(N) / N
    k = np.arange(1, H + 1)
    c, s = np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k))
    ones, zeros = np.ones((N, 1)), np.zeros((N, 1))
    values = np.hstack([ones, c, s])
    slopes = np.hstack([zeros, -s * k, c * k])
    curvatures = np.hstack([zeros, -c * k**2, -s * k**2])
    weights = np.concatenate([[1.0 / N], np.full(2 * H, 2.0 / N)])
    arrays = (theta, values, slopes, curvatures, weights[:, None] * values.T)
    for array in arrays:
        array.flags.writeable = False
    return FourierBasis(H, *arrays)


def coefficients_of_samples(samples: np.ndarray, harmonics: int) -> np.ndarray:
    """U ((2H + 1) x n) of a periodic signal given at N equally spaced phases (rows of ``samples``, N > 2H):
    the projection P x (module doc)."""
    samples = np.asarray(samples, float)
    return basis(harmonics, samples.shape[0]).projector @ samples


def evaluate(U: np.ndarray, theta: np.ndarray, derivative: int = 0) -> np.ndarray:
    """The series U ((2H + 1) x n) or its ``derivative``-th d/dtheta at the phases ``theta`` (rows)."""
    H = (U.shape[0] - 1) // 2
    k = np.arange(1, H + 1)
    c, s = np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k))
    if derivative == 0:
        G = np.hstack([np.ones((len(theta), 1)), c, s])
    elif derivative == 1:
        G = np.hstack([np.zeros((len(theta), 1)), -s * k, c * k])
    else:
        G = np.hstack([np.zeros((len(theta), 1)), -c * k**2, -s * k**2])
    return G @ U


def harmonics_table(U: np.ndarray, names: list[str]) -> dict:
    """Per coordinate: ``mean`` (U[0]), ``cos`` a_k and ``sin`` b_k (k = 1..H), ``amplitude``
    sqrt(a_k^2 + b_k^2) and ``phase`` atan2(-b_k, a_k) (rad), so that q = mean + sum amplitude_k
    cos(k theta + phase_k)."""
    H = (U.shape[0] - 1) // 2
    out = {}
    for i, name in enumerate(names):
        a, b = U[1:H + 1, i], U[H + 1:, i]
        out[name] = {"mean": float(U[0, i]), "cos": a.tolist(), "sin": b.tolist(),
                     "amplitude": np.hypot(a, b).tolist(), "phase": np.arctan2(-b, a).tolist()}
    return out


def peak(values: np.ndarray) -> float:
    """max |q| of a periodic signal at equally spaced phases, refined by the parabola through the largest sample
    and its two neighbours (wrapping around the period): the grid's O(h^2) error becomes O(h^3)."""
    y = np.abs(np.asarray(values, float))
    k = int(np.argmax(y))
    a, b, c = y[k - 1], y[k], y[(k + 1) % y.size]
    curvature = a - 2 * b + c
    if curvature >= 0:
        return float(b)
    shift = 0.5 * (a - c) / curvature
    return float(b - 0.25 * (a - c) * shift)
