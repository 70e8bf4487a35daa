"""Forced, damped Duffing oscillator: the classic hardening or softening nonlinear resonance.

    m x'' + c x' + k x + k3 x^3 = F cos(w t),

declared as T = m x'^2 / 2, V = k x^2 / 2 + k3 x^4 / 4, R = c x'^2 / 2 and the force F cos(w t). SI units (m,
kg, N, rad/s). k3 > 0 hardens the spring (the resonance bends to higher frequencies), k3 < 0 softens it. To
first order in harmonic balance, x ~ A cos(w t - phase) with

    ((k - m w^2 + 3/4 k3 A^2)^2 + (c w)^2) A^2 = F^2,

the backbone w^2 = (k + 3/4 k3 A^2) / m and, between two cyclic folds, three orbits (the middle one unstable)
(Nayfeh & Mook, Nonlinear Oscillations, 1979, sec. 4.1).
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("duffing", doc=__doc__, file=__file__)
model.params(Param("m", 1.0, "kg", "mass", positive=True), Param("c", 0.1, "N s/m", "damping", minimum=0.0),
             Param("k", 1.0, "N/m", "linear stiffness"), Param("k3", 1.0, "N/m^3", "cubic stiffness"),
             Param("F", 0.3, "N", "forcing amplitude"), Param("w", 1.0, "rad/s", "forcing frequency"))
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


model.output("position", lambda q: q.x, unit="m", doc="x, the mass's displacement")
