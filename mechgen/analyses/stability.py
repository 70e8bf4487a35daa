"""``stability``: eigenvalues of the gyroscopic / damped system and the verdict.

Scene keys: ``about``, ``at``, ``count`` (as for modes), ``tolerance``, ``refine`` and ``refine_rtol``
(a continuum's verdict checked at twice the size). ``tolerance`` left out (the default): each
eigenvalue counts as growing when Re s exceeds the eigen-solve's own error bound for it (its
condition number times the round-off of the solve, mechgen.runtime.linear.stability), so a light
physical damping shifts no stability boundary by more than that accuracy; ``tolerance = 1e-8``
(a number): a fixed threshold of that much times the spectrum's scale (the largest |s|) for every
eigenvalue, the rule before (the sparse path, above SPARSE_STABILITY_N unknowns with ``count``,
uses 1e-8 when none is given: ARPACK's accuracy). That sparse path is estimated before it starts, memory and wall
time (c n^(4/3) per solve, mechgen.runtime.linear.stability.sparse_seconds, the 2N check included), and refused
with exit 2 at ``params.N`` beyond the memory limit or ``max_seconds``.

Outputs: ``eigenvalues`` (list of [re, im]; with ``count``, the 2 count of smallest |s|, from which the
``count`` lowest ``frequencies`` are taken; the verdict is that of the whole computed spectrum),
``verdict`` (stable / neutral / divergence / flutter / unconverged; ``neutral``: stable apart from
rigid-body modes, which drift freely), ``frequencies``, ``growth_rate`` (of the modes that are not
rigid), ``rigid_modes`` (how many), ``unstable`` ({real, complex}: eigenvalues with Re s above their
threshold, complex ones counted once per pair), ``operating_point`` (when the given point was not an
equilibrium and Newton found one: mechgen.analyses.operating_point.equilibrium_point) and, refined,
``refinement``: the sizes, verdicts, sign structures (``unstable``) and growth rates at N and 2N, what
was ``compared`` and whether the growth rates agree to ``refine_rtol`` (``growth_rate_converged``). A continuum
also reports ``roundoff_bound`` (as modes': the bound on the lowest frequency's relative error from round-off,
about eps (omega_max / omega_1)^2) and is refused with exit 2 at ``params.N`` when it exceeds ``roundoff_rtol``
(default 1e-2) at N or at the 2N check (Beck's column: from N = 2000 with the check, 4000 without).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.operating_point import equilibrium_point, linear_about
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.modes import require_roundoff
from mechgen.analyses.schema import LINEAR_OPTIONS, Option
from mechgen.runtime.linear.modes import modes as solve_modes
from mechgen.errors import InputError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, require_seconds
from mechgen.runtime.core.memory import require, require_dense
from mechgen.runtime.linear.stability import stability as solve_stability
from mechgen.runtime.linear.stability import (SPARSE_BYTES_PER_UNKNOWN, sparse_seconds, stability_first_order,
                                              stability_sparse)

#: above this many unknowns, a stability analysis with a ``count`` of sparse matrices uses shift-invert
SPARSE_STABILITY_N = 400

SCHEMA = {**LINEAR_OPTIONS,
          "tolerance": Option(schema.positive, doc="a fixed growth threshold, times the spectrum's scale max |s| "
                              "(left out: each eigenvalue's own error bound)"),
          "refine": Option(schema.boolean, True, doc="check a continuum's verdict again at twice the size"),
          "refine_rtol": Option(schema.positive, 1e-2, doc="the relative agreement of the growth rates at N and "
                                "2N that counts as converged")}


def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel; the residual too, to check that the point is an equilibrium (no ``about``)."""
    return {"linear"} if options.get("about") else {"linear", "residual"}


