"""A test model: a free mass pushed by a constant force, which has no equilibrium at all.

T = m x'^2 / 2, V = -F x: the static residual is -F everywhere and K = 0, so Newton cannot find a rest
point and small-motion analyses must refuse instead of linearising about a point the mass never rests at.
"""
from mechgen import Model, Param

model = Model("pushed_mass", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("F", 3.0, "N"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return -p.F * q.x
