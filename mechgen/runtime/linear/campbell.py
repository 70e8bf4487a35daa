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
Whirl labels are :func:`.damped.whirl`'s at each speed: forward, backward, ``linear`` where the orbit is a
straight line at that speed (an anisotropic rotor's x-only and y-only modes: at rest, or at every speed
without gyroscopic coupling) and ``none`` where the mode leaves the stations at rest.

Reduced basis. When ``matrices_at`` is a :class:`SpeedPolynomial` (matrices that are polynomials of the
speed, as :func:`fit_speed_polynomial` detects them: a rotor's G grows linearly with the spin), the
modes are computed exactly (full size) only at the first and last speed; their q-parts (real and
imaginary parts, orthonormalised) span V, the polynomial's matrices are projected once (V^T A_k V)
and every other speed solves the small dense problem (V^T P(s) V) y = 0, x = V y. Safeguard: every
tracked mode's backward error

    eta = ||(s^2 M + s C + K) x|| / (|s|^2 ||M x|| + |s| ||C x|| + ||K x||)

is checked at full size; where eta is too large (``residual_tol``, see :func:`campbell`) or a curve's
MAC drops below ``mac_min``, that speed is solved exactly and its modes enrich V, and the speeds that
failed are solved again. The shapes (MAC, whirl labels) are the full-size x = V y.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from mechgen.errors import InputError
from mechgen.runtime.core.options import Options
from mechgen.runtime.linear.damped import (DampedModes, damped_modes, frequency_scale, has_symmetry, matrix_norm,
                                           normalise_columns, split_modes, station_indices, whirl,
                                           whirl_sign)

#: the automatic choice uses the reduced basis from this many speeds on ...
REDUCED_MIN_SPEEDS = 5
#: ... and for systems of at least this many times (count + spare) unknowns
REDUCED_MIN_RATIO = 4


@dataclass(frozen=True)
class CampbellResult:
    """Tracked modes over speeds; arrays are (speed, curve), ``shapes`` is (speed, dof, curve).

    ``mac`` is the MAC between a curve's shapes at consecutive speeds (1 at the first speed): a low
    value flags a step the grid resolves poorly. ``candidates`` is how many modes each speed computed.
    ``method`` is 'exact' (full-size eigen-solves at every speed) or 'reduced' (reduced basis, then
    ``exact_solves`` full-size solves and a basis of ``basis_size`` vectors; ``reduced`` holds the model).
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
    method: str = "exact"
    exact_solves: int = 0
    basis_size: int = 0
    reduced: object = field(default=None, repr=False, compare=False)


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
        V[:, J] = normalise_columns(np.column_stack(chosen))
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


# ------------------------------------------------------------------------------------ speed polynomial


class SpeedPolynomial:
    """Matrices that are polynomials of the speed w: ``A(w) = sum_k t^k terms[key][k]``, t = (w - center) / half.

    Called with a speed it returns the dict of matrices there (sparse adds, no assembly), so it serves as
    a ``matrices_at``. A ``None`` coefficient is a zero one.
    """

    def __init__(self, terms: dict, center: float, half: float):
        self.terms = {key: tuple(coefs) for key, coefs in terms.items()}
        self.center, self.half = float(center), float(half)

    def t(self, speed: float) -> float:
        return (float(speed) - self.center) / self.half

    def __call__(self, speed: float) -> dict:
        return _evaluate(self.terms, self.t(speed))

    @property
    def degree(self) -> int:
        return max(max((k for k, a in enumerate(c) if a is not None), default=0) for c in self.terms.values())

    def combined(self, groups: dict) -> "SpeedPolynomial":
        """The polynomial whose key g is the sum of the keys ``groups[g]`` (e.g. C = D + G)."""
        terms = {}
        for g, keys in groups.items():
            coefs = []
            for k in range(max(len(self.terms[key]) for key in keys)):
                parts = [self.terms[key][k] for key in keys
                         if k < len(self.terms[key]) and self.terms[key][k] is not None]
                total = None
                for p in parts:
                    total = p if total is None else total + p
                coefs.append(total)
            terms[g] = coefs
        return SpeedPolynomial(terms, self.center, self.half)


def _evaluate(terms: dict, t: float) -> dict:
    out = {}
    for key, coefs in terms.items():
        A = coefs[0]
        for k in range(1, len(coefs)):
            if coefs[k] is not None:
                A = A + (t**k) * coefs[k]
        out[key] = A
    return out


def fit_speed_polynomial(evaluate, lo: float, hi: float, *, rtol: float = 1e-12,
                         probe: float = 0.3819660112501051) -> SpeedPolynomial | None:
    """Detect numerically that the matrices ``evaluate(w)`` (a dict) are quadratic (or linear, constant) in w.

    With t = (w - centre) / half (t = -1, 0, 1 at lo, (lo + hi) / 2, hi) it evaluates at lo, hi and the
    probe t = ``probe``; fits A(t) = A0 + t A1 per matrix from lo and hi and checks it at the probe: every
    matrix must match to ``rtol`` (Frobenius norm of the difference over the largest norm sampled). If
    that fails, it also evaluates at the centre, fits A0 + t A1 + t^2 A2 through lo, centre, hi and checks
    that at the probe. Coefficients below 1e-14 of the matrix's size are dropped (a constant matrix keeps
    one term). Returns the polynomial, or None when the dependence is not polynomial of degree <= 2 (or
    lo >= hi). Three calls of ``evaluate`` for a linear dependence, four otherwise.
    """
    lo, hi = float(lo), float(hi)
    if not hi > lo:
        return None
    center, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    at_lo, at_hi, at_probe = (evaluate(w) for w in (lo, hi, center + probe * half))
    keys = list(at_lo)
    if any(set(d) != set(keys) for d in (at_hi, at_probe)):
        return None
    scale = {k: max(matrix_norm(d[k]) for d in (at_lo, at_hi, at_probe)) for k in keys}
    # linear first (three evaluations), then quadratic through lo, centre, hi (the probe checks either)
    poly = _fitted({k: [0.5 * (at_hi[k] + at_lo[k]), 0.5 * (at_hi[k] - at_lo[k])] for k in keys}, scale,
                   (probe, at_probe, rtol), center, half)
    if poly is not None:
        return poly
    at_mid = evaluate(center)
    if set(at_mid) != set(keys):
        return None
    scale = {k: max(scale[k], matrix_norm(at_mid[k])) for k in keys}
    return _fitted({k: [at_mid[k], 0.5 * (at_hi[k] - at_lo[k]), 0.5 * (at_hi[k] + at_lo[k]) - at_mid[k]]
                    for k in keys}, scale, (probe, at_probe, rtol), center, half)


def _fitted(terms: dict, scale: dict, check: tuple, center: float, half: float) -> SpeedPolynomial | None:
    """The SpeedPolynomial of the coefficient lists ``terms`` (in t = (w - center) / half), coefficients below
    1e-14 of the matrix's ``scale`` dropped, when every matrix matches its sample at the probe:
    ``check`` = (probe t, the matrices there, rtol relative to ``scale``); else None."""
    probe, at_probe, rtol = check
    for key, coefs in terms.items():
        for k in range(1, len(coefs)):
            if matrix_norm(coefs[k]) <= 1e-14 * scale[key]:
                coefs[k] = None
        if matrix_norm(_evaluate({key: coefs}, probe)[key] - at_probe[key]) > rtol * scale[key]:
            return None
        while coefs[-1] is None and len(coefs) > 1:
            coefs.pop()
    return SpeedPolynomial(terms, center, half)


# ----------------------------------------------------------------------------------------- reduced model


def backward_errors(mats: dict, s: np.ndarray, X: np.ndarray) -> np.ndarray:
    """eta_j = ||(s_j^2 M + s_j C + K) x_j|| / (|s_j|^2 ||M x_j|| + |s_j| ||C x_j|| + ||K x_j||) per column."""
    return residual_norms(mats["M"] @ X, mats["C"] @ X, mats["K"] @ X, s)


def residual_norms(MX: np.ndarray, CX: np.ndarray, KX: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The backward errors of :func:`backward_errors` from the products M X, C X, K X."""
    R = MX * s**2 + CX * s + KX
    a = np.abs(s)
    den = a**2 * np.linalg.norm(MX, axis=0) + a * np.linalg.norm(CX, axis=0) + np.linalg.norm(KX, axis=0)
    return np.linalg.norm(R, axis=0) / np.where(den > 0, den, 1.0)


