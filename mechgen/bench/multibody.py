"""``mechgen bench multibody``: the n-link planar pendulum, the scaling problem of symbolic multibody tools.

n rigid massless links of length l, a point mass m at the end of each, angles theta_i from the downward
vertical, written as a user writes it (:func:`pendulum_model`): with x_k = l sum_{i<=k} sin(theta_i),
y_k = -l sum_{i<=k} cos(theta_i),

    T = m/2 sum_k (x_k'^2 + y_k'^2),      V = m g sum_k y_k        (SI units).

Its equations of motion in closed form (the independent reference of the tests) are

    sum_j m l^2 c_ij [cos(theta_i - theta_j) a_j + sin(theta_i - theta_j) w_j^2] + m g l (n - i) sin(theta_i) = 0,

c_ij = n - max(i, j) the number of masses beyond both links (0-based i, j).
"""
from __future__ import annotations

import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param


def pendulum_model(n: int) -> Model:
    """The n-link planar pendulum as a mechgen model ``pendulum<n>`` (coordinates theta0 ... theta<n-1>)."""
    model = Model(f"pendulum{n}", doc=f"{n}-link planar pendulum, point masses at the link ends")
    model.params(Param("m", 1.0, "kg", "mass at each link end", positive=True),
                 Param("l", 1.0, "m", "link length", positive=True),
                 Param("g", 9.81, "m/s^2", "gravity"))
    names = [f"theta{i}" for i in range(n)]
    model.coordinates(*names)

    @model.kinetic
    def kinetic(q, v, p):
        xd = yd = T = 0
        for name in names:
            xd += p.l * sp.cos(q[name]) * v[name]
            yd += p.l * sp.sin(q[name]) * v[name]
            T += p.m / 2 * (xd**2 + yd**2)
        return T

    @model.potential
    def potential(q, p):
        y = V = 0
        for name in names:
            y -= p.l * sp.cos(q[name])
            V += p.m * p.g * y
        return V

    return model
