"""
A moving phase boundary: kinetics, nucleation and the hysteresis loop of a bar
==============================================================================

The bar of the previous page (length :math:`L`, phase 2 on :math:`0 < x < s(t)`) is pulled quasi-statically
by its end, :math:`\\delta(t) = r\\,(t_{turn} - |t - t_{turn}|)`. The boundary moves under the kinetic law
:math:`\\dot s = V = \\varphi(f) = f/\\eta` (the model's; :math:`\\eta` in Pa s/m), phase 2 nucleates at
:math:`x = 0` when the stress reaches :math:`\\sigma_{nuc}`, the boundary arrives at :math:`x = L`, phase 1
re-nucleates at :math:`x = L` when the stress falls to :math:`\\sigma_{rev}` on the way back, and the boundary
retreats to :math:`x = 0`: four events of a hybrid run (mechgen's event loop locates each).

For the trilinear law with both phases of modulus :math:`\\mu`, the stress is affine in :math:`s` and
:math:`\\delta` and :math:`f = \\gamma_T(\\sigma - \\sigma_M)`:

.. math::

    \\sigma = \\frac{\\mu(\\delta - \\gamma_T s)}{L},\\qquad
    \\dot s + k s = \\frac{\\gamma_T}{\\eta}\\left(\\frac{\\mu\\delta(t)}{L} - \\sigma_M\\right),\\qquad
    k = \\frac{\\mu\\gamma_T^2}{L\\eta},

a linear ODE; on a ramp :math:`\\delta = \\delta_0 + \\dot\\delta (t - t_0)` with :math:`s(t_0) = s_0`,
:math:`s(t) = p(t) + (s_0 - p(t_0)) e^{-k(t - t_0)}`, :math:`p(t) = (a - b/k)/k + (b/k)(t - t_0)`,
:math:`a = \\gamma_T(\\mu\\delta_0/L - \\sigma_M)/\\eta`, :math:`b = \\gamma_T\\mu\\dot\\delta/(L\\eta)`.
Dissipation: :math:`\\int f V\\,dt` = work done :math:`\\int \\sigma\\,d\\delta` minus the stored energy's change.

Reference: R. Abeyaratne and J. K. Knowles, "Kinetic relations and the propagation of phase boundaries in
solids", Arch. Rational Mech. Anal. 114 (1991) 119-154; *Evolution of Phase Transitions*, CUP (2006), ch. 3-4.

mechgen runs the ``phase_kinetics`` analysis of the shipped scene ``scenes/phase_bar.toml``.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
run = mechgen.run(str(SCENES / "phase_bar.toml"))
p = run["params"]
k = {a["name"]: a["outputs"] for a in run["analyses"]}["kinetics"]
mu, gT, L, eta, r, T = p["mu"], p["gamma_T"], p["L"], p["eta"], p["rate"], p["t_turn"]
sigma_m = k["maxwell_stress"]


def segment(t0, s0, delta0, rate):
    """The closed-form s(t) on a ramp from (t0, s0, delta0)."""
    kk = mu * gT**2 / (L * eta)
    a, b = gT / eta * (mu * delta0 / L - sigma_m), gT * mu * rate / (L * eta)
    return lambda t: (a - b / kk) / kk + b / kk * (t - t0) + (s0 - (a - b / kk) / kk) * np.exp(-kk * (t - t0))


# %%
# The events and s(t) against the closed form.
t_n = L * p["sigma_nucleation"] / (mu * r)
up = segment(t_n, 0.0, r * t_n, r)
t_a = brentq(lambda t: up(t) - L, t_n + 1e-9, T)
delta_r = L * (p["sigma_reversion"] / mu + gT)
t_r = 2 * T - delta_r / r
down = segment(t_r, L, delta_r, -r)
t_b = brentq(down, t_r + 1e-9, 2 * T)
for name, ref in (("nucleation_time", t_n), ("arrival_time", t_a), ("reversion_time", t_r), ("retreat_time", t_b)):
    print(f"{name:16s} mechgen {k[name]:.12f} s, closed form {ref:.12f} s, difference {abs(k[name] - ref):.1e}")
t, s = np.array(k["t"]), np.array(k["s"])
reference = np.where(t < t_n, 0.0, np.where(t < t_a, up(t), np.where(t < t_r, L, np.where(t < t_b, down(t), 0.0))))
away = np.min(np.abs(t[:, None] - np.array([t_n, t_a, t_r, t_b])[None, :]), axis=1) > 1e-6
error = np.max(np.abs(s - reference)[away])
print(f"s(t): max |s - closed form| over {away.sum()} samples: {error:.1e} m")
print(f"dissipation: int f V dt = {k['dissipated']:.12e} J/m^2, work = {k['work']:.12e} J/m^2, "
      f"residual work - dE - dissipated = {k['dissipation_residual']:.1e} J/m^2")
assert error < 1e-9 and abs(k["arrival_time"] - t_a) < 1e-9  # the integrator's rtol 1e-10 over 20 s
assert abs(k["dissipation_residual"]) < 1e-10 * k["work"]

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
left.plot(t, s, label="mechgen")
left.plot(t, reference, "k--", lw=1, label="closed form")
for when, what in ((k["nucleation_time"], "nucleation"), (k["arrival_time"], "arrival"),
                   (k["reversion_time"], "reversion"), (k["retreat_time"], "retreat")):
    left.axvline(when, color="0.7", lw=0.8)
    left.annotate(what, (when, 0.5 * L), rotation=90, fontsize=8)
left.set_xlabel("time t [s]")
left.set_ylabel("boundary position s [m]")
left.legend()
right.plot(k["elongation"], k["stress"], label="mechgen")
right.axhline(sigma_m, color="k", lw=1, ls="--", label="Maxwell stress")
right.set_xlabel("elongation delta [m]")
right.set_ylabel("stress sigma [Pa]")
right.set_title(f"hysteresis loop, area = dissipation {k['dissipated']:.3g} J/m^2")
right.legend()
fig.tight_layout()
plt.show()
