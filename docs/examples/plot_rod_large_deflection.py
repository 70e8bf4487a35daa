"""
A soft rod's large deflection: the cantilever elastica and the rolled-up rod (Cosserat rod on SE(3))
====================================================================================================

A geometrically exact (Cosserat) rod of length ``L`` (m): its configuration is a curve of frames
:math:`H(s) \\in SE(3)` with strains :math:`f = H^{-1} H'` (stretch and shear :math:`\\nu`, curvature and
twist :math:`\\kappa`), stress resultants :math:`\\sigma = K (f - f_0)`,
:math:`K = \\operatorname{diag}(EA, GA, GA, GJ, EI, EI)`, and the static balance
:math:`\\sigma' - \\operatorname{ad}^*_f \\sigma + \\bar q = 0` with the end loads as boundary conditions.

**Tip load.** A cantilever under a dead tip load ``P`` (N) perpendicular to it. In the inextensible limit
(:math:`EA, GA \\gg EI/L^2`) the shape is Euler's elastica; with :math:`\\alpha = P L^2/EI` the tip angle
:math:`\\phi` and position follow from elliptic integrals (Bisshopp & Drucker 1945), :math:`m = (1 + \\sin\\phi)/2`,
:math:`\\sin\\psi_0 = 1/\\sqrt{2m}`:

.. math::

    \\sqrt{\\alpha} = K(m) - F(\\psi_0, m), \\qquad \\frac{x}{L} = \\sqrt{\\frac{2\\sin\\phi}{\\alpha}}, \\qquad
    \\frac{y}{L} = 1 - \\frac{2}{\\sqrt\\alpha}\\left(E(m) - E(\\psi_0, m)\\right),

tabulated by Mattiasson (Int. J. Numer. Meth. Eng. 17, 1981, 145, table 1) for :math:`\\alpha` = 1 to 10.

**End torque.** A tip torque :math:`\\tau` bends the rod into a circular arc of curvature :math:`k = \\tau/EI`:
:math:`r(s) = (\\sin ks, 1 - \\cos ks, 0)/k` — at :math:`\\tau L/EI = 4\\pi` two full circles.

Reference: S. Grazioso, "Modeling of a soft link: continuum formulation" (Geometric Theory of Soft Robots,
April 2018; the seed, exercise 1: the end torque), with the elastica as above.

mechgen: the built-in model ``cosserat_rod`` through :func:`mechgen.compile` and :func:`mechgen.rod_statics`
(RKMK4 shooting on SE(3), load continuation to P L^2/EI = 10, each branch point compared), and the
shipped scene ``scenes/rod_end_torque.toml`` through :func:`mechgen.run`.
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

import mechgen

# Mattiasson (1981), table 1: P L^2/EI -> ((L - x)/L, y/L), 5 decimals
MATTIASSON = {1: (0.05643, 0.30172), 2: (0.16064, 0.49346), 3: (0.25442, 0.60325), 4: (0.32894, 0.66996),
              5: (0.38763, 0.71379), 6: (0.43459, 0.74457), 7: (0.47293, 0.76737), 8: (0.50483, 0.78498),
              9: (0.53182, 0.79906), 10: (0.55500, 0.81061)}


def elastica(alpha):
    """Bisshopp & Drucker: ((L - x)/L, y/L, tip angle phi) at alpha = P L^2/EI (scipy's parameter m = k^2)."""
    def gap(phi):
        m = (1 + math.sin(phi)) / 2
        return ellipk(m) - ellipkinc(math.asin(1 / math.sqrt(2 * m)), m) - math.sqrt(alpha)

    phi = brentq(gap, 1e-12, math.pi / 2 - 1e-13, xtol=1e-15)
    m = (1 + math.sin(phi)) / 2
    psi0 = math.asin(1 / math.sqrt(2 * m))
    return 1 - math.sqrt(2 * math.sin(phi) / alpha), 1 - 2 / math.sqrt(alpha) * (ellipe(m) - ellipeinc(psi0, m)), phi


rod = mechgen.compile("cosserat_rod", {"L": 1.0, "EI": 1.0, "GJ": 1.0, "EA": 1e8, "GA": 1e8})
result = mechgen.rod_statics(rod, method="shooting", elements=40, tip_force=[0.0, -10.0, 0.0], steps=10)
points = [point for point in result["branch"] if point["load"] > 0]
loads = np.array([10 * point["load"] for point in points])
tips = np.array([point["tip_position"] for point in points])
reference = np.array([elastica(alpha)[:2] for alpha in loads])
ours = np.column_stack([1 - tips[:, 0], -tips[:, 1]])
error = np.max(np.abs(ours - reference))
print(f"tip load: max |tip_mechgen - elastica| at the {len(loads)} continuation loads {np.round(loads, 2)}: {error:.1e} L")
# the continuation chooses its own load steps; where one lands on a tabulated load, compare with the table too
tabulated = [i for i, alpha in enumerate(loads) if abs(alpha - round(alpha)) < 1e-12 and round(alpha) in MATTIASSON]
table = np.array([MATTIASSON[round(loads[i])] for i in tabulated])
table_error = np.max(np.abs(ours[tabulated] - table))
print(f"          at P L^2/EI = {[round(loads[i]) for i in tabulated]}: max |tip_mechgen - Mattiasson's table| = "
      f"{table_error:.1e} L (table to 5 decimals)")
phi = elastica(10.0)[2]
print(f"          tip angle at P L^2/EI = 10: mechgen {-result['tip_rotation']:.8f} rad, elastica {phi:.8f} rad")
# RKMK4 shooting is of order 4: 40 steps leave under 2e-7 L (tests/test_rod_statics.py), and EA = GA = 1e8 EI/L^2
# adds an extension of order P/EA = 1e-7
assert error < 3e-7 and abs(-result["tip_rotation"] - phi) < 3e-7
assert table_error < 6e-6  # the table's rounding (5e-6) plus the above

# %%
# The end torque: two full turns, against the circular arc.
SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
run = mechgen.run(str(SCENES / "rod_end_torque.toml"))
rolled = {analysis["name"]: analysis["outputs"] for analysis in run["analyses"]}["rolled_up"]
s = np.asarray(rolled["s"])
k = 4 * math.pi  # tau / EI with EI = L = 1
arc = np.column_stack([np.sin(k * s), 1 - np.cos(k * s), 0 * s]) / k
shape = np.asarray(rolled["shape"])
arc_error = np.max(np.abs(shape - arc))
print(f"end torque 4 pi EI/L: max |r_mechgen - circular arc| = {arc_error:.1e} L, tip rotation "
      f"{rolled['tip_rotation']:.10f} rad (4 pi = {4 * math.pi:.10f})")
# both discretisations are exact on the arc (constant strain): what is left is Newton's tolerance
assert arc_error < 1e-8

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 4.2))
left.plot(result["shape"][:, 0], result["shape"][:, 1], label="mechgen, P L^2/EI = 10")
left.plot(tips[:, 0], tips[:, 1], "o", ms=4, label="mechgen tip, continuation steps")
locus = np.array([elastica(alpha) for alpha in np.linspace(0.2, 10.0, 50)])
left.plot(1 - locus[:, 0], -locus[:, 1], "k-", lw=0.8, label="elastica tip locus (Bisshopp & Drucker)")
mattiasson = np.array(list(MATTIASSON.values()))
left.plot(1 - mattiasson[:, 0], -mattiasson[:, 1], "kx", label="Mattiasson (1981), table 1")
left.set_xlabel("x [m]")
left.set_ylabel("y [m]")
left.set_aspect("equal")
left.set_title("Cantilever under a tip load")
left.legend(fontsize=7)
right.plot(shape[:, 0], shape[:, 1], label="mechgen")
right.plot(arc[:, 0], arc[:, 1], "k--", lw=1, label="circular arc")
right.set_xlabel("x [m]")
right.set_ylabel("y [m]")
right.set_aspect("equal")
right.set_title("Rolled up by an end torque (two turns)")
right.legend(fontsize=7)
fig.tight_layout()
plt.show()