def _symmetrised(B: np.ndarray, kind) -> np.ndarray:
    """B = V^T A V made exactly symmetric (kind 1: A symmetric) or skew (kind -1: A skew); kind 0 as it is."""
    if kind == 1:
        return 0.5 * (B + B.T)
    if kind == -1:
        return 0.5 * (B - B.T)
    return B


class ReducedModel:
    """Galerkin projection of a SpeedPolynomial (keys M, C, K) onto the span of V (orthonormal columns).

    ``conservative``: M, K symmetric and C skew at every speed (an undamped gyroscopic system); then the
    reduced eigenvalue is the Rayleigh functional of x = V y, stationary in x, so its error is of the
    order of eta^2 rather than eta.
    """

    #: directions new to V below this fraction of the shapes' size are round-off, not added
    rank_tol = 1e-9

    def __init__(self, poly: SpeedPolynomial, n: int):
        self.poly = poly
        self.V = np.zeros((n, 0))
        self.terms: dict = {}
        self.kinds = kinds = {key: [None if A is None else (1 if has_symmetry(A, 1) else -1 if has_symmetry(A, -1)
                                                            else 0) for A in coefs]
                              for key, coefs in poly.terms.items()}
        self.products: dict = {}  # key -> [A_k V]: full-size products with the basis (backward errors)
        self.conservative = (all(k in (None, 1) for k in kinds["M"]) and all(k in (None, 1) for k in kinds["K"])
                             and all(k in (None, -1) for k in kinds["C"]))

    @property
    def size(self) -> int:
        return self.V.shape[1]

    def enrich(self, shapes: np.ndarray) -> int:
        """Add the directions of the real and imaginary parts of ``shapes`` that V misses; re-project."""
        W = np.hstack([shapes.real, shapes.imag])  # columns of comparable size: each shape's largest entry is 1
        scale = np.linalg.norm(W, axis=0).max(initial=0.0)
        if scale == 0:
            return 0
        for _ in range(2):
            W = W - self.V @ (self.V.T @ W)
        U, sv, _ = np.linalg.svd(W, full_matrices=False)
        new = U[:, sv > self.rank_tol * scale]  # not the round-off parts (e.g. Im of a real mode's shape)
        if not new.shape[1]:
            return 0
        new = new - self.V @ (self.V.T @ new)
        new = np.linalg.qr(new)[0]
        self.V = np.hstack([self.V, new])
        V = self.V
        self.products = {key: [None if A is None else np.asarray(A @ V) for A in coefs]
                         for key, coefs in self.poly.terms.items()}
        self.terms = {key: [None if AV is None else _symmetrised(V.T @ AV, kind)
                            for AV, kind in zip(self.products[key], self.kinds[key])]
                      for key in self.poly.terms}
        return new.shape[1]

    def backward_errors(self, speed: float, s: np.ndarray, X: np.ndarray) -> np.ndarray:
        """:func:`backward_errors` of shapes X in the span of V at ``speed``, from the products A_k V kept by
        :meth:`enrich`: A(speed) X = sum_k t^k (A_k V)(V^T X), dense, no sparse sums per speed."""
        Y = self.V.T @ X
        t = self.poly.t(speed)
        prods = {}
        for key in ("M", "C", "K"):
            total = None
            for k, AV in enumerate(self.products[key]):
                if AV is not None:
                    term = (t**k) * (AV @ Y)
                    total = term if total is None else total + term
            prods[key] = np.zeros_like(X) if total is None else total
        return residual_norms(prods["M"], prods["C"], prods["K"], s)

    def modes(self, speed: float, m: int) -> DampedModes:
        """The ``m`` lowest damped modes of the reduced problem at ``speed``, shapes x = V y at full size."""
        mats = _evaluate(self.terms, self.poly.t(speed))
        dm = _gyroscopic_modes(mats["M"], mats["C"], mats["K"], min(m, self.size)) if self.conservative else None
        if dm is None:
            dm = damped_modes(mats["M"], mats["C"], mats["K"], min(m, self.size), sparse=False)
        return dataclasses.replace(dm, shapes=normalise_columns(self.V @ dm.shapes),
                                   real_shapes=normalise_columns(self.V @ dm.real_shapes).real)

    def accepted(self, eta: np.ndarray, residual_tol: float) -> np.ndarray:
        """True where the backward error promises an eigenvalue to about ``residual_tol`` relative."""
        est = eta**2 * 1e3 if self.conservative else eta
        return est <= residual_tol


