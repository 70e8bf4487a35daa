"""Impact oscillator: a forced, damped oscillator against a rigid stop with a coefficient of restitution.

    m x'' + c x' + k x = F cos(w t)   for x < d,      x' -> -cor x'   when x reaches d (moving towards it),

one mode ``free`` with a guard back into itself whose reset is Newton's impact law (Shaw & Holmes, "A periodically
forced piecewise linear oscillator", J. Sound Vib. 90, 1983; Thompson & Ghaffari, Phys. Lett. A 91, 1982). SI
units. Between impacts the motion is linear; the impacts make its periodic orbits bifurcate: with the stop at the
equilibrium (d = 0), cor = 0.8, c = 0.05, F = 1, the one-impact orbit period-doubles near w = 2.656 rad/s.
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("impact_oscillator", doc=__doc__, file=__file__)
model.params(Param("m", 1.0, "kg", "mass", positive=True), Param("k", 1.0, "N/m", "stiffness"),
             Param("c", 0.05, "N s/m", "damping", minimum=0.0), Param("F", 1.0, "N", "forcing amplitude"),
             Param("w", 2.5, "rad/s", "forcing frequency"), Param("d", 0.0, "m", "position of the stop"),
             Param("cor", 0.8, "-", "coefficient of restitution", minimum=0.0, maximum=1.0))
model.coordinates("x")
free = model.mode("free", initial=True)


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def drive(p, t):
    return {"x": p.F * sp.cos(p.w * t)}


@free.guard(to="free", direction="rising", reset=lambda v, p: {"x_dot": -p.cor * v.x})
def stop(q, p):
    return q.x - p.d


model.output("position", lambda q: q.x, unit="m", doc="x, the mass's displacement")
