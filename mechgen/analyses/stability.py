"""``stability``: eigenvalues of the gyroscopic / damped system and the verdict.

Scene keys: ``about``, ``at``, ``count`` (as for modes), ``tolerance`` (relative to the spectrum's
scale), ``refine`` and ``refine_rtol`` (a continuum's verdict checked at twice the size). Outputs:
``eigenvalues`` (list of [re, im]), ``verdict`` (stable / divergence / flutter / unconverged),
``frequencies``, ``growth_rate`` and, refined, ``refinement``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import figures, schema, summary
from mechgen.analyses.operating_point import linear_about, operating_point
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import LINEAR_OPTIONS, Option
from mechgen.runtime.core.memory import require_dense
from mechgen.runtime.linear.stability import stability as solve_stability
from mechgen.runtime.linear.stability import stability_first_order, stability_sparse

#: above this many unknowns, a stability analysis with a ``count`` of sparse matrices uses shift-invert
SPARSE_STABILITY_N = 400

SCHEMA = {**LINEAR_OPTIONS, "tolerance": Option(schema.positive, 1e-8), "refine": Option(schema.boolean, True),
          "refine_rtol": Option(schema.positive, 1e-2)}


def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel."""
    return {"linear"}


def _stability_of(system, q, options: dict, context: dict):
    tol = options.get("tolerance", 1e-8)
    if system.m:
        z = np.asarray(context[options["about"]]["_z"]) if options.get("about") else np.zeros(system.m)
        A = system.jacobian(0.0, np.concatenate([q, np.zeros(system.n), z]))
        return stability_first_order(A, np.eye(A.shape[0]), tolerance=tol)
    mats = linear_about(system, q, options, context)
    if options.get("count") and hasattr(mats["M"], "toarray") and system.n > SPARSE_STABILITY_N:
        return stability_sparse(mats["M"], mats["D"] + mats["G"], mats["K"], 2 * options["count"], tolerance=tol)
    require_dense(system.n, 40, "the dense stability eigenproblem", expected="a count with finite elements (sparse)")
    dense = {k: (v.toarray() if hasattr(v, "toarray") else v) for k, v in mats.items()}
    return solve_stability(dense["M"], dense["D"] + dense["G"], dense["K"], tolerance=tol)


def refinement_verdict(verdicts: list[str], growth: list[float], scales: list[float], tolerance: float,
                       rtol: float) -> str:
    """The continuum's verdict from verdicts at two refinements.

    Equal verdicts stand when stable, or when the growth rates agree to ``rtol``
    (relative); otherwise ``unconverged``.
    """
    if verdicts[0] != verdicts[1]:
        return "unconverged"
    if verdicts[0] == "stable":
        return "stable"
    g0, g1 = growth
    floor = tolerance * max(scales)
    return verdicts[0] if abs(g0 - g1) <= rtol * max(abs(g0), abs(g1)) + floor else "unconverged"


def run_stability(system, options: dict, context: dict) -> dict:
    """Eigenvalues of M q'' + (D + G) q' + K q = 0 and the verdict.

    With internal variables z the linearisation is the first-order one,
    x' = A x with A = d(dx/dt)/dx at (q, 0, z) (exact Jacobian, see System.jacobian).
    For a continuum (with ``refine``), the verdict is checked on the same model
    discretised twice as finely: ``unconverged`` when the verdict changes or the
    growth rate does not settle (``refinement`` reports both).
    """
    q = operating_point(system, options, context)
    res = _stability_of(system, q, options, context)
    eig = [[float(s.real), float(s.imag)] for s in res.eigenvalues]
    freqs = [float(f) for f in res.frequencies]
    if options.get("count"):
        freqs = freqs[: options["count"]]
    out = {"eigenvalues": eig, "verdict": res.verdict, "frequencies": freqs, "growth_rate": float(res.growth_rate)}
    if hasattr(system, "refined") and options.get("refine", True) and not options.get("about"):
        size = int(system.choices["N"])
        fine = system.refined(2 * size)
        res2 = _stability_of(fine, np.zeros(fine.n), options, context)
        out["verdict"] = refinement_verdict([res.verdict, res2.verdict], [res.growth_rate, res2.growth_rate],
                                            [res.scale, res2.scale], options.get("tolerance", 1e-8),
                                            options.get("refine_rtol", 1e-2))
        out["refinement"] = {"N": [size, 2 * size], "verdicts": [res.verdict, res2.verdict],
                             "growth_rates": [float(res.growth_rate), float(res2.growth_rate)]}
    return out


register(AnalysisKind("stability", SCHEMA, run_stability, needs, summary.lines, plot=figures.linear,
                      sweepable=True))
