"""Circular membrane under in-plane gravity: a disk of radius R fixed at its rim, loaded by its own weight in -y.

Plane stress (``plane = "strain"`` for a long cylinder) linear elasticity in the displacement (ux, uy):

    V = mu eps:eps + lambda*/2 (tr eps)^2 + rho_g u_y   (J/m^3: energy per unit area and unit thickness),
    eps = (grad u + grad u^T)/2,  mu = E/(2(1+nu)),  lambda* = E nu/(1-nu^2) (plane stress),

so that div sigma = (0, rho_g): the weight per unit volume rho_g (N/m^3) acts in -y. Michell's
general solution gives the exact field (mechgen.runtime.plane.closed_forms): u_x = 0,
u_y = -rho_g (R^2 - r^2) / (2 (lambda* + 3 mu)), a quadratic that P2 elements reproduce on a disk
whose curved rim they follow. Outputs: the strain energy U = int mu eps:eps + lambda*/2 (tr eps)^2 dA
(J per unit thickness). SI units.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import disk, gradient
from mechgen.symbolic.plane_materials import linear_elastic

model = Model("membrane_gravity", doc=__doc__, file=__file__)
model.params(
    Param("E", 1.0, "Pa", "Young's modulus", positive=True),
    Param("nu", 0.3, "", "Poisson's ratio", minimum=-0.99, maximum=0.49),
    Param("rho_g", 1.0, "N/m^3", "weight per unit volume, acting in -y"),
    Param("rho", 1.0, "kg/m^3", "density (the in-plane vibration modes)", positive=True),
    Param("R", 1.0, "m", "radius", positive=True),
    Param("plane", "stress", "", "plane stress (a thin disk) or plane strain (a long cylinder)",
          choices=("stress", "strain")),
)
model.plane("ux", "uy", domain=disk("R"), group="u", element="P2", h=0.25)


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
