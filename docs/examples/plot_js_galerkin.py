"""
Johnson-Segalman channel, the seed's low-order Galerkin system: steady branch in We, folds and stability
=========================================================================================================

Seed 002 (Khayat & Ashrafi) reduces the channel flow of the Johnson-Segalman fluid to a dynamical system by
Galerkin projection without stating its truncation. ``js_galerkin`` is the lowest natural one (velocity in
:math:`d/\\lambda`, time in :math:`\\lambda`, stress in :math:`\\eta_p/\\lambda`, :math:`y \\in [-1/2, 1/2]`):
the channel equations

.. math::

    Re\\,u_t = We + S_y + \\epsilon u_{yy}, \\quad N_t = -N + 2 S u_y, \\quad
    S_t = -S + u_y (1 + \\xi(\\xi/2 - 1) N)

projected on :math:`u = A\\phi`, :math:`S = B\\phi'`, :math:`N = C\\phi'^2`, :math:`\\phi = 1 - 4y^2`:

.. math::

    A' = \\tfrac{5}{4 Re}(We - 8B - 8\\epsilon A), \\quad B' = -B + A + \\tfrac{48}{5}\\xi(\\xi/2 - 1) A C,
    \\quad C' = -C + 2AB.

Steady states lie on :math:`We = (8/c)\\,T(cA)`, :math:`c = \\sqrt{48/5}`, with :math:`T(g) = \\epsilon g +
g/(1 + \\xi(2-\\xi)g^2)` the shear curve, so the folds are at :math:`(8/c) T_{max}` and :math:`(8/c) T_{min}`
(:math:`\\xi(2-\\xi)g^2 = ((1-2\\epsilon) \\mp \\sqrt{1-8\\epsilon})/(2\\epsilon)`). The paper's critical
Weissenberg numbers (8.48 and 16.53 at :math:`\\epsilon = 0.08`) are not reached by this truncation.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

scene = Path(mechgen.__file__).resolve().parents[1] / "scenes" / "js_galerkin.toml"
out = {a["name"]: a["outputs"] for a in mechgen.run(str(scene))["analyses"]}
branch = out["branch"]

eps, xi = 0.08, 0.2
k, c = xi * (2 - xi), np.sqrt(48 / 5)
s = np.array([(1 - 2 * eps) - np.sqrt(1 - 8 * eps), (1 - 2 * eps) + np.sqrt(1 - 8 * eps)]) / (2 * eps)
g_ref = np.sqrt(s / k)
we_ref = 8 / c * (eps * g_ref + g_ref / (1 + k * g_ref**2))
folds = [p for p in branch["special_points"] if p["type"] == "LP"]
print("fold   We (continuation)   We (closed form)   error    paper's critical We (eps = 0.08)")
for p, w0, paper in zip(folds, we_ref, (8.48, 16.53)):
    print(f"LP     {p['We']:.12f}      {w0:.12f}     {abs(p['We'] - w0):.1e}   {paper}")
print("stability changes:", [(q["from"], q["to"]) for q in branch["stability_changes"]])
print("at We = 2:", out["lower"]["verdict"], out["lower"]["eigenvalues"])
assert all(abs(p["We"] - w0) < 1e-8 for p, w0 in zip(folds, we_ref))

a_grid = np.linspace(0, 3, 600)
fig, ax = plt.subplots(figsize=(6, 4))
we_curve = 8 * eps * a_grid + 8 * a_grid / (1 + 48 / 5 * k * a_grid**2)
ax.plot(we_curve, 4 * a_grid, "k-", lw=0.8, label="closed form")
ax.plot([p["We"] for p in branch["branch"]], [p["wall_shear_rate"] for p in branch["branch"]], ".", ms=3,
        label="continuation in We")
ax.plot([p["We"] for p in folds], [p["wall_shear_rate"] for p in folds], "rs", mfc="none", label="folds (LP)")
ax.set(xlabel="We", ylabel="wall shear rate 4A (1/lambda)", xlim=(0, 4),
       title="js_galerkin, epsilon = 0.08, xi = 0.2: middle branch unstable")
ax.legend()
plt.tight_layout()
plt.show()
