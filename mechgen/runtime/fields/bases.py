"""Global Galerkin bases on s in [0, L]: values and derivatives D_s^k phi_j at any points.

* ``sine``:     phi_j = sin(j pi s / L), j = 1..N (zero value and curvature at both ends);
* ``cosine``:   phi_j = cos(j pi s / L), j = 0..N-1 (zero slope at both ends);
* ``legendre``: phi_j = P_j(2 s / L - 1), j = 0..N-1 (boundary conditions by constraints);
* ``beam``:     Euler-Bernoulli beam eigenfunctions for the end conditions (clamped,
  pinned or free at each end), in the overflow-free form
  phi = a1 e^{-beta s} + a2 e^{-beta (L - s)} + a3 cos(beta s) + a4 sin(beta s),
  with beta_j the roots of the 4 x 4 boundary determinant, plus rigid-body modes
  when an end condition allows them. Each is scaled to (1/L) int phi^2 ds = 1/2.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.polynomial import legendre as Leg

END_ORDERS = {"clamped": (0, 1), "pinned": (0, 2), "free": (2, 3)}


def trig(kind: str, s: np.ndarray, n: int, length: float, max_order: int) -> np.ndarray:
    """Sine or cosine basis: array (len(s), max_order + 1, n)."""
    j = np.arange(1, n + 1) if kind == "sine" else np.arange(n)
    k = j * np.pi / length
    phase = 0.0 if kind == "sine" else np.pi / 2
    out = np.empty((len(s), max_order + 1, n))
    for order in range(max_order + 1):
        out[:, order, :] = k**order * np.sin(np.outer(s, k) + phase + order * np.pi / 2)
    return out


def legendre(s: np.ndarray, n: int, length: float, max_order: int) -> np.ndarray:
    """Legendre polynomials of x = 2 s / L - 1: array (len(s), max_order + 1, n)."""
    x = 2.0 * np.asarray(s, float) / length - 1.0
    out = np.empty((len(x), max_order + 1, n))
    eye = np.eye(n)
    for order in range(max_order + 1):
        coef = Leg.legder(eye, order, scl=2.0 / length, axis=0) if order else eye
        out[:, order, :] = Leg.legval(x, coef).T if coef.shape[0] else 0.0
    return out


def _end_rows(beta: float, length: float, end: str, at_end: bool) -> np.ndarray:
    """Boundary rows (divided by beta^k) of the four exponential/trigonometric terms at one end."""
    rows = []
    decay = np.exp(-beta * length)
    for k in END_ORDERS[end]:
        if at_end:
            rows.append([(-1) ** k * decay, 1.0, np.cos(beta * length + k * np.pi / 2),
                         np.sin(beta * length + k * np.pi / 2)])
        else:
            rows.append([(-1) ** k, decay, np.cos(k * np.pi / 2), np.sin(k * np.pi / 2)])
    return np.asarray(rows)


def _boundary_matrix(beta: float, length: float, ends: tuple[str, str]) -> np.ndarray:
    return np.vstack([_end_rows(beta, length, ends[0], False), _end_rows(beta, length, ends[1], True)])


def _rigid_modes(ends: tuple[str, str]) -> list[tuple[float, float]]:
    """Rigid-body modes a + b s/L allowed by the end conditions (as (a, b))."""
    if ends == ("free", "free"):
        return [(1.0, 0.0), (-1.0, 2.0)]
    if ends == ("pinned", "free"):
        return [(0.0, 1.0)]
    if ends == ("free", "pinned"):
        return [(1.0, -1.0)]
    return []


@lru_cache(maxsize=64)
def beam_roots(n: int, length: float, ends: tuple[str, str]) -> tuple[tuple[float, ...], tuple[np.ndarray, ...]]:
    """The first ``n`` roots beta_j > 0 of det H(beta) = 0 and the coefficient vectors a_j."""
    det = lambda b: np.linalg.det(_boundary_matrix(b, length, ends))  # noqa: E731
    grid = np.arange(1, 64 * (n + 4)) * (np.pi / 16) / length
    values = np.array([det(b) for b in grid])
    roots, vectors = [], []
    for b0, b1, f0, f1 in zip(grid[:-1], grid[1:], values[:-1], values[1:]):
        if len(roots) == n:
            break
        if f0 == 0.0 or f0 * f1 < 0:
            from scipy.optimize import brentq  # loaded on use (startup)

            beta = b0 if f0 == 0.0 else brentq(det, b0, b1, xtol=1e-15 / length, rtol=1e-15)
            _, _, vt = np.linalg.svd(_boundary_matrix(beta, length, ends))
            roots.append(beta)
            vectors.append(vt[-1])
    if len(roots) < n:
        raise ValueError(f"found {len(roots)} of {n} beam eigenvalues for ends {ends}")
    return tuple(roots), tuple(vectors)


def _beam_unscaled(s: np.ndarray, n: int, length: float, max_order: int, ends: tuple[str, str]) -> np.ndarray:
    out = np.zeros((len(s), max_order + 1, n))
    rigid = _rigid_modes(ends)[:n]
    for j, (a, b) in enumerate(rigid):
        out[:, 0, j] = a + b * s / length
        if max_order >= 1:
            out[:, 1, j] = b / length
    flexible = n - len(rigid)
    if flexible:
        betas, vectors = beam_roots(flexible, float(length), tuple(ends))
        for j, (beta, a) in enumerate(zip(betas, vectors), start=len(rigid)):
            for k in range(max_order + 1):
                out[:, k, j] = beta**k * (a[0] * (-1) ** k * np.exp(-beta * s) + a[1] * np.exp(-beta * (length - s))
                                          + a[2] * np.cos(beta * s + k * np.pi / 2)
                                          + a[3] * np.sin(beta * s + k * np.pi / 2))
    return out


def beam(s: np.ndarray, n: int, length: float, max_order: int, ends: tuple[str, str]) -> np.ndarray:
    """Beam eigenfunctions (rigid modes first) and derivatives: array (len(s), max_order + 1, n)."""
    x, w = np.polynomial.legendre.leggauss(max(64, 4 * n + 16))
    probe = _beam_unscaled((x + 1) * length / 2, n, length, 0, ends)[:, 0, :]
    scale = np.sqrt(0.5 / (0.5 * w @ probe**2))
    return _beam_unscaled(np.asarray(s, float), n, length, max_order, ends) * scale[None, None, :]
