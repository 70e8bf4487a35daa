"""Damped (gyroscopic) modes of M q'' + C q' + K q = 0 (C = D + G, K possibly non-symmetric), and whirl.

First-order pencil with x = (q, q'): A x = s B x, A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]].
Each oscillatory mode is one eigenvalue s = -zeta wn + i wd of a complex-conjugate pair,
kept with Im s > 0, so that the motion is q(t) = Re(X e^{s t}). Reported per mode:

* damped natural frequency  wd = Im s            (the sort key, ascending),
* natural frequency         wn = |s|,
* damping ratio             zeta = -Re s / |s|,
* logarithmic decrement     delta = -2 pi Re s / Im s = 2 pi zeta / sqrt(1 - zeta^2)  (ROSS's log_dec),
* the q-part X of the right eigenvector, scaled so that its largest |component| is 1 (real, positive).

Eigenvalues with |Im s| <= ``imag_tol`` * scale (scale = sqrt(||K||_F / ||M||_F)) are real:
overdamped or rigid-body (s = 0) motions. They are kept apart, in ``real_eigenvalues`` and
``real_shapes`` (ascending |s|), and never count towards ``count``.

Dense path: ``scipy.linalg.eig`` of the standard problem for M^-1 [K, C] when M is symmetric
positive definite (Cholesky), else the generalized QZ problem; there a singular M (massless
Lagrange multipliers) gives infinite eigenvalues (beta = 0, or |s| > 1e10 scale), which are dropped.
Sparse path: ARPACK on the shift-inverted operator (A - sigma B)^-1 B, whose eigenvalues
nu = 1 / (s - sigma) are largest for s nearest sigma (infinite s give nu = 0 and never show up);
sigma defaults to a small negative real number below the lowest frequency scale, so a singular K
(rigid modes) does not make A - sigma B singular. It returns the oscillatory modes of smallest
|s - sigma| (for light damping: the lowest wn), sorted by wd.

Whirl: with x = Re(X e^{i wd t}), y = Re(Y e^{i wd t}) the orbit's signed area rate is
x y' - y x' averaged = wd Im(X conj(Y)), so the orbit is counter-clockwise about z = x cross y
(forward, the sense of a positive spin) when Im(X conj(Y)) > 0 and clockwise (backward) when < 0.
The orbit is an ellipse (:func:`orbit_axes`: semi-axes, the major axis's angle, the signed ratio
kappa = minor / major); a straight line (|kappa| <= 1e-6) has no direction and is labelled 'linear', a
mode that leaves the stations at rest 'none' (:func:`whirl`). A double eigenvalue's plane is re-chosen
as its backward and forward circles by :func:`circular_pair`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


#: with sparse input and ``sparse=None``, systems of at most this many unknowns are solved densely
SPARSE_MIN_N = 100

#: |s| beyond this many times the scale counts as an infinite eigenvalue (singular M).
INFINITE_FACTOR = 1e10


@dataclass(frozen=True)
class DampedModes:
    """Oscillatory modes (one of each conjugate pair, Im s > 0) sorted by wd, and the real eigenvalues.

    ``shapes`` holds the q-parts of the right eigenvectors as columns (n x k, complex), the largest
    |component| of each equal to 1. ``scale`` is the frequency scale the tolerances are relative to.
    """

    eigenvalues: np.ndarray
    wd: np.ndarray
    wn: np.ndarray
    damping_ratio: np.ndarray
    log_dec: np.ndarray
    shapes: np.ndarray
    real_eigenvalues: np.ndarray
    real_shapes: np.ndarray
    scale: float

    @property
    def frequencies(self) -> np.ndarray:
        """The damped natural frequencies wd (the ``frequencies`` output name of the design)."""
        return self.wd


# ----------------------------------------------------------------------------------------------- input


def _as_matrix(x, name: str):
    """A float matrix, sparse (CSR) if given sparse; InputError when not a finite 2-D array."""
    if sps.issparse(x):
        try:
            x = sps.csr_matrix(x, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{name} is not a real matrix ({exc})", key=name, expected="a real matrix") from exc
        data = x.data
    else:
        try:
            x = np.asarray(x, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"{name} is not a real matrix ({exc})", key=name, expected="a real matrix") from exc
        if x.ndim == 0 or (x.ndim == 1 and x.size == 1):
            x = x.reshape(1, 1)
        data = x
    if x.ndim != 2 or x.shape[0] != x.shape[1]:
        raise InputError(f"{name} has shape {x.shape}", key=name, expected="a square matrix")
    if not np.all(np.isfinite(data)):
        raise InputError(f"{name} holds NaN or Inf", key=name, expected="finite entries")
    return x


def _check_system(M, C, K):
    M, C, K = _as_matrix(M, "M"), _as_matrix(C, "C"), _as_matrix(K, "K")
    n = M.shape[0]
    for name, X in (("C", C), ("K", K)):
        if X.shape != (n, n):
            raise InputError(f"{name} has shape {X.shape} but M has shape {(n, n)}", key=name,
                             expected=f"a {n} x {n} matrix, the shape of M")
    return M, C, K, n


def _check_count(count, n: int) -> int | None:
    if count is None:
        return None
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError(f"count is {count!r}", key="count", expected="a positive integer")
    if count > n:
        raise InputError(f"count {count} is larger than the {n} modes a system of {n} degrees of freedom has",
                         key="count", expected=f"at most {n}")
    return int(count)


def matrix_norm(X) -> float:
    """The Frobenius norm ||X||_F of a dense or sparse matrix."""
    return float(spla.norm(X) if sps.issparse(X) else np.linalg.norm(X))


def frequency_scale(M, C, K) -> float:
    """sqrt(||K|| / ||M||) (Frobenius); ||C|| / ||M|| when K = 0; 1 when nothing sets a scale."""
    nm, nk, nc = matrix_norm(M), matrix_norm(K), matrix_norm(C)
    if nm > 0 and nk > 0:
        return float(np.sqrt(nk / nm))
    if nm > 0 and nc > 0:
        return nc / nm
    return 1.0


# -------------------------------------------------------------------------------------------- solvers


def normalise_columns(Q: np.ndarray) -> np.ndarray:
    """Columns divided by their largest component (the first within 1e-9 of the largest |.|)."""
    Q = np.array(Q, dtype=complex)
    if Q.size == 0:
        return Q
    mag = np.abs(Q)
    top = mag.max(axis=0)
    idx = np.argmax(mag >= (1.0 - 1e-9) * top[None, :], axis=0)
    pivot = Q[idx, np.arange(Q.shape[1])]
    return Q / np.where(pivot == 0, 1.0, pivot)[None, :]


def _dense_eig(M, C, K, n: int, scale: float):
    eye, zero = np.eye(n), np.zeros((n, n))
    symmetric = np.abs(M - M.T).max(initial=0.0) <= 1e-12 * max(np.abs(M).max(initial=0.0), 1e-300)
    factor = None
    if symmetric:
        try:
            factor = sla.cho_factor(M)
        except np.linalg.LinAlgError:
            factor = None
    if factor is not None:
        A = np.block([[zero, eye], [-sla.cho_solve(factor, K), -sla.cho_solve(factor, C)]])
        s, X = sla.eig(A)
        return np.asarray(s), X[:n]
    A = np.block([[zero, eye], [-K, -C]])
    B = np.block([[eye, zero], [zero, M]])
    (alpha, beta), X = sla.eig(A, B, homogeneous_eigvals=True)
    finite = np.abs(beta) > 0
    s = np.full(alpha.shape, np.inf, dtype=complex)
    s[finite] = alpha[finite] / beta[finite]
    keep = np.isfinite(s) & (np.abs(s) <= INFINITE_FACTOR * scale)
    return s[keep], X[:n, keep]


def _default_sigma(M, K) -> float:
    """-1e-3 times the lowest local frequency scale sqrt(K_ii / M_ii) (over entries with both > 0)."""
    kd, md = np.abs(K.diagonal()), np.abs(M.diagonal())
    ok = (kd > 0) & (md > 0)
    low = float(np.sqrt((kd[ok] / md[ok]).min())) if ok.any() else 1.0
    return -1e-3 * low


def _sparse_eig(M, C, K, n: int, count: int, sigma: float, scale: float, imag_tol: float):
    M, C, K = (sps.csc_matrix(x) for x in (M, C, K))
    eye = sps.identity(n, format="csc")
    A = sps.bmat([[None, eye], [-K, -C]], format="csc")
    B = sps.bmat([[eye, None], [None, M]], format="csc")
    N = 2 * n
    try:
        lu = spla.splu((A - sigma * B).tocsc())
    except RuntimeError as exc:
        raise ConvergenceError(f"sparse eigensolver: A - sigma B is singular at sigma = {sigma:.6g} ({exc}); "
                               f"sigma is an eigenvalue, pass another sigma") from exc
    op = spla.LinearOperator((N, N), matvec=lambda x: lu.solve(np.asarray(B @ x, dtype=float)), dtype=float)
    k = min(2 * count + max(4, count // 2), N - 2)
    while True:
        try:
            nu, X = spla.eigs(op, k=k, which="LM", ncv=min(N, max(2 * k + 1, 20)), v0=np.ones(N))
        except (RuntimeError, spla.ArpackError) as exc:
            raise ConvergenceError(f"sparse eigensolver (ARPACK shift-invert about sigma = {sigma:.6g}) failed "
                                   f"for {k} eigenvalues of a {N} x {N} pencil: {exc}") from exc
        nonzero = np.abs(nu) > 0
        s = np.full(nu.shape, np.inf, dtype=complex)
        s[nonzero] = sigma + 1.0 / nu[nonzero]
        keep = np.isfinite(s) & (np.abs(s) <= INFINITE_FACTOR * scale)
        s, Q = s[keep], X[:n, keep]
        if np.count_nonzero(s.imag > imag_tol * scale) >= count or k >= N - 2:
            return s, Q
        k = min(2 * k, N - 2)


def has_symmetry(A, sign: int, tol: float = 1e-12) -> bool:
    """True when A = sign A^T to ``tol`` relative (sparse or dense; a zero matrix is both)."""
    return bool(abs(A - sign * A.T).max() <= tol * max(abs(A).max(), 1e-300))


def _rayleigh_refined(M, C, K, s: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Conservative gyroscopic systems (M, K symmetric, C skew): s = i omega from the Rayleigh functional.

    For X the q-part of a mode, X^H (K - omega^2 M + i omega C) X = 0 is a real quadratic in omega
    (X^H C X is imaginary) whose root nearest Im s is stationary in X: its error is quadratic in the
    eigenvector's, so ARPACK's shift-invert eigenvalues (about 1e-7 relative for modes far from the
    shift) come back to round-off. Real eigenvalues are left as they are.
    """
    out = s.copy()
    for j in np.flatnonzero(np.abs(s.imag) > 0):
        x = Q[:, j]
        a = -np.real(np.vdot(x, M @ x))
        b = np.real(1j * np.vdot(x, C @ x))
        c = np.real(np.vdot(x, K @ x))
        roots = np.roots([a, b, c])
        roots = roots[np.abs(roots.imag) <= 1e-9 * np.abs(roots).max()].real
        if roots.size:
            out[j] = 1j * roots[np.argmin(np.abs(roots - s[j].imag))]
    return out


