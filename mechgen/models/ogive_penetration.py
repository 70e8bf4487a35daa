"""Rigid ogive-nose projectile penetrating a geological target: crater phase, tunnel phase, rest.

A projectile of mass m (kg) and shank radius a (m) strikes the target at speed Vs (m/s); x (m) is the
depth of its nose. Forrestal, Altman, Cargile & Hanchak (1994) and Frew, Forrestal & Hanchak (2002,
limestone; their eqs. 1-2) describe the target's resistance in two phases:

* mode ``crater`` (0 <= x < 4a): a force linear in depth, F = c x, with c fixed by continuity of the
  force at x = 4a: c = pi a (R + N rho V1^2) / 4;
* mode ``tunnel`` (x >= 4a, entered by the guard ``tunnel_entry``): F = pi a^2 (R + N rho V^2),
  a quasi-static strength term R (Pa) and an inertial term with the target density rho (kg/m^3);

N = (8 psi - 1) / (24 psi^2) is the nose factor of an ogive of caliber-radius-head psi, and the
energy balance of the crater phase, m (Vs^2 - V1^2)/2 = c (4a)^2 / 2, gives the speed entering the
tunnel V1^2 = (m Vs^2 - 4 pi a^3 R) / (m + 4 pi a^3 N rho). Integrating the tunnel phase to rest,

    P = m / (2 pi a^2 rho N) ln(1 + N rho V1^2 / R) + 4a      (the depth of penetration).

When m Vs^2 < 4 pi a^3 R the projectile stops in the crater: V1^2 is taken as 0 (c = pi a R / 4) and
P = Vs sqrt(m / c). A run starts at x = 0 with V = Vs (``@model.initial``). The terminal guard ``at_rest`` (V falling through 0) ends the run in either phase.
Outputs: ``depth`` x (m) and ``velocity`` V (m/s).
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("ogive_penetration", doc=__doc__)
model.params(
    Param("m", 0.931, "kg", "projectile mass", positive=True),
    Param("a", 0.0127, "m", "shank radius", positive=True),
    Param("psi", 3.0, "", "caliber-radius-head of the ogive nose", positive=True),
    Param("rho", 2300.0, "kg/m^3", "target density", positive=True),
    Param("R", 693e6, "Pa", "target strength constant", positive=True),
    Param("Vs", 1000.0, "m/s", "striking velocity", minimum=0.0),
)
model.coordinates("x")
crater = model.mode("crater", initial=True)
tunnel = model.mode("tunnel")


def nose_factor(p):
    """N = (8 psi - 1) / (24 psi^2)."""
    return (8 * p.psi - 1) / (24 * p.psi**2)


def tunnel_speed_squared(p):
    """V1^2 = (m Vs^2 - 4 pi a^3 R) / (m + 4 pi a^3 N rho), m^2/s^2 (0 when the projectile stops in the crater)."""
    v1 = (p.m * p.Vs**2 - 4 * sp.pi * p.a**3 * p.R) / (p.m + 4 * sp.pi * p.a**3 * nose_factor(p) * p.rho)
    return sp.Max(v1, 0)


def crater_stiffness(p):
    """c = pi a (R + N rho V1^2) / 4 (N/m)."""
    return sp.pi * p.a * (p.R + nose_factor(p) * p.rho * tunnel_speed_squared(p)) / 4


@model.initial
def strike(p):
    """At the target's face (x = 0) at the striking velocity."""
    return {"x_dot": p.Vs}


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@crater.forces
def crater_resistance(q, p):
    return {"x": -crater_stiffness(p) * q.x}


@tunnel.forces
def tunnel_resistance(v, p):
    return {"x": -sp.pi * p.a**2 * (p.R + nose_factor(p) * p.rho * v.x**2)}


@crater.guard(to="tunnel", direction="rising")
def tunnel_entry(q, p):
    return q.x - 4 * p.a


@model.terminal(direction="falling")
def at_rest(v):
    return v.x


model.output("depth", lambda q: q.x, unit="m", doc="depth of the nose")
model.output("velocity", lambda v: v.x, unit="m/s", doc="projectile speed")
