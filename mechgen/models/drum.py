"""Circular drum: a membrane of radius R under uniform tension, transverse deflection w(x, y, t), fixed rim.

    T = rho/2 w_t^2,   V = P/2 (w_x^2 + w_y^2) - q w   (per unit area),
    rho w_tt - P (w_xx + w_yy) = q,   w = 0 on r = R,

with P the tension per unit length (N/m), rho the mass per unit area (kg/m^2) and q a uniform pressure
(Pa). Exact: the natural frequencies are omega_mn = j_mn / R sqrt(P / rho) rad/s, j_mn the n-th zero of
the Bessel function J_m (each m >= 1 twice: cos and sin m theta); the static deflection under q is
w = q (R^2 - r^2) / (4 P). SI units.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import disk

model = Model("drum", doc=__doc__, file=__file__)
model.params(
    Param("P", 1.0, "N/m", "tension per unit length", positive=True),
    Param("rho", 1.0, "kg/m^2", "mass per unit area", positive=True),
    Param("q", 0.0, "Pa", "uniform transverse pressure"),
    Param("R", 1.0, "m", "radius", positive=True),
)
model.plane("w", domain=disk("R"), element="P2", h=0.15)


@model.kinetic_density
def kinetic(u, p):
    return p.rho / 2 * u.w_t**2


@model.potential_density
def potential(u, p):
    return p.P / 2 * (u.w_x**2 + u.w_y**2) - p.q * u.w


@model.boundary
def boundary():
    return [fix("w", "outer")]