def _gyroscopic_modes(M: np.ndarray, G: np.ndarray, K: np.ndarray, count: int) -> DampedModes | None:
    """Modes of a small dense conservative gyroscopic system (M, K symmetric positive definite, G skew) from
    a Hermitian eigenproblem; None when M or K is not positive definite (use the general solver).

    With z = (s x, x): (s B + A) z = 0, B = diag(M, K), A = [[G, K], [-K, 0]] skew. With B = L L^T and
    w = L^T z, H = L^-1 A L^-T is real skew, so i H is Hermitian: i H w = mu w gives s = i mu
    (exactly imaginary, as the undamped system's are), x = L_K^-T w_2.
    """
    try:
        LM = sla.cholesky(M, lower=True)
        LK = sla.cholesky(K, lower=True)
    except np.linalg.LinAlgError:
        return None
    r = M.shape[0]
    H = np.zeros((2 * r, 2 * r))
    tmp = sla.solve_triangular(LM, G, lower=True)
    H[:r, :r] = sla.solve_triangular(LM, tmp.T, lower=True).T
    H[:r, r:] = sla.solve_triangular(LM, LK, lower=True)
    H[r:, :r] = -H[:r, r:].T
    # eigenvalues +-mu in pairs, ascending: the count smallest positive ones are r .. r + count - 1
    mu, W = sla.eigh(1j * H, driver="evx", subset_by_index=[r, r + min(count, r) - 1])
    X = sla.solve_triangular(LK.T, W[r:], lower=False)
    return split_modes(1j * mu, X, count, frequency_scale(M, G, K), 1e-6)


