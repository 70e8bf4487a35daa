"""
Phase boundaries in a bar: the Maxwell stress and the driving traction
======================================================================

A bar of a material whose stored energy :math:`W(\\gamma)` (Pa) is not convex: the stress
:math:`\\sigma = W'(\\gamma)` rises (phase 1), falls (unstable) and rises again (phase 2). Two phases can
coexist at one stress; across a phase boundary the stress is continuous and the **driving traction**

.. math::

    f = [[W]] - \\sigma [[\\gamma]] = W(\\gamma_1) - W(\\gamma_2) - \\sigma (\\gamma_1 - \\gamma_2)

(phase 2 on the left of the boundary) is the force on it: the dissipation rate per unit area is
:math:`f \\dot s \\ge 0`. A boundary at rest under any kinetic law has :math:`f = 0`, Maxwell's rule of equal
areas: :math:`\\int_{\\gamma_1}^{\\gamma_2} \\sigma\\,d\\gamma = \\sigma_M (\\gamma_2 - \\gamma_1)`.

For the cubic-stress law :math:`\\sigma = \\mu(\\gamma - \\beta\\gamma^2 + c\\gamma^3)` (non-monotone when
:math:`\\beta^2 > 3c`) the cubic is point-symmetric about its inflection :math:`\\gamma_i = \\beta/(3c)`, so

.. math::

    \\sigma_M = \\sigma(\\gamma_i) = \\mu\\left(\\frac{\\beta}{3c} - \\frac{2\\beta^3}{27c^2}\\right),\\qquad
    \\gamma_{1,2} = \\gamma_i \\mp \\sqrt{\\frac{\\beta^2 - 3c}{3c^2}} .

For the trilinear law (phase 1 :math:`\\sigma = \\mu\\gamma` up to :math:`\\gamma_M`, phase 2
:math:`\\sigma = \\mu(\\gamma - \\gamma_T)` from :math:`\\gamma_m`, a straight falling branch between)
:math:`f = \\gamma_T(\\sigma - \\sigma_M)` with :math:`\\sigma_M = w_0/\\gamma_T`,
:math:`w_0 = W_2(\\gamma) - \\mu(\\gamma - \\gamma_T)^2/2`.

Reference: R. Abeyaratne and J. K. Knowles, "On the driving traction acting on a surface of strain
discontinuity in a continuum", J. Mech. Phys. Solids 38 (1990) 345-360; *Evolution of Phase Transitions*,
Cambridge University Press (2006), ch. 2-3.

mechgen runs the ``phase_boundary`` analysis on the built-in model ``phase_bar``: the shipped scenes
``scenes/phase_bar_cubic.toml`` (cubic law) and ``scenes/phase_bar.toml`` (trilinear law).
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"

# %%
# The cubic law: the Maxwell stress against the closed form.
cubic_run = mechgen.run(str(SCENES / "phase_bar_cubic.toml"))
mu, beta, c = (cubic_run["params"][k] for k in ("mu", "beta", "c"))
cubic = {a["name"]: a["outputs"] for a in cubic_run["analyses"]}["maxwell"]
gi = beta / (3 * c)
closed = mu * (beta / (3 * c) - 2 * beta**3 / (27 * c**2))
u = np.sqrt((beta**2 - 3 * c) / (3 * c**2))
err = abs(cubic["maxwell_stress"] - closed)
err_strains = np.max(np.abs(np.array(cubic["phase_strains"]) - [gi - u, gi + u]))
print(f"cubic: sigma_M mechgen {cubic['maxwell_stress']:.15f}, closed form {closed:.15f}, difference {err:.1e}")
print(f"cubic: phase strains {np.round(cubic['phase_strains'], 12)}, difference {err_strains:.1e}")
assert err < 1e-11 and err_strains < 1e-9  # Brent's method on double-precision kernels

# %%
# The trilinear law of the shipped scene, and the driving traction of its two-phase equilibria under an
# elongation: f = gamma_T (sigma - sigma_M) in closed form, zero at the Maxwell stress only.
run = mechgen.run(str(SCENES / "phase_bar.toml"))
p = run["params"]
tri = {a["name"]: a["outputs"] for a in run["analyses"]}["maxwell"]
gM, gm, gT = p["gamma_M"], p["gamma_m"], p["gamma_T"]
w0 = gM**2 / 2 + gM * (gm - gM) + ((gm - gT) - gM) * (gm - gM) / 2 - (gm - gT)**2 / 2
print(f"trilinear: sigma_M mechgen {tri['maxwell_stress']:.15f}, closed form {w0 / gT:.15f}, "
      f"difference {abs(tri['maxwell_stress'] - w0 / gT):.1e}")
family = tri["equilibria"][0]["family"]
f_err = np.max(np.abs(np.array(family["driving_traction"]) - gT * (np.array(family["stress"]) - tri["maxwell_stress"])))
print(f"trilinear: max |f - gamma_T (sigma - sigma_M)| over {len(family['stress'])} equilibria: {f_err:.1e} Pa")
assert abs(tri["maxwell_stress"] - w0 / gT) < 1e-13 and f_err < 1e-15

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
law = cubic["law"]
g, s = np.array(law["strain"]), np.array(law["stress"])
g1, g2 = cubic["phase_strains"]
left.plot(g, s, label="sigma(gamma), cubic")
left.axhline(cubic["maxwell_stress"], color="k", lw=1, ls="--", label="Maxwell stress")
between = (g >= g1) & (g <= g2)
left.fill_between(g[between], s[between], cubic["maxwell_stress"], alpha=0.3, label="equal areas")
left.set_xlabel("strain gamma")
left.set_ylabel("stress sigma / mu")
left.legend()
right.plot(family["stress"], family["driving_traction"], "o", label="mechgen")
right.plot(family["stress"], gT * (np.array(family["stress"]) - tri["maxwell_stress"]), "k-", lw=1,
           label="gamma_T (sigma - sigma_M)")
right.set_xlabel("stress sigma / mu")
right.set_ylabel("driving traction f / mu")
right.set_title(f"trilinear, elongation {tri['equilibria'][0]['elongation']} L")
right.legend()
fig.tight_layout()
plt.show()