def _stability_of(system, q, options: dict, context: dict, what: str = "stability"):
    """(the eigenvalues and verdict, a continuum's round-off bound on its lowest frequency or None)."""
    tol = options.get("tolerance")
    if system.m:
        z = np.asarray(context[options["about"]]["_z"]) if options.get("about") else np.zeros(system.m)
        A = system.jacobian(0.0, np.concatenate([q, np.zeros(system.n), z]))
        return stability_first_order(A, np.eye(A.shape[0]), tolerance=tol), None
    mats = linear_about(system, q, options, context)
    if options.get("count") and hasattr(mats["M"], "toarray") and system.n > SPARSE_STABILITY_N:
        res = stability_sparse(mats["M"], mats["D"] + mats["G"], mats["K"], 2 * options["count"], tolerance=tol)
    else:
        require_dense(system.n, 40, "the dense stability eigenproblem",
                      expected="a count with finite elements (sparse)")
        dense = {k: (v.toarray() if hasattr(v, "toarray") else v) for k, v in mats.items()}
        res = solve_stability(dense["M"], dense["D"] + dense["G"], dense["K"], tolerance=tol)
    return res, stability_roundoff(system, mats, res, options, what)


def stability_roundoff(system, mats: dict, res, options: dict, what: str = "stability") -> float | None:
    """A continuum's bound on the relative error of its lowest frequency from round-off in the assembled M and K
    (mechgen.analyses.modes.require_roundoff: exit 2 at params.N above ``roundoff_rtol``), lam = min |s|^2 of the
    computed (non-rigid) eigenvalues, the spread |phi|^T |K| |phi| from the lowest elastic mode phi of the symmetric
    pencil ((K + K^T) / 2, M) (one more sparse solve for one mode); None for a lumped model, no eigenvalue, or a
    mass that is not positive definite (massless first-order fields, multipliers: that pencil has no modes)."""
    s = np.asarray(res.eigenvalues)
    if not getattr(system, "is_field", False) or not s.size:
        return None
    M, K = mats["M"], mats["K"]
    if getattr(system, "has_multipliers", False) or not np.all(np.asarray(M.diagonal()) > 0):
        return None
    try:
        sym = solve_modes(M, (K + K.T) / 2, count=1)
    except InputError:  # M not positive definite after all (its diagonal is)
        return None
    if sym.shapes.shape[1] <= sym.rigid:
        return None
    elastic = np.sort(np.abs(s))[2 * int(res.rigid):]  # a rigid mode is a double zero of the first-order form
    if not elastic.size:
        return None
    lam = float(elastic[0]) ** 2
    return require_roundoff(system, M, K, sym.shapes[:, sym.rigid], lam, options, what=what)


def require_sparse_stability(system, options: dict) -> None:
    """Refuse up front (exit 2 at params.N) a continuum's sparse stability solve whose memory, SPARSE_BYTES_PER_UNKNOWN
    x the unknowns of its largest solve (2n when refined at 2N), exceeds the limit (mechgen.runtime.core.memory), or
    whose wall time, sparse_seconds(n) (+ sparse_seconds(2n) refined), exceeds ``max_seconds``."""
    if not (options.get("count") and getattr(system, "is_field", False)):
        return
    n = int(system.n)
    if n <= SPARSE_STABILITY_N:
        return
    refined = hasattr(system, "refined") and options.get("refine", True) and not options.get("about")
    largest = 2 * n if refined else n
    require(SPARSE_BYTES_PER_UNKNOWN * largest, f"the sparse stability solve of {largest} unknowns"
            + (f" (refined at 2N from {n})" if refined else ""), key="params.N",
            expected="a smaller N" + (", or refine = false" if refined else ""))
    seconds = sparse_seconds(n, general=True) + (sparse_seconds(2 * n, general=True) if refined else 0.0)
    require_seconds(seconds, float(options.get("max_seconds", DEFAULT_SECONDS)), f"the sparse stability solve of {n} "
                    "unknowns" + (f" and its check at 2N ({2 * n} unknowns)" if refined else ""), key="params.N",
                    basis="c n^(4/3) per solve of n unknowns, measured", expected="a smaller N"
                    + (", or refine = false" if refined else ""))


