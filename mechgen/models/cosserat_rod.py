"""Geometrically exact (Cosserat) rod: an initially straight rod of length L along x from the origin.

Seed 001 (Grazioso, "Modeling of a soft link"): poses H(s) in SE(3), twist f = vee6(H^-1 H') = (nu, kappa),
strain eps = f - f0 with f0 = (1, 0, 0, 0, 0, 0), strain energy

    V = 1/2 int_0^L eps^T K eps ds,   K = diag(EA, GA, GA, GJ, EI, EI)   (principal section axes),

equilibrium (mechgen.runtime.rods.statics)  n' + kappa x n + R^T q = 0,  m' + kappa x m + nu x n + R^T l = 0
with sigma = (n, m) = K eps. The distributed load per unit length (spatial frame) is gravity and, for a rod
steadily rotating at omega about the z axis through the origin (seen in the co-rotating frame), the
centrifugal force:

    q = rhoA (g_x, g_y, g_z) + rhoA omega^2 (x, y, 0)    (N/m),   l = 0.

The kinetic energy is 1/2 int eta^T M eta ds with the velocity twist eta = (R^T r_t, omega) and
M = diag(rhoA, rhoA, rhoA, rhoJ, rhoI, rhoI) (the ``rod_dynamics`` analysis; a rod at rest in statics needs none).

SI units: EA, GA in N, GJ, EI in N m^2, rhoA in kg/m, rhoI, rhoJ in kg m, g in m/s^2, omega in rad/s. The
``rod_statics`` analysis takes the ends, the tip force and torque and the discretisation; ``rod_dynamics``
the ends, loads, time step and damping; the ``cross_section`` analysis reports K.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.rod import rod_inertia, rod_stiffness

model = Model("cosserat_rod", doc=__doc__, file=__file__)
model.params(
    Param("L", 1.0, "m", "reference length", positive=True),
    Param("EA", 1.0e4, "N", "axial stiffness"),
    Param("GA", 1.0e4, "N", "shear stiffness (both directions)"),
    Param("GJ", 1.0, "N m^2", "torsional stiffness"),
    Param("EI", 1.0, "N m^2", "bending stiffness (both directions)"),
    Param("rhoA", 0.0, "kg/m", "mass per unit length"),
    Param("rhoI", 0.0, "kg m", "rotational inertia per unit length about each bending axis (rho I)"),
    Param("rhoJ", 0.0, "kg m", "polar rotational inertia per unit length (rho J)"),
    Param("g_x", 0.0, "m/s^2", "gravity, x component"),
    Param("g_y", 0.0, "m/s^2", "gravity, y component"),
    Param("g_z", 0.0, "m/s^2", "gravity, z component"),
    Param("omega", 0.0, "rad/s", "steady rotation rate about the z axis (centrifugal load)"),
)


def _load(r, p):
    c = p.rhoA * p.omega**2
    return (p.rhoA * p.g_x + c * r.x, p.rhoA * p.g_y + c * r.y, p.rhoA * p.g_z)


model.rod(length=lambda p: p.L, stiffness=lambda p: rod_stiffness(p.EA, p.GA, p.GJ, p.EI), load=_load,
          inertia=lambda p: rod_inertia(p.rhoA, p.rhoJ, p.rhoI))
