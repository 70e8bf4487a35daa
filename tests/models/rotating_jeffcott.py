"""A test model: a Jeffcott rotor seen from a frame spinning at Omega (two degrees of freedom, a whirl pair).

x, y in the frame rotating at Omega: T = m ((x' - Omega y)^2 + (y' + Omega x)^2) / 2, V = k (x^2 + y^2) / 2.
With w0 = sqrt(k / m) the frame sees the two whirls at |w0 - Omega| and w0 + Omega.
"""
from mechgen import Model, Param

model = Model("rotating_jeffcott", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("k", 100.0, "N/m", positive=True),
             Param("Omega", 0.0, "rad/s"))
model.coordinates("x", "y")
model.whirl_pair("x", "y")


@model.kinetic
def kinetic(v, q, p):
    return p.m * ((v.x - p.Omega * q.y) ** 2 + (v.y + p.Omega * q.x) ** 2) / 2


@model.potential
def potential(q, p):
    return p.k * (q.x**2 + q.y**2) / 2
