"""Natural frequencies and mode shapes: K phi = omega^2 M phi (M symmetric positive definite).

Frequencies are sign(lambda) sqrt(|lambda|) for the eigenvalues lambda = omega^2,
ascending: a negative frequency flags a divergence (negative-stiffness) mode.
Shapes are mass-normalised (phi^T M phi = I). Units: rad/s, or the model's
nondimensional frequency unit.

Rigid-body modes (K phi = 0: a free-free continuum, an unsupported chain) have lambda = 0, which the
solver returns as a round-off value of size at most about eps * max|lambda| (either sign; LAPACK's
bound p(n) eps ||A||, with p(n) of order 1 in practice: measured |lambda| <= 3e-17 Lambda for a free
chain and free-free beams of 16 to 512 elements). An eigenvalue with |lambda| <= RIGID_FACTOR * eps *
Lambda, Lambda = max(max|lambda|, max_i K_ii / M_ii) (the largest Rayleigh quotient of a unit vector
bounds max lambda from below, so Lambda is the spectrum's scale even when only the lowest modes are
computed), is indistinguishable from zero at this accuracy: it counts as rigid (:func:`rigid_count`,
``ModesResult.rigid``), not as a frequency. A factor n in the bound would swallow real modes of fine
meshes (the free-free beam's first elastic lambda = 500.6 lies below 10 n eps Lambda = 561 at 512
hermite elements). On the sparse path (the lowest ``count`` modes) a rigid eigenvalue must also be below
sqrt(eps) times the largest computed one: a penalty makes max K_ii / M_ii huge there.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


@dataclass(frozen=True)
class ModesResult:
    """Eigenvalues omega^2, signed frequencies and mass-normalised shapes (columns)."""

    eigenvalues: np.ndarray
    frequencies: np.ndarray
    shapes: np.ndarray
    rigid: int = 0  #: how many of the leading modes are rigid-body modes (lambda = 0 to the solver's accuracy)


#: |lambda| <= RIGID_FACTOR * eps * Lambda counts as zero (the symmetric solver's error is about p(n) eps Lambda
#: with p(n) of order 1 in practice; the factor leaves a margin for the assembly's own round-off)
RIGID_FACTOR = 10.0


def spectrum_scale(M, K, lam: np.ndarray) -> float:
    """Lambda = max(max|lambda|, max_i K_ii / M_ii): the scale round-off in lambda is relative to."""
    kd, md = np.abs(np.asarray(K.diagonal(), float)), np.abs(np.asarray(M.diagonal(), float))
    both = md > 0
    ratio = float((kd[both] / md[both]).max()) if both.any() else 0.0
    return max(float(np.abs(lam).max(initial=0.0)), ratio)


def rigid_tolerance(scale: float) -> float:
    """RIGID_FACTOR * eps * scale: the largest |lambda| indistinguishable from zero (scale: Lambda)."""
    return RIGID_FACTOR * np.finfo(float).eps * scale


def rigid_count(lam: np.ndarray, scale: float) -> int:
    """How many eigenvalues lambda = omega^2 are rigid-body modes (|lambda| <= :func:`rigid_tolerance`)."""
    return int(np.count_nonzero(np.abs(lam) <= rigid_tolerance(scale)))


def _with_rigid(res: "ModesResult", M, K, *, partial: bool = False) -> "ModesResult":
    """The result with its rigid modes moved to the front (their round-off eigenvalues kept) and counted.

    ``partial`` (the lowest modes of the sparse path): a rigid eigenvalue must also be below sqrt(eps) times
    the largest computed one, since max K_ii / M_ii there can be a penalty's (penalised supports make it
    huge while the shift-inverted low modes stay accurate), which alone would take real modes for rigid.
    """
    lam = np.asarray(res.eigenvalues)
    rigid = np.abs(lam) <= rigid_tolerance(spectrum_scale(M, K, lam))
    if partial:
        rigid &= np.abs(lam) <= np.sqrt(np.finfo(float).eps) * float(np.abs(lam).max(initial=0.0))
    if not rigid.any():
        return res
    order = np.concatenate([np.flatnonzero(rigid), np.flatnonzero(~rigid)])
    return ModesResult(lam[order], np.asarray(res.frequencies)[order], res.shapes[:, order], int(rigid.sum()))


def _check_symmetric(A: np.ndarray, name: str) -> None:
    scale = max(np.abs(A).max(), 1e-300)
    if np.abs(A - A.T).max() > 1e-10 * scale:
        raise InputError(f"{name} is not symmetric (asymmetry {np.abs(A - A.T).max():.3g} of scale {scale:.3g})",
                         key=name, expected="a symmetric matrix (use a stability analysis for circulatory systems)")


def _dense_inverse(M: np.ndarray, K: np.ndarray) -> ModesResult | None:
    """For positive definite K: M phi = mu K phi, lambda = 1/mu (None if K is not positive definite).

    The symmetric solver's error is about eps * max|eigenvalue|, so solving for mu
    = 1/omega^2 gets the *lowest* frequencies to full relative accuracy even when
    K holds huge entries (penalty constraints, stiff supports). With K and M positive
    definite every mu > 0; the highest modes' mu (below the solver's error n eps max mu)
    are unresolved and may come out zero or slightly negative by round-off: they are held
    at that error (lambda = 1 / (n eps max mu), beyond every resolved mode) instead of
    abandoning this solver. A mu below minus that error means M is not positive definite (None).
    """
    try:
        sla.cho_factor(K)
    except np.linalg.LinAlgError:
        return None
    mu, phi = sla.eigh(M, K)
    resolution = len(mu) * np.finfo(float).eps * max(float(mu.max()), 0.0)
    if resolution <= 0 or np.any(mu < -resolution):
        return None
    mu = np.maximum(mu, resolution)
    order = np.argsort(1.0 / mu)
    mu, phi = mu[order], phi[:, order]
    lam = 1.0 / mu
    return ModesResult(lam, np.sqrt(lam), phi / np.sqrt(mu)[None, :])


def _wide_spectrum(M: np.ndarray, K: np.ndarray, span: float = 1e6) -> bool:
    """Whether the spectrum may span more than ``span``: huge entries of K against its smallest diagonal
    (penalties, stiff supports), or diagonal ratios K_ii / M_ii that far apart (light slope dofs, fine
    meshes). Then the lowest modes are solved for mu = 1/omega^2 (:func:`_dense_inverse`)."""
    kd, md = np.abs(np.diag(K)), np.abs(np.diag(M))
    if np.abs(K).max() > span * kd.min(initial=np.inf):
        return True
    both = (kd > 0) & (md > 0)
    ratios = kd[both] / md[both]
    return bool(ratios.size) and ratios.max() > span * ratios.min()


def _dense(M, K, allow_singular_mass: bool = False) -> ModesResult:
    M, K = np.asarray(M, float), np.asarray(K, float)
    _check_symmetric(M, "M")
    _check_symmetric(K, "K")
    if _wide_spectrum(M, K):
        inverse = _dense_inverse(M, K)
        if inverse is not None:
            return inverse
    try:
        lam, phi = sla.eigh(K, M)
    except np.linalg.LinAlgError as exc:
        singular = _semidefinite_mass(M, K) if allow_singular_mass else None
        if singular is not None:
            return _with_rigid(singular, M, K)
        raise InputError("the mass matrix is not positive definite (singular or indefinite)", key="M",
                         expected="a positive definite mass matrix (check masses and inertias are > 0)") from exc
    _warn_if_inaccurate(lam)
    return _with_rigid(ModesResult(lam, np.sign(lam) * np.sqrt(np.abs(lam)), phi), M, K)


class AccuracyWarning(UserWarning):
    """Round-off limits the accuracy of the computed frequencies."""


def _warn_if_inaccurate(lam: np.ndarray, target: float = 1e-4) -> None:
    """Warn when the symmetric solver's error bound, about eps * max|lambda|, exceeds ``target`` * |lambda_min|.

    The lowest nonzero eigenvalue is then accurate only to that bound (a stiffness
    contrast of 1e12 between modes, e.g. a nearly rigid shear term, leaves ~1e-4; a worst-case bound).
    """
    nonzero = np.abs(lam[np.abs(lam) > 64 * np.finfo(float).eps * np.abs(lam).max()])
    if not nonzero.size:
        return
    bound = np.finfo(float).eps * np.abs(lam).max() / nonzero.min()
    if bound > target:
        import warnings

        warnings.warn(f"the lowest eigenvalues are accurate only to about {bound:.1g} (relative): the spectrum spans "
                      f"{np.abs(lam).max() / nonzero.min():.1g}; refine less, rescale, or stiffen less",
                      AccuracyWarning, stacklevel=3)


def roundoff_bound(M, K, phi: np.ndarray, lam: float) -> float:
    """The relative error of an eigenvalue lam = omega^2 of K phi = lam M phi that the round-off of the assembled
    matrices allows, to first order in eps: entries each rounded (|dK| <= eps |K|, |dM| <= eps |M| entrywise) move
    lam by at most

        |d lam| / |lam| <= eps (|phi|^T |K| |phi| + |lam| |phi|^T |M| |phi|) / |lam phi^T M phi|       (dimensionless)

    (|.| entrywise; M, K dense or sparse). For the lowest mode of a fine mesh the sum |phi|^T |K| |phi| does not
    cancel as phi^T K phi does: a Hermite beam's bound grows as eps (omega_max / omega_1)^2 ~ eps N^4 (measured
    on Euler-Bernoulli beams and Beck's column: the solvers' actual errors stay below 0.3 of it). An infinite bound
    for lam = 0."""
    phi = np.real(np.asarray(phi, dtype=float))
    size, lam = np.abs(phi), float(abs(lam))
    norm = abs(float(phi @ (M @ phi)))
    if lam == 0.0 or norm == 0.0:
        return float("inf")
    spread = float(size @ (abs(K) @ size)) + lam * float(size @ (abs(M) @ size))
    return float(np.finfo(float).eps * spread / (lam * norm))


def _semidefinite_mass(M: np.ndarray, K: np.ndarray) -> ModesResult | None:
    """K phi = lambda M phi with M positive semi-definite (constraint multipliers carry no mass).

    The QZ algorithm gives infinite eigenvalues for the massless directions; the
    finite ones are the constrained system's (None when M has a negative direction).
    """
    if np.linalg.eigvalsh(M).min() < -1e-12 * max(np.abs(M).max(), 1e-300):
        return None
    w, vr = sla.eig(K, M)
    finite = np.isfinite(w)
    lam, phi = w[finite].real, vr[:, finite].real
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    norms = np.sqrt(np.abs(np.einsum("ik,ij,jk->k", phi, M, phi)))
    return ModesResult(lam, np.sign(lam) * np.sqrt(np.abs(lam)), phi / np.where(norms > 0, norms, 1.0))


def _sparse(M, K, count: int) -> ModesResult:
    """Shift-invert about sigma = 0 (the lowest modes converge fastest there); if K is singular (rigid
    modes), about a small negative sigma scaled by the smallest diagonal ratio K_ii / M_ii."""
    kd, md = np.abs(K.diagonal()), np.abs(M.diagonal())
    ratios = kd[(kd > 0) & (md > 0)] / md[(kd > 0) & (md > 0)]
    fallback = -1e-3 * (ratios.min() if ratios.size else 1.0)
    last: Exception | None = None
    # a fixed starting vector (ARPACK's default is random: reruns would differ in the last bits); pseudo-random,
    # not ones, so that no symmetry class of modes is missing from the Krylov space
    v0 = np.random.default_rng(0).standard_normal(K.shape[0])
    for sigma in (0.0, fallback):
        try:
            lam, phi = spla.eigsh(K.tocsc(), k=count, M=M.tocsc(), sigma=sigma, which="LM", v0=v0)
            break
        except (RuntimeError, spla.ArpackError) as exc:
            last = exc
    else:
        raise InputError(f"sparse eigensolver failed: {last}", key="M",
                         expected="a positive definite mass matrix") from last
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    return ModesResult(lam, np.sign(lam) * np.sqrt(np.abs(lam)), phi)


def modes(M, K, count: int | None = None, *, allow_singular_mass: bool = False) -> ModesResult:
    """Solve K phi = omega^2 M phi; dense (eigh) or sparse shift-invert about 0 for the lowest ``count``.

    ``allow_singular_mass``: M may be semi-definite (massless Lagrange multipliers); its
    infinite eigenvalues are dropped. Otherwise a singular M is an input error.
    ``count`` counts elastic modes: rigid-body modes (``rigid`` of them, first, their eigenvalues the
    solver's round-off) come on top of it.
    """
    n = M.shape[0]
    if not ((sps.issparse(M) or sps.issparse(K)) and count is not None and count < n - 1 and n > 200):
        require_dense(n, 6, "the dense symmetric eigenproblem")
    if sps.issparse(M) or sps.issparse(K):
        if count is not None and count < n - 1 and n > 200:
            Ms, Ks = sps.csr_matrix(M), sps.csr_matrix(K)
            res = _with_rigid(_sparse(Ms, Ks, count), Ms, Ks, partial=True)
            if res.rigid and count + res.rigid < n - 1:
                res = _with_rigid(_sparse(Ms, Ks, count + res.rigid), Ms, Ks, partial=True)
            return res
        M = M.toarray() if sps.issparse(M) else M
        K = K.toarray() if sps.issparse(K) else K
    res = _dense(M, K, allow_singular_mass)  # rigid modes counted on the direct paths (K > 0 on the inverse one)
    if count is not None:
        keep = res.rigid + count
        res = ModesResult(res.eigenvalues[:keep], res.frequencies[:keep], res.shapes[:, :keep], res.rigid)
    return res
