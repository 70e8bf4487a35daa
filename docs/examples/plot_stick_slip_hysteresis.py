"""
Stick-slip friction contact: the hysteresis loop and its equivalent stiffness and damping (Jenkins element)
===========================================================================================================

A friction contact under a prescribed tangential displacement :math:`u(t) = U\\cos\\omega t` (m) and a
constant normal load ``N`` (N): a tangential spring :math:`k_u` (N/m) in series with a Coulomb slider
(friction coefficient :math:`\\mu`). With ``w`` the slip, the friction force :math:`f = k_u (u - w)` obeys

.. math::

    \\dot w = 0 \\ \\text{while}\\ |f| < \\mu N \\ \\text{(stick)}, \\qquad f = \\pm\\mu N \\ \\text{(slip)} .

With :math:`\\Delta = \\mu N / k_u < U` the steady loop is :math:`f = \\mu N - k_u (U - u)` on
:math:`\\theta = \\omega t \\in [0, \\beta]` and :math:`f = -\\mu N` on :math:`[\\beta, \\pi]`, with
:math:`\\cos\\beta = 1 - 2\\Delta/U` and :math:`f(\\theta + \\pi) = -f(\\theta)`. Its area and its first
harmonic :math:`f \\approx k_{eq} u + c_{eq} \\dot u` follow by integrating the two branches:

.. math::

    W = \\oint f\\,du = 4\\mu N (U - \\Delta), \\qquad
    k_{eq} = \\frac{k_u}{\\pi}\\left(\\beta - \\frac{\\sin 2\\beta}{2}\\right), \\qquad
    c_{eq} = \\frac{W}{\\pi\\omega U^2}.

Reference: B. D. Yang, M. L. Chu and C. H. Menq, "Stick-slip-separation analysis and nonlinear stiffness
and damping characterization of friction contacts having variable normal load", J. Sound Vib. 210(4) (1998)
461-481, the contact model that the seed paper (V. Chiroiu, C. Rugina, D. Dumitriu, L. Munteanu, "On the
acoustics and friction", SISOM 2012) builds on; the constant-load limit is Griffin's (ASME J. Eng. Power 102,
1980, 329-333).

mechgen runs the shipped scene ``scenes/stick_slip_element.toml`` (model ``stick_slip_contact``, a hybrid
model with stick, slip and separation modes; the ``periodic`` analysis integrates period by period to the
steady loop) through :func:`mechgen.run`.
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
run = mechgen.run(str(SCENES / "stick_slip_element.toml"))
loop = {analysis["name"]: analysis["outputs"] for analysis in run["analyses"]}["hysteresis"]
p = run["params"]
k_u, mu, N, U, omega = p["k_u"], p["mu"], p["N"], p["amplitude"], p["omega"]

# %%
# The closed forms of the Jenkins element:
delta = mu * N / k_u
beta = math.acos(1 - 2 * delta / U)
W = 4 * mu * N * (U - delta)
k_eq = k_u / math.pi * (beta - math.sin(2 * beta) / 2)
c_eq = W / (math.pi * omega * U**2)
for name, ours, closed in (("energy per cycle W [J]", loop["energy_per_cycle"], W),
                           ("equivalent stiffness [N/m]", loop["equivalent_stiffness"], k_eq),
                           ("equivalent damping [N s/m]", loop["equivalent_damping"], c_eq)):
    print(f"{name:28s} mechgen {ours:.12f}, closed form {closed:.12f}, difference {abs(ours - closed):.1e}")
# the force is piecewise linear in u and the mode switches are events located to the integrator's tolerance:
# 1e-8 on quantities of order 1 (tests/test_stick_slip.py asserts the same)
assert abs(loop["energy_per_cycle"] - W) < 1e-8 and abs(loop["equivalent_stiffness"] - k_eq) < 1e-8
assert abs(loop["equivalent_damping"] - c_eq) < 1e-8

# %%
# The loop itself: on the unloading branch (u decreasing) f = max(mu N - k_u (U - u), -mu N), on the
# reloading branch f = min(-mu N + k_u (U + u), mu N).
u = np.array(loop["displacement_series"])
f = np.array(loop["force_series"])
falling = np.gradient(u) < 0
reference = np.where(falling, np.maximum(mu * N - k_u * (U - u), -mu * N), np.minimum(-mu * N + k_u * (U + u), mu * N))
error = np.max(np.abs(f - reference))
print(f"loop: max |f_mechgen - f_closed form| over {len(u)} samples: {error:.1e} N")
assert error < 1e-8  # the same event tolerance on forces of order mu N = 0.3

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 4))
left.plot(u, f, label="mechgen (periodic)")
u_fine = np.linspace(-U, U, 200)
left.plot(u_fine, np.maximum(mu * N - k_u * (U - u_fine), -mu * N), "k--", lw=1, label="closed form")
left.plot(u_fine, np.minimum(-mu * N + k_u * (U + u_fine), mu * N), "k--", lw=1)
left.set_xlabel("tangential displacement u [m]")
left.set_ylabel("friction force f [N]")
left.set_title("Hysteresis loop, U = 1 m, mu N = 0.3 N")
left.legend()
right.semilogy(np.abs(f - reference) + 1e-18)
right.set_xlabel("sample along the period")
right.set_ylabel("|f - closed form| [N]")
right.set_title("Error along the loop")
fig.tight_layout()
plt.show()
