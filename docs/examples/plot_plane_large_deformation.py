"""
A plane block in large deformation: Newton branches in a dead load, and a limit point
=====================================================================================

The built-in model ``plane_block`` is a block :math:`0 < x < L_x,\\ 0 < y < L_y` on rollers (:math:`u_x = 0` on the
left edge, :math:`u_y = 0` on the bottom) pulled by a dead (nominal) traction :math:`P` on its right edge:

.. math::

    \\Pi[u] = \\int W(\\nabla u)\\, dA - \\int_{\\text{right}} P\\, u_x\\, ds,

with :math:`W` a plane law of ``mechgen.symbolic.plane_materials``. The exact state is homogeneous,
:math:`F = \\mathrm{diag}(\\lambda_1, \\lambda_2)`, with the first Piola stresses
:math:`P_{11} = \\partial W/\\partial\\lambda_1 = P`, :math:`P_{22} = 0`. For the compressible neo-Hookean solid in
plane strain, :math:`W = \\frac{\\mu}{2}(\\lambda_1^2 + \\lambda_2^2 - 2) - \\mu \\ln J + \\frac{\\lambda}{2}(\\ln J)^2`,
:math:`J = \\lambda_1 \\lambda_2`:

.. math::

    \\mu(\\lambda_1 - \\lambda_1^{-1}) + \\lambda \\frac{\\ln J}{\\lambda_1} = P, \\qquad
    \\mu(\\lambda_2 - \\lambda_2^{-1}) + \\lambda \\frac{\\ln J}{\\lambda_2} = 0,

solved here independently by scipy's ``brentq``. Saint Venant-Kirchhoff in plane strain has the closed form
:math:`P = E' \\lambda_1 (\\lambda_1^2 - 1)/2`, :math:`E' = E/(1 - \\nu^2)`: in compression the load is largest
at :math:`\\lambda_1 = 1/\\sqrt 3`, :math:`P = -E'/(3\\sqrt 3)`, a limit point that a dead load cannot pass (``steady``
is refused there with a ConvergenceError) and that ``continuation`` turns around and reports as a fold.

mechgen follows both branches by pseudo-arclength continuation in :math:`P` on the assembled sparse tangent
(``scenes/plane_block_continuation.toml`` for the neo-Hookean one); the corner :math:`(L_x, L_y)` moves by
:math:`(L_x(\\lambda_1 - 1), L_y(\\lambda_2 - 1))`.
"""
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
E, NU, LX, LY = 1.0, 0.3, 2.0, 1.0
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))


def neo_hookean(l1, l2):
    """(P_11, P_22) of the plane strain neo-Hookean law at F = diag(l1, l2)."""
    lnJ = math.log(l1 * l2)
    return MU * (l1 - 1 / l1) + LAM * lnJ / l1, MU * (l2 - 1 / l2) + LAM * lnJ / l2


def stretches(P):
    """(l1, l2) with P_11 = P, P_22 = 0 (nested brentq)."""
    def l2_of(l1):
        return brentq(lambda l2: neo_hookean(l1, l2)[1], 0.3, 5.0, xtol=1e-15)
    if P == 0:
        return 1.0, 1.0
    l1 = brentq(lambda l1: neo_hookean(l1, l2_of(l1))[0] - P, 0.6, 5.0, xtol=1e-15)
    return l1, l2_of(l1)


pull = mechgen.run(str(SCENES / "plane_block_continuation.toml"))["analyses"][1]["outputs"]
P = np.array([p["P"] for p in pull["branch"]])
corner = np.array([p["corner_displacement"] for p in pull["branch"]])
exact = np.array([[LX * (l1 - 1), LY * (l2 - 1)] for l1, l2 in map(stretches, P)])
error = np.abs(corner - exact).max()
print(f"neo-Hookean branch: {len(P)} points up to P = {P[-1]:.3f}, folds {pull['folds']}; "
      f"max |corner - exact| = {error:.1e}")
assert error < 1e-8  # each point solves F = 0 to 1e-10

# %%
# Saint Venant-Kirchhoff in compression: the branch turns at the limit point.
scene = {"title": "SVK block in compression", "model": "plane_block",
         "params": {"law": "saint_venant_kirchhoff", "plane": "strain", "P": 0.0, "h": 0.5, "E": E, "nu": NU},
         "analysis": [{"name": "rest", "kind": "steady"},
                      {"name": "press", "kind": "continuation", "about": "rest", "parameter": "P", "stop": -0.3,
                       "max_points": 40, "stability": False, "special_points": False,
                       "points": {"corner": [LX, LY]}}]}
press = mechgen.run(scene)["analyses"][1]["outputs"]
E_PRIME = E / (1 - NU**2)
fold = press["folds"][0]
l_fold = 1 + fold["corner_displacement"][0] / LX
print(f"SVK limit point: P = {fold['P']:.10f} (exact {-E_PRIME / (3 * math.sqrt(3)):.10f}), "
      f"stretch {l_fold:.8f} (exact {1 / math.sqrt(3):.8f})")
assert abs(fold["P"] + E_PRIME / (3 * math.sqrt(3))) < 1e-8
Ps = np.array([p["P"] for p in press["branch"]])
ls = np.array([1 + p["corner_displacement"][0] / LX for p in press["branch"]])
inside = ls > 0  # before the branch crosses l1 = 0 (an inverted block, which SVK's energy does not exclude)
svk_error = np.abs(Ps[inside] - E_PRIME * ls[inside] * (ls[inside]**2 - 1) / 2).max()
print(f"SVK branch: max |P - E' l (l^2 - 1)/2| over {inside.sum()} points = {svk_error:.1e}")

# %%
fig, ax = plt.subplots(figsize=(6.4, 4.2))
grid = np.linspace(0.0, 1.6, 300)
ax.plot(grid, [E_PRIME * l * (l**2 - 1) / 2 for l in grid], "C1-", lw=1, label="SVK, closed form")
ax.plot(ls[inside], Ps[inside], "C1o", ms=4, label="SVK, mechgen branch (past the fold: unstable)")
ax.plot(l_fold, fold["P"], "k*", ms=12, label="limit point (fold)")
l_nh = np.linspace(1.0, exact[-1, 0] / LX + 1, 200)
ax.plot(l_nh, [neo_hookean(l, brentq(lambda l2: neo_hookean(l, l2)[1], 0.3, 5.0))[0] for l in l_nh], "C0-", lw=1,
        label="neo-Hookean, brentq")
ax.plot(1 + corner[:, 0] / LX, P, "C0s", ms=3, label="neo-Hookean, mechgen branch")
ax.set_xlabel(r"stretch $\lambda_1$ (-)")
ax.set_ylabel(r"nominal traction $P$ (Pa)")
ax.set_ylim(-0.3, 1.05)
ax.axhline(0, color="0.8", lw=0.8)
ax.legend(fontsize=8)
ax.set_title("Plane strain block under a dead load (E = 1 Pa, nu = 0.3)")
fig.tight_layout()
plt.show()
