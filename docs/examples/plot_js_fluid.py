"""
Johnson-Segalman channel declared as four fields: steady flow, spectrum and the fold at spurt
=============================================================================================

A non-variational continuum written the way a user writes one (model ``js_fluid``): the velocity :math:`u(y, t)`
along a channel of half-width 1 and the three polymer stresses are fields, and the momentum balance and the
Johnson-Segalman law (Gordon-Schowalter derivative, slip :math:`\\xi`; stress in :math:`\\eta_p/\\lambda`, time in
:math:`\\lambda`) are one weak form, :math:`g = u_y`:

.. math::

    Re\\,u_t = G + \\epsilon u_{yy} + (\\tau_{xy})_y, \\quad
    \\dot\\tau_{xx} = -\\tau_{xx} + (2-\\xi) g \\tau_{xy}, \\quad
    \\dot\\tau_{yy} = -\\tau_{yy} - \\xi g \\tau_{xy}, \\quad
    \\dot\\tau_{xy} = -\\tau_{xy} + g\\,(1 - \\tfrac{\\xi}{2}\\tau_{xx} + \\tfrac{2-\\xi}{2}\\tau_{yy}),

with :math:`u = 0` at the walls; declared as

.. code-block:: python

    model.field("u", "txx", "tyy", "txy", length="width", discretisation="lagrange2", N=16)

    @model.weak_form
    def balance(test, u, p):
        g = u.u_s
        momentum = test.u * (p.Re * u.u_t - p.G) + test.u_s * (p.epsilon * g + u.txy)
        ...

    model.output("flow_rate", lambda u: u.u, integrate=True)

The generic analyses run it, ``simulate`` included: the fields carry no mass, so the state is q alone and its
rate the root of :math:`r(q, \dot q, 0) = 0`. References: the steady flow rate :math:`Q(G) = 2\\int_0^1 y\\,g(Gy)\\,dy` in closed
form, the spurt threshold :math:`T_{max}` (the maximum of the local shear curve
:math:`T(g) = \\epsilon g + g/(1 + \\xi(2-\\xi) g^2)`), and the Chebyshev-collocated channel of
``scenes/js_channel.toml`` for the spectrum.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen
from mechgen.runtime.fluids import johnson_segalman as js

scene = Path(mechgen.__file__).resolve().parents[1] / "scenes" / "js_fluid.toml"
out = {a["name"]: a["outputs"] for a in mechgen.run(str(scene))["analyses"]}
eps, xi = 0.06, 0.2
q_exact = js.flow_rate(0.5, eps, xi)[0]
t_max = js.extrema(eps, xi)[0][1]
print(f"flow rate at G = 0.5: {out['base']['flow_rate']:.10f}  closed form {q_exact:.10f}  "
      f"error {abs(out['base']['flow_rate'] - q_exact):.1e}")
lam = np.array([complex(*v) for v in out["spectrum"]["eigenvalues"]])
right = lam[np.argsort(-lam.real)][:2]
print("rightmost eigenvalues:", np.round(right, 6), " collocated channel: -0.607201 +- 1.482470 i")
fold = out["flow_curve"]["folds"][0]["G"]
print(f"first fold G = {fold:.6f} at N = 16; spurt threshold T_max = {t_max:.6f} (the fold tends to it as h)")

branch = out["flow_curve"]["branch"]
G_grid = np.linspace(0.02, t_max, 200)
start = out["start_up"]
print(f"start-up from rest: Q(t = 30) = {start['flow_rate']:.10f}, steady {out['base']['flow_rate']:.10f}")

fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(14, 4))
ax.plot([p["G"] for p in branch], [p["flow_rate"] for p in branch], ".-", ms=3, lw=0.6, label="continuation (N = 16)")
ax.plot(G_grid, [js.flow_rate(g, eps, xi)[0] for g in G_grid], "k-", lw=0.8, label="classical branch, closed form")
ax.axvline(t_max, color="tab:red", ls="--", lw=0.8, label="spurt threshold T_max")
ax.plot(fold, out["flow_curve"]["folds"][0]["flow_rate"], "x", color="tab:purple", ms=8, label="first fold")
ax.set(xlabel="G", ylabel="flow rate Q", title="flow curve: classical branch, then the jump moves in")
ax.legend(fontsize=8)
bx.plot(lam.real, lam.imag, ".", ms=3, label="eigenvalues (N = 16)")
bx.plot([-0.607201, -0.607201], [1.482470, -1.482470], "o", mfc="none", ms=8, label="collocated channel")
bx.set(xlabel="Re lambda", ylabel="Im lambda", xlim=(-4, 0.2), ylim=(-6, 6), title="spectrum at G = 0.5, Re = 1")
bx.legend(fontsize=8)
cx.plot(start["t"], start["trajectory"]["flow_rate"], "-", label="simulate from rest")
cx.axhline(out["base"]["flow_rate"], color="k", ls=":", lw=0.8, label="steady state (Newton)")
cx.set(xlabel="t (lambda)", ylabel="flow rate Q", title="start-up at G = 0.5: elastic overshoot")
cx.legend(fontsize=8)
plt.tight_layout()
plt.show()
