"""Stick-slip-separation friction contact driven by prescribed relative displacements (no inertia).

Yang, Chu & Menq 1998, "Stick-slip-separation analysis and non-linear stiffness and damping
characterization of friction contacts having variable normal load", J. Sound Vib. 210(4), 461-481
(quoted as eqs. 2.1-2.4 of the project's seed paper). The contact point has a tangential spring k_u
(N/m) in series with a Coulomb slider (coefficient mu) and a normal spring k_v (N/m) with preload N (N).
The relative displacements are prescribed (m):

    u(t) = U cos(omega t),   v(t) = V cos(omega t + phase)      (U = amplitude, V = normal_amplitude)

normal force n = N + k_v v while positive (separation when it would be negative); the slip
displacement is w (m), the friction force f = k_u (u - w) (N). The internal variable is f, the slip's
change of variable w = u - f / k_u: for a stiff contact (k_u U / (mu N) up to 1e10) u and w agree to
mu N / k_u and f = k_u (u - w) would lose k_u ulp(U) and k_u rtol U to cancellation, while f itself
carries the integrator's relative error (tests/test_stick_slip.py, k_u = 1e10 to 1e-8). Modes and laws:

* ``stick``: dw/dt = 0, so df/dt = k_u du/dt, while |f| < mu n. Leaves for ``slip_positive`` when
  f - mu n rises through 0, for ``slip_negative`` when f + mu n falls through 0, for ``separated``
  when n falls through 0.
* ``slip_positive``: f = mu n, so df/dt = mu dn/dt and the slip rate dw/dt = du/dt - (mu k_v / k_u) dv/dt
  must stay >= 0; back to ``stick`` when k_u dw/dt = k_u du/dt - mu dn/dt falls through 0 (the paper's
  stick condition), ``separated`` when n -> 0.
* ``slip_negative``: f = -mu n, df/dt = -mu dn/dt, k_u dw/dt = k_u du/dt + mu dn/dt <= 0; ``stick`` when it
  rises through 0.
* ``separated``: f = 0 (reset to 0 on separating; w follows u); back to ``stick`` when n rises through 0,
  with f = 0 at re-contact; a stick that would at once exceed mu n slips at once (the event loop's
  start-of-mode rule: the slip guard sits on zero moving in its direction).

At a reversal (slip -> stick) the slip rate and the rate of |f| - mu n both vanish, so the stick
mode's slip guard starts on its surface with a rate of round-off size, whose sign would decide at once
between stick and a chattering return to slip; the reset of the slip -> stick guards moves f by
64 ulps of |f| + mu |n| into stick, so the guard starts strictly inside and fires only on a real crossing.

The run starts in ``stick`` at f(0) = mu n(0) (the state at the reversal of the steady Jenkins cycle, so
a constant-load contact is periodic from the first period). The model has no coordinates and no inertia:
its state is the internal variable f alone. Outputs: ``friction_force`` f, ``tangential_displacement`` u,
``normal_displacement`` v, ``normal_force`` n (0 when separated), ``slip`` w = u - f / k_u.
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


def slip_rate_force(p, t, sign):
    """k_u du/dt - sign mu dn/dt (N/s): k_u times the slip rate with f = sign mu n held."""
    return p.k_u * sp.diff(tangential(p, t), t) - sign * p.mu * sp.diff(normal_load(p, t), t)


@model.initial
def reversal(p):
    """Stick at f = mu n(0)."""
    return {"f": p.mu * normal_load(p, 0)}


stick.internal("f", lambda p, t: p.k_u * sp.diff(tangential(p, t), t), doc="friction force (N)")
slip_positive.internal("f", lambda p, t: p.mu * sp.diff(normal_load(p, t), t))
slip_negative.internal("f", lambda p, t: -p.mu * sp.diff(normal_load(p, t), t))
separated.internal("f", lambda: 0)


@stick.guard(to="slip_positive", direction="rising")
def slip_forward(z, p, t):
    return z.f - p.mu * normal_load(p, t)


@stick.guard(to="slip_negative", direction="falling")
def slip_backward(z, p, t):
    return z.f + p.mu * normal_load(p, t)


#: the slip -> stick reset moves f into the stick cone by this many ulps of |f| + mu |n| (module doc)
NUDGE = 64 * 2.220446049250313e-16


def _nudge(z, p, t, sign):
    """f - sign NUDGE (|f| + mu |n|): f a few ulps inside the stick cone."""
    return {"f": z.f - sign * NUDGE * (sp.Abs(z.f) + p.mu * sp.Abs(normal_load(p, t)))}


@slip_positive.guard(to="stick", direction="falling", reset=lambda z, p, t: _nudge(z, p, t, 1))
def stop_forward(p, t):
    return slip_rate_force(p, t, 1)


@slip_negative.guard(to="stick", direction="rising", reset=lambda z, p, t: _nudge(z, p, t, -1))
def stop_backward(p, t):
    return slip_rate_force(p, t, -1)


def separate(p, t):
    return normal_load(p, t)


for _scope in (stick, slip_positive, slip_negative):
    _scope.guard(to="separated", direction="falling", reset=lambda: {"f": 0})(separate)


@separated.guard(to="stick", direction="rising", reset=lambda: {"f": 0})
def recontact(p, t):
    return normal_load(p, t)


model.output("friction_force", lambda z: z.f, unit="N", doc="friction force f = k_u (u - w)")
model.output("tangential_displacement", lambda p, t: tangential(p, t), unit="m", doc="prescribed u(t)")
model.output("normal_displacement", lambda p, t: normal(p, t), unit="m", doc="prescribed v(t)")
model.output("normal_force", lambda p, t: normal_load(p, t), unit="N", doc="normal force n (0 when separated)")
model.output("slip", lambda z, p, t: tangential(p, t) - z.f / p.k_u, unit="m", doc="slip displacement w = u - f/k_u")
separated.output("friction_force", lambda: 0)
separated.output("normal_force", lambda: 0)
