"""Essential boundary conditions C x = 0 on discretised fields: elimination or penalty.

* eliminate: x = Z q with C Z = 0. Rows that hit single dofs (nodal values of
  finite elements) drop those dofs (Z a column selection, matrices stay sparse);
  other rows (global bases) use an orthonormal null-space basis Z = null(C).
  Rows the basis already satisfies (sin(j pi s/L) at s = 0, L) are dropped.
  Reduced matrices are Z^T A Z, reduced vectors Z^T r.
* penalty: x = q and K gets alpha C^T C with alpha = f * max|diag K| (K unconstrained,
  at the zero state), the paper's way (seed 002), with the factor f chosen from the
  spectrum and the working precision (:func:`penalty_choice`): the penalty error of
  the low eigenvalues, P / f, balanced against the round-off, eps f Lambda / lambda_lo;
  frequencies converge to the constrained ones as 1/f. ``FIXED_FACTOR`` (None: the
  rule) forces a factor, e.g. the paper's PENALTY_FACTOR = 1e6, and the predicted
  error still decides the AccuracyWarning.
* joints (substructures joined at segment interfaces): their continuity rows are
  eliminated by the null space together with eliminated boundary rows, kept beside
  penalty boundary rows (x = null(J) q, penalty on C x), or bordered with multiplier ones.
* multiplier: the unknowns are (x, lambda); K is bordered, [[K, C^T], [C, 0]], the
  residual is (r + C^T lambda, C x) and M, D, G get zero rows and columns for
  lambda (a singular mass: modes and stability solve the generalized problem and
  drop its infinite eigenvalues). lambda are the boundary reactions.
"""
from __future__ import annotations

import functools

from dataclasses import dataclass

import numpy as np

from mechgen.runtime.core.lazy_import import lazy_module

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


PENALTY_FACTOR = 1e6  # the paper's fixed factor (seed 002); kept as a name, used only through FIXED_FACTOR

#: None: choose the factor by the balance rule of :func:`penalty_choice`; a number forces alpha = it * max|diag K|
FIXED_FACTOR: float | None = None

#: calibration factor: alpha0 = CALIBRATION * max|diag K| is soft enough that its round-off never matters
CALIBRATION = 1e2

#: AccuracyWarning above this predicted relative error of the lowest eigenvalue (or above 4 R, when the
#: unpenalised problem's own worst-case round-off R = eps Lambda / lambda_lo is larger already)
PENALTY_TARGET = 1e-6

EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class PenaltyChoice:
    """Row penalties alphas = factor * k_max (alpha their largest) and the error model behind them.

    Relative errors of the lowest eigenvalue:

    penalty_error(f) = P / f, roundoff(f) = R f, R = eps Lambda / lambda_lo; predicted = both at ``factor``.
    """

    alpha: float
    factor: float
    k_max: float
    P: float
    R: float
    alphas: np.ndarray | None = None

    def predicted(self, factor: float | None = None) -> float:
        """P / f + R f: the penalty's first-order error plus the solver's worst-case round-off at factor f."""
        f = self.factor if factor is None else factor
        return self.P / f + self.R * f


def _lowest_mode(A, B):
    """Lowest (lambda, phi) of A phi = lambda B phi, phi^T B phi = 1 (A positive definite: dense inverse
    eigh, or sparse shift-invert about 0)."""
    if sps.issparse(A) and A.shape[0] > 400:
        start = np.random.default_rng(0).standard_normal(A.shape[0])  # fixed: the same mode every call
        lam, phi = spla.eigsh(A.tocsc(), k=1, M=sps.csc_matrix(B), sigma=0.0, which="LM", v0=start)
        return float(lam[0]), phi[:, 0]
    A = A.toarray() if sps.issparse(A) else np.asarray(A)
    B = B.toarray() if sps.issparse(B) else np.asarray(B)
    n = A.shape[0]
    # the inverse problem B phi = mu A phi (Cholesky of A): its round-off, eps * max mu, is small
    # relative to the largest mu = 1 / lambda_lo; eigh(A, B) would err by eps * lambda_max instead
    mu, phi = sla.eigh(B, A, subset_by_index=[n - 1, n - 1])
    lam = 1.0 / float(mu[0])
    return lam, phi[:, 0] * np.sqrt(lam)


