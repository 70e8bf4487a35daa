"""
Bifurcations of equilibria: a pitchfork with branch switching, and Hopf points with their criticality
=====================================================================================================

``continuation`` follows an equilibrium F(y, p) = 0 in a parameter p and reports its **special points**: folds
(``LP``), branch points (``BP``) and Hopf points (``H``), each the zero of a test function located along the
branch.

**A pitchfork.** The Duffing-type buckling oscillator

.. math::

    \\ddot x + c\\,\\dot x + (k - P)\\,x + a\\,x^3 = 0

has the trivial equilibrium x = 0 for every load P and, for a > 0, the buckled branch :math:`x^2 = (P - k)/a`
for P > k; they cross at the branch point P = k. The test function of a BP is

.. math::

    \\psi_{BP} = \\det \\begin{pmatrix} F_y & F_P \\\\ c^T \\end{pmatrix}

(c the branch segment's direction). It changes sign where two branches cross and not at a fold, and it counts no
eigenvalues: along the buckled branch :math:`F_y = 2 a x^2 \\ge 0` never changes sign, yet the BP is found from
there too. ``switch_branches = true`` follows the other branch from the BP, both ways.

**A Hopf point.** The Rayleigh oscillator :math:`\\ddot x + \\omega_0^2 x = (\\mu + \\beta x^2)\\,\\dot x` loses the
stability of x = 0 at :math:`\\mu = 0` through the pair :math:`\\pm i\\omega_0`. The test function is the
bialternate product :math:`\\prod_{i<j} (\\lambda_i + \\lambda_j)` of the eigenvalues; at the located point the first
Lyapunov coefficient (Kuznetsov, *Elements of Applied Bifurcation Theory*, eq. 3.20) decides: :math:`l_1 < 0`,
a stable limit cycle is born (supercritical); :math:`l_1 > 0`, an unstable one (subcritical). Averaging
(x = r cos φ) gives :math:`\\dot r = \\mu r / 2 + \\beta r^3 / 8`, and with Kuznetsov's normalisation

.. math::

    l_1 = \\frac{\\beta}{2\\,\\omega_0\\,(1 + \\omega_0^2)} .
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

PITCHFORK = '''\
"""x'' + c x' + (k - P) x + a x^3 = 0."""
from mechgen import Model, Param

model = Model("gallery_pitchfork", doc=__doc__)
model.params(Param("P", 0.5, "N"), Param("k", 1.0, "N/m"), Param("a", 2.0, "N/m^3"), Param("c", 0.1, "N s/m"))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: (p.k - p.P) * q.x**2 / 2 + p.a * q.x**4 / 4)
model.dissipation(lambda v, p: p.c * v.x**2 / 2)
'''

RAYLEIGH = '''\
"""x'' + w0^2 x = (mu + beta x^2) x'."""
from mechgen import Model, Param

model = Model("gallery_rayleigh", doc=__doc__)
model.params(Param("mu", -0.5), Param("w0", 1.5), Param("beta", -1.0))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: p.w0**2 * q.x**2 / 2)


@model.forces
def forces(q, v, p):
    return {"x": (p.mu + p.beta * q.x**2) * v.x}
'''

folder = Path(tempfile.mkdtemp())
(folder / "pitchfork.py").write_text(PITCHFORK)
(folder / "rayleigh.py").write_text(RAYLEIGH)
column = mechgen.compile(str(folder / "pitchfork.py"), free=["P"])
rest = mechgen.steady(column, guess={"x": 0.0})
branch = mechgen.continuation(column, about=rest, parameter="P", stop=2.0, max_step=0.1, switch_branches=True)

# %%
# The branch point against the closed form P = k, and every switched point against x^2 = (P - k) / a.
(bp,) = [s for s in branch["special_points"] if s["type"] == "BP"]
print(f"BP at P = {bp['P']:.12f} (closed form 1), error {abs(bp['P'] - 1.0):.1e}")
worst = max(abs(p["coordinates"]["x"] ** 2 - (p["P"] - 1.0) / 2.0)
            for half in branch["switched_branches"] for p in half["branch"])
print(f"largest |x^2 - (P - k)/a| on the switched branch: {worst:.1e}")
assert abs(bp["P"] - 1.0) < 1e-8 and worst < 1e-9

# %%
# The Hopf point of the Rayleigh oscillator for a supercritical (beta < 0) and a subcritical (beta > 0) case.
w0 = 1.5
hopf = {}
for beta in (-1.0, 0.5):
    oscillator = mechgen.compile(str(folder / "rayleigh.py"), {"beta": beta}, free=["mu"])
    origin = mechgen.steady(oscillator, guess={"x": 0.0})
    found = mechgen.continuation(oscillator, about=origin, parameter="mu", stop=0.5)
    (h,) = [s for s in found["special_points"] if s["type"] == "H"]
    expected = beta / (2 * w0 * (1 + w0**2))
    print(f"beta = {beta:+.1f}: H at mu = {h['mu']:.1e}, omega = {h['frequency']:.12f} (closed form {w0}), "
          f"l1 = {h['lyapunov']:.10f} (closed form {expected:.10f}, relative error "
          f"{abs(h['lyapunov'] / expected - 1):.1e}), {h['criticality']}")
    assert abs(h["lyapunov"] / expected - 1) < 1e-6
    hopf[beta] = h

# %%
# The pitchfork diagram: the trivial branch (its stability changes at the BP) and the two switched halves.
fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
P = [p["P"] for p in branch["branch"]]
left.plot(P, [p["coordinates"]["x"] for p in branch["branch"]], "k-", label="x = 0")
for half in branch["switched_branches"]:
    left.plot([p["P"] for p in half["branch"]], [p["coordinates"]["x"] for p in half["branch"]], "o", ms=3,
              label=f"switched, half {half['half']}")
grid = np.linspace(1.0, 2.0, 101)
left.plot(grid, np.sqrt((grid - 1.0) / 2.0), "c-", lw=0.8, label="closed form")
left.plot(grid, -np.sqrt((grid - 1.0) / 2.0), "c-", lw=0.8)
left.plot(bp["P"], 0.0, "ks", mfc="none", ms=9, label="BP")
left.set_xlabel("P (N)")
left.set_ylabel("x (m)")
left.legend(fontsize=7)
left.set_title("pitchfork: BP located, other branch switched onto", fontsize=9)

# %%
# Amplitude of the limit cycle near the Hopf point, from averaging: r^2 = -4 mu / beta on the side where it
# exists (mu > 0 for beta < 0: stable; mu < 0 for beta > 0: unstable).
for beta, style in ((-1.0, "b-"), (0.5, "r--")):
    mu = np.linspace(0.0, 0.4, 50) * (1 if beta < 0 else -1)
    right.plot(mu, np.sqrt(-4 * mu / beta), style,
               label=f"beta = {beta:+.1f}: {hopf[beta]['criticality']} (l1 = {hopf[beta]['lyapunov']:.4f})")
right.axhline(0.0, color="k", lw=0.8)
right.plot(0.0, 0.0, "k*", ms=10, label="H")
right.set_xlabel("mu")
right.set_ylabel("cycle amplitude r (averaging)")
right.legend(fontsize=7)
right.set_title("Hopf point: the sign of l1 tells which side the cycle is on", fontsize=9)
fig.tight_layout()
plt.show()