def split_modes(s: np.ndarray, Q: np.ndarray, count: int | None, scale: float, imag_tol: float) -> DampedModes:
    """Eigenpairs (s, Q) sorted into :class:`DampedModes`: oscillating ones (Im s > imag_tol * scale) by
    wd = Im s (the first ``count`` kept), real ones (|Im s| <= imag_tol * scale) by |s|, columns
    normalised (:func:`normalise_columns`); the conjugates (Im s < 0) are dropped."""
    tol = imag_tol * scale
    osc = s.imag > tol
    real = np.abs(s.imag) <= tol
    so, Qo = s[osc], Q[:, osc]
    order = np.lexsort((so.real, so.imag))
    if count is not None:
        order = order[:count]
    so, Qo = so[order], normalise_columns(Qo[:, order])
    sr, Qr = s[real].real, Q[:, real]
    order = np.argsort(np.abs(sr), kind="stable")
    sr, Qr = sr[order], normalise_columns(Qr[:, order]).real
    wd, wn = so.imag, np.abs(so)
    zeta = -so.real / np.where(wn > 0, wn, 1.0)
    log_dec = -2.0 * np.pi * so.real / wd + 0.0  # + 0.0: no -0.0 for undamped modes
    return DampedModes(so, wd, wn, zeta, log_dec, Qo, sr, Qr, scale)


