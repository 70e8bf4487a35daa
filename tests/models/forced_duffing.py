"""A test model: the forced, damped Duffing oscillator m x'' + c x' + k x + k3 x^3 = F cos(w t).

T = m x'^2 / 2, V = k x^2 / 2 + k3 x^4 / 4, Rayleigh R = c x'^2 / 2, generalised force F cos(w t) on x.
Its power balance: d(T + V)/dt = F cos(w t) x' - c x'^2.
"""
import sympy as sp

from mechgen import Model, Param

model = Model("forced_duffing", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("c", 0.05, "N s/m", minimum=0.0),
             Param("k", 1.0, "N/m"), Param("k3", 0.5, "N/m^3"), Param("F", 0.3, "N"), Param("w", 1.2, "rad/s"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2 + p.k3 * q.x**4 / 4


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def forces(p, t):
    return {"x": p.F * sp.cos(p.w * t)}


model.output("position", lambda q: q.x, unit="m")
