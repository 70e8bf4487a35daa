"""Annulus under in-plane gravity: a < r < b, inner edge free, outer edge fixed, its own weight acting in -y.

Plane stress (or ``plane = "strain"``) linear elasticity in the displacement (ux, uy), as the circular
membrane (mechgen.models.membrane_gravity):

    V = mu eps:eps + lambda*/2 (tr eps)^2 + rho_g u_y   (J/m^3),   u = 0 on r = b,   sigma n = 0 on r = a.

The traction-free hole makes the solution non-polynomial: Michell's n = 1 terms (r^3, r, r^-1, r ln r
times sin/cos theta) carry it (mechgen.runtime.plane.closed_forms); the finite element solution converges to
it. Outputs: the strain energy (J per unit thickness). SI units.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import annulus, gradient
from mechgen.symbolic.plane_materials import linear_elastic

model = Model("annulus_gravity", doc=__doc__, file=__file__)
model.params(
    Param("E", 1.0, "Pa", "Young's modulus", positive=True),
    Param("nu", 0.3, "", "Poisson's ratio", minimum=-0.99, maximum=0.49),
    Param("rho_g", 1.0, "N/m^3", "weight per unit volume, acting in -y"),
    Param("rho", 1.0, "kg/m^3", "density (the in-plane vibration modes)", positive=True),
    Param("a", 0.5, "m", "inner radius (free edge)", positive=True),
    Param("b", 1.0, "m", "outer radius (fixed edge)", positive=True),
    Param("plane", "stress", "", "plane stress (a thin disk) or plane strain (a long tube)",
          choices=("stress", "strain")),
)
model.plane("ux", "uy", domain=annulus("a", "b"), group="u", element="P2", h=0.1)


def strain_energy(u, p):
    """mu eps:eps + lambda*/2 (tr eps)^2 (J/m^3)."""
    return linear_elastic(gradient(u, "ux", "uy"), p.E, p.nu, p.plane)


@model.potential_density
def potential(u, p):
    return strain_energy(u, p) + p.rho_g * u.uy


@model.kinetic_density
def kinetic(u, p):
    return p.rho / 2 * (u.ux_t**2 + u.uy_t**2)


@model.boundary
def boundary():
    return [fix("u", "outer")]


model.output("strain_energy", strain_energy, unit="J/m", doc="stored elastic energy per unit thickness")