def damped_modes(M, C, K, count: int | None = None, *, sparse: bool | None = None, sigma: float | None = None,
                 imag_tol: float = 1e-6) -> DampedModes:
    """The ``count`` oscillatory modes of lowest wd of M q'' + C q' + K q = 0 (all of them when None).

    ``sparse``: None picks ARPACK when an input is a scipy.sparse matrix, ``count`` is given and
    n > SPARSE_MIN_N (below that the dense solver is faster and more accurate), True forces it
    (``count`` required), False forces the dense solver. The sparse path needs
    2 count < 2 n - 2; otherwise the dense solver answers. ``sigma`` is the real shift of the
    sparse path. Fewer than ``count`` modes come back when the system has fewer oscillatory ones.
    Raises InputError on bad shapes or count > n, ConvergenceError when ARPACK fails.
    """
    M, C, K, n = _check_system(M, C, K)
    count = _check_count(count, n)
    if sparse and count is None:
        raise InputError("the sparse eigensolver needs a mode count", key="count", expected="a positive integer")
    anysparse = any(sps.issparse(x) for x in (M, C, K))
    use_sparse = (anysparse and count is not None and n > SPARSE_MIN_N) if sparse is None else bool(sparse)
    if use_sparse and 2 * count >= 2 * n - 2:
        use_sparse = False  # ARPACK needs k < N - 1; a problem this small is solved densely
    scale = frequency_scale(M, C, K)
    if use_sparse:
        if sigma is None:
            sigma = _default_sigma(M, K)
        s, Q = _sparse_eig(M, C, K, n, count, float(sigma), scale, imag_tol)
        if has_symmetry(C, -1) and has_symmetry(M, 1) and has_symmetry(K, 1):
            s = _rayleigh_refined(M, C, K, s, Q)
    else:
        require_dense(n, 24, "the dense damped eigenproblem")
        dense = [x.toarray() if sps.issparse(x) else x for x in (M, C, K)]
        s, Q = _dense_eig(*dense, n, scale)
    return split_modes(s, Q, count, scale, imag_tol)


