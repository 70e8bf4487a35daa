"""A system's equilibrium equations as functions of two of its parameters: :class:`Parametrised`, what the curves
of special points (mechgen.analyses.special_curves) and the cycles born at a Hopf point
(mechgen.analyses.hopf_cycles) solve."""
from __future__ import annotations

import numpy as np

from mechgen.analyses.steady import equilibrium_functions


class Parametrised:
    """F, F_y and the first-order A of ``system`` at two parameter values (a memo of the last few systems)."""

    def __init__(self, system, first: str, second: str) -> None:
        self.system, self.first, self.second = system, first, second
        self.memo: dict = {}

    def at(self, a: float, b: float):
        key = (float(a), float(b))
        if key not in self.memo:
            if len(self.memo) > 16:
                self.memo.clear()
            moved = self.system.with_params(**{self.first: key[0], self.second: key[1]})
            self.memo[key] = (moved, *equilibrium_functions(moved))
        return self.memo[key]

    def residual(self, y, a, b):
        return np.asarray(self.at(a, b)[1](y), float)

    def jacobian(self, y, a, b):
        J = self.at(a, b)[2](y)
        return J.toarray() if hasattr(J, "toarray") else np.asarray(J, float)

    def state_jacobian(self, y, a, b):
        moved, n = self.at(a, b)[0], self.system.n
        return np.asarray(moved.jacobian(0.0, np.concatenate([y[:n], np.zeros(n), y[n:]])), float)
