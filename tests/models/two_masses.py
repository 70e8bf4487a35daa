"""A test model: two masses on three springs (ground - m1 - m2 - ground), a linear lumped system.

T = (m1 x1'^2 + m2 x2'^2) / 2, V = (k1 x1^2 + k12 (x2 - x1)^2 + k2 x2^2) / 2 (SI units).
"""
from mechgen import Model, Param

model = Model("two_masses", doc=__doc__)
model.params(Param("m1", 1.0, "kg", positive=True), Param("m2", 2.0, "kg", positive=True),
             Param("k1", 4.0e4, "N/m"), Param("k12", 2.0e4, "N/m"), Param("k2", 6.0e4, "N/m"))
model.coordinates("x1", "x2")


@model.kinetic
def kinetic(v, p):
    return (p.m1 * v.x1**2 + p.m2 * v.x2**2) / 2


@model.potential
def potential(q, p):
    return (p.k1 * q.x1**2 + p.k12 * (q.x2 - q.x1) ** 2 + p.k2 * q.x2**2) / 2
