"""The rules the variational integrator's two steppers share: the Python one (mechgen.runtime.core.variational)
and the compiled loop (mechgen.runtime.core.variational_c): Newton's stop (NEWTON_RTOL, STALL, MAX_NEWTON), the
Gauss-Legendre tableaux and the errors of a failed step."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mechgen.errors import ConvergenceError

#: Newton stops when its correction is below this many times the velocity scale (quadratic convergence
#: puts the accepted point far below it), or when it stalls at round-off below STALL of the scale
NEWTON_RTOL = 1e-13
STALL = 1e-9
MAX_NEWTON = 25
STAGES = (1, 2, 3)


@dataclass(frozen=True)
class Tableau:
    """Gauss-Legendre coefficients of ``stages`` points on [0, 1]: a (s x s), b (s), c (s); order 2 s."""

    stages: int
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray

    @property
    def order(self) -> int:
        """The classical order 2 s."""
        return 2 * self.stages


def gauss_legendre(stages: int) -> Tableau:
    """The s-stage Gauss-Legendre tableau (Hairer, Norsett & Wanner I, Table II.7.3-7.4), s = 1, 2, 3."""
    if stages == 1:
        return Tableau(1, np.array([[0.5]]), np.array([1.0]), np.array([0.5]))
    if stages == 2:
        r = math.sqrt(3.0) / 6.0
        a = np.array([[0.25, 0.25 - r], [0.25 + r, 0.25]])
        return Tableau(2, a, np.array([0.5, 0.5]), np.array([0.5 - r, 0.5 + r]))
    if stages == 3:
        r = math.sqrt(15.0)
        a = np.array([[5 / 36, 2 / 9 - r / 15, 5 / 36 - r / 30],
                      [5 / 36 + r / 24, 2 / 9, 5 / 36 - r / 24],
                      [5 / 36 + r / 30, 2 / 9 + r / 15, 5 / 36]])
        return Tableau(3, a, np.array([5 / 18, 4 / 9, 5 / 18]), np.array([0.5 - r / 10, 0.5, 0.5 + r / 10]))
    raise ValueError(f"Gauss-Legendre tableaux are tabulated for stages in {STAGES}, not {stages}")


def singular(t: float) -> ConvergenceError:
    """The error of a singular Newton matrix."""
    return ConvergenceError(f"variational: the Newton matrix of the step from t = {t:.6g} is singular (the mass "
                            "matrix dp/dv is singular: a coordinate without inertia? The variational integrator "
                            "needs a regular Lagrangian)")


def newton_failure(t: float, h: float) -> ConvergenceError:
    """The error of stage equations that Newton did not solve within MAX_NEWTON iterations."""
    return ConvergenceError(f"variational: the stage equations of the step from t = {t:.6g} did not converge in "
                            f"{MAX_NEWTON} Newton iterations; the step h = {h:.6g} is too large for the motion "
                            "there: a smaller dt")


def nonfinite(t: float) -> ConvergenceError:
    """The error of a state or a Newton correction that is no longer finite."""
    return ConvergenceError(f"variational: the state became NaN/Inf in the step from t = {t:.6g} (a smaller dt?)")
