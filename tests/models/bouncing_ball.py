"""A test model: a bouncing ball, flight under gravity; y falling through 0 resets y' -> -cor y'.

Dropped from rest at height h: the first impact at t1 = sqrt(2 h / g), the accumulation (Zeno) time
T = t1 (1 + e) / (1 - e), and after k impacts the resets have taken m g h (1 - e^(2k)).
"""
from mechgen import Model, Param

model = Model("test_bouncing_ball", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("g", 9.81, "m/s^2", positive=True),
             Param("cor", 0.8, "", minimum=0.0))
model.coordinates("y")
flight = model.mode("flight")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@flight.guard(to="flight", direction="falling", reset=lambda v, p: {"y_dot": -p.cor * v.y})
def floor(q):
    return q.y
