"""A test model: three equal masses joined by two equal springs, nothing holding them (a free chain).

T = m (x1'^2 + x2'^2 + x3'^2) / 2, V = k ((x2 - x1)^2 + (x3 - x2)^2) / 2. K has one null vector, the rigid
translation (1, 1, 1); the elastic modes have omega^2 = k/m and 3 k/m (the free-free chain of three).
"""
from mechgen import Model, Param

model = Model("free_chain", doc=__doc__)
model.params(Param("m", 2.0, "kg", positive=True), Param("k", 50.0, "N/m", positive=True))
model.coordinates("x1", "x2", "x3")


@model.kinetic
def kinetic(v, p):
    return p.m * (v.x1**2 + v.x2**2 + v.x3**2) / 2


@model.potential
def potential(q, p):
    return p.k * ((q.x2 - q.x1) ** 2 + (q.x3 - q.x2) ** 2) / 2
