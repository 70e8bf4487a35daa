"""Stability of M q'' + C q' + K q = 0 (C = D + G, K possibly non-symmetric), and of E x' = A x.

First-order form with x = (q, q'/w0) (w0 the frequency scale, so that both blocks of A have the
size of the spectrum): A = [[0, w0 I], [-M^-1 K / w0, -M^-1 C]] when M is symmetric positive
definite, else the pencil A x = s B x, A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]]
(``scipy.linalg.eig``). ``scale`` is the largest finite |s| (at least sqrt(||K|| / ||M||)).

Each eigenvalue is significant beyond a threshold ``tol_i``:

* ``tolerance`` given (a number): ``tol_i = tolerance * scale`` for every eigenvalue (relative to the
  spectrum's scale, the rule before the automatic one);
* ``tolerance = None`` (the default): the eigen-solve's own accuracy, LAPACK's error bound
  ``tol_i = ACCURACY_FACTOR * eps * ||A||_F * kappa_i`` of the balanced matrix (LAPACK Users' Guide,
  section 4.8; kappa_i = ||y_i|| ||x_i|| / |y_i^H B x_i| the condition number of s_i from its left and
  right eigenvectors; for a pencil ||A||_F + |s_i| ||B||_F in place of ||A||_F). A physical damping
  level then never shifts a stability boundary by more than the eigen-solve's accuracy (a fixed
  1e-8 * scale put the flutter onset of Ziegler's column with dashpots of 1e-3 3.9e-5 high; this rule
  3e-12), while round-off on an eigenvalue that is ill-conditioned (near a coalescence) is still not
  taken for growth. The eigenvectors are computed only when some Re s lies in (0, AMBIGUOUS * scale]:
  below 0 nothing grows, above it nothing is round-off. The frequencies' distinctness uses
  ``(tolerance or 1e-8) * scale``.

Undamped systems (C = 0, M positive definite, K not symmetric positive definite: circulatory or
buckled) are solved as the n x n problem mu = -s^2 of M^-1 K (:func:`_undamped`), whose real
eigenvalues are exactly real: s = +-i sqrt(mu) has Re s = 0 exactly, and only complex pairs (flutter)
and negative mu (divergence) grow.

Rigid-body modes (K phi = 0: a free body, a continuum without supports) give s = 0 (a double root
without damping, perturbed by round-off to about sqrt(eps) * scale). Their number ``rigid`` is the
number of singular values of L^-1 K L^-T (M = L L^T) below RIGID_FACTOR * eps times the largest
(mechgen.runtime.linear.modes.RIGID_FACTOR), looked for only when some |s| is below
sqrt(RIGID_FACTOR * eps) * scale; the ``rigid`` ... ``2 rigid`` eigenvalues of smallest |s|
within that bound are set apart (``rigid_eigenvalues``) and the verdict is that of the others:

* ``stable``      - every Re s <= tol_i and no rigid-body mode,
* ``neutral``     - every Re s <= tol_i apart from the rigid-body modes (neutral equilibrium: the
  free body drifts, q = a + b t in those modes, nothing grows exponentially),
* ``divergence``  - the most unstable s has Re s > tol_i and |Im s| <= tol_i,
* ``flutter``     - the most unstable s has Re s > tol_i and |Im s| > tol_i.

``unstable`` counts the eigenvalues with Re s > tol_i: (real ones, complex ones with Im s > 0), the sign
structure a refinement compares.

Conservative gyroscopic systems with a positive definite energy (M and K symmetric
positive definite, C skew-symmetric; all to rounding) are stable whatever G (the energy
q'^T M q' + q^T K q is conserved), and their spectrum is found from a Hermitian problem
at about a third of the cost: with M = L_M L_M^T, K = L_K L_K^T and z = (L_M^T q', L_K^T q),
z' = S z with the real skew-symmetric

    S = [[-L_M^-1 C L_M^-T, -L_M^-1 L_K], [L_K^T L_M^-T, 0]],   s = i mu,  mu = eigvalsh(-i S).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense

sla = lazy_module("scipy.linalg")


#: the automatic threshold: ACCURACY_FACTOR * eps * ||A|| * kappa_i (LAPACK's bound, see the module doc)
ACCURACY_FACTOR = 1.0
#: Re s above AMBIGUOUS * scale is growth whatever the conditioning (round-off reaches it only for kappa > 1e9)
AMBIGUOUS = 1e-5
#: the frequencies' distinctness, relative to the scale, when no tolerance is given
FREQUENCY_RTOL = 1e-8


@dataclass(frozen=True)
class StabilityResult:
    """Eigenvalues (sorted by imaginary, then real part), verdict, growth rate, frequencies, scale.

    ``rigid``: the number of rigid-body modes (their eigenvalues, near 0, are in ``rigid_eigenvalues``
    and not in ``frequencies``; ``growth_rate`` and the verdict are those of the others).
    ``unstable``: (real, complex with Im s > 0) eigenvalues beyond their threshold. ``threshold``: the
    largest threshold tol_i used (absolute, 1/s).
    """

    eigenvalues: np.ndarray
    verdict: str
    growth_rate: float
    frequencies: np.ndarray
    scale: float
    rigid: int = 0
    rigid_eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    unstable: tuple[int, int] = (0, 0)
    threshold: float = 0.0


def spectrum_scale(s: np.ndarray, floor: float = 0.0) -> float:
    """The largest finite |s|, at least ``floor`` (and 1e-300)."""
    s = s[np.isfinite(s)]
    return max(float(np.max(np.abs(s))) if s.size else 0.0, floor, 1e-300)


def _verdict(s: np.ndarray, tolerance: float | None, floor: float = 0.0, *, errors: np.ndarray | None = None,
             rigid: int = 0, rigid_bound: float = 0.0) -> StabilityResult:
    """The verdict of the eigenvalues ``s``: thresholds ``tolerance * scale``, or ``errors`` (per eigenvalue)
    when ``tolerance`` is None (zero without them); ``rigid`` modes set apart (the eigenvalues of smallest |s|
    within ``rigid_bound``, between ``rigid`` and ``2 rigid`` of them)."""
    finite = np.isfinite(s)
    s = np.asarray(s)[finite]
    errors = None if errors is None else np.asarray(errors)[finite]
    scale = spectrum_scale(s, floor)
    if tolerance is not None:
        tol = np.full(s.shape, tolerance * scale)
    elif errors is not None:
        tol = errors
    else:
        tol = np.zeros(s.shape)
    order = np.lexsort((s.real, s.imag))
    s, tol = s[order], tol[order]
    apart = np.zeros(s.shape, bool)
    if rigid:
        near = np.argsort(np.abs(s), kind="stable")
        near = near[np.abs(s[near]) <= rigid_bound][: 2 * rigid]
        apart[near] = True
        if np.count_nonzero(apart) < rigid:  # fewer near-zero eigenvalues than K's null space: not rigid modes
            apart[:] = False
            rigid = 0
    rest, rest_tol = s[~apart], tol[~apart]
    growth = float(np.max(rest.real)) if rest.size else 0.0
    grows = rest.real > rest_tol
    if not grows.any():
        verdict = "neutral" if rigid else "stable"
    else:
        worst = int(np.argmax(np.where(grows, rest.real, -np.inf)))
        verdict = "divergence" if abs(rest[worst].imag) <= rest_tol[worst] else "flutter"
    unstable = (int(np.count_nonzero(grows & (np.abs(rest.imag) <= rest_tol))),
                int(np.count_nonzero(grows & (rest.imag > rest_tol))))
    ftol = (FREQUENCY_RTOL if tolerance is None else tolerance) * scale
    pos = np.sort(rest.imag[rest.imag > ftol])
    freqs = pos[np.concatenate([[True], np.diff(pos) > ftol])] if pos.size else pos
    return StabilityResult(s, verdict, growth, freqs, scale, rigid, s[apart], unstable,
                           float(rest_tol.max(initial=0.0)))


def eigenvalue_errors(A: np.ndarray, B: np.ndarray | None, *, factor: float = ACCURACY_FACTOR):
    """Eigenvalues s of A x = s B x (B None: the identity) and their error bounds (LAPACK Users' Guide,
    section 4.8: ``eps * ||A|| / RCONDE_i``).

    ``factor * eps * ||A||_F * kappa_i`` with kappa_i = ||y_i|| ||x_i|| / |y_i^H B x_i| (left and right
    eigenvectors) of the balanced matrix (``scipy.linalg.matrix_balance``, as the eigensolver itself
    balances); for a pencil ``||A||_F + |s_i| ||B||_F`` in place of ``||A||_F``. A defective eigenvalue
    (y^H B x = 0) gets an infinite bound.
    """
    if B is None:
        A, _ = sla.matrix_balance(A)
        s, vl, vr = sla.eig(A, left=True, right=True)
        Bx = vr
        size = np.full(s.shape, np.linalg.norm(A))
    else:
        s, vl, vr = sla.eig(A, B, left=True, right=True)
        Bx = B @ vr
        with np.errstate(invalid="ignore"):
            size = np.linalg.norm(A) + np.abs(s) * np.linalg.norm(B)
    dots = np.abs(np.einsum("ij,ij->j", np.conj(vl), Bx))
    norms = np.linalg.norm(vl, axis=0) * np.linalg.norm(vr, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = np.where(dots > 0, norms / dots, np.inf)
    return np.asarray(s), factor * np.finfo(float).eps * size * kappa


def _undamped(M: np.ndarray, K: np.ndarray, tolerance: float | None, floor: float) -> StabilityResult | None:
    """C = 0 (K possibly non-symmetric): the eigenvalues mu = -s^2 of M^-1 K (n x n, real), None when M is not
    positive definite.

    A real matrix's eigenvalues come back either exactly real or as exact conjugate pairs, so mu > 0 gives
    s = +-i sqrt(mu) with Re s = 0 exactly; only a complex pair (flutter, or a round-off coalescence near
    one) or a negative mu (divergence) has growth, and its error bound is that of mu, divided by 2 |s|
    (ds = dmu / (2 s)).
    """
    try:
        factor = sla.cho_factor(M)
    except np.linalg.LinAlgError:
        return None
    X = sla.cho_solve(factor, K)
    mu = np.asarray(sla.eig(X, right=False))
    errors = None
    if tolerance is None and np.any(np.abs(mu.imag) > 0):  # a complex pair: is it beyond its accuracy?
        mu, err_mu = eigenvalue_errors(X, None)
        root = np.sqrt(-mu.astype(complex))
        with np.errstate(divide="ignore", invalid="ignore"):
            err_s = np.where(np.abs(root) > 0, err_mu / (2 * np.abs(root)), np.inf)
        errors = np.concatenate([err_s, err_s])
    root = np.sqrt(-mu.astype(complex))
    s = np.concatenate([root, -root])
    scale = spectrum_scale(s, floor)
    bound = rigid_bound(2 * M.shape[0], scale)
    rigid = rigid_modes(M, K) if s.size and np.min(np.abs(s)) <= bound else 0
    return _verdict(s, tolerance, floor, errors=errors, rigid=rigid, rigid_bound=bound)


def rigid_modes(M: np.ndarray, K: np.ndarray) -> int:
    """How many rigid-body modes K phi = 0 has relative to M: singular values of L^-1 K L^-T (M = L L^T, or M
    itself when not positive definite) below RIGID_FACTOR * eps times the largest."""
    from mechgen.runtime.linear.modes import rigid_tolerance

    try:
        L = np.linalg.cholesky(0.5 * (M + M.T))
        X = sla.solve_triangular(L, sla.solve_triangular(L, K, lower=True).T, lower=True).T
    except np.linalg.LinAlgError:
        X = K
    sv = sla.svdvals(X)
    if not sv.size or sv[0] <= 0:
        return int(sv.size)
    return int(np.count_nonzero(sv <= rigid_tolerance(float(sv[0]))))


def rigid_bound(N: int, scale: float) -> float:
    """sqrt(RIGID_FACTOR * eps) * scale: how far round-off moves the double root s = 0 of a rigid mode (lambda =
    s^2 within RIGID_FACTOR eps scale^2; ``N``, the pencil's size, is not a factor: see modes.RIGID_FACTOR)."""
    from mechgen.runtime.linear.modes import RIGID_FACTOR

    return float(np.sqrt(RIGID_FACTOR * np.finfo(float).eps) * scale)


def _symmetric(A: np.ndarray, sign: float, rel: float = 1e-10) -> bool:
    """A = sign A^T to ``rel`` of its largest entry."""
    scale = float(np.max(np.abs(A))) if A.size else 0.0
    return float(np.max(np.abs(A - sign * A.T))) <= rel * scale if scale > 0 else True


def conservative_gyroscopic(M, C, K) -> np.ndarray | None:
    """The eigenvalues s = i mu of M q'' + C q' + K q = 0 when M, K are symmetric positive definite and C is
    skew-symmetric (to rounding: see the module doc), else None."""
    if not (_symmetric(M, 1.0) and _symmetric(K, 1.0) and _symmetric(C, -1.0)):
        return None
    try:
        LM = np.linalg.cholesky(0.5 * (M + M.T))
        LK = np.linalg.cholesky(0.5 * (K + K.T))
    except np.linalg.LinAlgError:
        return None
    n = M.shape[0]
    # numpy's LU solve with the triangular factor (backward stable like a triangular solve; the eigensolve of 2n
    # dominates): a small scene's stability then needs no scipy.linalg (0.2-0.4 s of import at start)
    G = np.linalg.solve(LM, np.linalg.solve(LM, 0.5 * (C - C.T)).T).T
    B = np.linalg.solve(LM, LK)
    S = np.block([[-G, -B], [B.T, np.zeros((n, n))]])
    if not np.isfinite(S).all():  # an overflow in the factors (scipy's solves raise the same ValueError)
        raise ValueError("array must not contain infs or NaNs")
    mu = np.linalg.eigvalsh(-1j * S)
    return 1j * mu


def stability(M, C, K, *, tolerance: float | None = None) -> StabilityResult:
    """Eigenvalues and verdict of M q'' + C q' + K q = 0 (dense); ``tolerance`` None: automatic (module doc)."""
    M, C, K = (np.atleast_2d(np.asarray(x, float)) for x in (M, C, K))
    n = M.shape[0]
    require_dense(n, 40, "the dense stability eigenproblem")
    s = conservative_gyroscopic(M, C, K)
    if s is not None:  # K > 0 to rounding: Re s = 0, and a K singular to the solver's accuracy has rigid modes
        scale = spectrum_scale(s)
        bound = rigid_bound(2 * n, scale)
        rigid = rigid_modes(M, K) if s.size and np.min(np.abs(s)) <= bound else 0
        return _verdict(s, tolerance, rigid=rigid, rigid_bound=bound)
    norm_m = np.linalg.norm(M, 2)
    floor = np.sqrt(np.linalg.norm(K, 2) / norm_m) if norm_m > 0 else 0.0
    if not np.any(C):
        undamped = _undamped(M, K, tolerance, floor)
        if undamped is not None:
            return undamped
    w0 = floor if floor > 0 else 1.0
    eye, zero = np.eye(n), np.zeros((n, n))
    try:
        # M symmetric positive definite: the standard problem for M^-1 [K, C] (3-4x faster than QZ)
        factor = sla.cho_factor(M)
        A, B = np.block([[zero, w0 * eye], [-sla.cho_solve(factor, K) / w0, -sla.cho_solve(factor, C)]]), None
    except np.linalg.LinAlgError:
        A = np.block([[zero, eye], [-K, -C]])
        B = np.block([[eye, zero], [zero, M]])
    s = np.asarray(sla.eig(A, B, right=False))
    return _judged(s, A, B, tolerance, floor, lambda: rigid_modes(M, K))


def _judged(s: np.ndarray, A, B, tolerance: float | None, floor: float, count_rigid) -> StabilityResult:
    """The verdict of the eigenvalues s of A x = s B x, with the error bounds and the rigid modes computed only
    where they can change it (module doc)."""
    scale = spectrum_scale(np.asarray(s), floor)
    finite = s[np.isfinite(s)]
    rigid, bound = 0, rigid_bound(A.shape[0], scale)
    if count_rigid is not None and finite.size and np.min(np.abs(finite)) <= bound:
        rigid = count_rigid()
    errors = None
    if tolerance is None:
        ambiguous = (finite.real > 0) & (finite.real <= AMBIGUOUS * scale)
        if ambiguous.any():
            s, errors = eigenvalue_errors(A, B)
    return _verdict(np.asarray(s), tolerance, floor, errors=errors, rigid=rigid, rigid_bound=bound)


def stability_first_order(A, E, *, tolerance: float | None = None) -> StabilityResult:
    """Eigenvalues and verdict of E x' = A x (E may be singular: infinite eigenvalues are dropped)."""
    A, E = np.asarray(A, float), np.asarray(E, float)
    B = None if np.array_equal(E, np.eye(E.shape[0])) else E
    s = np.asarray(sla.eig(A, B, right=False))
    return _judged(s, A, B, tolerance, 0.0, None)


#: memory per unknown of the sparse stability solve (A, B of size 2n, the SuperLU factors of A - sigma B and of
#: K + mu M, ARPACK's Krylov basis), bytes: peak RSS of Beck's column (scenes/beck_column.toml, stability with
#: count = 3, refined at 2N) 199 MB at N = 10^4 and 1220 MB at N = 10^5, i.e. 1021 MB for the 360 000 unknowns added
#: at 2N (hermite: 2 per node): 2.8 kB per unknown, with a margin (issue 33: N = 10^6 ran 10 min past 3.4 GiB)
SPARSE_BYTES_PER_UNKNOWN = 4_000

#: wall time of one sparse shift-invert eigen-solve of n unknowns (n: the size of M and K; the non-symmetric solve
#: works on the first-order pencil of size 2n), c n^(4/3) seconds: ARPACK's iterations grow with n, so the time
#: per unknown does too. Measured on a 2-core machine (issue 33): Beck's column (scenes/beck_column.toml,
#: stability, count = 3, solves at N and 2N, c (n^(4/3) + (2n)^(4/3))) 1.91 s at N = 10^4 and 40.9 s at N = 10^5
#: (c = 1.00e-6 and 0.99e-6: exponent 1.33); the Euler-Bernoulli beam's modes (quintic, count = 5) 0.37 s at
#: 4 x 10^4 unknowns and 6.5 s at 4 x 10^5 (c = 2.7e-7 and 2.2e-7: exponent 1.25), the string's (lagrange1) about a
#: minute at 2 x 10^6 (c n^(4/3) = 50 s); rounded down. Beck's column at N = 10^6: about 15 min (issue 33: it ran
#: past 10 minutes).
SPARSE_SECONDS = {"symmetric": 2.0e-7, "general": 9.0e-7}


def sparse_seconds(n: int, *, general: bool) -> float:
    """The estimated wall time (s) of one sparse shift-invert eigen-solve of n unknowns: c n^(4/3), c from
    SPARSE_SECONDS (``general``: the non-symmetric solve of stability and damped modes; else K x = w^2 M x)."""
    return SPARSE_SECONDS["general" if general else "symmetric"] * float(n) ** (4.0 / 3.0)


def low_shift(M, K, scale: float, steps: int = 8) -> float:
    """The shift sigma = -1e-3 omega_low of the sparse stability solve, omega_low^2 the Rayleigh quotient
    |x^T K x| / |x^T M x| after ``steps`` inverse iterations (K + mu M) x_{j+1} = M x_j, mu = (1e-6 scale)^2.

    ``scale`` = sqrt(max K_ii / max M_ii) tracks the highest frequency, which grows as N^2 for a beam: a shift
    -1e-6 scale, far beyond the lowest eigenvalues at large N, left them nearly equidistant from it and ARPACK
    crawled (Beck's column, 16 000 elements: 101 s). omega_low tracks the lowest mode at every N, so the
    eigenvalues nearest 0 stay well separated about sigma; mu keeps K + mu M invertible with rigid modes (K
    singular; their zero eigenvalues are then a distance |sigma| >= 1e-9 scale away from the shift).
    """
    import scipy.sparse.linalg as spla

    mu = (1e-6 * scale) ** 2
    try:
        lu = spla.splu((K + mu * M).tocsc())
    except RuntimeError:
        return -1e-6 * scale
    x = np.ones(K.shape[0])
    for _ in range(steps):
        x = lu.solve(M @ x)
        size = np.linalg.norm(x)
        if not np.isfinite(size) or size == 0.0:
            return -1e-6 * scale
        x /= size
    quotient = abs(x @ (K @ x)) / max(abs(x @ (M @ x)), 1e-300)
    return -1e-3 * float(np.sqrt(max(quotient, mu)))


def stability_sparse(M, C, K, count: int, *, tolerance: float | None = None) -> StabilityResult:
    """The 2 ``count`` eigenvalues nearest 0 of M q'' + C q' + K q = 0 (sparse shift-invert, ARPACK).

    A x = s B x with A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]], shifted by a small
    negative sigma so that a singular K (rigid modes) does not make A - sigma B
    singular. The verdict is about the computed part of the spectrum: the lowest
    modes, where a discretised continuum is accurate. ARPACK's eigenvalues are accurate to about
    1e-8 relative (its tolerance), so ``tolerance`` None means 1e-8 here.
    """
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    M, C, K = (sps.csc_matrix(x) for x in (M, C, K))
    n = M.shape[0]
    eye = sps.identity(n, format="csc")
    A = sps.bmat([[None, eye], [-K, -C]], format="csc")
    B = sps.bmat([[eye, None], [None, M]], format="csc")
    scale = np.sqrt(max(abs(K.diagonal()).max(), 1e-300) / max(abs(M.diagonal()).max(), 1e-300))
    sigma = low_shift(M, K, scale)
    k = min(2 * count, 2 * n - 2)
    try:
        start = np.random.default_rng(0).standard_normal(2 * n)  # a fixed start vector: the same verdict every call
        s = spla.eigs(A, k=k, M=B, sigma=sigma, which="LM", return_eigenvectors=False, v0=start)
    except (RuntimeError, spla.ArpackError) as exc:
        from mechgen.errors import ConvergenceError

        raise ConvergenceError(f"sparse eigensolver (ARPACK shift-invert) failed: {exc}") from exc
    return _verdict(np.asarray(s), 1e-8 if tolerance is None else tolerance,
                    floor=float(np.max(np.abs(s))) if len(s) else 0.0)
