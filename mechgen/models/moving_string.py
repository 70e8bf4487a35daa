"""Axially moving tensioned string (a band or thread line): transverse w(s, t), s in [0, L].

Material particles move at the axial speed c through the span, so their
transverse velocity is the material derivative w_t + c w_s and

    T = rhoA/2 (w_t + c w_s)^2,   V = P/2 w_s^2,   w(0) = w(L) = 0,
    rhoA (w_tt + 2 c w_st + c^2 w_ss) - P w_ss = 0.

The cross term 2 c w_t w_s gives the gyroscopic matrix; -rhoA c^2 w_s^2/2 softens
the stiffness. With c0 = sqrt(P/rhoA), the exact frequencies are
omega_n = (n pi / L) (c0^2 - c^2) / c0 (Wickert & Mote, J. Appl. Mech. 57, 1990);
all vanish at the critical speed c = c0. SI units (P in N, rhoA in kg/m, c in m/s).
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("moving_string", doc=__doc__, file=__file__)
model.params(
    Param("P", 1.0, "N", "tension", positive=True),
    Param("rhoA", 1.0, "kg/m", "mass per unit length", positive=True),
    Param("c", 0.0, "m/s", "axial speed"),
    Param("L", 1.0, "m", "span", positive=True),
)
model.field("w", length="L", discretisation="sine", N=32)


@model.kinetic_density
def kinetic(u, p):
    return p.rhoA / 2 * (u.w_t + p.c * u.w_s) ** 2


@model.potential_density
def potential(u, p):
    return p.P / 2 * u.w_s**2


@model.boundary
def boundary():
    return [fix("w", "start"), fix("w", "end")]
