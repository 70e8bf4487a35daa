"""Where a linear analysis linearises: an operating point, or a steady state found before.

``operating_point`` gives the q about which M, D, G, K are assembled: the q of an earlier
``steady`` analysis named by ``about``, the coordinates of ``at``, or zero. ``linear_about``
gives the matrices themselves; about a continuum's boundary-value steady state they come from
its jets at the quadrature points (mechgen.runtime.steady.constrained.linear_about_bvp).
"""
from __future__ import annotations

import numpy as np

from mechgen.runtime.steady.constrained import linear_about_bvp


def vector(system, table: dict | None, base: np.ndarray | None = None) -> np.ndarray:
    """A vector of the system's coordinates: zero (or ``base``) with the entries ``table`` names set."""
    q = np.zeros(system.n) if base is None else np.array(base, dtype=float)
    names = system.coordinates
    for name, value in (table or {}).items():
        q[names.index(name)] = float(value)
    return q


def operating_point(system, options: dict, context: dict) -> np.ndarray:
    """q about which to linearise: a previous steady state, an explicit point, or zero."""
    if options.get("about"):
        steady = context[options["about"]]
        return np.zeros(system.n) if "_bvp" in steady else np.asarray(steady["_q"])
    return vector(system, options.get("at"))


def linear_about_steady(system, steady: dict) -> dict:
    """M, D, G, K of the model's discretisation about a boundary-value steady state (its jets at the points)."""
    return linear_about_bvp(system, steady["_bvp"], steady["_result"])


def linear_about(system, q, options: dict, context: dict) -> dict:
    """M, D, G, K about the operating point, or about a boundary-value steady state named by ``about``."""
    if options.get("about") and "_bvp" in context[options["about"]]:
        return linear_about_steady(system, context[options["about"]])
    return system.linear(q)

