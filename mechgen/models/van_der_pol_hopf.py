"""van der Pol's oscillator in its Hopf form: the rest state becomes a limit cycle through a Hopf point.

    x'' - (mu - x^2) x' + x = 0,

declared as T = x'^2 / 2, V = x^2 / 2 and the generalised force Q = (mu - x^2) x'. The rest state x = 0 loses
stability at mu = 0 through the pair +-i (a supercritical Hopf point: averaging gives dr/dt = r (mu - r^2/4) / 2,
a cycle of amplitude 2 sqrt(mu)). For mu > 0 the substitution x = sqrt(mu) y gives van der Pol's equation
y'' - mu (1 - y^2) y' + y = 0 (the built-in ``van_der_pol``): the same period, 6.6632868593 at mu = 1, and the
amplitude sqrt(mu) times van der Pol's. Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("van_der_pol_hopf", doc=__doc__, file=__file__)
model.params(Param("mu", -0.5, "-", "the distance past the Hopf point (negative damping)"))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q):
    return q.x**2 / 2


@model.forces
def forces(q, v, p):
    return {"x": (p.mu - q.x**2) * v.x}


model.output("position", lambda q: q.x, unit="-", doc="x, the oscillator's displacement")
