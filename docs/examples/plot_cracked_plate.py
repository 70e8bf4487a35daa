"""
A Griffith crack: J, K, T, M, L and Bueckner's integrals, path independence on a finite plate
===============================================================================================

A slit :math:`|x| < a` on :math:`y = 0` in the plate :math:`[-W, W]\\times[-H, H]` (plane strain). The model
``cracked_plate`` loads the plate's sides with the exact tractions of the infinite plate's Griffith field
under remote :math:`\\sigma_{11}, \\sigma_{22}, \\sigma_{12}` (Westergaard's functions in real form, declared
as an analytic field of :math:`x, y`: ``mechgen.symbolic.plane_fields.griffith_stress``), so the finite plate
carries that field exactly and the integrals can be checked against closed forms:

.. math::

    K_I = \\sigma_{22}\\sqrt{\\pi a}, \\quad K_{II} = \\sigma_{12}\\sqrt{\\pi a}, \\quad T = \\sigma_{11} - \\sigma_{22},
    \\quad J = \\frac{(\\kappa + 1)(K_I^2 + K_{II}^2)}{8\\mu},

    M = \\frac{(\\kappa+1)\\pi a^2 (\\sigma_{22}^2 + \\sigma_{12}^2)}{4\\mu}, \\qquad
    L = \\frac{(\\kappa+1)\\pi a^2 \\sigma_{12}(\\sigma_{11} + \\sigma_{22})}{4\\mu},

:math:`\\kappa = 3 - 4\\nu` (Tada, Paris & Irwin's handbook; M and L derived in the notes
:doc:`../plane_fracture_notes`). ``crack_integrals`` takes each integral in its domain form
:math:`I = -\\int_A F_l\\, q_{,l}\\, dA` over rings, :math:`q` interpolated from nodal values, with the FE
state's stresses from the model's own kernel; K and T come from interaction integrals with the Williams
fields, Bueckner's integrals from his :math:`r^{-3/2}` field, and the whole-crack Bueckner integral from Shi,
Liu & Li's supplemental field, which equals :math:`2L`. The paper's other relation (its eq. 8, L from the tips'
K alone) misses :math:`(\\kappa+1)\\pi a^2\\sigma_{12}T/(4\\mu)` when the T-stress and :math:`K_{II}` are both
non-zero: the notes show the case.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
result = mechgen.run(str(SCENES / "cracked_plate.toml"))
out = result["analyses"][1]["outputs"]
p = result["params"]
a, mu, nu = p["a"], p["mu"], p["nu"]
s11, s22, s12 = p["sigma11"], p["sigma22"], p["sigma12"]
kappa = 3 - 4 * nu
KI, KII = s22 * np.sqrt(np.pi * a), s12 * np.sqrt(np.pi * a)
exact = {"J": (kappa + 1) * (KI**2 + KII**2) / (8 * mu), "K_I": KI, "K_II": KII, "T_stress": s11 - s22,
         "bueckner_K_I": KI, "bueckner_K_II": KII}
crack_exact = {"M": (kappa + 1) * np.pi * a**2 * (s22**2 + s12**2) / (4 * mu),
               "L": (kappa + 1) * np.pi * a**2 * s12 * (s11 + s22) / (4 * mu)}
crack_exact["bueckner"] = 2 * crack_exact["L"]

table = out["contours"]
print("ring about each tip  " + "  ".join(f"{k:>13s}" for k in exact))
for i, ring in enumerate(table["rings"]):
    print(f"[{ring[0]:.1f}, {ring[1]:.1f}] right tip   " + "  ".join(f"{table[k][i][0]:13.6f}" for k in exact))
    print(f"{'':11s}left tip    " + "  ".join(f"{table[k][i][1]:13.6f}" for k in exact))
print("closed form          " + "  ".join(f"{v:13.6f}" for v in exact.values()))
print()
print("ring about the crack " + "  ".join(f"{k:>10s}" for k in crack_exact))
for i, ring in enumerate(table["crack_rings"]):
    print(f"[{ring[0]:.1f}, {ring[1]:.1f}]           " + "  ".join(f"{table[k][i]:10.6f}" for k in crack_exact))
print("closed form          " + "  ".join(f"{v:10.6f}" for v in crack_exact.values()))
worst = max(max(np.abs(np.asarray(table[k]) - v).max() / abs(v) for k, v in exact.items()),
            max(np.abs(np.asarray(table[k]) - v).max() / abs(v) for k, v in crack_exact.items()))
print(f"\nlargest relative error over every ring and integral: {worst:.1e}")

fig, ax = plt.subplots(figsize=(6.4, 4.2))
names = list(exact) + list(crack_exact)
errors = [abs(out[k][0] - exact[k]) / abs(exact[k]) for k in exact] + \
         [abs(out[k] - v) / abs(v) for k, v in crack_exact.items()]
ax.bar(names, errors)
ax.set_yscale("log")
ax.set(ylabel="relative error (first ring)", title="Griffith crack, graded P2, h = 0.1")
ax.tick_params(axis="x", labelrotation=45)
fig.tight_layout()
