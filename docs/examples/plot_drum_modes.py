"""
A circular drum: plane modes against Bessel zeros
==================================================

A membrane of radius :math:`R` (m) under a tension :math:`P` per unit length (N/m), mass :math:`\\rho` per
unit area (kg/m\\ :sup:`2`), fixed at its rim. The built-in model ``drum`` declares, per unit area,

.. math::

    T = \\frac{\\rho}{2} w_t^2, \\qquad V = \\frac P2 (w_x^2 + w_y^2), \\qquad w = 0 \\text{ on } r = R,

and ``modes`` solves :math:`K\\phi = \\omega^2 M\\phi` with the sparse shift-invert Lanczos for the lowest
``count``. Reference: separation in polar coordinates gives :math:`w = J_m(k r)\\cos m\\theta`,
:math:`\\omega_{mn} = j_{mn}\\sqrt{P/\\rho}/R` with :math:`j_{mn}` the :math:`n`-th zero of the Bessel function
:math:`J_m` (each :math:`m \\ge 1` twice: the cos and sin shapes), from ``scipy.special.jn_zeros``. The
eigenvalue error of P2 elements falls as :math:`h^{2p} = h^4` with curved (isoparametric) rim edges and as
:math:`h^2` with straight ones: the polygon's lost area, not the element, limits it.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.special import jn_zeros

import mechgen
from mechgen.runtime.linear.modes import modes as solve_modes

zeros = sorted((z, m) for m in range(8) for z in jn_zeros(m, 4))
exact = np.array([z for z, m in zeros for _ in range(1 if m == 0 else 2)][:8])
labels = [f"j_{m}{sum(1 for z2, m2 in zeros if m2 == m and z2 <= z)}" for z, m in zeros for _ in range(1 if m == 0 else 2)][:8]

drum = mechgen.compile("drum", kernels=("linear",))
fig, ax = plt.subplots(figsize=(6.4, 4.4))
hs = np.array([0.2, 0.1, 0.05])
for edges in ("straight", "curved"):
    errors = []
    for h in hs:
        L = drum.with_params(h=h, edges=edges).linear()
        omega = solve_modes(L["M"], L["K"], count=8).frequencies[:8]
        errors.append(np.max(np.abs(omega - exact) / exact))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    print(f"{edges:8s} edges: largest relative error of the first eight {', '.join(f'{e:.2e}' for e in errors)} "
          f"at h = {', '.join(map(str, hs))}; rates {', '.join(f'{r:.2f}' for r in rates)}")
    ax.loglog(hs, errors, "o-", label=f"P2, {edges} edges (rate {rates[-1]:.1f})")
ax.set(xlabel="h (m)", ylabel="max relative error, first 8 frequencies", title="drum: frequencies against j_mn")
ax.legend(fontsize=8)
fig.tight_layout()

# %%
# The shipped scene ``scenes/drum_modes.toml`` at h = 0.1, frequency by frequency, and its mode shapes.
SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
out = mechgen.run(str(SCENES / "drum_modes.toml"))["analyses"][0]["outputs"]
for label, w, ref in zip(labels, out["frequencies"], exact):
    print(f"{label}: omega = {w:.6f} rad/s, exact {ref:.6f}, relative error {abs(w - ref) / ref:.1e}")
system = mechgen.compile("drum", kernels=("linear",))
L = system.linear()
res = solve_modes(L["M"], L["K"], count=6)
data = system.figure_data(res.shapes[:, :6])
from mechgen.analyses.plane_figures import panel  # noqa: E402

fig2, axes = plt.subplots(2, 3, figsize=(10, 6))
for k, ax2 in enumerate(axes.ravel()):
    panel(plt, ax2, data, np.asarray(data["values"][k]), f"mode {k + 1}: {res.frequencies[k]:.5f} rad/s")
    ax2.set_xticks([])
    ax2.set_yticks([])
fig2.tight_layout()
