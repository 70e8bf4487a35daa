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

is summed in closed form (``channel_flow``). With ``discrete = true`` the collocated steady channel (the model's
generated stress laws at every Chebyshev point) is continued in G past its first fold, which converges to
:math:`G_s` under refinement. Above :math:`G_s` the rate must jump to the high branch: at
:math:`G y = T_{max}` (top-jumping) or :math:`G y = T_{min}` (bottom-jumping). A quasi-static ramp up and down
without inertia (each y on its own S-curve, jumping up at :math:`T_{max}`, down at :math:`T_{min}`) loads along
the top-jumping curve and unloads with the interface latched at :math:`T_{max}/G_{max}`, then bottom-jumping:
the hysteresis loop (checked against a slow ramp of the local dynamics in tests/test_js_channel.py). Reference: scipy's ``quad`` of the
defining integral with the rate found by ``brentq``; :math:`\\epsilon = 0.06`, :math:`\\xi = 0.2` as in the paper.

**Spectrum.** ``channel_spectrum`` linearises the classical state at G = 0.5, Re = 1 (Chebyshev collocation at
two resolutions, the local blocks from the model's generated stress laws):

.. math::

    Re\\,\\lambda u = \\epsilon u'' + \\tau_{xy}', \\qquad \\lambda \\sigma = J_\\sigma(y)\\,\\sigma + J_g(y)\\, u' .

The local stress-controlled eigenvalues :math:`\\lambda_{loc}(T = G y)` (the eigenvalues of
:math:`J_\\sigma - J_g e_{xy}^T/\\epsilon`) form the essential spectrum, drawn as a band and reported apart
from the point eigenvalues. Reference for the point eigenvalues: for :math:`\\xi = 0` the closed form
:math:`Re\\,\\lambda^2 + (Re + \\epsilon\\kappa^2)\\lambda + \\kappa^2(1 + \\epsilon) = 0`,
:math:`\\kappa = n\\pi/2` (drawn here), and an independent finite-difference discretisation (tests/test_js_channel_spectrum.py).
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

import mechgen

scene = Path(mechgen.__file__).resolve().parents[1] / "scenes" / "js_channel.toml"
results = {a["name"]: a["outputs"] for a in mechgen.run(str(scene))["analyses"]}
out, spectrum = results["flow_curve"], results["spectrum"]

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
fold17, fold25 = out["spurt_gradient_discrete"]
print(f"collocated steady branch's first fold: N = 17: {fold17:.6f}, N = 25: {fold25:.6f} "
      f"(errors {fold17 - out['spurt_gradient']:.1e}, {fold25 - out['spurt_gradient']:.1e}: O(N^-2))")

fig, ax = plt.subplots(figsize=(6.4, 4.4))
ax.plot(G, Q, "k-", label="classical branch")
ax.plot(out["G_above"], out["flow_rate_top"], "C0-", label="top-jumping")
ax.plot(out["G_above"], out["flow_rate_bottom"], "C1--", label="bottom-jumping")
ax.plot(out["G_down"], out["flow_rate_down"], "C3:", label="quasi-static unloading (loop)")
ax.plot([c[0] for c in check], [c[2] for c in check], "r+", ms=9, label="quad (reference)")
ax.plot(out["discrete_G"], out["discrete_flow_rate"], "o", mfc="none", ms=5, color="C2",
        label="collocated steady branch, N = 25")
ax.axvline(out["spurt_gradient"], color="0.5", lw=0.8, ls=":")
ax.text(out["spurt_gradient"], 0.2, " spurt", color="0.4")
ax.set(xlabel="pressure gradient G (eta_p / lambda per half-width)", ylabel="flow rate Q",
       title="Johnson-Segalman channel, epsilon = 0.06, xi = 0.2")
ax.legend()
plt.show()

# %%
# The spectrum at G = 0.5, Re = 1: point eigenvalues and the essential band; the same analysis at xi = 0 against the
# Oldroyd-B closed form.
point = np.array([complex(*v) for v in spectrum["eigenvalues"]])
print("rightmost point eigenvalues:", ", ".join(f"{v.real:.6f}{v.imag:+.6f}i" for v in point[:5]))
print("essential spectrum, centre:", [complex(*v) for v in spectrum["essential_spectrum"][0]])
print("essential spectrum, wall:  ", [complex(*v) for v in spectrum["essential_spectrum"][1]])
oldroyd = next(a["outputs"] for a in mechgen.run(str(scene), overrides=["xi=0"])["analyses"] if a["name"] == "spectrum")
found = np.array([complex(*v) for v in oldroyd["eigenvalues"]])
roots = [r for n in range(1, 5) for r in np.roots([1.0, 1.0 + eps * (n * np.pi / 2) ** 2, (n * np.pi / 2) ** 2 * (1 + eps)])]
err = max(np.min(np.abs(found - r)) for r in roots)
print(f"xi = 0: point eigenvalues vs Re l^2 + (Re + eps k^2) l + k^2 (1 + eps) = 0, n = 1..4: largest error {err:.1e}")
assert err < 1e-8

fig, ax = plt.subplots(figsize=(6.4, 4.4))
ax.plot(point.real, point.imag, "o", mfc="none", color="C0", label="point eigenvalues, xi = 0.2")
ax.plot(found.real, found.imag, "x", color="C1", label="point eigenvalues, xi = 0")
ax.plot(np.real(roots), np.imag(roots), "+", color="k", ms=12, label="closed form, xi = 0")
for end in spectrum["essential_spectrum"]:
    ax.plot([v[0] for v in end], [v[1] for v in end], "s", color="0.5", mfc="none", ms=8)
ax.plot([], [], "s", color="0.5", mfc="none", label="essential band ends, xi = 0.2 (centre, wall)")
ax.set(xlim=(-3, 0.2), ylim=(-6, 6), xlabel="Re lambda", ylabel="Im lambda",
       title=f"linearised channel, G = 0.5, Re = 1 (band's right end {spectrum['essential_rightmost']:.3f})")
ax.legend(loc="upper left", fontsize=8)
plt.show()
