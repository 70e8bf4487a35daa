"""Spinning Timoshenko shaft with rigid disks and bearings: lateral whirl of a rotor.

Fields on s in [0, L] (the shaft axis z, inertial frame): lateral displacements
ux, uy (m) of the centroid and the cross-section rotations psix, psiy (rad) about
x and y. The section's orientation is Rx(psix) Ry(psiy) Rz(Omega t), so its
normal is (psiy, -psix, 1) to first order: shear-free bending has psiy = ux_s and
psix = -uy_s, and the shear strains are gamma_x = ux_s - psiy, gamma_y = uy_s + psix.
With omega = (psix_t cos psiy, psiy_t, Omega + psix_t sin psiy) (the body rate,
mechgen.symbolic.kinematics.angular_velocity_cardan_xy), per unit length:

    T = rho A/2 (ux_t^2 + uy_t^2) + rotary [rho I/2 (omega_1^2 + omega_2^2) + rho Ip/2 omega_3^2],
    V = E I/2 (psix_s^2 + psiy_s^2) + kappa G A/2 (gamma_x^2 + gamma_y^2),

A = pi/4 (D^2 - d^2), I = pi/64 (D^4 - d^4), Ip = 2 I (outer diameter D, inner d).
Linearised about rest, rho Ip Omega psix_t psiy gives the gyroscopic matrix G
(skew, proportional to Omega). The shear coefficient kappa is ``shear_kappa`` for
``shear = "constant"``, else Cowper's (1966) value for a hollow circular section,

    kappa = 6 (1 + nu)(1 + m^2)^2 / ((7 + 6 nu)(1 + m^2)^2 + (20 + 12 nu) m^2),  m = d/D,

with nu = E/(2 G) - 1, or Hutchinson's (2001),

    kappa = 6 (1 + nu)(1 + m^2)^2 / ((7 + 12 nu + 4 nu^2)(1 + m^2)^2 + 4 (5 + 6 nu + 2 nu^2) m^2).

``rotary = 0`` drops the rotary and
polar inertia (with a large G: the Euler-Bernoulli shaft; rotary = 1 and large G:
Rayleigh's).

Parts placed by a scene (``[[parts]]`` with ``kind`` and ``at`` = s in m):

* ``disk``: rigid disk, T = m/2 (ux_t^2 + uy_t^2) + Id/2 (omega_1^2 + omega_2^2) + Ip/2 omega_3^2,
  with m, Id, Ip given, plus those of a solid of revolution of density ``rho``, width
  ``width`` and diameters ``outer``/``inner``: m_g = rho pi/4 (outer^2 - inner^2) width,
  Ip_g = m_g (outer^2 + inner^2)/8, Id_g = Ip_g/2 + m_g width^2/12.
* ``bearing``: linear support forces -[kxx kxy; kyx kyy](ux, uy) - [cxx cxy; cyx cyy](ux_t, uy_t)
  (a weak form: cross-coupled terms need not be symmetric).

Ends (``bc`` = start-end): free, pinned (ux = uy = 0), clamped (all four fields 0).
A stepped shaft is a scene's ``[[segments]]`` (length, elements, and D, d, E,
G_s, rho per segment; E_s is Young's modulus (E is sympy's e)). SI units; frequencies in rad/s.
"""
import sympy as sp

from mechgen.symbolic.field import fix_ends
from mechgen.symbolic.kinematics import angular_velocity_cardan_xy
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

BCS = ("free-free", "pinned-pinned", "clamped-free", "clamped-clamped", "clamped-pinned", "free-clamped",
       "pinned-free", "free-pinned")

