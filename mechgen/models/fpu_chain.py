"""Fermi-Pasta-Ulam-Tsingou chain: N unit masses between fixed walls.

Equation of motion of particle n (seed 003, eq. 1.1; FPU 1955):

    u_n'' = f(u_{n+1} - u_n) - f(u_n - u_{n-1}),   f(r) = gamma r + alpha r^2 + beta r^3,
    u_0 = u_{N+1} = 0 (``ends = "fixed"``), or u_0 = u_N, u_{N+1} = u_1 (``ends = "periodic"``),

from the site and bond energies T_s = u'^2/2 and V_b(r) = gamma r^2/2 + alpha r^3/3 + beta r^4/4.
Linear mode k has frequency omega_k = 2 sqrt(gamma) sin(k pi / (2 (N + 1))) and shape
sin(n k pi / (N + 1)); periodic: omega_k = 2 sqrt(gamma) |sin(k pi / N)|, k = 0..N-1. Nondimensional: unit mass, unit lattice spacing.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("fpu_chain", doc=__doc__, file=__file__)
model.params(
    Param("N", 32, "", "number of moving particles", size=True),
    Param("gamma", 1.0, "", "linear bond stiffness"),
    Param("alpha", 0.25, "", "quadratic (FPU-alpha) coefficient"),
    Param("beta", 0.0, "", "cubic (FPU-beta) coefficient"),
    Param("ends", "fixed", "", "chain ends: fixed walls (u_0 = u_{N+1} = 0) or periodic (u_{N+1} = u_1)",
          choices=("fixed", "periodic")),
)
model.chain("u", sites="N", ends="ends")


@model.site_kinetic
def site_kinetic(s):
    return s.v**2 / 2


@model.bond_potential
def bond_potential(a, b, p):
    r = b.q - a.q
    return p.gamma * r**2 / 2 + p.alpha * r**3 / 3 + p.beta * r**4 / 4