# ------------------------------------------------------------------------------------------- tracking


@dataclass(frozen=True)
class _Tracking:
    """What the tracking needs besides the candidates: the whirl stations (lateral dofs) and the options
    ``freq_weight``, ``cluster_tol``, ``planar_tol`` of :class:`CampbellOptions`."""

    x_index: object
    y_index: object
    freq_weight: float
    cluster_tol: float
    planar_tol: float


def _first_curves(s0: np.ndarray, V0: np.ndarray, V1, count: int, tracking: _Tracking):
    """(candidate index of each curve at the first speed, the shapes V0 with degenerate clusters aligned to
    the next speed's modes V1, None for a single speed). Curves are numbered by cluster, then whirl
    (backward before forward within a cluster), then wd."""
    if V1 is not None:
        V0 = _align(s0, V0, V1, tracking.cluster_tol)
    sign0 = whirl_sign(V0, tracking.x_index, tracking.y_index, planar_tol=tracking.planar_tol)
    cluster_id = np.empty(len(s0), dtype=int)
    for c, J in enumerate(_clusters(s0, tracking.cluster_tol)):
        cluster_id[J] = c
    return np.lexsort((s0.imag, sign0, cluster_id))[:count], V0


def _predicted(speeds, eig: np.ndarray, i: int) -> np.ndarray:
    """The curves' eigenvalues at speed i + 1 extrapolated linearly from speeds i - 1, i (speed i alone at i = 0)."""
    if i == 0:
        return eig[0]
    h = (speeds[i + 1] - speeds[i]) / (speeds[i] - speeds[i - 1])
    return eig[i] + h * (eig[i] - eig[i - 1])


def _match(s: np.ndarray, V: np.ndarray, shapes: np.ndarray, pred: np.ndarray, tracking: _Tracking):
    """One step's assignment of the curves (``shapes``, predicted eigenvalues ``pred``) to the candidates
    (s, V) on the cost of the module docstring: (rows, cols, V aligned to the curves, MAC matrix)."""
    V = _align(s, V, shapes, tracking.cluster_tol)
    mac_ij = mac_matrix(shapes, V)
    dist = np.abs(s[None, :] - pred[:, None]) / np.maximum(np.abs(pred), 1e-300)[:, None]
    from scipy.optimize import linear_sum_assignment  # loaded on use (startup)

    rows, cols = linear_sum_assignment((1.0 - mac_ij) + tracking.freq_weight * dist)
    return rows, cols, V, mac_ij


def _track(speeds, cand_s, cand_V, count: int, tracking: _Tracking):
    """Follow ``count`` curves over the candidates: (eigenvalues, shapes, mac, chosen candidate per speed)."""
    S = len(speeds)
    n = cand_V[0].shape[0]
    start, V0 = _first_curves(cand_s[0], cand_V[0], cand_V[1] if S > 1 else None, count, tracking)
    eig = np.empty((S, count), dtype=complex)
    shp = np.empty((S, n, count), dtype=complex)
    mac = np.ones((S, count))
    chosen = np.empty((S, count), dtype=int)
    eig[0], shp[0], chosen[0] = cand_s[0][start], V0[:, start], start
    for i in range(S - 1):
        rows, cols, V, mac_ij = _match(cand_s[i + 1], cand_V[i + 1], shp[i], _predicted(speeds, eig, i), tracking)
        eig[i + 1, rows], shp[i + 1][:, rows] = cand_s[i + 1][cols], V[:, cols]
        mac[i + 1, rows] = mac_ij[rows, cols]
        chosen[i + 1, rows] = cols
    return eig, shp, mac, chosen


def _check_method(method: str) -> None:
    if method not in ("auto", "exact", "reduced"):
        raise InputError(f"method is {method!r}", key="method", expected="'auto', 'exact' or 'reduced'")


