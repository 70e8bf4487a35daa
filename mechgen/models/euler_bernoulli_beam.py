"""Euler-Bernoulli beam: transverse deflection w(s, t) on s in [0, L].

    T = rhoA/2 w_t^2,   V = EI/2 w_ss^2 - q w   (per unit length)
    rhoA w_tt + EI w_ssss = q

Boundary conditions (``bc``): pinned (w = 0; the moment w_ss = 0 is natural),
clamped (w = w_s = 0), free (natural). Natural frequencies
omega_n = (beta_n L)^2 sqrt(EI / (rhoA L^4)) rad/s, beta_n L the roots of
sin = 0 (pinned-pinned), cos cosh = 1 (clamped-clamped), cos cosh = -1
(clamped-free). A uniform load q (N/m) deflects a pinned-pinned beam to
w(s) = q s (L^3 - 2 L s^2 + s^3) / (24 EI), total potential -q^2 L^5 / (240 EI). SI units.
"""
from mechgen.symbolic.field import fix_ends
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

BCS = ("pinned-pinned", "clamped-clamped", "clamped-free", "clamped-pinned", "free-free")

model = Model("euler_bernoulli_beam", doc=__doc__, file=__file__)
model.params(
    Param("EI", 1.0, "N m^2", "bending stiffness", positive=True),
    Param("rhoA", 1.0, "kg/m", "mass per unit length", positive=True),
    Param("L", 1.0, "m", "length", positive=True),
    Param("q", 0.0, "N/m", "distributed transverse load"),
    Param("bc", "pinned-pinned", "", "end conditions (start-end)", choices=BCS),
)
model.field("w", length="L", discretisation="hermite", N=128)

_END = {"pinned": ("w",), "clamped": ("w", "w_s"), "free": ()}


@model.kinetic_density
def kinetic(u, p):
    return p.rhoA / 2 * u.w_t**2


@model.potential_density
def potential(u, p):
    return p.EI / 2 * u.w_ss**2 - p.q * u.w


@model.boundary
def boundary(p):
    return fix_ends(p.bc, _END)
