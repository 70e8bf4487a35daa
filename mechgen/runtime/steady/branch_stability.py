"""Stability along a branch of steady states: the Galerkin linearisation about every point.

For each point (u, lam) of a :class:`~mechgen.runtime.steady.continuation.Branch` of a steady BVP
(:func:`mechgen.runtime.steady.continuation.continue_bvp` on a
:class:`~mechgen.runtime.steady.steady_bvp.SteadyBVP`), the steady state's jets at the
discretisation's quadrature points give the linearised M, D, G, K
(FieldSystem.linear(jets=...)), and :func:`mechgen.runtime.linear.stability.stability` the
eigenvalues of M q'' + (D + G) q' + K q = 0 and the verdict, each with a system at that
point's parameters (System.with_param_vector: the given system is never changed).
"""
from __future__ import annotations

import numpy as np

from mechgen.runtime.core.memory import require_dense
from mechgen.runtime.steady.constrained import linear_about_bvp
from mechgen.runtime.linear.stability import StabilityResult, stability


def _dense(A) -> np.ndarray:
    return A.toarray() if hasattr(A, "toarray") else np.asarray(A, float)


def stability_at(system, bvp, result) -> StabilityResult:
    """Eigenvalues and verdict about one steady state ``result`` (a BVPResult of ``bvp``), with the result's
    parameters (a system at them, when ``system``'s differ)."""
    mats = linear_about_bvp(system.with_param_vector(result.p), bvp, result)
    require_dense(mats["M"].shape[0], 40, "the dense stability eigenproblem along a branch")
    return stability(_dense(mats["M"]), _dense(mats["D"]) + _dense(mats["G"]), _dense(mats["K"]))


def stability_along(system, bvp, branch, results=None) -> list[StabilityResult]:
    """The stability verdict at every point of ``branch`` (or of ``results``, BVPResults of its points)."""
    if results is None:
        results = [branch.system.to_result(u, lam) for u, lam in zip(branch.u, branch.lam)]
    return [stability_at(system, bvp, res) for res in results]
