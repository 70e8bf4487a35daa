"""Stick-slip-separation friction contact driven by prescribed relative displacements (no inertia).

Yang, Chu & Menq 1998, "Stick-slip-separation analysis and non-linear stiffness and damping
characterization of friction contacts having variable normal load", J. Sound Vib. 210(4), 461-481
(quoted as eqs. 2.1-2.4 of the project's seed paper). The contact point has a tangential spring k_u
(N/m) in series with a Coulomb slider (coefficient mu) and a normal spring k_v (N/m) with preload N (N).
The relative displacements are prescribed (m):

    u(t) = U cos(omega t),   v(t) = V cos(omega t + phase)      (U = amplitude, V = normal_amplitude)

normal force n = N + k_v v while positive (separation when it would be negative); the slip
displacement w (m) is the internal variable, the friction force f = k_u (u - w) (N). Modes and laws:

* ``stick``: dw/dt = 0 while |f| < mu n. Leaves for ``slip_positive`` when f - mu n rises through 0,
  for ``slip_negative`` when f + mu n falls through 0, for ``separated`` when n falls through 0.
* ``slip_positive``: f = mu n, so dw/dt = du/dt - (mu k_v / k_u) dv/dt, which must stay >= 0; back to
  ``stick`` when that slip rate falls through 0 (the paper's stick condition), ``separated`` when n -> 0.
* ``slip_negative``: f = -mu n, dw/dt = du/dt + (mu k_v / k_u) dv/dt <= 0; ``stick`` when it rises
  through 0.
* ``separated``: f = 0, w follows u (dw/dt = du/dt); back to ``stick`` when n rises through 0, with the
  reset w = u (f = 0 at re-contact); a stick that would at once exceed mu n slips at once (the event
  loop's start-of-mode rule: the slip guard sits on zero moving in its direction).

At a reversal (slip -> stick) the slip rate and the rate of |f| - mu n both vanish, so the stick
mode's slip guard starts on its surface with a rate of round-off size, whose sign would decide at once
between stick and a chattering return to slip; the reset of the slip -> stick guards moves w by
64 ulps of |u| + |w| into stick (f changes by k_u times that: 1e-14 of mu n for k_u U ~ mu n), so the
guard starts strictly inside and fires only on a real crossing.

The run starts in ``stick`` at w(0) = U - mu n(0) / k_u (f(0) = mu n(0): the state at the reversal of
the steady Jenkins cycle, so a constant-load contact is periodic from the first period).

The model has no inertia; the event loop integrates lumped models of coordinates, so it carries one
``clock`` coordinate of unit mass that no force acts on (it stays at rest, kinetic energy 0) and
that nothing depends on. Outputs: ``friction_force`` f, ``tangential_displacement`` u,
``normal_displacement`` v, ``normal_force`` n (0 when separated), ``slip`` w.
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("stick_slip_contact", doc=__doc__)
model.params(
    Param("k_u", 1.0, "N/m", "tangential contact stiffness", positive=True),
    Param("k_v", 1.0, "N/m", "normal contact stiffness", minimum=0.0),
    Param("mu", 0.3, "", "Coulomb friction coefficient", positive=True),
    Param("N", 1.0, "N", "normal preload", positive=True),
    Param("amplitude", 1.0, "m", "tangential relative displacement amplitude U", minimum=0.0),
    Param("normal_amplitude", 0.0, "m", "normal relative displacement amplitude V", minimum=0.0),
    Param("phase", 0.0, "rad", "phase of v ahead of u"),
    Param("omega", 1.0, "rad/s", "drive frequency", positive=True),
)
model.coordinates("clock")
stick = model.mode("stick", initial=True)
slip_positive = model.mode("slip_positive")
slip_negative = model.mode("slip_negative")
separated = model.mode("separated")


def tangential(p, t):
    """u(t) = U cos(omega t) (m)."""
    return p.amplitude * sp.cos(p.omega * t)


def normal(p, t):
    """v(t) = V cos(omega t + phase) (m)."""
    return p.normal_amplitude * sp.cos(p.omega * t + p.phase)


def normal_load(p, t):
    """N + k_v v(t) (N): the normal force while in contact."""
    return p.N + p.k_v * normal(p, t)


def friction(z, p, t):
    """f = k_u (u - w) (N)."""
    return p.k_u * (tangential(p, t) - z.w)


def _rate(p, t, sign):
    """du/dt - sign (mu / k_u) dn/dt (m/s): the slip rate with f = sign mu n held."""
    return sp.diff(tangential(p, t), t) - sign * p.mu / p.k_u * sp.diff(normal_load(p, t), t)


@model.initial
def reversal(p):
    """Stick at f = mu n(0)."""
    return {"w": p.amplitude - p.mu * normal_load(p, 0) / p.k_u}


@model.kinetic
def kinetic(v):
    return v.clock**2 / 2


stick.internal("w", lambda: 0, doc="slip displacement (m)")
slip_positive.internal("w", lambda p, t: _rate(p, t, 1))
slip_negative.internal("w", lambda p, t: _rate(p, t, -1))
separated.internal("w", lambda p, t: sp.diff(tangential(p, t), t))


@stick.guard(to="slip_positive", direction="rising")
def slip_forward(z, p, t):
    return friction(z, p, t) - p.mu * normal_load(p, t)


@stick.guard(to="slip_negative", direction="falling")
def slip_backward(z, p, t):
    return friction(z, p, t) + p.mu * normal_load(p, t)


#: the slip -> stick reset moves w into the stick region by this many ulps of |u| + |w| (module doc)
NUDGE = 64 * 2.220446049250313e-16


def _nudge(z, p, t, sign):
    """w + sign NUDGE (|u| + |w|): f a few ulps inside the stick cone."""
    return {"w": z.w + sign * NUDGE * (sp.Abs(tangential(p, t)) + sp.Abs(z.w))}


@slip_positive.guard(to="stick", direction="falling", reset=lambda z, p, t: _nudge(z, p, t, 1))
def stop_forward(p, t):
    return _rate(p, t, 1)


@slip_negative.guard(to="stick", direction="rising", reset=lambda z, p, t: _nudge(z, p, t, -1))
def stop_backward(p, t):
    return _rate(p, t, -1)


def separate(p, t):
    return normal_load(p, t)


for _scope in (stick, slip_positive, slip_negative):
    _scope.guard(to="separated", direction="falling")(separate)


@separated.guard(to="stick", direction="rising", reset=lambda p, t: {"w": tangential(p, t)})
def recontact(p, t):
    return normal_load(p, t)


model.output("friction_force", friction, unit="N", doc="friction force f = k_u (u - w)")
model.output("tangential_displacement", lambda p, t: tangential(p, t), unit="m", doc="prescribed u(t)")
model.output("normal_displacement", lambda p, t: normal(p, t), unit="m", doc="prescribed v(t)")
model.output("normal_force", lambda p, t: normal_load(p, t), unit="N", doc="normal force n (0 when separated)")
model.output("slip", lambda z: z.w, unit="m", doc="slip displacement w")
separated.output("friction_force", lambda: 0)
separated.output("normal_force", lambda: 0)