def refinement_verdict(verdicts: list[str], structures: list[tuple[int, int]]) -> str:
    """The continuum's verdict from the verdicts at two refinements: it stands when the verdicts agree and so
    does the sign structure (how many eigenvalues grow, real and complex); otherwise ``unconverged``.

    Near a stability boundary (just above a buckling load) the growth rate is small and converges slowly
    with the mesh while the sign structure is already settled, so the growth rates are reported (with
    whether they agree to ``refine_rtol``) but do not decide.
    """
    if verdicts[0] != verdicts[1] or tuple(structures[0]) != tuple(structures[1]):
        return "unconverged"
    return verdicts[0]


def _structure(res) -> dict:
    return {"real": int(res.unstable[0]), "complex": int(res.unstable[1])}


def _trimmed(res, count: int | None) -> tuple[list, list]:
    """Eigenvalues and frequencies as reported: with ``count``, the 2 (count + rigid modes) eigenvalues of
    smallest |s| (the part of the spectrum the sparse path computes) and the lowest ``count`` frequencies
    among them."""
    s = np.asarray(res.eigenvalues)
    freqs = np.asarray(res.frequencies)
    if count:
        near = np.sort(np.argsort(np.abs(s), kind="stable")[: 2 * (count + res.rigid)])  # (imag, real) order
        kept = s[near]
        top = float(np.max(np.abs(kept.imag))) if kept.size else 0.0
        freqs = freqs[freqs <= top * (1 + 1e-12)][:count]
        s = kept
    return [[float(x.real), float(x.imag)] for x in s], [float(f) for f in freqs]


def run_stability(system, options: dict, context: dict) -> dict:
    """Eigenvalues of M q'' + (D + G) q' + K q = 0 and the verdict.

    With internal variables z the linearisation is the first-order one,
    x' = A x with A = d(dx/dt)/dx at (q, 0, z) (exact Jacobian, see System.jacobian).
    For a continuum (with ``refine``), the verdict is checked on the same model
    discretised twice as finely: ``unconverged`` when the verdict or the sign structure
    changes (``refinement`` reports both, and the growth rates).
    """
    require_sparse_stability(system, options)
    q, found = equilibrium_point(system, options, context)
    res, bound = _stability_of(system, q, options, context)
    eig, freqs = _trimmed(res, options.get("count"))
    out = {"eigenvalues": eig, "verdict": res.verdict, "frequencies": freqs, "growth_rate": float(res.growth_rate),
           "rigid_modes": int(res.rigid), "unstable": _structure(res)}
    if bound is not None:
        out["roundoff_bound"] = bound
    if found is not None:
        out["operating_point"] = found
    if hasattr(system, "refined") and options.get("refine", True) and not options.get("about"):
        size = int(system.choices["N"])
        fine = system.refined(2 * size)
        q_fine = equilibrium_point(fine, options, context)[0] if found is not None else np.zeros(fine.n)
        res2, bound2 = _stability_of(fine, q_fine, options, context, f"stability (its check at 2N = {2 * size})")
        out["verdict"] = refinement_verdict([res.verdict, res2.verdict], [res.unstable, res2.unstable])
        g0, g1 = float(res.growth_rate), float(res2.growth_rate)
        rtol = options.get("refine_rtol", 1e-2)
        floor = max(res.threshold, res2.threshold)
        out["refinement"] = {"N": [size, 2 * size], "verdicts": [res.verdict, res2.verdict],
                             "unstable": [_structure(res), _structure(res2)], "growth_rates": [g0, g1],
                             "growth_rate_converged": bool(abs(g0 - g1) <= rtol * max(abs(g0), abs(g1)) + floor),
                             "compared": "verdict and sign structure (numbers of growing real and complex "
                                         "eigenvalues) at N and 2N; growth rates reported, to refine_rtol"}
        if bound is not None and bound2 is not None:
            out["refinement"]["roundoff_bounds"] = [bound, bound2]
    return out


register(AnalysisKind("stability", SCHEMA, run_stability, needs, summary.lines, plot=figures.linear,
                      sweepable=True))