@dataclass(frozen=True)
class CampbellOptions(Options):
    """The solver and tracking options of :func:`campbell` (the defaults are its defaults).

    Attributes:
        sparse: the eigensolver per speed (None: ARPACK for sparse input above SPARSE_MIN_N dofs, see
            :func:`~mechgen.runtime.linear.damped.damped_modes`; True/False force it).
        spare: extra modes per speed so that curves may reorder between speeds (None: max(2, count // 2)).
        sigma: the sparse path's real shift (None: chosen from M and K).
        freq_weight: weight of the frequency distance against the shape distance (MAC) in the tracking.
        cluster_tol: relative frequency gap under which modes count as one degenerate cluster (aligned
            within it instead of matched one by one).
        planar_tol: an orbit whose minor/major axis ratio is below this is a straight line (whirl 'linear').
        method: 'exact', 'reduced' or 'auto' (see :func:`campbell`).
        residual_tol: the largest backward error eta of a reduced speed's tracked modes.
        mac_min: the smallest MAC of a curve to the previous speed that a reduced speed may have.
        budget: a :class:`mechgen.runtime.core.budget.Budget` checked at every speed's solve (None: none);
            the exact path projects the whole diagram's time from its first speeds.
        executor: where the exact path's per-speed eigen-solves run, a
            :class:`mechgen.runtime.core.sweep.SweepExecutor` (None: serial, here). The solves are
            independent (each speed's matrices are assembled here and sent with its task); the tracking
            runs here afterwards on the same candidates, so every executor gives the serial result. The
            reduced path carries its basis from speed to speed and runs here only: with a parallel
            executor, 'auto' takes the exact path and 'reduced' is refused (InputError at ``executor``).
    """

    sparse: bool | None = None
    spare: int | None = None
    sigma: float | None = None
    freq_weight: float = 1.0
    cluster_tol: float = 1e-6
    planar_tol: float = 1e-6
    method: str = "auto"
    residual_tol: float = 1e-9
    mac_min: float = 0.8
    budget: object = None
    executor: object = None


