"""Elastic (spring) pendulum: a point mass on a linear spring swinging in gravity.

Polar coordinates r (m, spring length) and theta (rad, from the downward vertical):

    T = m/2 (r'^2 + r^2 theta'^2),   V = k/2 (r - l0)^2 - m g r cos(theta).

Equilibrium r_eq = l0 + m g / k, theta = 0; small oscillations have the spring
frequency sqrt(k/m) and the pendulum frequency sqrt(g / r_eq) (rad/s).
The total energy T + V is conserved. SI units.
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("spring_pendulum", doc=__doc__, file=__file__)
model.params(
    Param("m", 1.0, "kg", "mass", positive=True),
    Param("k", 40.0, "N/m", "spring stiffness", positive=True),
    Param("l0", 1.0, "m", "unstretched spring length", positive=True),
    Param("g", 9.81, "m/s^2", "gravity"),
)
model.coordinates("r", "theta")


@model.kinetic
def kinetic(q, v, p):
    return p.m / 2 * (v.r**2 + q.r**2 * v.theta**2)


@model.potential
def potential(q, p):
    return p.k / 2 * (q.r - p.l0) ** 2 - p.m * p.g * q.r * sp.cos(q.theta)


model.output("x", lambda q: q.r * sp.sin(q.theta), unit="m", doc="horizontal position of the mass")
model.output("y", lambda q: -q.r * sp.cos(q.theta), unit="m", doc="vertical position of the mass")