def penalty_errors(red: "Reduction", alphas, shapes: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray:
    """A-posteriori penalty error of each computed mode: e_i = sum_j alpha_j (C x_i)_j^2 / lambda_i (relative).

    For a mass-normalised penalised mode x_i (x_i^T M x_i = 1, reduced shapes expanded by x = Z q)
    the reactions are r = diag(alpha) C x_i, and lambda_i(alpha) = lambda_c,i - sum_j r_j^2 / alpha_j + ...,
    so e_i estimates (lambda_c,i - lambda_i) / lambda_i to first order in 1/alpha (frequencies: e_i / 2),
    for every mode asked for (higher modes carry larger reactions than the lowest one the rule balances).
    """
    if red.penalty_rows is None:
        return np.zeros(len(eigenvalues))
    X = np.column_stack([red.expand(q) for q in np.asarray(shapes, float).T])
    CX = np.asarray(red.penalty_rows, float) @ X
    alphas = np.broadcast_to(np.asarray(alphas, float), (CX.shape[0],))
    return np.einsum("j,ji->i", alphas, CX**2) / np.asarray(eigenvalues, float)


#: a-posteriori AccuracyWarning when a computed mode's predicted penalty error exceeds this (relative eigenvalue)
MODE_TARGET = 1e-4


def warn_penalty_errors(errors: np.ndarray, target: float = MODE_TARGET) -> None:
    """AccuracyWarning naming the worst mode when any a-posteriori penalty error e_i exceeds ``target``."""
    errors = np.asarray(errors, float)
    if errors.size and errors.max() > target:
        import warnings

        from mechgen.runtime.linear.modes import AccuracyWarning

        i = int(np.argmax(errors))
        warnings.warn(f"penalty constraints: mode {i + 1}'s eigenvalue is low by about {errors[i]:.1g} (relative, "
                      "from its reactions sum_j alpha_j (C x)_j^2 / lambda); use constraints = 'eliminate' or "
                      "'multiplier', or ask for fewer modes", AccuracyWarning, stacklevel=3)


def penalty_choice(red: "Reduction", K, M, fixed: float | None = None) -> PenaltyChoice:
    """The penalty alpha = f k_max on every row (k_max = max|diag K|) from the spectrum and the precision eps.

    Lambda = max_j K_jj / M_jj is the top of the unpenalised spectrum. (Row penalties
    scaled by the rows' masses, alpha_j ~ f Lambda M_jj, were tried: a light slope dof then
    gets too soft a spring and its reaction dominates P; one alpha on all rows is kept,
    as in the paper; Reduction.matrix takes one penalty per row all the same.)
    Error model for the lowest constrained eigenvalue lambda_lo (relative):

    * penalty: lambda(alpha) = lambda_c - sum_j r_j^2 / alpha_j + O(alpha^-2), r = diag(alpha) C phi
      the reactions of the mass-normalised mode (phi^T M phi = 1), so
      delta_p = sum_j r_j^2 / (alpha_j lambda_lo) = P / f,  P = |r|^2 / (k_max lambda_lo);
      P is calibrated by one solve of the lowest mode at f0 = CALIBRATION (r is the same
      to first order at every alpha): P = f0^2 k_max |C phi0|^2 / lambda0.
    * round-off: a backward-stable eigensolver errs by about eps * lambda_max, and the
      penalised spectrum reaches lambda_max ~ f Lambda, so
      delta_r = eps f Lambda / lambda_lo = R f  (a worst case; the inverse and
      shift-invert solvers usually do better).

    delta(f) = P / f + R f is least at the balance f* = sqrt(P / R), where it is
    delta* = 2 sqrt(P R); higher modes i carry a larger penalty error sum_j r_ij^2 / (alpha_j lambda_i)
    (frequencies: half these). ``fixed`` forces f (the paper's way: PENALTY_FACTOR = 1e6;
    the prediction then uses the same formula). Falls back to PENALTY_FACTOR
    when no low mode can be calibrated (unconstrained rigid modes: lambda_lo <= 0).
    """
    kd = np.abs(K.diagonal()) if sps.issparse(K) else np.abs(np.diag(np.asarray(K)))
    md = np.abs(M.diagonal()) if sps.issparse(M) else np.abs(np.diag(np.asarray(M)))
    k_max = max(float(kd.max()), 1e-300)
    heavy = md > 0
    Lam = float((kd[heavy] / md[heavy]).max()) if heavy.any() else k_max
    C = np.asarray(red.penalty_rows, float)
    s = np.full(len(C), k_max)
    P = R = 0.0
    try:
        lam0, phi0 = _lowest_mode(red.matrix(K, CALIBRATION * s), red.matrix(M))
        if lam0 > 0:
            Cphi = C @ red.expand(phi0)
            P = CALIBRATION**2 * float(np.sum(s * Cphi**2)) / lam0
            R = EPS * Lam / lam0
    except (np.linalg.LinAlgError, RuntimeError, ValueError, spla.ArpackError):
        P = R = 0.0
    if fixed is not None:
        f = float(fixed)
    elif P > 0 and R > 0:
        f = float(np.clip(np.sqrt(P / R), 1.0, 1e12))
    else:
        f = PENALTY_FACTOR
    choice = PenaltyChoice(float(f * s.max()), f, k_max, P, R, f * s)
    error = choice.predicted()
    if error > max(PENALTY_TARGET, 4 * R):  # 4 R: beyond the unpenalised problem's own round-off bound R
        import warnings

        from mechgen.runtime.linear.modes import AccuracyWarning

        warnings.warn(f"penalty constraints: the lowest eigenvalues are accurate only to about {error:.1g} "
                      f"(relative; penalty {P / f:.1g}, round-off {R * f:.1g} at alpha = {f:.3g} max|diag K|); "
                      "use constraints = 'eliminate' or 'multiplier'", AccuracyWarning, stacklevel=4)
    return choice


@dataclass(frozen=True)
class Reduction:
    """x = Z q (Z None: identity); ``penalty_rows`` C for the penalty method."""

    ndof: int
    Z: object
    penalty_rows: np.ndarray | None = None
    keep: np.ndarray | None = None
    multiplier_rows: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Reduced unknowns (dofs plus multipliers for the multiplier method)."""
        if self.multiplier_rows is not None:
            return self.ndof + len(self.multiplier_rows)
        return self.ndof if self.Z is None else self.Z.shape[1]

    def expand(self, q: np.ndarray) -> np.ndarray:
        """Full dof vector x = Z q (the first ndof unknowns with multipliers)."""
        q = np.asarray(q, float)
        if self.multiplier_rows is not None:
            return q[:self.ndof]
        return q if self.Z is None else self.Z @ q

    def vector(self, r: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """Z^T r; with multipliers (r + C^T lambda, C x) at the unknowns q = (x, lambda)."""
        if self.multiplier_rows is not None:
            C = self.multiplier_rows
            q = np.zeros(self.n) if q is None else np.asarray(q, float)
            return np.concatenate([r + C.T @ q[self.ndof:], C @ q[:self.ndof]])
        if self.keep is not None:  # Z^T r of a column selection Z (each kept row once, times 1.0: exact)
            return np.asarray(r, float)[self.keep]
        return r if self.Z is None else self.Z.T @ r

    def _bordered(self, A, border: bool):
        C = sps.csr_matrix(self.multiplier_rows)
        m = C.shape[0]
        top, bottom = (C.T, C) if border else (None, sps.csr_matrix((m, self.ndof)))
        out = sps.bmat([[sps.csr_matrix(A), top], [bottom, sps.csr_matrix((m, m))]], format="csr")
        return out if sps.issparse(A) else out.toarray()

    def matrix(self, A, penalty=0.0, border: bool = False):
        """Z^T A Z, plus C^T diag(penalty) C (the penalty method's stiffness term; a number: the same on
        every row); bordered for multipliers."""
        if self.multiplier_rows is not None:
            return self._bordered(A, border)
        if self.penalty_rows is not None and np.any(penalty):
            C = sps.csr_matrix(self.penalty_rows)
            extra = C.T @ sps.diags(np.broadcast_to(np.asarray(penalty, float), (C.shape[0],))) @ C
            A = (A + extra).tocsr() if sps.issparse(A) else A + extra.toarray()
        if self.Z is None:
            return A
        if self.keep is not None:  # a column selection: slicing, not two sparse products
            return self.kept(A) if sps.issparse(A) else A[np.ix_(self.keep, self.keep)]
        out = self.Z.T @ A @ self.Z
        return sps.csr_matrix(out) if sps.issparse(out) else np.asarray(out)

    @functools.cached_property
    def kept_index(self) -> np.ndarray:
        """For each dof, its place among the kept ones (-1: eliminated); read-only."""
        index = np.full(self.ndof, -1, np.int64)
        index[self.keep] = np.arange(len(self.keep))
        index.flags.writeable = False
        return index

    def kept(self, A):
        """A[keep][:, keep] of a sparse A as CSR, in one pass over A's entries (scipy's two fancy indexings build
        an intermediate matrix and check both: they were most of a small continuum's right-hand side)."""
        A = A.tocsr() if A.format != "csr" else A
        index = self.kept_index
        rows = np.repeat(index, np.diff(A.indptr))
        cols = index[A.indices]
        on = (rows >= 0) & (cols >= 0)
        n = len(self.keep)
        indptr = np.zeros(n + 1, np.int64)
        np.cumsum(np.bincount(rows[on], minlength=n), out=indptr[1:])
        return sps.csr_matrix((A.data[on], cols[on], indptr), shape=(n, n))

    def penalty_force(self, x: np.ndarray, penalty) -> np.ndarray:
        """C^T diag(penalty) C x (zero without penalty rows)."""
        if self.penalty_rows is None or not np.any(penalty):
            return np.zeros_like(x)
        return self.penalty_rows.T @ (penalty * (self.penalty_rows @ x))


def binding(row: np.ndarray, scale: float) -> bool:
    """False for a condition the basis satisfies by itself (its row vanishes at the jet's scale)."""
    return bool(np.abs(row).max() > 1e-10 * max(scale, 1.0))


def reduction(rows: np.ndarray, scales: np.ndarray, ndof: int, method: str, sparse: bool,
              joints: np.ndarray | None = None) -> Reduction:
    """Reduction for constraint rows (one per condition) whose jets have table magnitudes ``scales``.

    ``joints`` are further rows that join substructures (continuity at segment
    interfaces): eliminated exactly by their null space, x = null(J) q (the
    reduction of the constrained problem to a standard one), together with the
    boundary rows when those are eliminated too; kept as multipliers with them.
    """
    rows = np.atleast_2d(np.asarray(rows, float)).reshape(-1, ndof)
    keep = [binding(r, s) for r, s in zip(rows, scales)]
    rows = rows[np.asarray(keep, bool)] if len(rows) else rows
    joints = np.zeros((0, ndof)) if joints is None else np.atleast_2d(np.asarray(joints, float)).reshape(-1, ndof)
    if len(joints) and method != "multiplier":
        if method == "penalty":
            return Reduction(ndof, sla.null_space(joints, rcond=1e-10), rows if len(rows) else None)
        rows = np.vstack([rows, joints])
    elif len(joints):
        rows = np.vstack([rows, joints])
    if not len(rows):
        return Reduction(ndof, None)
    if method == "penalty":
        return Reduction(ndof, None, rows)
    if method == "multiplier":
        return Reduction(ndof, None, multiplier_rows=rows)
    nonzero = [np.flatnonzero(np.abs(r) > 1e-12 * np.abs(r).max()) for r in rows]
    if all(len(nz) == 1 for nz in nonzero):
        fixed = {int(nz[0]) for nz in nonzero}
        free = np.array([i for i in range(ndof) if i not in fixed])
        Z = sps.csr_matrix((np.ones(len(free)), (free, np.arange(len(free)))), shape=(ndof, len(free)))
        return Reduction(ndof, Z if sparse else Z.toarray(), keep=free)
    return Reduction(ndof, sla.null_space(rows, rcond=1e-10))
