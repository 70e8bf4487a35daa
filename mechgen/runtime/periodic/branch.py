"""A branch of periodic orbits in a model parameter p: the continuation's equations built on a method's problem.

Each method's problem (mechgen.runtime.periodic: HarmonicBalance, Shooting) gives R(u) and dR/du at fixed
parameters. Along p, with the problem rebuilt at each value (``make(p)``: the system at p, and the forcing's
frequency omega(p) when the forcing follows the parameter: ``frequency = "w"`` continued in w),

    F(u, p) = R(u; p),   F_u = dR/du,   F_p = (R(u; p + h) - R(u; p - h)) / (2 h),  h = PARAM_STEP (1 + |p|),

for mechgen.runtime.steady.continuation (pseudo-arclength: frequency-response curves through their folds, the
cyclic folds LPC). F_p by central differences enters the bordered system's last column only: it slows the
corrector, it never moves a point (each solves R = 0 to the corrector's tolerance). The residual alone is
evaluated where the Jacobian is not needed (harmonic balance's ``residual``; shooting's flow map without its
monodromy); a point's (R, dR/du) is kept so that the corrector's F and F_u at one point cost one evaluation.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from mechgen.runtime.steady.continuation import ParametricEquations

#: the central-difference step of F_p, relative to 1 + |p|
PARAM_STEP = 1e-6


def residual_only(problem, u: np.ndarray) -> np.ndarray:
    """R(u) without dR/du where the problem allows it (module doc)."""
    if hasattr(problem, "residual"):
        return problem.residual(u)
    if getattr(problem, "segments", 1) > 1:  # multiple shooting: every segment's flow
        return problem.residual_jacobian(u)[0]
    x0, T = problem.split(u)
    if problem.compiled is not None:
        xT = problem.compiled(x0, np.array([0.0, T]))[-1]
    else:
        from mechgen.runtime.periodic.flow import states_at

        xT = states_at(problem.system, x0, 0.0, np.array([0.0, T]), problem.rtol, problem.atol)[-1]
    R = xT - x0
    return np.append(R, x0[problem.system.n + problem.phase]) if problem.autonomous else R


class OrbitBranch:
    """F, F_u, F_p of the orbits of the problems ``make(p)`` (module doc), with a small memo."""

    def __init__(self, make: Callable[[float], object], name: str) -> None:
        self.make, self.name = make, name
        self.problems: dict = {}
        self.points: dict = {}

    def problem(self, p: float):
        p = float(p)
        if p not in self.problems:
            if len(self.problems) > 16:
                self.problems.clear()
            self.problems[p] = self.make(p)
        return self.problems[p]

    def residual_jacobian(self, u: np.ndarray, p: float) -> tuple[np.ndarray, np.ndarray]:
        key = (np.asarray(u, float).tobytes(), float(p))
        if key not in self.points:
            if len(self.points) > 16:
                self.points.clear()
            self.points[key] = self.problem(p).residual_jacobian(np.asarray(u, float))
        return self.points[key]

    def F(self, u, p) -> np.ndarray:
        key = (np.asarray(u, float).tobytes(), float(p))
        if key in self.points:
            return self.points[key][0]
        return residual_only(self.problem(p), np.asarray(u, float))

    def F_p(self, u, p) -> np.ndarray:
        h = PARAM_STEP * (1.0 + abs(p))
        u = np.asarray(u, float)
        return (residual_only(self.problem(p + h), u) - residual_only(self.problem(p - h), u)) / (2 * h)

    def equations(self, weights: np.ndarray | None = None):
        """F, F_u, F_p for mechgen.runtime.steady.continuation; ``weights`` (u's size + 1, the parameter last):
        the arclength's inner product (an orbit given by its states at many nodes weighs each node's state by
        1 / nodes, so that a step measures the orbit's mean change, not the number of nodes)."""
        eqs = ParametricEquations(self.F, lambda u, p: self.residual_jacobian(u, p)[1], self.F_p,
                                  name=f"the periodic orbits in {self.name}")
        return eqs if weights is None else WeightedEquations(eqs, np.asarray(weights, float))


class WeightedEquations:
    """ParametricEquations with the continuation's ``arclength_weights``."""

    def __init__(self, eqs: ParametricEquations, weights: np.ndarray) -> None:
        self.F, self.F_u, self.F_lam, self.name = eqs.F, eqs.F_u, eqs.F_lam, eqs.name
        self.arclength_weights = weights


def node_weights(size: int, repeats: int, trailing: int, scale: float = 1.0) -> np.ndarray:
    """Weights of unknowns made of ``repeats`` equal blocks (node or segment states) followed by ``trailing``
    scalars (a period) and the parameter: scale^2 / repeats on the blocks, scale^2 on the rest, 1 on the parameter.
    ``scale`` = max(1, |p0|) of a parameter of size |p0| (a stiffness of 5e9 Pa/m) makes the arclength measure its
    relative change against the unknowns' (a fold's turn then spans steps the step control can take)."""
    w = np.full(size + 1, float(scale) ** 2)
    w[:size - trailing] /= repeats
    w[-1] = 1.0
    return w
