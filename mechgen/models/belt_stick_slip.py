"""Mass-spring on a moving belt with dry friction: the autonomous stick-slip oscillator.

    m x'' + k x = F(v_rel),   v_rel = v_belt - x'   (SI units: m kg, k N/m, N the normal force N, v_belt m/s)

Leine, van Campen & van de Vrande, "Bifurcations in nonlinear discontinuous systems", Nonlinear Dyn. 23 (2000)
105-164; di Bernardo, Budd, Champneys & Kowalczyk, *Piecewise-smooth Dynamical Systems* (2008), sec. 1.2.3.
The friction coefficient while slipping is a Stribeck curve

    mu(v_rel) = mu_k + stribeck (mu_s - mu_k) exp(-|v_rel| / v_s),

``stribeck`` = 1 continuous at v_rel = 0 with the static coefficient mu_s, ``stribeck`` = 0 Coulomb friction with
a static coefficient mu_s above the kinetic one mu_k (a jump at v_rel = 0). Modes:

* ``stick``: x' = v_belt, the friction force holds the spring, F = k x (so x'' = 0), while |k x| < mu_s N; leaves
  for ``slip`` when k x - mu_s N rises through 0 (guard ``breakaway``), for ``slip_back`` when k x + mu_s N falls
  through 0 (guard ``breakaway_back``).
* ``slip``: v_rel > 0, F = mu(v_rel) N; back to ``stick`` when v_rel falls through 0 (guard ``catch``, reset
  x' = v_belt exactly).
* ``slip_back``: v_rel < 0, F = -mu(v_rel) N; back to ``stick`` when v_rel rises through 0 (guard
  ``catch_back``, reset x' = v_belt).

With ``stribeck`` = 1 the slip starts tangentially (x'' = 0 at the breakaway, v_rel growing as t^2), so the catch
guard would start on its surface with a rate of round-off size and its sign would decide between slip and an
at-once return to stick (a Zeno chatter); the breakaway resets scale x' by 1 -+ 64 ulps, so that v_rel starts
strictly inside the slip mode (the stick-slip contact's rule, mechgen/models/stick_slip_contact.py).

The run starts in ``stick`` at x = 0, x' = v_belt. With mu_s > mu_k the motion settles on a stick-slip limit cycle:
stick from x = (2 mu_k - mu_s) N / k to x = mu_s N / k, then a slip arc about x = mu_k N / k back to it (in closed
form for Coulomb friction: tests/test_hybrid_autonomous.py). The stick phase forgets the state it started from, so
the cycle's monodromy matrix has rank 1: multipliers 1 (along the cycle) and 0.
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("belt_stick_slip", doc=__doc__, file=__file__)
model.params(
    Param("m", 1.0, "kg", "mass", positive=True),
    Param("k", 1.0, "N/m", "spring stiffness", positive=True),
    Param("N", 1.0, "N", "normal force", positive=True),
    Param("mu_s", 0.4, "", "static friction coefficient", positive=True),
    Param("mu_k", 0.3, "", "kinetic friction coefficient (the Stribeck curve's asymptote)", positive=True),
    Param("stribeck", 0.0, "", "weight of the Stribeck drop (0: Coulomb, 1: continuous at v_rel = 0)",
          minimum=0.0, maximum=1.0),
    Param("v_s", 0.1, "m/s", "Stribeck velocity", positive=True),
    Param("v_belt", 0.5, "m/s", "belt velocity", positive=True),
)
model.coordinates("x")
stick = model.mode("stick", initial=True)
slip = model.mode("slip")
slip_back = model.mode("slip_back")


def friction(p, speed):
    """mu(|v_rel|) N (N): the Stribeck curve at the slip speed |v_rel| (m/s)."""
    return p.N * (p.mu_k + p.stribeck * (p.mu_s - p.mu_k) * sp.exp(-speed / p.v_s))


@model.initial
def at_rest_on_belt(p):
    """Stick at x = 0, x' = v_belt."""
    return {"x": 0, "x_dot": p.v_belt}


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2


stick.forces(lambda q, p: {"x": p.k * q.x})
slip.forces(lambda v, p: {"x": friction(p, p.v_belt - v.x)})
slip_back.forces(lambda v, p: {"x": -friction(p, v.x - p.v_belt)})


#: the stick -> slip resets scale x' by (1 -+ NUDGE): v_rel starts a few ulps inside the slip mode (module doc)
NUDGE = 64 * 2.220446049250313e-16


@stick.guard(to="slip", direction="rising", reset=lambda v: {"x_dot": v.x * (1 - NUDGE)})
def breakaway(q, p):
    return p.k * q.x - p.mu_s * p.N


@stick.guard(to="slip_back", direction="falling", reset=lambda v: {"x_dot": v.x * (1 + NUDGE)})
def breakaway_back(q, p):
    return p.k * q.x + p.mu_s * p.N


@slip.guard(to="stick", direction="falling", reset=lambda p: {"x_dot": p.v_belt})
def catch(v, p):
    return p.v_belt - v.x


@slip_back.guard(to="stick", direction="rising", reset=lambda p: {"x_dot": p.v_belt})
def catch_back(v, p):
    return p.v_belt - v.x


model.output("position", lambda q: q.x, unit="m", doc="x, the mass's displacement")
model.output("relative_velocity", lambda v, p: p.v_belt - v.x, unit="m/s", doc="v_rel = v_belt - x'")
model.output("friction_force", lambda q, p: p.k * q.x, unit="N", doc="the friction force on the mass")
slip.output("friction_force", lambda v, p: friction(p, p.v_belt - v.x))
slip_back.output("friction_force", lambda v, p: -friction(p, v.x - p.v_belt))
