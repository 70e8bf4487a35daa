"""Timoshenko beam: deflection w(s, t) and cross-section rotation psi(s, t), s in [0, L].

Shear deformation (kGA = kappa G A) and rotary inertia (rhoI = rho I):

    T = rhoA/2 w_t^2 + rhoI/2 psi_t^2,   V = EI/2 psi_s^2 + kGA/2 (w_s - psi)^2,
    rhoA w_tt = kGA (w_ss - psi_s),   rhoI psi_tt = EI psi_ss + kGA (w_s - psi).

Ends (``bc``): pinned (w = 0; moment EI psi_s = 0 natural), clamped (w = psi = 0),
free (natural). Pinned-pinned modes w = W sin(k s), psi = Psi cos(k s), k = n pi/L,
have two frequencies each (two spectra), the roots in omega^2 of
(kGA k^2 - rhoA omega^2)(EI k^2 + kGA - rhoI omega^2) = kGA^2 k^2. As kGA -> oo
and rhoI -> 0 the lower spectrum tends to the Euler-Bernoulli one. SI units.
"""
from mechgen.symbolic.field import fix_ends
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

BCS = ("pinned-pinned", "clamped-clamped", "clamped-free", "clamped-pinned", "free-free")

model = Model("timoshenko_beam", doc=__doc__, file=__file__)
model.params(
    Param("EI", 1.0, "N m^2", "bending stiffness", positive=True),
    Param("kGA", 1.0e3, "N", "shear stiffness kappa G A", positive=True),
    Param("rhoA", 1.0, "kg/m", "mass per unit length", positive=True),
    Param("rhoI", 1.0e-3, "kg m", "rotary inertia per unit length", positive=True),
    Param("L", 1.0, "m", "length", positive=True),
    Param("bc", "pinned-pinned", "", "end conditions (start-end)", choices=BCS),
)
model.field("w", "psi", length="L", discretisation="quintic", N=16)

_END = {"pinned": ("w",), "clamped": ("w", "psi"), "free": ()}


@model.kinetic_density
def kinetic(u, p):
    return p.rhoA / 2 * u.w_t**2 + p.rhoI / 2 * u.psi_t**2


@model.potential_density
def potential(u, p):
    return p.EI / 2 * u.psi_s**2 + p.kGA / 2 * (u.w_s - u.psi) ** 2


@model.boundary
def boundary(p):
    return fix_ends(p.bc, _END)
