"""A rectangular block on rollers under dead loads: large homogeneous deformations of a plane law.

The block 0 < x < Lx, 0 < y < Ly rests on rollers (u_x = 0 on ``left``, u_y = 0 on ``bottom``; ``support =
"clamped"``: u = 0 on ``left``, a non-homogeneous state) and carries
dead (nominal) tractions P on ``right`` (in +x) and Q on ``top`` (in +y), per unit reference length:

    V = W(grad u) (J/m^3),  V_right = -P u_x,  V_top = -Q u_y   (J/m^2 per unit thickness),

W the plane law ``law`` (linear, saint_venant_kirchhoff, neo_hookean: mechgen.symbolic.plane_materials) in
plane strain or stress (``plane``). The exact state is homogeneous, F = diag(l1, l2), with the first Piola
stresses P_11 = dW/dl1 = P, P_22 = dW/dl2 = Q; every element holds it (u is linear), so the discrete solution is
exact to round-off. Saint Venant-Kirchhoff in plane strain, uniaxial (Q = 0): P = E' l (l^2 - 1)/2 with
E' = E/(1 - nu^2), a limit point at l = 1/sqrt(3), P = -E'/(3 sqrt 3) in compression. SI units.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.plane import gradient, rectangle
from mechgen.symbolic.plane_materials import LAWS, plane_law

model = Model("plane_block", doc=__doc__, file=__file__)
model.params(
    Param("E", 1.0, "Pa", "Young's modulus", positive=True),
    Param("nu", 0.3, "", "Poisson's ratio", minimum=-0.99, maximum=0.49),
    Param("P", 0.1, "Pa", "nominal (dead) traction on the right edge, +x"),
    Param("Q", 0.0, "Pa", "nominal (dead) traction on the top edge, +y"),
    Param("rho", 1.0, "kg/m^3", "density (modes)", positive=True),
    Param("Lx", 2.0, "m", "length", positive=True),
    Param("Ly", 1.0, "m", "height", positive=True),
    Param("law", "neo_hookean", "", "plane law (mechgen.symbolic.plane_materials)", choices=tuple(LAWS)),
    Param("support", "rollers", "", "rollers (u_x = 0 on left, u_y = 0 on bottom: homogeneous states) or clamped "
          "(u = 0 on left: a non-homogeneous state)", choices=("rollers", "clamped")),
    Param("plane", "strain", "", "plane strain (eps_33 = 0) or plane stress (sigma_33 = 0; an incompressible "
          "neo-Hookean sheet)", choices=("strain", "stress")),
)
model.plane("ux", "uy", domain=rectangle("Lx", "Ly"), group="u", element="P1", h=0.5)


def strain_energy(u, p):
    """W(grad u) of the chosen law (J/m^3)."""
    return plane_law(p.law, gradient(u, "ux", "uy"), p.E, p.nu, p.plane)


@model.potential_density
def potential(u, p):
    return strain_energy(u, p)


@model.kinetic_density
def kinetic(u, p):
    return p.rho / 2 * (u.ux_t**2 + u.uy_t**2)


@model.edge_potential("right")
def pull(u, p, n):
    return -p.P * u.ux


@model.edge_potential("top")
def lift(u, p, n):
    return -p.Q * u.uy


@model.boundary
def boundary(p):
    if p.support == "clamped":
        return [fix("u", "left")]
    return [fix("ux", "left"), fix("uy", "bottom")]


model.output("strain_energy", strain_energy, unit="J/m", doc="stored elastic energy per unit thickness")
