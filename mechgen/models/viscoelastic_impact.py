"""Compliant impact of a mass on a viscoelastic contact: five contact laws, flight and contact modes.

A mass m (kg) moves along x (m, the penetration, > 0 in contact) and meets the contact at x = 0 with
speed v_in (m/s). In mode ``flight`` no force acts; the guard ``touch`` (x rising through 0) enters
``contact``, where the law ``law`` acts until its guard ``release`` (falling) returns to ``flight``.
omega_n = sqrt(k/m) (rad/s) and the damping ratio ``zeta`` set the dashpot of each law (Butcher &
Segalman 2000, ASME J. Appl. Mech. 67, 831-834; equation numbers are theirs):

* ``kelvin_voigt``: F = k x + c x', c = 2 zeta sqrt(k m) (eqs. 1-2); release when x returns to 0, the
  half period of the damped oscillation: e = exp(-zeta pi / sqrt(1 - zeta^2)) (eq. 4); none for zeta >= 1.
* ``modified_kelvin_voigt``: the same force, release when F falls to 0 (eqs. 9-11; no tension).
* ``maxwell``: spring k in series with a dashpot c, zeta = sqrt(k m) / (2 c) (eqs. 13-14); the dashpot
  stretch y is an internal variable, y' = (k/c)(x - y) = 2 zeta omega_n (x - y) (third-order dynamics);
  F = k (x - y); release when F falls to 0.
* ``standard_linear``: spring k1 in series with a Kelvin-Voigt element (k2 parallel to c) (eq. 18);
  y is the element's deflection, c y' = k1 (x - y) - k2 y, F = k1 (x - y). The paper's parameters
  omega_n^2 = k1 k2 / ((k1 + k2) m), zeta = k1 c / (2 (k1 + k2) m omega_n) and the stiffness ratio
  epsilon = k2 / (k1 + k2) (eq. 19) give k1 = k / epsilon, k2 = k / (1 - epsilon),
  c = 2 zeta m omega_n / (1 - epsilon), with k = m omega_n^2 the static stiffness; epsilon -> 0 is the
  Kelvin-Voigt limit. Release when F falls to 0. zeta = 0 has no dashpot (y' unbounded): refused.
* ``hunt_crossley`` (Hunt & Crossley 1975): F = k x^n (1 + alpha x'), release at x = 0. Its damping is
  set from zeta by alpha v_in = 3 pi zeta / 2, so that e = 1 - pi zeta + O(zeta^2) as for Kelvin-Voigt
  (e = 1 - 2 alpha v_in / 3 + ... for Hunt-Crossley); e depends on alpha v_in only.

Outputs: ``penetration`` x, ``velocity`` x', ``force`` F (0 in flight). The energy reported includes
the elastic energy stored in the contact's springs.
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.powers import abs_power, signed_power

LAWS = ("kelvin_voigt", "modified_kelvin_voigt", "maxwell", "standard_linear", "hunt_crossley")

model = Model("viscoelastic_impact", doc=__doc__)
model.params(
    Param("m", 1.0, "kg", "impacting mass", positive=True),
    Param("k", 1.0, "N/m", "contact stiffness (static stiffness of the standard linear solid)", positive=True),
    Param("v_in", 1.0, "m/s", "speed at first contact", positive=True),
    Param("zeta", 0.1, "", "damping ratio", minimum=0.0),
    Param("epsilon", 0.1, "", "standard linear solid: stiffness ratio k2 / (k1 + k2)", positive=True, below=1.0),
    Param("n", 1.5, "", "Hunt-Crossley stiffness exponent", positive=True),
    Param("law", "kelvin_voigt", "", "contact law", choices=LAWS),
)
model.coordinates("x")
flight = model.mode("flight", initial=True)
contact = model.mode("contact")


def _omega(p):
    return sp.sqrt(p.k / p.m)


def _sls(p):
    """(k1, k2, c) of the standard linear solid from k, epsilon, zeta (module doc)."""
    return p.k / p.epsilon, p.k / (1 - p.epsilon), 2 * p.zeta * p.m * _omega(p) / (1 - p.epsilon)


def contact_force(q, v, z, p):
    """The contact force F of the law (N), compressive > 0."""
    if p.law in ("kelvin_voigt", "modified_kelvin_voigt"):
        return p.k * q.x + 2 * p.zeta * sp.sqrt(p.k * p.m) * v.x
    if p.law == "maxwell":
        return p.k * (q.x - z.y)
    if p.law == "standard_linear":
        return _sls(p)[0] * (q.x - z.y)
    alpha = 3 * sp.pi * p.zeta / (2 * p.v_in)
    return p.k * signed_power(q.x, p.n) * (1 + alpha * v.x)


@model.initial
def first_contact(p):
    """At the contact (x = 0) moving in at v_in."""
    return {"x_dot": p.v_in}


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@contact.potential
def stored(q, z, p):
    """Elastic energy in the contact's springs (J)."""
    if p.law in ("kelvin_voigt", "modified_kelvin_voigt"):
        return p.k / 2 * q.x**2
    if p.law == "maxwell":
        return p.k / 2 * (q.x - z.y) ** 2
    if p.law == "standard_linear":
        k1, k2, _ = _sls(p)
        return k1 / 2 * (q.x - z.y) ** 2 + k2 / 2 * z.y**2
    return p.k * abs_power(q.x, p.n + 1) / (p.n + 1)


@contact.dissipation
def dashpot(q, v, p):
    """Rayleigh function of the dashpot in parallel with x (the internal-variable laws dissipate through y)."""
    if p.law in ("kelvin_voigt", "modified_kelvin_voigt"):
        return p.zeta * sp.sqrt(p.k * p.m) * v.x**2
    if p.law == "hunt_crossley":
        alpha = 3 * sp.pi * p.zeta / (2 * p.v_in)
        return p.k * alpha * abs_power(q.x, p.n) * v.x**2 / 2
    return 0


def _stretch_rate(q, z, p):
    if p.law == "maxwell":
        return 2 * p.zeta * _omega(p) * (q.x - z.y)
    if p.law == "standard_linear":
        k1, k2, c = _sls(p)
        return (k1 * (q.x - z.y) - k2 * z.y) / c
    return 0


contact.internal("y", _stretch_rate, doc="dashpot stretch (Maxwell) or Kelvin-Voigt element deflection (m)")


@flight.guard(to="contact", direction="rising")
def touch(q):
    return q.x


@contact.guard(to="flight", direction="falling")
def release(q, v, z, p):
    if p.law in ("kelvin_voigt", "hunt_crossley"):
        return q.x
    return contact_force(q, v, z, p)


model.output("penetration", lambda q: q.x, unit="m", doc="penetration x")
model.output("velocity", lambda v: v.x, unit="m/s", doc="velocity x'")
model.output("force", lambda: 0, unit="N", doc="contact force (compressive > 0)")
contact.output("force", contact_force)
