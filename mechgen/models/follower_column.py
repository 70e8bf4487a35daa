"""Beck's column: a cantilever under a tangential (follower) end load P, a non-conservative system.

Deflection w(s, t), s in [0, L], clamped at s = 0, free at s = L, where a
compressive force P stays tangent to the deformed axis. Conservative part
(energy per unit length) and the follower load's virtual work at the tip:

    T = rhoA/2 w_t^2,   V = EI/2 w_ss^2 - P/2 w_s^2,   W_L = P w_s(L) test(L)

(weak form: int rhoA w_tt v + EI w_ss v_ss - P w_s v_s ds + P w_s(L) v(L) = 0, i.e.
EI w_ssss + P w_ss + rhoA w_tt = 0 with w''(L) = w'''(L) = 0). The tip term makes
the stiffness non-symmetric: the column never buckles statically but flutters
when the two lowest frequencies merge, at P_cr = 20.05 EI/L^2 (Beck, Z. angew.
Math. Phys. 3, 1952). SI units.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("follower_column", doc=__doc__, file=__file__)
model.params(
    Param("EI", 1.0, "N m^2", "bending stiffness", positive=True),
    Param("rhoA", 1.0, "kg/m", "mass per unit length", positive=True),
    Param("L", 1.0, "m", "length", positive=True),
    Param("P", 0.0, "N", "compressive follower load at the free end"),
)
model.field("w", length="L", discretisation="hermite", N=32)


@model.kinetic_density
def kinetic(u, p):
    return p.rhoA / 2 * u.w_t**2


@model.potential_density
def potential(u, p):
    return p.EI / 2 * u.w_ss**2 - p.P / 2 * u.w_s**2


@model.point_weak_form("end")
def follower(test, u, p):
    return p.P * u.w_s * test.w


@model.boundary
def boundary():
    return [fix("w", "start"), fix("w_s", "start")]