def campbell(matrices_at, speeds, count: int, options: CampbellOptions | None = None, *, x_index, y_index,
             **overrides) -> CampbellResult:
    """Track the ``count`` lowest damped modes (at the first speed) over increasing ``speeds``.

    ``matrices_at(speed)`` returns ``dict(M=..., C=..., K=...)`` (the caller forms C = D + G(speed));
    ``x_index``, ``y_index`` name the lateral dofs of the stations used for the whirl labels.
    ``options`` (a :class:`CampbellOptions`, its defaults when None) choose the solver and the
    tracking; keyword ``overrides`` replace single options (``campbell(..., sparse=True)``).
    ``spare`` extra modes per speed (default max(2, count // 2)) let curves reorder between speeds.

    ``method``: 'exact' solves the full problem at every speed; 'reduced' uses the reduced basis (module
    docstring; ``matrices_at`` must be a :class:`SpeedPolynomial`); 'auto' (default) picks 'reduced' for
    a SpeedPolynomial with at least REDUCED_MIN_SPEEDS speeds and REDUCED_MIN_RATIO * (count + spare)
    unknowns. A reduced speed is accepted when every tracked mode's backward error eta is at most
    ``residual_tol`` (for a conservative gyroscopic system, whose reduced eigenvalues err by about
    eta^2: when 1e3 eta^2 is) and no curve's MAC to the previous speed is below ``mac_min``.
    """
    opts = CampbellOptions.of(options, **overrides)
    parallel = _parallel(opts)
    speeds = _speed_grid(speeds)
    _check_count(count)
    spare = max(2, count // 2) if opts.spare is None else opts.spare
    first, n = _first_matrices(matrices_at, speeds, count)
    station_indices(x_index, y_index, n)
    m = min(count + int(spare), n)
    solve = (n, m, count, opts.sparse, opts.sigma)
    poly = _polynomial(matrices_at, opts.method)
    reduced = not parallel and poly is not None and (opts.method == "reduced" or (
        opts.method == "auto" and len(speeds) >= REDUCED_MIN_SPEEDS and n >= REDUCED_MIN_RATIO * m))
    tracking = _Tracking(x_index, y_index, opts.freq_weight, opts.cluster_tol, opts.planar_tol)
    model = None
    if reduced:
        eig, shp, mac, model, n_exact = _campbell_reduced(poly, speeds, first, solve, opts, tracking)
    else:
        found = (solve_speeds(matrices_at, first, speeds, solve, opts.executor, opts.budget) if parallel
                 else _solve_serial(matrices_at, first, speeds, solve, opts.budget))
        eig, shp, mac, _ = _track(speeds, [dm.eigenvalues for dm in found], [dm.shapes for dm in found], count,
                                  tracking)
        n_exact = len(speeds)
    return _result(speeds, eig, shp, mac, tracking, m, model, n_exact)


def _parallel(opts: CampbellOptions) -> bool:
    """Whether the options' executor runs the speeds in parallel (checks the method and refuses 'reduced' there)."""
    _check_method(opts.method)
    parallel = opts.executor is not None and opts.executor.kind != "serial"
    if parallel and opts.method == "reduced":
        raise InputError(f"method 'reduced' carries its basis from speed to speed and cannot run on executor "
                         f"{opts.executor.kind!r}", key="executor",
                         expected="executor 'serial' for method 'reduced', or method 'exact' (or 'auto': exact "
                                  "solves at every speed on a parallel executor)")
    return parallel


def _speed_grid(speeds) -> np.ndarray:
    """``speeds`` as a 1-D float array, checked: non-empty, finite, strictly increasing."""
    speeds = np.asarray(speeds, dtype=float)
    if speeds.ndim != 1 or speeds.size == 0 or not np.all(np.isfinite(speeds)):
        raise InputError("speeds must be a non-empty list of finite numbers", key="speeds",
                         expected="a 1-D array of increasing speeds")
    if speeds.size > 1 and np.any(np.diff(speeds) <= 0):
        raise InputError("speeds are not strictly increasing", key="speeds", expected="increasing speeds")
    return speeds


def _check_count(count) -> None:
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError(f"count is {count!r}", key="count", expected="a positive integer")


def _first_matrices(matrices_at, speeds: np.ndarray, count: int) -> tuple[dict, int]:
    """(the matrices at the first speed, the number of dofs n), checked: a dict with a square 'M', count <= n."""
    first = matrices_at(float(speeds[0]))
    if not isinstance(first, dict) or "M" not in first or np.ndim(first["M"]) != 2:
        raise InputError(f"matrices_at({float(speeds[0])!r}) returned {type(first).__name__}", key="matrices_at",
                         expected="a dict with keys 'M', 'C' and 'K' (square matrices)")
    n = np.shape(first["M"])[0]
    if count > n:
        raise InputError(f"count {count} is larger than the {n} modes a system of {n} degrees of freedom has",
                         key="count", expected=f"at most {n}")
    return first, n


def _polynomial(matrices_at, method: str):
    """``matrices_at`` when it is a SpeedPolynomial with terms M, C, K (the reduced path's input), else None;
    method 'reduced' without one is refused."""
    poly = matrices_at if isinstance(matrices_at, SpeedPolynomial) else None
    usable = poly is not None and {"M", "C", "K"} <= set(poly.terms)
    if method == "reduced" and not usable:
        raise InputError("method 'reduced' needs the matrices as a SpeedPolynomial with keys M, C, K",
                         key="matrices_at", expected="fit_speed_polynomial(...) or method='exact'")
    return poly if usable else None


def _solve_serial(matrices_at, first: dict, speeds: np.ndarray, solve: tuple, budget) -> list:
    """The DampedModes of every speed, here, in order; ``budget`` (or None) projects the diagram's time."""
    S = len(speeds)
    found = []
    for i, w in enumerate(speeds):
        found.append(_modes_at(first if i == 0 else matrices_at(float(w)), float(w), *solve))
        if budget is not None:
            budget.project(i + 1, S, lambda: f"{i + 1:,} of {S:,} speeds (up to {float(w):g})")
    return found


def _result(speeds, eig, shp, mac, tracking: _Tracking, m: int, model, n_exact: int) -> CampbellResult:
    """The CampbellResult of the tracked curves: whirl labels, wd, log decrement, damping ratio."""
    labels = [whirl(shp[i], tracking.x_index, tracking.y_index, planar_tol=tracking.planar_tol)
              for i in range(len(speeds))]
    wd = eig.imag
    wn = np.abs(eig)
    return CampbellResult(
        speeds=speeds, frequencies=wd, eigenvalues=eig, whirl=labels,
        log_dec=-2.0 * np.pi * eig.real / wd + 0.0, damping_ratio=-eig.real / np.where(wn > 0, wn, 1.0),
        shapes=shp, mac=mac, x_index=tuple(np.atleast_1d(tracking.x_index).tolist()),
        y_index=tuple(np.atleast_1d(tracking.y_index).tolist()), candidates=m,
        method="exact" if model is None else "reduced", exact_solves=n_exact,
        basis_size=0 if model is None else model.size, reduced=model)


class SpeedTasks:
    """The exact path's per-speed tasks for :func:`speed_modes`, made when a speed is reached:
    (matrices at the speed, the speed, n, m, count, sparse, sigma); speed 0 reuses the matrices already built."""

    def __init__(self, matrices_at, first: dict, speeds, solve: tuple) -> None:
        self.matrices_at, self.first, self.speeds, self.solve = matrices_at, first, speeds, solve

    def __len__(self) -> int:
        return len(self.speeds)

    def __getitem__(self, i: int) -> tuple:
        w = float(self.speeds[i])
        return (self.first if i == 0 else self.matrices_at(w), w, *self.solve)


def speed_modes(task: tuple) -> DampedModes:
    """The candidate damped modes of one speed (a :class:`SpeedTasks` task); module level: it runs in workers."""
    return _modes_at(*task)


def solve_speeds(matrices_at, first: dict, speeds, solve: tuple, executor, budget=None) -> list:
    """The DampedModes of every speed on ``executor`` (mechgen.runtime.core.sweep.sweep_points: local
    processes or Dask chunks), in speed order; the first failure stops the diagram (naming the speed)."""
    from mechgen.runtime.core.sweep import sweep_points

    run = sweep_points(speed_modes, SpeedTasks(matrices_at, first, speeds, solve), executor=executor,
                       desc="campbell", budget=budget, inner="campbell",
                       labels=[{"speed": float(w)} for w in speeds], on_error="raise")
    return run.results


class _ReducedRun:
    """The state of a reduced-basis diagram (module docstring): the basis, every speed's candidates and their
    backward errors (zero at a full-size solve), and the speeds solved at full size.

    ``solve`` is (n, m, count, sparse, sigma) as for :func:`speed_modes`; ``budget`` (or None) is checked at
    every full-size solve."""

    def __init__(self, poly: SpeedPolynomial, speeds: np.ndarray, first: dict, solve: tuple, budget) -> None:
        self.poly, self.speeds, self.first, self.solve, self.budget = poly, speeds, first, solve, budget
        self.m, self.count = solve[1], solve[2]
        self.model = ReducedModel(poly, solve[0])
        self.found: list = [None] * len(speeds)
        self.eta: list = [None] * len(speeds)
        self.exact: set = set()

    def solve_exact(self, i: int) -> None:
        """Speed i at full size; its modes enrich the basis."""
        w = float(self.speeds[i])
        dm = _modes_at(self.first if i == 0 else self.poly(w), w, *self.solve)
        self.found[i], self.eta[i] = dm, np.zeros(len(dm.eigenvalues))
        self.exact.add(i)
        self.model.enrich(dm.shapes)
        if self.budget is not None:
            self.budget.check_time(lambda: f"{len(self.exact)} full-size solves of {len(self.speeds):,} speeds")

    def solve_reduced(self, todo: list) -> None:
        """The speeds ``todo`` (those not solved at full size) on the basis; at full size where the basis
        gives fewer than ``count`` oscillatory modes."""
        for i in todo:
            if i in self.exact:
                continue
            w = float(self.speeds[i])
            dm = self.model.modes(w, self.m)
            if len(dm.eigenvalues) < self.count:
                self.solve_exact(i)
                continue
            self.found[i] = dm
            self.eta[i] = self.model.backward_errors(w, dm.eigenvalues, dm.shapes)

    def failing(self, mac: np.ndarray, chosen: np.ndarray, opts: CampbellOptions, cluster_tol: float) -> dict:
        """{speed index: worst backward error} of the reduced speeds the safeguard refuses (eta above
        ``residual_tol``, or a MAC to a neighbour speed below ``mac_min``)."""
        S = len(self.speeds)
        bad = {}
        for i in range(S):
            if i in self.exact:
                continue
            s = self.found[i].eigenvalues
            worst = np.zeros(len(s))  # the backward error of a degenerate cluster's worst member
            for J in _clusters(s, cluster_tol):
                worst[J] = self.eta[i][J].max()
            ok = self.model.accepted(worst[chosen[i]], opts.residual_tol)
            nxt = mac[i + 1] if i + 1 < S else np.ones(self.count)
            if not ok.all() or mac[i].min() < opts.mac_min or nxt.min() < opts.mac_min:
                bad[i] = float(worst[chosen[i]].max())
        return bad

    def refine(self, bad: dict) -> list:
        """Solve exactly at the worst speed of every run of consecutive failing speeds (at every failing speed
        when the basis keeps failing) and enrich; returns the failing speeds left to solve again."""
        runs = _consecutive_runs(sorted(bad))
        if len(self.exact) + len(runs) > len(self.speeds) // 2:  # the basis keeps failing
            runs = [[i] for i in bad]
        for run in runs:
            self.solve_exact(max(run, key=lambda i: bad[i]))
        return [i for i in bad if i not in self.exact]


def _consecutive_runs(indices: list) -> list[list[int]]:
    """Increasing ``indices`` split into runs of consecutive integers."""
    runs: list[list[int]] = []
    for i in indices:
        if runs and i == runs[-1][-1] + 1:
            runs[-1].append(i)
        else:
            runs.append([i])
    return runs


def _campbell_reduced(poly, speeds, first: dict, solve: tuple, opts: CampbellOptions, tracking: _Tracking):
    """Reduced-basis candidates with the safeguard (module docstring): (eig, shp, mac, model, exact solves)."""
    run = _ReducedRun(poly, speeds, first, solve, opts.budget)
    S = len(speeds)
    for i in sorted({0, S - 1}):
        run.solve_exact(i)
    todo = [i for i in range(S) if i not in run.exact]
    while True:
        run.solve_reduced(todo)
        eig, shp, mac, chosen = _track(speeds, [dm.eigenvalues for dm in run.found],
                                       [dm.shapes for dm in run.found], run.count, tracking)
        bad = run.failing(mac, chosen, opts, tracking.cluster_tol)
        if not bad:
            return eig, shp, mac, run.model, len(run.exact)
        todo = run.refine(bad)


def _pick(dm: DampedModes, ref: np.ndarray, pred: complex) -> float:
    """wd of the mode of ``dm`` closest to the reference shape and predicted eigenvalue."""
    cost = (1.0 - mac_matrix(ref, dm.shapes)[0]) + np.abs(dm.eigenvalues - pred) / max(abs(pred), 1e-300)
    return float(dm.wd[int(np.argmin(cost))])


def _secant(g, a: float, b: float, ga: float, gb: float, x: float, tol: float, maxit: int = 30):
    """Root of g in [a, b] (g(a) g(b) < 0) by the secant method from x, kept in the bracket (bisection
    when a step leaves it); returns (root, slope of the last secant, evaluations)."""
    lo, hi, glo = a, b, ga
    px, pg = (a, ga) if abs(x - a) <= abs(b - x) else (b, gb)
    slope = (gb - ga) / (b - a)
    for k in range(1, maxit + 1):
        gx = g(x)
        if gx == 0.0:
            return x, slope, k
        if (gx < 0) == (glo < 0):
            lo, glo = x, gx
        else:
            hi = x
        if gx != pg:
            slope = (gx - pg) / (x - px)
        nx = x - gx / slope if slope != 0 else 0.5 * (lo + hi)
        if not lo < nx < hi:
            nx = 0.5 * (lo + hi)
        px, pg, x = x, gx, nx
        if abs(x - px) <= tol * max(abs(x), 1e-300):
            return x, slope, k
    return x, slope, maxit


def _refined_crossing(result: CampbellResult, j: int, r: float, i: int, matrices_at, sparse, xtol: float):
    """f_j(Omega) - r Omega = 0 in [speeds[i], speeds[i + 1]], f_j the mode best matching curve j's shape
    and interpolated eigenvalue: secant steps from the linear interpolation on the reduced model (when the
    result has one for these matrices), then one exact solve and a Newton step with the last secant slope;
    secant steps on exact solves when there is no reduced model or it disagrees with the exact solve."""
    a, b = float(result.speeds[i]), float(result.speeds[i + 1])
    sa, sb = result.eigenvalues[i, j], result.eigenvalues[i + 1, j]
    ga = float(result.frequencies[i, j] - r * a)
    gb = float(result.frequencies[i + 1, j] - r * b)
    if ga * gb > 0:
        return None
    if ga == 0.0 or gb == 0.0:
        return a if ga == 0.0 else b

    def refs(w: float):
        t = (w - a) / (b - a)
        return result.shapes[i if t < 0.5 else i + 1][:, j:j + 1], sa + t * (sb - sa)

    def g_exact(w: float) -> float:
        dm = damped_modes(**{k: v for k, v in matrices_at(w).items() if k in ("M", "C", "K")},
                          count=result.candidates, sparse=sparse)
        return _pick(dm, *refs(w)) - r * w

    x0 = a + (b - a) * ga / (ga - gb)
    tol = xtol
    model = result.reduced
    if isinstance(model, ReducedModel) and model.poly is matrices_at:
        def g_red(w: float) -> float:
            return _pick(model.modes(w, result.candidates), *refs(w)) - r * w

        x, slope, _ = _secant(g_red, a, b, ga, gb, x0, tol)
        ge = g_exact(x)
        step = ge / slope if slope != 0 else np.inf
        if abs(step) <= 1e-6 * max(abs(x), 1e-300) and a <= x - step <= b:
            return x - step
        x0 = x
    x, _, _ = _secant(g_exact, a, b, ga, gb, x0, tol)
    return x


def critical_speeds(result: CampbellResult, multiples=(1.0,), *, refine=None, sparse: bool | None = None,
                    xtol: float = 1e-12) -> list[dict]:
    """Speeds where a tracked curve crosses r * Omega, r in ``multiples`` (1: synchronous excitation).

    A crossing is a sign change of f_j(Omega) - r Omega between grid speeds (or an exact zero on
    one), placed by linear interpolation; when ``refine`` (a ``matrices_at`` callable) is given, by
    secant steps from there to ``xtol`` relative: on the result's reduced model when ``refine`` is the
    SpeedPolynomial it was computed from (then confirmed by one exact solve and a Newton step), else on
    the recomputed modes (see :func:`_refined_crossing`). Returns dicts {mode, multiple,
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
