"""van der Pol oscillator: a self-excited oscillator with a limit cycle.

    x'' - mu (1 - x^2) x' + x = 0,

declared as T = x'^2 / 2, V = x^2 / 2 and the generalised force Q = mu (1 - x^2) x' (negative damping for
|x| < 1, positive beyond). Dimensionless: x and t scaled by the linear oscillator's amplitude and 1 / omega_0. For
mu > 0 every motion but the rest state tends to one limit cycle, of period 2 pi (1 + mu^2/16 + O(mu^4)) and
amplitude 2 + O(mu^2) for small mu (6.6632868593 for mu = 1).
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("van_der_pol", doc=__doc__, file=__file__)
model.params(Param("mu", 1.0, "-", "nonlinear damping coefficient", minimum=0.0))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q):
    return q.x**2 / 2


@model.forces
def forces(q, v, p):
    return {"x": p.mu * (1 - q.x**2) * v.x}


model.output("position", lambda q: q.x, unit="-", doc="x, the oscillator's displacement")
