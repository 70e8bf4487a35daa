"""A test model: a mass on a hardening spring under a constant load, whose origin is not an equilibrium.

T = m x'^2 / 2, V = k x^2 / 2 + b x^4 / 4 - F x. The equilibrium x* solves k x + b x^3 = F and small
motions about it have omega^2 = V''(x*) / m = (k + 3 b x*^2) / m; about the origin they would have
omega^2 = k / m, a frequency of no state the mass can rest in.
"""
from mechgen import Model, Param

model = Model("loaded_duffing", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("k", 4.0, "N/m", positive=True),
             Param("b", 2.0, "N/m^3"), Param("F", 3.0, "N"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2 + p.b * q.x**4 / 4 - p.F * q.x


model.output("position", lambda q: q.x, unit="m")
