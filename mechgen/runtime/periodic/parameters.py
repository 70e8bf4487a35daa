"""dR/d(parameter) of a periodic-orbit problem by central differences through the compiled system's parameters.

    dR/dp ~ (R(u; p + h) - R(u; p - h)) / (2 h),   h = step (|p| + 1)   (default step 1e-6: the truncation
    error h^2 R''' / 6 and the rounding error eps |R| / h balance near the cube root of eps, 6e-6)

``make(system) -> problem`` builds the problem (HarmonicBalance or Shooting) of a system at other parameter values.
"""
from __future__ import annotations

from typing import Callable

import numpy as np


def parameter_derivative(make: Callable, system, u: np.ndarray, name: str, step: float = 1e-6) -> np.ndarray:
    """dR/d``name`` at u (module doc)."""
    value = float(system.param_values()[name])
    h = step * (abs(value) + 1.0)
    up = make(system.with_params(**{name: value + h})).residual_jacobian(u)[0]
    down = make(system.with_params(**{name: value - h})).residual_jacobian(u)[0]
    return (up - down) / (2 * h)
