"""Campbell diagram: damped modes of M q'' + C(Omega) q' + K(Omega) q = 0 tracked over spin speeds Omega.

At every speed the ``count`` + ``spare`` lowest damped modes are computed (:mod:`.damped`); the
curves are then followed from speed to speed, so that curve j is the same physical mode at every
speed and curves cross instead of swapping. A step from speed i to i + 1 solves the assignment
problem (``scipy.optimize.linear_sum_assignment``) on the cost

    cost_jk = (1 - MAC(phi_j, psi_k)) + freq_weight |s_k - s_j^pred| / |s_j^pred|,
    MAC(phi, psi) = |phi^H psi|^2 / (|phi|^2 |psi|^2),

phi_j the shape of curve j at speed i, psi_k a candidate at speed i + 1, s_j^pred the eigenvalue of
curve j linearly extrapolated from speeds i - 1, i (from speed i alone at the first step).

Degenerate eigenvalues (|s_a - s_b| <= cluster_tol |s|: the forward/backward pair of an isotropic
rotor at Omega = 0, or two curves crossing exactly on a grid speed) have an arbitrary eigenbasis. The
basis of such a cluster is re-chosen before matching: its vectors become the projections onto the
cluster's eigenspace of the neighbouring speed's shapes that lie (mostly) in it - of the next
speed's modes for a cluster at the first speed (so the Omega = 0 pair becomes the limit of the
backward and forward modes), of the tracked curves for a cluster later on.

Curves are numbered by wd at the first speed; ties (a degenerate cluster) put backward before forward.
Whirl labels follow :func:`.damped.whirl_sign`; a planar (straight-line) orbit takes the label of the
nearest speed on the same curve where the orbit is not planar ('forward' if it is planar everywhere).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, linear_sum_assignment

from mechgen.errors import InputError
from mechgen.runtime.damped import DampedModes, _normalise, _stations, damped_modes, whirl_sign


@dataclass(frozen=True)
class CampbellResult:
    """Tracked modes over speeds; arrays are (speed, curve), ``shapes`` is (speed, dof, curve).

    ``mac`` is the MAC between a curve's shapes at consecutive speeds (1 at the first speed): a low
    value flags a step the grid resolves poorly. ``candidates`` is how many modes each speed computed.
    """

    speeds: np.ndarray
    frequencies: np.ndarray
    eigenvalues: np.ndarray
    whirl: list[list[str]]
    log_dec: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    mac: np.ndarray
    x_index: tuple
    y_index: tuple
    candidates: int


def mac_matrix(Phi: np.ndarray, Psi: np.ndarray) -> np.ndarray:
    """MAC_jk = |phi_j^H psi_k|^2 / (|phi_j|^2 |psi_k|^2) between the columns of Phi and Psi."""
    num = np.abs(Phi.conj().T @ Psi) ** 2
    den = np.outer(np.sum(np.abs(Phi) ** 2, axis=0), np.sum(np.abs(Psi) ** 2, axis=0))
    return num / np.where(den > 0, den, 1.0)


def _clusters(s: np.ndarray, tol: float) -> list[list[int]]:
    """Runs of consecutive eigenvalues (sorted by wd) within tol * |s| of their neighbour."""
    groups: list[list[int]] = []
    for k in range(len(s)):
        if groups and abs(s[k] - s[k - 1]) <= tol * max(abs(s[k]), abs(s[k - 1])):
            groups[-1].append(k)
        else:
            groups.append([k])
    return groups


def _align(s: np.ndarray, V: np.ndarray, R: np.ndarray, tol: float) -> np.ndarray:
    """V with the basis of every degenerate cluster re-chosen as projections of reference columns R."""
    V = V.copy()
    rnorm2 = np.sum(np.abs(R) ** 2, axis=0)
    for J in _clusters(s, tol):
        p = len(J)
        if p < 2:
            continue
        W = V[:, J]
        coef = np.linalg.lstsq(W, R, rcond=None)[0]
        P = W @ coef
        frac = np.sum(np.abs(P) ** 2, axis=0) / np.where(rnorm2 > 0, rnorm2, 1.0)
        chosen: list[np.ndarray] = []
        Qb = np.zeros((V.shape[0], 0), dtype=complex)
        for k in np.argsort(-frac, kind="stable"):
            if len(chosen) == p or frac[k] < 0.5:
                break
            v = P[:, k]
            resid = v - Qb @ (Qb.conj().T @ v)
            if np.linalg.norm(resid) > 0.1 * np.linalg.norm(v):
                chosen.append(v)
                Qb = np.column_stack([Qb, resid / np.linalg.norm(resid)])
        if len(chosen) < p:  # complete with the directions of the eigenspace the references miss
            rest = W - Qb @ (Qb.conj().T @ W)
            U = np.linalg.svd(rest, full_matrices=False)[0]
            chosen.extend(U[:, j] for j in range(p - len(chosen)))
        V[:, J] = _normalise(np.column_stack(chosen))
    return V


def _modes_at(mats, speed: float, n: int, m: int, count: int, sparse, sigma) -> DampedModes:
    if not isinstance(mats, dict) or not {"M", "C", "K"} <= set(mats):
        raise InputError(f"matrices_at({speed!r}) returned {type(mats).__name__}", key="matrices_at",
                         expected="a dict with keys 'M', 'C' and 'K'")
    dm = damped_modes(mats["M"], mats["C"], mats["K"], m, sparse=sparse, sigma=sigma)
    if dm.shapes.shape[0] != n:
        raise InputError(f"matrices_at({speed!r}) returned {dm.shapes.shape[0]} dofs, the first speed {n}",
                         key="matrices_at", expected=f"{n} x {n} matrices at every speed")
    if len(dm.eigenvalues) < count:
        raise InputError(f"only {len(dm.eigenvalues)} oscillatory modes at speed {speed:g}, fewer than count "
                         f"{count} (the others are overdamped or rigid)", key="count",
                         expected=f"at most {len(dm.eigenvalues)}")
    return dm


def _fill_planar(signs: np.ndarray) -> np.ndarray:
    """Each 0 (planar) of a curve takes the sign of the nearest nonzero speed (the later one on a tie)."""
    out = signs.copy()
    for j in range(signs.shape[1]):
        nz = np.flatnonzero(signs[:, j])
        if not nz.size:
            out[:, j] = 1
            continue
        for i in np.flatnonzero(signs[:, j] == 0):
            d = np.abs(nz - i)
            best = nz[d == d.min()].max()
            out[i, j] = signs[best, j]
    return out


def campbell(matrices_at, speeds, count: int, *, x_index, y_index, sparse: bool | None = None,
             spare: int | None = None, sigma: float | None = None, freq_weight: float = 1.0,
             cluster_tol: float = 1e-6, planar_tol: float = 1e-6) -> CampbellResult:
    """Track the ``count`` lowest damped modes (at the first speed) over increasing ``speeds``.

    ``matrices_at(speed)`` returns ``dict(M=..., C=..., K=...)`` (the caller forms C = D + G(speed));
    ``x_index``, ``y_index`` name the lateral dofs of the stations used for the whirl labels.
    ``spare`` extra modes per speed (default max(2, count // 2)) let curves reorder between speeds.
    """
    speeds = np.asarray(speeds, dtype=float)
    if speeds.ndim != 1 or speeds.size == 0 or not np.all(np.isfinite(speeds)):
        raise InputError("speeds must be a non-empty list of finite numbers", key="speeds",
                         expected="a 1-D array of increasing speeds")
    if speeds.size > 1 and np.any(np.diff(speeds) <= 0):
        raise InputError("speeds are not strictly increasing", key="speeds", expected="increasing speeds")
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError(f"count is {count!r}", key="count", expected="a positive integer")
    if spare is None:
        spare = max(2, count // 2)
    first = matrices_at(float(speeds[0]))
    if not isinstance(first, dict) or "M" not in first or np.ndim(first["M"]) != 2:
        raise InputError(f"matrices_at({float(speeds[0])!r}) returned {type(first).__name__}", key="matrices_at",
                         expected="a dict with keys 'M', 'C' and 'K' (square matrices)")
    n = np.shape(first["M"])[0]
    if count > n:
        raise InputError(f"count {count} is larger than the {n} modes a system of {n} degrees of freedom has",
                         key="count", expected=f"at most {n}")
    _stations(x_index, y_index, n)
    m = min(count + int(spare), n)

    found = [_modes_at(first if i == 0 else matrices_at(float(w)), float(w), n, m, count, sparse, sigma)
             for i, w in enumerate(speeds)]
    cand_s = [dm.eigenvalues for dm in found]
    cand_V = [dm.shapes for dm in found]

    # first speed: resolve degenerate pairs with the next speed's modes, then number the curves
    if len(speeds) > 1:
        cand_V[0] = _align(cand_s[0], cand_V[0], cand_V[1], cluster_tol)
    sign0 = whirl_sign(cand_V[0], x_index, y_index, planar_tol=planar_tol)
    cluster_id = np.empty(len(cand_s[0]), dtype=int)
    for c, J in enumerate(_clusters(cand_s[0], cluster_tol)):
        cluster_id[J] = c
    start = np.lexsort((cand_s[0].imag, sign0, cluster_id))[:count]

    S = len(speeds)
    eig = np.empty((S, count), dtype=complex)
    shp = np.empty((S, n, count), dtype=complex)
    mac = np.ones((S, count))
    eig[0], shp[0] = cand_s[0][start], cand_V[0][:, start]
    for i in range(S - 1):
        if i == 0:
            pred = eig[0]
        else:
            h = (speeds[i + 1] - speeds[i]) / (speeds[i] - speeds[i - 1])
            pred = eig[i] + h * (eig[i] - eig[i - 1])
        V = _align(cand_s[i + 1], cand_V[i + 1], shp[i], cluster_tol)
        mac_ij = mac_matrix(shp[i], V)
        dist = np.abs(cand_s[i + 1][None, :] - pred[:, None]) / np.maximum(np.abs(pred), 1e-300)[:, None]
        rows, cols = linear_sum_assignment((1.0 - mac_ij) + freq_weight * dist)
        eig[i + 1, rows], shp[i + 1][:, rows] = cand_s[i + 1][cols], V[:, cols]
        mac[i + 1, rows] = mac_ij[rows, cols]

    signs = np.array([whirl_sign(shp[i], x_index, y_index, planar_tol=planar_tol) for i in range(S)])
    signs = _fill_planar(signs.reshape(S, count))
    labels = [["forward" if v > 0 else "backward" for v in row] for row in signs]
    wd = eig.imag
    wn = np.abs(eig)
    return CampbellResult(
        speeds=speeds, frequencies=wd, eigenvalues=eig, whirl=labels,
        log_dec=-2.0 * np.pi * eig.real / wd + 0.0, damping_ratio=-eig.real / np.where(wn > 0, wn, 1.0),
        shapes=shp, mac=mac, x_index=tuple(np.atleast_1d(x_index).tolist()),
        y_index=tuple(np.atleast_1d(y_index).tolist()), candidates=m)


def _refined_crossing(result: CampbellResult, j: int, r: float, i: int, matrices_at, sparse, xtol: float):
    """Brent's method on f_j(Omega) - r Omega in [speeds[i], speeds[i + 1]], f_j the best-matching mode."""
    a, b = result.speeds[i], result.speeds[i + 1]
    sa, sb = result.eigenvalues[i, j], result.eigenvalues[i + 1, j]

    def g(w: float) -> float:
        dm = damped_modes(**{k: v for k, v in matrices_at(w).items() if k in ("M", "C", "K")},
                          count=result.candidates, sparse=sparse)
        t = (w - a) / (b - a)
        ref = result.shapes[i if t < 0.5 else i + 1][:, j:j + 1]
        pred = sa + t * (sb - sa)
        cost = (1.0 - mac_matrix(ref, dm.shapes)[0]) + np.abs(dm.eigenvalues - pred) / max(abs(pred), 1e-300)
        return float(dm.wd[int(np.argmin(cost))] - r * w)

    ga, gb = g(a), g(b)
    if ga * gb > 0:
        return None
    return brentq(g, a, b, xtol=xtol * max(abs(a), abs(b), 1e-300), rtol=4 * np.finfo(float).eps)


def critical_speeds(result: CampbellResult, multiples=(1.0,), *, refine=None, sparse: bool | None = None,
                    xtol: float = 1e-12) -> list[dict]:
    """Speeds where a tracked curve crosses r * Omega, r in ``multiples`` (1: synchronous excitation).

    A crossing is a sign change of f_j(Omega) - r Omega between grid speeds (or an exact zero on
    one), placed by linear interpolation; when ``refine`` (a ``matrices_at`` callable) is given, by
    Brent's method on the recomputed modes to ``xtol`` relative. Returns dicts {mode, multiple,
    speed, frequency (= r speed), whirl (the curve's label at the nearer grid speed)}, by speed.
    """
    out: list[dict] = []
    w = result.speeds
    for r in multiples:
        r = float(r)
        for j in range(result.frequencies.shape[1]):
            g = result.frequencies[:, j] - r * w
            for i in range(len(w)):
                if g[i] == 0.0:
                    speed, near = float(w[i]), i
                elif i + 1 < len(w) and g[i] * g[i + 1] < 0:
                    speed = float(w[i] + (w[i + 1] - w[i]) * g[i] / (g[i] - g[i + 1]))
                    if refine is not None:
                        refined = _refined_crossing(result, j, r, i, refine, sparse, xtol)
                        speed = speed if refined is None else float(refined)
                    near = i if speed - w[i] <= w[i + 1] - speed else i + 1
                else:
                    continue
                out.append({"mode": j, "multiple": r, "speed": speed, "frequency": r * speed,
                            "whirl": result.whirl[near][j]})
    out.sort(key=lambda d: (d["speed"], d["mode"], d["multiple"]))
    return out