model = Model("spinning_shaft", doc=__doc__, file=__file__)
model.params(
    Param("E_s", 211e9, "Pa", "Young's modulus", positive=True),
    Param("G_s", 81.2e9, "Pa", "shear modulus", positive=True),
    Param("rho", 7810.0, "kg/m^3", "density", positive=True),
    Param("D", 0.05, "m", "outer diameter", positive=True),
    Param("d", 0.0, "m", "inner diameter (0: solid)"),
    Param("L", 1.5, "m", "length (the sum of the segments' lengths when a scene gives segments)", positive=True),
    Param("Omega", 0.0, "rad/s", "spin speed"),
    Param("rotary", 1.0, "", "rotary and polar inertia factor (1: on, 0: off)"),
    Param("shear", "cowper", "", "shear coefficient", choices=("cowper", "hutchinson", "constant")),
    Param("shear_kappa", 0.9, "", "shear coefficient when shear = 'constant'", positive=True),
    Param("bc", "free-free", "", "end conditions (start-end)", choices=BCS),
)
model.field("ux", "uy", "psix", "psiy", length="L", discretisation="quintic", N=8)
model.shear_pair("ux", "psiy")
model.shear_pair("uy", "psix", sign=-1)
model.whirl_pair("ux", "uy")
model.part("disk", Param("m", 0.0, "kg", "mass"), Param("Id", 0.0, "kg m^2", "diametral moment of inertia"),
           Param("Ip", 0.0, "kg m^2", "polar moment of inertia"), Param("rho", 0.0, "kg/m^3", "density"),
           Param("width", 0.0, "m", "axial width"), Param("outer", 0.0, "m", "outer diameter"),
           Param("inner", 0.0, "m", "inner (bore) diameter"),
           checks={"inner": ("inner < outer or inner == 0 and outer == 0",
                             "an inner (bore) diameter below the outer diameter (both 0: no disk geometry)")})
model.part("bearing", *(Param(f"k{ij}", 0.0, "N/m", f"stiffness {ij}") for ij in ("xx", "xy", "yx", "yy")),
           *(Param(f"c{ij}", 0.0, "N s/m", f"damping {ij}") for ij in ("xx", "xy", "yx", "yy")))

_END = {"free": (), "pinned": ("ux", "uy"), "clamped": ("ux", "uy", "psix", "psiy")}


def section(p):
    """(A, I, kappa) of the hollow circular section of outer diameter D and inner d."""
    A = sp.pi / 4 * (p.D**2 - p.d**2)
    I = sp.pi / 64 * (p.D**4 - p.d**4)  # noqa: E741
    nu = p.E_s / (2 * p.G_s) - 1
    m2 = (p.d / p.D) ** 2
    if p.shear == "constant":
        kappa = p.shear_kappa
    elif p.shear == "cowper":
        kappa = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
    else:
        kappa = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 12 * nu + 4 * nu**2) * (1 + m2) ** 2
                                                + 4 * (5 + 6 * nu + 2 * nu**2) * m2)
    return A, I, kappa


def body_rate(u, p):
    """Angular velocity of the section (tilts psix, psiy, spin Omega)."""
    return angular_velocity_cardan_xy(u.psix, u.psiy, u.psix_t, u.psiy_t, p.Omega)


@model.kinetic_density
def kinetic(u, p):
    A, I, _ = section(p)
    w = body_rate(u, p)
    return p.rho * A / 2 * (u.ux_t**2 + u.uy_t**2) + p.rotary * p.rho * I / 2 * (w[0] ** 2 + w[1] ** 2 + 2 * w[2] ** 2)


@model.potential_density
def potential(u, p):
    A, I, kappa = section(p)
    return p.E_s * I / 2 * (u.psix_s**2 + u.psiy_s**2) + kappa * p.G_s * A / 2 * (
        (u.ux_s - u.psiy) ** 2 + (u.uy_s + u.psix) ** 2)


@model.point_kinetic("disk")
def disk(u, p, part):
    m_g = part.rho * sp.pi / 4 * (part.outer**2 - part.inner**2) * part.width
    Ip = part.Ip + m_g * (part.outer**2 + part.inner**2) / 8
    Id = part.Id + m_g * (part.outer**2 + part.inner**2) / 16 + m_g * part.width**2 / 12
    w = body_rate(u, p)
    return (part.m + m_g) / 2 * (u.ux_t**2 + u.uy_t**2) + Id / 2 * (w[0] ** 2 + w[1] ** 2) + Ip / 2 * w[2] ** 2


@model.point_weak_form("bearing")
def bearing(test, u, part):
    fx = part.kxx * u.ux + part.kxy * u.uy + part.cxx * u.ux_t + part.cxy * u.uy_t
    fy = part.kyx * u.ux + part.kyy * u.uy + part.cyx * u.ux_t + part.cyy * u.uy_t
    return test.ux * fx + test.uy * fy


@model.boundary
def boundary(p):
    return fix_ends(p.bc, _END)
