"""Griffith crack in a finite plate: a slit |x| < a on y = 0 in [-W, W] x [-H, H], loaded on its four sides by
the exact tractions of the infinite plate's Griffith solution under remote sigma11, sigma22, sigma12, so that
the finite plate carries that field exactly (mechgen.symbolic.plane_fields.griffith_stress, declared here as
an analytic field of x and y). Crack faces traction-free; the rigid motions are held by pins at two corners
(``fix("u", "rigid")``: the load is self-equilibrated, so the pins carry nothing but round-off).

    V = mu eps:eps + lambda*/2 (tr eps)^2,  V_edge = -(sigma_exact n) . u   (J/m^3, J/m^2 per unit thickness)

Exact at each tip: K_I = sigma22 sqrt(pi a), K_II = sigma12 sqrt(pi a) (Pa m^0.5), T = sigma11 - sigma22 (Pa),
J = (kappa + 1)(K_I^2 + K_II^2)/(8 mu) (N/m) with kappa = 3 - 4 nu (plane strain) or (3 - nu)/(1 + nu)
(plane stress). SI units.
"""
import sympy as sp

from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import gradient, slit_plate
from mechgen.symbolic.plane_fields import griffith_stress
from mechgen.symbolic.plane_materials import linear_elastic

model = Model("cracked_plate", doc=__doc__, file=__file__)
model.params(
    Param("mu", 1.0, "Pa", "shear modulus", positive=True),
    Param("nu", 0.3, "", "Poisson's ratio", minimum=-0.99, maximum=0.49),
    Param("a", 1.0, "m", "half-length of the crack", positive=True),
    Param("W", 4.0, "m", "half-width of the plate", positive=True),
    Param("H", 4.0, "m", "half-height of the plate", positive=True),
    Param("sigma11", 0.0, "Pa", "remote stress along the crack (sets the T-stress)"),
    Param("sigma22", 1.0, "Pa", "remote stress normal to the crack (mode I)"),
    Param("sigma12", 0.0, "Pa", "remote shear stress (mode II)"),
    Param("plane", "strain", "", "plane strain or plane stress", choices=("strain", "stress")),
)
model.plane("ux", "uy", domain=slit_plate("W", "H", "a"), group="u", element="P2", h=0.25)


@model.potential_density
def potential(u, p):
    return linear_elastic(gradient(u, "ux", "uy"), 2 * p.mu * (1 + p.nu), p.nu, p.plane)


def griffith_load(u, p, n, x, y):
    """-(sigma_exact n) . u: the Griffith field's traction on an outer side does work on u."""
    sigma = griffith_stress(x, y, p.a, p.sigma11, p.sigma22, p.sigma12)
    t = sigma * sp.Matrix([n.x, n.y])
    return -(t[0] * u.ux + t[1] * u.uy)


for side in ("bottom", "right", "top", "left"):
    model.edge_potential(side)(griffith_load)


@model.boundary
def boundary():
    return [fix("u", "rigid")]
