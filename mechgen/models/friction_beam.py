"""Euler-Bernoulli beam of circular section rubbed along a corrugated interface: w(s, t), s in [0, L].

Chiroiu, Rugina, Dumitriu, Munteanu, "On the acoustics and friction", section 3, eqs. 3.1-3.4:

    rho A w_tt + (E I w_ss)_ss + Upsilon = 0,   I = pi d^4 / 64,  A = pi d^2 / 4   (d: diameter, m)
    T = rho A/2 w_t^2,   V = E I/2 w_ss^2       (per unit length, J/m)

clamped at both ends by default (eq. 3.4: w = w_s = 0 at s = 0 and s = L). The friction term
Upsilon, impulses travelling at the sliding velocity ``v_slide`` (m/s) along a corrugation of
wavelength ``wavelength`` (m), is not in the energies: the ``spectrum`` analysis applies it in
modal coordinates (mechgen.analyses.spectrum), reading both parameters through the scene.
Natural frequencies f_n = (beta_n L)^2 / (2 pi L^2) sqrt(E I / (rho A)) = (beta_n L)^2 d / (8 pi L^2)
sqrt(E / rho) Hz, beta_n L the roots of cos cosh = 1 (clamped-clamped), cos cosh = -1 (clamped-free).
SI units.
"""
import sympy as sp

from mechgen.symbolic.field import fix_ends
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

BCS = ("clamped-clamped", "clamped-free", "pinned-pinned", "clamped-pinned", "free-free")

model = Model("friction_beam", doc=__doc__, file=__file__)
model.params(
    Param("L", 0.28, "m", "length", positive=True),
    Param("d", 0.03, "m", "diameter of the circular section", positive=True),
    Param("E", 70e9, "Pa", "Young's modulus", positive=True),
    Param("rho", 2700.0, "kg/m^3", "density", positive=True),
    Param("v_slide", 1.0, "m/s", "sliding velocity of the contact (used by the spectrum analysis)", positive=True),
    Param("wavelength", 0.01, "m", "wavelength of the corrugation (used by the spectrum analysis)",
          positive=True),
    Param("bc", "clamped-clamped", "", "end conditions (start-end)", choices=BCS),
)
model.field("w", length="L", discretisation="hermite", N=32)

ENDS = {"pinned": ("w",), "clamped": ("w", "w_s"), "free": ()}


@model.kinetic_density
def kinetic(u, p):
    return p.rho * sp.pi * p.d**2 / 8 * u.w_t**2


@model.potential_density
def potential(u, p):
    return p.E * sp.pi * p.d**4 / 128 * u.w_ss**2


@model.boundary
def boundary(p):
    return fix_ends(p.bc, ENDS)
