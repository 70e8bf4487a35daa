"""A test model: Ziegler's column, two rigid bars under a follower force, with joint dashpots.

Two bars of length l, absolute angles phi1, phi2 from the vertical; a mass 2m at the middle joint and m at
the tip; rotational springs c at both joints; a compressive follower force P at the tip that stays along
the upper bar; dashpots d1 (lower joint) and d2 (upper joint) on the relative rotations (Ziegler,
Ing.-Arch. 20 (1952) 49-56; Kirillov, Nonconservative Stability Problems of Modern Physics, 2013, ch. 1):

    T = m l^2 (3 phi1'^2 / 2 + phi2'^2 / 2 + phi1' phi2' cos(phi2 - phi1)),
    V = c phi1^2 / 2 + c (phi2 - phi1)^2 / 2,   R = d1 phi1'^2 / 2 + d2 (phi2' - phi1')^2 / 2,
    Q_phi1 = -P l sin(phi2 - phi1),  Q_phi2 = 0   (virtual work of the force -P (sin phi2, cos phi2) at the tip).

Linearised: M = m l^2 [[3, 1], [1, 1]], C = [[d1 + d2, -d2], [-d2, d2]], K = [[2c - P l, P l - c], [-c, c]].
"""
import sympy as sp

from mechgen import Model, Param

model = Model("ziegler_column", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("l", 1.0, "m", positive=True),
             Param("c", 1.0, "N m/rad", positive=True), Param("P", 0.0, "N"),
             Param("d1", 0.0, "N m s/rad"), Param("d2", 0.0, "N m s/rad"))
model.coordinates("phi1", "phi2")


@model.kinetic
def kinetic(q, v, p):
    return p.m * p.l**2 * (sp.Rational(3, 2) * v.phi1**2 + v.phi2**2 / 2
                           + v.phi1 * v.phi2 * sp.cos(q.phi2 - q.phi1))


@model.potential
def potential(q, p):
    return p.c * q.phi1**2 / 2 + p.c * (q.phi2 - q.phi1) ** 2 / 2


@model.dissipation
def dissipation(v, p):
    return p.d1 * v.phi1**2 / 2 + p.d2 * (v.phi2 - v.phi1) ** 2 / 2


@model.forces
def follower(q, p):
    return {"phi1": -p.P * p.l * sp.sin(q.phi2 - q.phi1)}
