"""
Johnson-Segalman channel flow: the spurt threshold and the flow curve
=====================================================================

Seed 002 (Khayat & Ashrafi). In a steady pressure-driven channel (walls at :math:`y = \\pm 1`, pressure gradient
G in stress units :math:`\\eta_p/\\lambda` per half-width) the total shear stress is :math:`G|y|`, so the shear rate
at each y is a root of the local law

.. math::

    T(g) = \\epsilon g + \\frac{g}{1 + \\xi(2 - \\xi) g^2} = G |y| .

The classical (low-rate) solution exists while the wall stress stays below the curve's maximum: the **spurt
threshold** :math:`G_s = T_{max}`, exact before any discretisation. Its flux per unit width

.. math::

    Q(G) = 2\\int_0^1 y\\, g(G y)\\, dy = \\frac{2}{G^2}\\int_0^G T\\, g(T)\\, dT
         = \\frac{2}{G^2}\\Big[\\frac{g T^2}{2} - \\frac12\\int_0^g T^2\\, dg'\\Big]_{g_w}

is summed in closed form (``channel_flow``). Above :math:`G_s` the rate must jump to the high branch: at
:math:`G y = T_{max}` (top-jumping) or :math:`G y = T_{min}` (bottom-jumping). Reference: scipy's ``quad`` of the
defining integral with the rate found by ``brentq``; :math:`\\epsilon = 0.06`, :math:`\\xi = 0.2` as in the paper.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

import mechgen

here = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
scene = next(p / "scenes" / "js_channel.toml" for p in (here, *here.parents) if (p / "scenes").is_dir())
out = mechgen.run(str(scene))["analyses"][0]["outputs"]

eps, xi = 0.06, 0.2
k = xi * (2 - xi)
g_max = np.sqrt(((1 - 2 * eps) - np.sqrt(1 - 8 * eps)) / (2 * eps) / k)
T = lambda g: eps * g + g / (1 + k * g**2)  # noqa: E731
print(f"spurt_gradient = {out['spurt_gradient']:.15f}   T(g_max) closed form = {T(g_max):.15f}")


def reference(G):
    """2 int_0^1 y g(G y) dy with g from brentq on the classical branch."""
    return 2 * quad(lambda y: y * brentq(lambda g: T(g) - G * y, 0, g_max) if y > 0 else 0.0, 0, 1,
                    epsabs=0, epsrel=1e-12)[0]


G, Q = np.array(out["G"]), np.array(out["flow_rate"])
check = [(g, q, reference(g)) for g, q in zip(G[1::20], Q[1::20])]
err = max(abs(q / r - 1) for _, q, r in check)
print(f"flow rate vs quad at {len(check)} gradients: largest relative error {err:.1e}")
assert err < 1e-10

fig, ax = plt.subplots(figsize=(6.4, 4.4))
ax.plot(G, Q, "k-", label="classical branch")
ax.plot(out["G_above"], out["flow_rate_top"], "C0-", label="top-jumping")
ax.plot(out["G_above"], out["flow_rate_bottom"], "C1--", label="bottom-jumping")
ax.plot([c[0] for c in check], [c[2] for c in check], "r+", ms=9, label="quad (reference)")
ax.axvline(out["spurt_gradient"], color="0.5", lw=0.8, ls=":")
ax.text(out["spurt_gradient"], 0.2, " spurt", color="0.4")
ax.set(xlabel="pressure gradient G (eta_p / lambda per half-width)", ylabel="flow rate Q",
       title="Johnson-Segalman channel, epsilon = 0.06, xi = 0.2")
ax.legend()
plt.show()
