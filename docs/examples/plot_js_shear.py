"""
Johnson-Segalman fluid in homogeneous shear: the non-monotone shear curve, its folds and no Hopf point
======================================================================================================

Seed 002 (Khayat & Ashrafi). The Johnson-Segalman fluid (polymer viscosity :math:`\\eta_p`, relaxation time
:math:`\\lambda`, solvent viscosity :math:`\\epsilon\\,\\eta_p`, slip parameter :math:`\\xi` of the
Gordon-Schowalter derivative) in simple shear at rate :math:`g`, stresses in :math:`\\eta_p/\\lambda`, time in
:math:`\\lambda`:

.. math::

    \\dot\\tau_{xx} = -\\tau_{xx} + (2 - \\xi) g \\tau_{xy}, \\quad
    \\dot\\tau_{yy} = -\\tau_{yy} - \\xi g \\tau_{xy}, \\quad
    \\dot\\tau_{xy} = -\\tau_{xy} + g - \\tfrac{\\xi}{2} g \\tau_{xx} + \\tfrac{2 - \\xi}{2} g \\tau_{yy}.

Steady shear gives the total stress (the paper's eq. 4)

.. math::

    T(g) = \\epsilon g + \\frac{g}{1 + \\xi(2 - \\xi) g^2},

monotone for :math:`\\epsilon \\ge 1/8`; below, a local maximum and minimum at
:math:`\\xi(2-\\xi) g^2 = ((1 - 2\\epsilon) \\mp \\sqrt{1 - 8\\epsilon})/(2\\epsilon)`. Under an imposed total
stress T (so :math:`g = (T - \\tau_{xy})/\\epsilon`) the equilibria form an S-curve, continued in T by mechgen's
``continuation``; its folds (LP) are the extrema. :math:`W = \\xi\\tau_{xx} + (2-\\xi)\\tau_{yy}` obeys
:math:`\\dot W = -W` (the eigenvalue -1 off the seed's invariant two-stress plane), and the Jacobian's trace
:math:`-3 - 1/(\\epsilon(1 + \\xi(2-\\xi)g^2))` leaves the other pair a sum below -2: no Hopf point.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

scene = Path(mechgen.__file__).resolve().parents[1] / "scenes" / "js_shear.toml"
out = {a["name"]: a["outputs"] for a in mechgen.run(str(scene))["analyses"]}
curve, branch = out["curve"], out["s_curve"]

eps, xi = 0.06, 0.2
k = xi * (2 - xi)
s_lo, s_hi = ((1 - 2 * eps) - np.sqrt(1 - 8 * eps)) / (2 * eps), ((1 - 2 * eps) + np.sqrt(1 - 8 * eps)) / (2 * eps)
g_ref = np.sqrt(np.array([s_lo, s_hi]) / k)
T_ref = eps * g_ref + g_ref / (1 + k * g_ref**2)
folds = [p for p in branch["special_points"] if p["type"] == "LP"]
print("fold   T (continuation)   T (closed form)   error     g (continuation)   g (closed form)")
for p, g0, T0 in zip(folds, g_ref, T_ref):
    print(f"LP     {p['T']:.12f}     {T0:.12f}    {abs(p['T'] - T0):.1e}   {p['shear_rate']:.9f}        {g0:.9f}")
print("special point types:", [p["type"] for p in branch["special_points"]], "(no H); hopf verdict:", curve["hopf"],
      f"(largest pair trace {curve['pair_trace_max']:.4f} < 0)")
assert all(abs(p["T"] - T0) < 1e-9 for p, T0 in zip(folds, T_ref))

fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
g = np.linspace(0, 12, 600)
for e in (0.0, 0.06, 0.08, 0.125, 0.2, 1.0):
    a1.plot(g, e * g + g / (1 + k * g**2), lw=1, label=f"epsilon = {e:g}")
a1.set(xlabel="shear rate g (1/lambda)", ylabel="T (eta_p / lambda)", ylim=(0, 2.5),
       title="steady shear curves, xi = 0.2 (paper's Fig. 1)")
a1.legend(fontsize=8)
rates = [p["shear_rate"] for p in branch["branch"]]
stress = [p["T"] for p in branch["branch"]]
a2.plot(curve["shear_rate"], curve["stress"], "k-", lw=0.8, label="closed form")
a2.plot(rates, stress, ".", ms=3, label="continuation in T")
a2.plot([p["shear_rate"] for p in folds], [p["T"] for p in folds], "rs", mfc="none", label="folds (LP)")
a2.set(xlabel="shear rate g", ylabel="imposed T", xlim=(0, 12), title="S-curve, epsilon = 0.06")
a2.legend()
plt.tight_layout()
plt.show()
