"""
Compliant impacts: restitution against damping for five contact laws (Butcher & Segalman)
=========================================================================================

A mass ``m`` (kg) meets a compliant contact at speed :math:`v_{in}` (m/s); ``x`` (m) is the penetration,
:math:`\\omega_n = \\sqrt{k/m}` (rad/s), :math:`\\zeta` the damping ratio. In contact

* Kelvin-Voigt (spring and dashpot in parallel): :math:`m\\ddot x + c\\dot x + k x = 0`,
  :math:`c = 2\\zeta m\\omega_n`; the mass leaves when ``x`` returns to 0 (half-period model) or, in the
  *modified* model, when the contact force :math:`k x + c \\dot x` first vanishes;
* Maxwell (spring and dashpot in series), the standard linear solid (a Maxwell arm beside a spring,
  stiffness ratio :math:`\\epsilon = 0.1`);
* Hunt-Crossley: :math:`m\\ddot x = -k x^{n}(1 + \\alpha\\dot x)`, :math:`\\alpha v_{in} = 3\\pi\\zeta/2`.

The coefficient of restitution is :math:`e = -\\dot x(t_r)/v_{in}` at release. The closed forms, rebuilt
from the physics (derivations in ``tests/impact_reference.py``):

.. math::

    e_{KV} = e_{Maxwell} = \\exp\\left(-\\frac{\\pi\\zeta}{\\sqrt{1-\\zeta^2}}\\right)\\ (\\zeta < 1,
    \\text{no release beyond}), \\qquad
    e_{MKV} = \\exp\\left(-\\frac{2\\zeta\\arccos\\zeta}{\\sqrt{1-\\zeta^2}}\\right)
    \\ (\\arccos \\to \\operatorname{arccosh} \\text{ for } \\zeta > 1),

and, integrating :math:`m v\\,dv/(1 + \\alpha v) = -k x^n dx` over the whole contact, Hunt-Crossley's
:math:`\\ln\\frac{1 + a}{1 - a e} = a (1 + e)` with :math:`a = \\alpha v_{in}`, solved here for ``e``.

Reference: E. A. Butcher and D. J. Segalman, "Characterizing Damping and Restitution in Compliant Impacts
via Modified K-V and Higher-Order Linear Viscoelastic Models", ASME J. Appl. Mech. 67 (December 2000),
831-834 (the seed paper; its figure 2 plots e against zeta for these laws); K. H. Hunt and F. R. E.
Crossley, J. Appl. Mech. 42 (1975) 440-445. The standard linear solid has no closed form: its curve is
drawn without a reference here (``tests/test_impacts.py`` checks it against the exact solution of its
linear third-order equation).

mechgen runs the shipped scene ``scenes/impact_models.toml`` (the built-in model ``viscoelastic_impact``,
one event-driven impact per law and damping ratio) through :func:`mechgen.run`.
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
run = mechgen.run(str(SCENES / "impact_models.toml"))
outputs = {analysis["name"]: analysis["outputs"] for analysis in run["analyses"]}["restitution"]
zeta = np.array(outputs["zeta"])
ours = {law: np.array(values, dtype=float) for law, values in outputs["restitution"].items()}

# %%
# The closed forms.


def kelvin_voigt(z):
    """Half-period Kelvin-Voigt (and Maxwell): exp(-pi z / sqrt(1 - z^2)); 0 (no release) from z = 1."""
    return math.exp(-math.pi * z / math.sqrt(1 - z * z)) if z < 1 else 0.0


def modified_kelvin_voigt(z):
    """exp(-2 z q(z)), q = acos(z)/sqrt(1 - z^2) below 1, 1 at 1, acosh(z)/sqrt(z^2 - 1) above."""
    if z < 1:
        q = math.acos(z) / math.sqrt(1 - z * z)
    elif z == 1:
        q = 1.0
    else:
        q = math.acosh(z) / math.sqrt(z * z - 1)
    return math.exp(-2 * z * q)


def hunt_crossley(z):
    """The root e of ln((1 + a)/(1 - a e)) = a (1 + e), a = 3 pi z / 2, in w = 1 - a e:
    w - ln w = 1 + a - ln(1 + a), w in (0, 1)."""
    a = 1.5 * math.pi * z
    rhs = 1 + a - math.log1p(a)
    w = brentq(lambda w: w - math.log(w) - rhs, 1e-300, 1 - 1e-16, xtol=1e-300, rtol=1e-15)
    return (1 - w) / a


closed = {"kelvin_voigt": kelvin_voigt, "modified_kelvin_voigt": modified_kelvin_voigt, "maxwell": kelvin_voigt,
          "hunt_crossley": hunt_crossley}
errors = {}
for law, formula in closed.items():
    reference = np.array([formula(z) for z in zeta])
    errors[law] = np.max(np.abs(ours[law] - reference))
    print(f"{law:22s} max |e_mechgen - e_closed form| over {len(zeta)} damping ratios: {errors[law]:.2e}")
# each impact is integrated at the scene's rtol = 1e-10, atol = 1e-12 and its release located as an event on
# velocities of order 1: a bound 100 times the tolerance (measured about 3e-11)
assert max(errors.values()) < 1e-8

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
styles = {"kelvin_voigt": "C0", "modified_kelvin_voigt": "C1", "maxwell": "C2", "standard_linear": "C3",
          "hunt_crossley": "C4"}
fine = np.linspace(zeta[0], zeta[-1], 400)
for law, color in styles.items():
    top.plot(zeta, ours[law], "o", color=color, ms=3, label=f"{law} (mechgen)")
    if law in closed:
        top.plot(fine, [closed[law](z) for z in fine], "-", color=color, lw=1)
        bottom.semilogy(zeta, np.abs(ours[law] - [closed[law](z) for z in zeta]) + 1e-17, ".-", color=color,
                        label=law)
top.plot([], [], "k-", lw=1, label="closed forms (lines)")
top.set_ylabel("restitution e [-]")
top.set_title("Restitution against damping ratio (Butcher & Segalman 2000, fig. 2)")
top.legend(fontsize=7)
bottom.set_xlabel("damping ratio zeta [-]")
bottom.set_ylabel("|e - closed form| [-]")
bottom.legend(fontsize=7)
fig.tight_layout()
plt.show()
