"""A test model: a pinned-pinned column under a dead compressive load P (Euler's column).

T = rhoA w_t^2 / 2, V = EI w_ss^2 / 2 - P w_s^2 / 2, w = 0 at both ends. Small motions
w = sin(n pi s / L) e^(s t) have rhoA s^2 = P (n pi / L)^2 - EI (n pi / L)^4: the column buckles (one real
s > 0, a divergence) above the Euler load P_E = pi^2 EI / L^2, with growth rate
s = (pi / L) sqrt((P - P_E) / rhoA).
"""
from mechgen import Model, Param, fix

model = Model("euler_column", doc=__doc__)
model.params(Param("EI", 1.0, "N m^2", positive=True), Param("rhoA", 1.0, "kg/m", positive=True),
             Param("L", 1.0, "m", positive=True), Param("P", 0.0, "N"))
model.field("w", length="L", discretisation="hermite", N=4)


@model.kinetic_density
def kinetic(u, p):
    return p.rhoA / 2 * u.w_t**2


@model.potential_density
def potential(u, p):
    return p.EI / 2 * u.w_ss**2 - p.P / 2 * u.w_s**2


@model.boundary
def boundary():
    return [fix("w", "start"), fix("w", "end")]
