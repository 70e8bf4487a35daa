"""
A circular membrane under in-plane gravity: plane elasticity, Michell's solution and what limits convergence
=============================================================================================================

A disk of radius :math:`R` (m) fixed at its rim carries its own weight :math:`\\rho g` (N/m\\ :sup:`3`)
acting in :math:`-y` (seed: *In-plane gravity loading of a circular membrane*). The built-in model
``membrane_gravity`` declares the plane stress strain energy and the weight per unit area (per unit
thickness) in the displacement gradient's jets,

.. math::

    V = \\mu\\,\\varepsilon:\\varepsilon + \\tfrac{\\lambda^*}{2}(\\operatorname{tr}\\varepsilon)^2 + \\rho g\\,u_y,
    \\qquad \\mu = \\frac{E}{2(1+\\nu)}, \\quad \\lambda^* = \\frac{E\\nu}{1-\\nu^2},

and mechgen derives the pointwise residual and tangent once (Hooke's tensor), then assembles them over P2
triangles. Reference: Michell's general solution for this load (rebuilt and checked symbolically in the
tests) is a polynomial,

.. math::

    u_x = 0, \\qquad u_y = -\\frac{\\rho g\\,(R^2 - r^2)}{2(\\lambda^* + 3\\mu)}, \\qquad
    U = \\frac{\\pi \\rho g^2 R^4}{8(\\lambda^* + 3\\mu)} .

A quadratic field lies in the P2 space, so on the exact disk P2 elements would reproduce it. What is left is
the boundary: a polygonal disk (straight-sided edges) loses :math:`O(h^2)` in energy, isoparametric (curved)
edges :math:`O(h^4)`. The annulus (``annulus_gravity``, a free hole) has no polynomial solution (Michell's
:math:`n = 1` terms with :math:`r\\ln r`), and the same rates hold there.
"""
import matplotlib.pyplot as plt
import numpy as np

import mechgen
from mechgen.analyses.plane_states import plane_steady
from mechgen.runtime.plane.closed_forms import PlaneElastic, annulus_strain_energy

E, nu, rho_g, R = 1.0, 0.3, 1.0, 1.0
mu, lam = E / (2 * (1 + nu)), E * nu / (1 - nu**2)
U_exact = np.pi * rho_g**2 * R**4 / (8 * (lam + 3 * mu))
uy_exact = -rho_g * R**2 / (2 * (lam + 3 * mu))

membrane = mechgen.compile("membrane_gravity", {"E": E, "nu": nu, "rho_g": rho_g, "R": R},
                           kernels=("residual", "tangent", "outputs"))
annulus = mechgen.compile("annulus_gravity", kernels=("residual", "tangent", "outputs"))
U_annulus = annulus_strain_energy(0.5, 1.0, PlaneElastic(1.0, 0.3, "stress"), 1.0)

hs = np.array([0.2, 0.1, 0.05])
fig, ax = plt.subplots(figsize=(6.4, 4.4))
print("case                        h      unknowns  |U - U_exact|/U   |u_y(0) - exact|/|u_y|")
for label, system, exact, edges in (("disk, straight edges", membrane, U_exact, "straight"),
                                    ("disk, curved edges", membrane, U_exact, "curved"),
                                    ("annulus, straight edges", annulus, U_annulus, "straight"),
                                    ("annulus, curved edges", annulus, U_annulus, "curved")):
    errors = []
    for h in hs:
        s = system.with_params(h=h, edges=edges)
        out = plane_steady(s, {"points": {"centre": [0.0, 0.0]}} if system is membrane else {})
        errors.append(abs(out["strain_energy"] - exact) / exact)
        tip = f"{abs(out['centre_displacement'][1] - uy_exact) / abs(uy_exact):.2e}" if system is membrane else "-"
        print(f"{label:26s} {h:5.3f} {s.n:9d}  {errors[-1]:.2e}          {tip}")
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    print(f"{'':26s} energy rates: {', '.join(f'{r:.2f}' for r in rates)}")
    ax.loglog(hs, errors, "o-", label=f"{label} (rate {rates[-1]:.1f})")
ax.loglog(hs, 0.3 * hs**2, "k:", lw=0.8, label="h^2")
ax.loglog(hs, 0.01 * hs**4, "k--", lw=0.8, label="h^4")
ax.set(xlabel="h (m)", ylabel="relative error of the strain energy",
       title="P2 elements: the boundary, not the element, sets the rate")
ax.legend(fontsize=7)
fig.tight_layout()

# %%
# The scene ``scenes/membrane_gravity.toml`` runs the steady state with outputs at named points; its figure
# shows the deformed mesh and the von Mises stress per element.
from pathlib import Path  # noqa: E402

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
out = mechgen.run(str(SCENES / "membrane_gravity.toml"))["analyses"][0]["outputs"]
print(f"centre u_y = {out['center_displacement'][1]:.9f} (exact {uy_exact:.9f}), "
      f"rim reaction {out['reactions']['outer']['uy']:.9f} (the weight pi R^2 rho_g = {np.pi * R**2 * rho_g:.9f})")
