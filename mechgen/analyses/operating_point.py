"""Where a linear analysis linearises: an operating point, or a steady state found before.

``operating_point`` gives the q about which M, D, G, K are assembled: the q of an earlier
``steady`` analysis named by ``about``, the coordinates of ``at``, or zero. ``linear_about``
gives the matrices themselves; about a continuum's boundary-value steady state they come from
its jets at the quadrature points (mechgen.runtime.steady.constrained.linear_about_bvp).

Small motions are motions about an equilibrium: linearising a nonlinear model about a point
whose static residual r(q, 0, 0) is not zero gives frequencies of no physical state (the
origin of V = k x^2/2 + b x^4/4 - F x is not where the mass rests). :func:`equilibrium_point`
therefore checks the residual at the given point (``at``, or zero) and, when it is not zero,
finds the equilibrium by Newton from that point (J = K of the linear kernel, which is dr/dq at
v = a = 0); the analysis then reports ``operating_point`` (the start, its residual norm, the
equilibrium, the Newton iterations). When Newton fails, or the model has internal variables
(whose rates also have to vanish), it refuses with a ConvergenceError that names the residual
norm and suggests a ``steady`` analysis first (``about``).
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.steady.constrained import linear_about_bvp

#: the static residual counts as zero when ||r|| <= RESIDUAL_RTOL * ||K||_F * max(1, ||q||) (force units)
RESIDUAL_RTOL = 1e-10


def vector(system, table: dict | None, base: np.ndarray | None = None) -> np.ndarray:
    """A vector of the system's coordinates: zero (or ``base``) with the entries ``table`` names set."""
    q = np.zeros(system.n) if base is None else np.array(base, dtype=float)
    names = system.coordinates
    for name, value in (table or {}).items():
        q[names.index(name)] = float(value)
    return q


def operating_point(system, options: dict, context: dict) -> np.ndarray:
    """q about which to linearise: a previous steady state, an explicit point, or zero (unchecked)."""
    if options.get("about"):
        steady = context[options["about"]]
        return np.zeros(system.n) if "_bvp" in steady else np.asarray(steady["_q"])
    return vector(system, options.get("at"))


def _norm(X) -> float:
    """||X||_F of a dense or sparse matrix."""
    if hasattr(X, "toarray"):
        return float(np.sqrt((abs(X).power(2)).sum()))
    return float(np.linalg.norm(X))


def residual_tolerance(system, q: np.ndarray) -> float:
    """RESIDUAL_RTOL * ||K(q)||_F * max(1, ||q||): the size of a static residual that counts as zero.

    ||K|| ||q|| is the size of the forces the linearisation itself holds at q (the 1 stands in for a
    length scale at the origin), so the rule is independent of the units of the forces.
    """
    K = system.linear(q)["K"]
    return RESIDUAL_RTOL * max(_norm(K), 1e-300) * max(1.0, float(np.linalg.norm(q)))


def equilibrium_point(system, options: dict, context: dict) -> tuple[np.ndarray, dict | None]:
    """The point to linearise about, and what was done to find it (None when the given point is used as is).

    ``about`` a steady analysis: its state. Otherwise the point of ``at`` (or zero) when its static
    residual r(q, 0, 0) is zero to :func:`residual_tolerance`; else the equilibrium that Newton finds
    from it, with the report ``{"found": "newton", "start", "start_residual_norm", "residual_norm",
    "iterations", "coordinates"}`` (coordinates: lumped models). A system compiled without the
    residual kernel cannot be checked and is used as is. Raises ConvergenceError (exit 1) naming the
    residual norm when no equilibrium is found (or the model has internal variables) and suggesting
    a steady analysis.
    """
    q0 = operating_point(system, options, context)
    if options.get("about") or "residual" not in system.kernels:
        return q0, None
    r0 = np.asarray(system.residual(q0), float)
    start = float(np.linalg.norm(r0))
    if start == 0.0:  # the common case (an unloaded model at its origin): no assembly of K for the scale
        return q0, None
    tol = residual_tolerance(system, q0)
    if start <= tol:
        return q0, None
    where = _where(system, q0, options)
    if getattr(system, "m", 0):
        raise ConvergenceError(
            f"the point {where} is not an equilibrium (static residual norm {start:.3g}; zero is below {tol:.3g}) "
            f"and model "
            f"{system.metadata.model} has internal variables: run a steady analysis first and linearise about it "
            "(about = \"<its name>\")")
    from mechgen.runtime.steady.newton import newton

    try:
        res = newton(lambda q: system.residual(q), lambda q: system.linear(q)["K"], q0, tol=tol, max_iter=50)
    except ConvergenceError as exc:
        raise ConvergenceError(
            f"the point {where} is not an equilibrium (static residual norm {start:.3g}; zero is below {tol:.3g}) "
            "and Newton "
            f"from it found none ({exc}): run a steady analysis first (with a guess) and linearise about it "
            "(about = \"<its name>\")") from exc
    meshed = system.is_field or getattr(system, "is_plane", False)  # thousands of dofs: not listed
    report = {"found": "newton", "start": _coordinates(system, q0) if not meshed else where,
              "start_residual_norm": start, "residual_norm": float(res.residual_norm),
              "iterations": int(res.iterations)}
    if not meshed and not system.is_lattice:
        report["coordinates"] = _coordinates(system, res.x)
    return np.asarray(res.x), report


def _coordinates(system, q) -> dict[str, float]:
    return {n: float(x) for n, x in zip(system.coordinates, q)}


def _where(system, q, options: dict) -> str:
    if options.get("at"):
        return "at = {" + ", ".join(f"{k} = {v:g}" for k, v in options["at"].items()) + "}"
    return "q = 0 (no 'at' and no 'about')"


def linear_about_steady(system, steady: dict) -> dict:
    """M, D, G, K of the model's discretisation about a boundary-value steady state (its jets at the points)."""
    return linear_about_bvp(system, steady["_bvp"], steady["_result"])


def linear_about(system, q, options: dict, context: dict) -> dict:
    """M, D, G, K about the operating point, or about a boundary-value steady state named by ``about``."""
    if options.get("about") and "_bvp" in context[options["about"]]:
        return linear_about_steady(system, context[options["about"]])
    return system.linear(q)