# ---------------------------------------------------------------------------------------------- whirl


def station_indices(x_index, y_index, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The x and y dof indices of the stations as equal-length integer arrays in [0, n) (InputError otherwise)."""
    xi = np.atleast_1d(np.asarray(x_index))
    yi = np.atleast_1d(np.asarray(y_index))
    if xi.ndim != 1 or yi.ndim != 1 or xi.shape != yi.shape or xi.size == 0:
        raise InputError(f"x_index {x_index!r} and y_index {y_index!r} do not pair up", key="x_index",
                         expected="two integers, or two sequences of equal length (one entry per station)")
    if not (np.issubdtype(xi.dtype, np.integer) and np.issubdtype(yi.dtype, np.integer)):
        raise InputError("x_index and y_index must be integers", key="x_index", expected="integer dof indices")
    for name, ix in (("x_index", xi), ("y_index", yi)):
        if ix.min() < -n or ix.max() >= n:
            raise InputError(f"{name} {ix.tolist()} is out of range for {n} degrees of freedom", key=name,
                             expected=f"indices in [0, {n})")
    return xi, yi


def _orbits(shapes, x_index, y_index):
    """Per mode: signed area P = Im(X conj Y) and size S = |X|^2 + |Y|^2 at the dominant station, and totals."""
    Q = np.asarray(shapes, dtype=complex)
    if Q.ndim == 1:
        Q = Q[:, None]
    xi, yi = station_indices(x_index, y_index, Q.shape[0])
    X, Y = Q[xi], Q[yi]                         # stations x modes
    P = np.imag(X * np.conj(Y))
    S = np.abs(X) ** 2 + np.abs(Y) ** 2
    top = S.max(axis=0) if S.size else np.zeros(0)
    dom = np.argmax(S >= (1.0 - 1e-9) * top[None, :], axis=0)
    cols = np.arange(Q.shape[1])
    return P[dom, cols], S[dom, cols], P.sum(axis=0), S.sum(axis=0)


def orbit_kappa(shapes, x_index, y_index) -> np.ndarray:
    """Signed minor / major axis ratio of each mode's orbit at its largest station (ROSS's kappa).

    +1: circular forward, -1: circular backward, 0: a straight line. With P = Im(X conj Y),
    S = |X|^2 + |Y|^2 the semi-axes satisfy a^2 + b^2 = S, a b = |P|, so kappa = P / a^2 with
    a^2 = (S + sqrt(S^2 - 4 P^2)) / 2.
    """
    return orbit_axes(shapes, x_index, y_index)["kappa"]


def orbit_axes(shapes, x_index, y_index) -> dict[str, np.ndarray]:
    """The ellipse x = Re(X e^{i w t}), y = Re(Y e^{i w t}) of each mode at its largest station.

    Returns arrays (one entry per mode): ``major`` a and ``minor`` b, the semi-axes (a >= b >= 0, in the
    units of the shape's x and y entries: a^2, b^2 are the eigenvalues of Re(v v^H), v = (X, Y), so
    a^2 + b^2 = |X|^2 + |Y|^2 and a b = |Im(X conj Y)|); ``angle``, the major axis's angle from x towards y
    (rad, in (-pi/2 + 1e-9, pi/2 + 1e-9]: an axis within 1e-9 of vertical is pi/2;
    tan 2 angle = 2 Re(X conj Y) / (|X|^2 - |Y|^2), 0 for a circle); ``kappa``, the
    signed ratio b / a (:func:`orbit_kappa`: its sign is that of the orbit's angular momentum x y' - y x',
    whose time average is w Im(X conj Y)); ``station``, the index (into the stations) of the largest orbit.
    """
    Q = np.asarray(shapes, dtype=complex)
    Q = Q[:, None] if Q.ndim == 1 else Q
    xi, yi = station_indices(x_index, y_index, Q.shape[0])
    S = np.abs(Q[xi]) ** 2 + np.abs(Q[yi]) ** 2
    top = S.max(axis=0) if S.size else np.zeros(0)
    dom = np.argmax(S >= (1.0 - 1e-9) * top[None, :], axis=0)
    X, Y = Q[xi[dom], np.arange(Q.shape[1])], Q[yi[dom], np.arange(Q.shape[1])]
    P, C = np.imag(X * np.conj(Y)), np.real(X * np.conj(Y))
    S = np.abs(X) ** 2 + np.abs(Y) ** 2
    # S^2 - 4 P^2 = (|X|^2 - |Y|^2)^2 + 4 C^2, free of cancellation (a circle: both terms vanish), and
    # b = |P| / a (not sqrt((S - root) / 2), which cancels for a near-straight line)
    root = np.hypot(np.abs(X) ** 2 - np.abs(Y) ** 2, 2.0 * C)
    a2 = 0.5 * (S + root)
    b2 = np.where(a2 > 0, P * P / np.where(a2 > 0, a2, 1.0), 0.0)
    angle = 0.5 * np.arctan2(2.0 * C, np.abs(X) ** 2 - np.abs(Y) ** 2)
    angle = np.where(angle <= -np.pi / 2 + 1e-9, angle + np.pi, angle) + 0.0
    kappa = np.where(a2 > 0, P / np.where(a2 > 0, a2, 1.0), 0.0)
    return {"major": np.sqrt(a2), "minor": np.sqrt(b2), "angle": angle, "kappa": kappa, "station": dom}


#: a mode whose orbit at every station is below this times its largest entry does not move the stations
STILL_TOL = 1e-6


def still_modes(shapes, x_index, y_index, tol: float = STILL_TOL) -> np.ndarray:
    """True for each mode (column) whose orbits at all stations are below ``tol`` times its largest entry:
    sqrt(max_station |X|^2 + |Y|^2) <= tol max_i |Q_i| (a mode that leaves the whirl stations at rest, e.g.
    a tilt mode of a rotor whose whirl pair is the translations). Its whirl is ``none``."""
    Q = np.asarray(shapes, dtype=complex)
    Q = Q[:, None] if Q.ndim == 1 else Q
    xi, yi = station_indices(x_index, y_index, Q.shape[0])
    S = np.abs(Q[xi]) ** 2 + np.abs(Q[yi]) ** 2
    size = np.sqrt(S.max(axis=0)) if S.size else np.zeros(Q.shape[1])
    return size <= tol * np.abs(Q).max(axis=0, initial=0.0)


def whirl_sign(shapes, x_index, y_index, *, planar_tol: float = 1e-6) -> np.ndarray:
    """+1 forward, -1 backward, 0 planar (a straight-line orbit at every station, within ``planar_tol``).

    The sign of Im(X conj Y) at the station with the largest orbit (|X|^2 + |Y|^2); when that orbit is a
    straight line (|kappa| <= planar_tol), the sign of the sum of Im(X conj Y) over all stations (the
    orbit-size weighted majority); 0 when that sum is within planar_tol of the summed size too.
    """
    P, S, Ptot, Stot = _orbits(shapes, x_index, y_index)
    kappa = orbit_kappa(shapes, x_index, y_index)
    sign = np.where(np.abs(kappa) > planar_tol, np.sign(P), 0.0)
    fallback = np.where(np.abs(Ptot) > planar_tol * Stot, np.sign(Ptot), 0.0)
    return np.where(sign != 0, sign, fallback).astype(int)


#: the labels :func:`whirl` gives
WHIRL_LABELS = ("forward", "backward", "linear", "none")


def whirl(shapes, x_index, y_index, *, planar: str = "linear", planar_tol: float = 1e-6) -> list[str]:
    """'forward', 'backward', 'linear' or 'none' for each mode (column of ``shapes``, eigenvalue with Im s > 0).

    ``x_index``, ``y_index``: the dofs of the lateral displacements (or tilts about x and y) of one
    station, or sequences of them, one entry per station. Forward = counter-clockwise about
    z = x cross y (Im(X conj Y) > 0: the orbit's angular momentum x y' - y x' is positive), judged at the
    station with the largest orbit (see :func:`whirl_sign`). A mode whose orbits are all straight lines
    (|kappa| <= ``planar_tol``, kappa the signed minor/major ratio) is 'linear' (``planar``: the label
    such a mode gets; 'forward' or 'backward' give the rule of mechgen before issue 25): a straight line
    is the sum of equal forward and backward circles and has no whirl direction. A mode that does not
    move the stations (:func:`still_modes`) is 'none'.
    """
    if planar not in ("linear", "forward", "backward"):
        raise InputError(f"planar is {planar!r}", key="planar", expected="'linear', 'forward' or 'backward'")
    signs = whirl_sign(shapes, x_index, y_index, planar_tol=planar_tol)
    still = still_modes(shapes, x_index, y_index)
    return ["none" if z else "forward" if v > 0 else "backward" if v < 0 else planar for v, z in zip(signs, still)]


def circular_pair(pair: np.ndarray, x_index, y_index) -> np.ndarray:
    """The basis of a double eigenvalue's plane (two columns) re-chosen as (backward, forward) circles.

    An isotropic rotor's double frequency has an arbitrary eigenbasis; its plane holds one mode with a
    backward circle Y = i X and one with a forward circle Y = -i X at the station where the plane's orbits
    are largest. With r_f = Y + i X and r_b = Y - i X (rows over the two columns), the forward mode is
    the combination c with r_f c = 0, c = (r_f[1], -r_f[0]), and likewise the backward one. The pair is
    returned unchanged when either row vanishes (the plane holds no such circles at that station).
    """
    Q = np.asarray(pair, dtype=complex)
    xi, yi = station_indices(x_index, y_index, Q.shape[0])
    S = (np.abs(Q[xi]) ** 2 + np.abs(Q[yi]) ** 2).sum(axis=1)
    k = int(np.argmax(S >= (1.0 - 1e-9) * S.max()))
    X, Y = Q[xi[k]], Q[yi[k]]
    rows = (Y - 1j * X, Y + 1j * X)  # backward, forward conditions
    scale = np.sqrt(S[k]) if S[k] > 0 else 0.0
    if scale == 0.0 or min(np.abs(r).max() for r in rows) <= 1e-9 * scale:
        return Q
    out = np.column_stack([Q @ np.array([r[1], -r[0]]) for r in rows])
    return normalise_columns(out)
