"""
Unbalance response of a Jeffcott rotor: Bode plot, orbits and backward whirl
============================================================================

A disk of mass :math:`M` (kg) at mid-span of a massless shaft of stiffness :math:`k` (N/m), with viscous damping
:math:`c` (N s/m), spins at :math:`\\Omega` (rad/s, counter-clockwise about :math:`z`). A small mass :math:`m`
(kg) at an eccentricity :math:`e` (m) from the shaft axis applies the force :math:`m e \\Omega^2` rotating with
the shaft:

.. math::

    M \\ddot x + c \\dot x + k_x x = m e \\Omega^2 \\cos(\\Omega t + \\varphi), \\qquad
    M \\ddot y + c \\dot y + k_y y = m e \\Omega^2 \\sin(\\Omega t + \\varphi).

Reference (the closed form; Genta, *Dynamics of Rotating Systems*, 2005, sec. 3.3; Friswell et al., *Dynamics
of Rotating Machines*, 2010, sec. 2.6): with isotropic supports (:math:`k_x = k_y = k`) the disk whirls
forward on a circle of radius

.. math::

    |r| = \\frac{m e \\Omega^2}{\\sqrt{(k - M \\Omega^2)^2 + (c \\Omega)^2}},

lagging the unbalance by :math:`\\arctan(c \\Omega / (k - M \\Omega^2))`. With anisotropic supports
(:math:`k_x < k_y`) each axis has its own closed form, :math:`X = m e \\Omega^2 / (k_x - M \\Omega^2 + i c \\Omega)`,
:math:`Y = -i\\, m e \\Omega^2 / (k_y - M \\Omega^2 + i c \\Omega)`; the orbit is an ellipse, and between the two
critical speeds :math:`\\sqrt{k_x/M} < \\Omega < \\sqrt{k_y/M}` the disk whirls *backward*, against the spin
(the angular momentum :math:`x \\dot y - y \\dot x = \\Omega\\, \\mathrm{Im}(X \\bar Y)` changes sign).

mechgen runs the shipped scene ``scenes/jeffcott_unbalance.toml`` (the built-in ``laval_rotor``, speeds in rpm)
and an anisotropic rotor of our own, with the ``response`` kind's ``unbalance``.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

ROOT = Path(mechgen.__file__).resolve().parents[1]
run = mechgen.run(str(ROOT / "scenes" / "jeffcott_unbalance.toml"))
out = run["analyses"][0]["outputs"]

# %%
# The isotropic rotor against the closed form (the scene's values: M = 10 kg, k = 4e5 N/m, c = 200 N s/m,
# m e = 1e-4 kg m).
M, k, c, me = 10.0, 4.0e5, 200.0, 0.01 * 0.01
W = np.asarray(out["omega"])  # rad/s, whatever the scene's speed_unit (rpm here: out["omega_in_unit"])
closed = me * W**2 / np.sqrt((k - M * W**2) ** 2 + (c * W) ** 2)
lag = np.arctan2(c * W, k - M * W**2)
amp_error = np.max(np.abs(np.asarray(out["amplitude"]["x"]) - closed) / np.maximum(closed, 1e-300))
phase_error = np.max(np.abs(np.asarray(out["phase"]["x"]) + lag))
print(f"max relative amplitude error over {len(W)} speeds: {amp_error:.1e}; max phase error {phase_error:.1e} rad")
assert amp_error < 1e-12 and phase_error < 1e-12  # a 4 x 4 complex solve per speed: round-off
orbit = out["orbit"]["x,y"]
assert set(orbit["whirl"][1:]) == {"forward"}  # speed 0: no force, no orbit ("none")
circle = np.max(np.abs(np.subtract(orbit["major"], orbit["minor"]))[1:] / closed[1:])
print(f"whirl: {sorted(set(orbit['whirl'][1:]))}; (major - minor) / |r| at most {circle:.0e} (a circle)")
assert circle < 1e-12

rpm = np.asarray(out["omega_in_unit"])
fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
ax1.semilogy(rpm[1:], out["amplitude"]["x"][1:], "o", ms=3, label="mechgen (x)")
ax1.semilogy(rpm[1:], closed[1:], "-", color="C1", label="closed form")
ax1.set_ylabel("|r| (m)")
ax1.legend()
ax2.plot(rpm, np.rad2deg(out["phase"]["x"]), "o", ms=3, label="mechgen (x)")
ax2.plot(rpm, -np.rad2deg(lag), "-", color="C1", label="closed form")
ax2.set_xlabel("spin speed (rpm)")
ax2.set_ylabel("phase (deg)")
ax2.legend()
ax1.set_title("Jeffcott rotor: unbalance response (Bode plot)")
fig.tight_layout()

# %%
# An anisotropic rotor written here (k_x = 800 N/m, k_y = 1800 N/m, M = 2 kg: critical speeds 20 and 30 rad/s),
# lightly damped (c = 0.5 N s/m), against the per-axis closed forms and the whirl direction they give.
MODEL = '''\
"""Jeffcott rotor on anisotropic supports; Omega is the spin speed (the unbalance's frequency)."""
from mechgen import Model, Param

model = Model("gallery_anisotropic_jeffcott", doc=__doc__)
model.params(Param("M", 2.0, "kg"), Param("k_x", 800.0, "N/m"), Param("k_y", 1800.0, "N/m"),
             Param("c", 0.5, "N s/m"), Param("Omega", 0.0, "rad/s"))
model.coordinates("x", "y")
model.whirl_pair("x", "y")


@model.kinetic
def kinetic(q, v, p):
    return p.M / 2 * (v.x**2 + v.y**2)


@model.potential
def potential(q, p):
    return (p.k_x * q.x**2 + p.k_y * q.y**2) / 2


@model.dissipation
def dissipation(v, p):
    return p.c / 2 * (v.x**2 + v.y**2)
'''
folder = Path(tempfile.mkdtemp())
(folder / "anisotropic.py").write_text(MODEL)
rotor = mechgen.compile(str(folder / "anisotropic.py"))
speeds = np.linspace(2.0, 45.0, 200)
res = mechgen.response(rotor, unbalance={"coordinates": ["x", "y"], "mass": 0.01, "eccentricity": 0.05},
                       over={"Omega": speeds.tolist()}, orbit_at=[15.0, 25.0, 40.0])
mex = 0.01 * 0.05 * speeds**2
X = mex / (800.0 - 2.0 * speeds**2 + 0.5j * speeds)
Y = -1j * mex / (1800.0 - 2.0 * speeds**2 + 0.5j * speeds)
got_x = np.asarray(res["amplitude"]["x"]) * np.exp(1j * np.asarray(res["phase"]["x"]))
error = np.max(np.abs(got_x - X) / np.abs(X))
expected = np.where(np.imag(X * np.conj(Y)) > 0, "forward", "backward")
backward = speeds[expected == "backward"]
print(f"max relative error of X: {error:.1e}; backward whirl from {backward.min():.2f} to {backward.max():.2f} rad/s "
      "(critical speeds 20 and 30 rad/s)")
assert error < 1e-12 and list(expected) == res["orbit"]["x,y"]["whirl"]

fig, axes = plt.subplots(1, 3, figsize=(10, 3.8))
theta = np.linspace(0.0, 2 * np.pi, 181)
got_y = np.asarray(res["amplitude"]["y"]) * np.exp(1j * np.asarray(res["phase"]["y"]))
for ax, w in zip(axes, res["orbit_at"]):
    i = int(np.argmin(np.abs(speeds - w)))
    ax.plot((X[i] * np.exp(1j * theta)).real, (Y[i] * np.exp(1j * theta)).real, label="closed form")
    ax.plot((got_x[i] * np.exp(1j * theta[::12])).real, (got_y[i] * np.exp(1j * theta[::12])).real, "o", ms=4,
            label="mechgen")
    ax.set_aspect("equal", adjustable="datalim")
    ax.ticklabel_format(style="sci", scilimits=(0, 0))
    ax.set_title(f"{w:.1f} rad/s: {res['orbit']['x,y']['whirl'][i]}", fontsize=9)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=7, loc="lower right")
fig.suptitle("anisotropic Jeffcott rotor: orbits below, between and above the critical speeds")
fig.tight_layout()
plt.show()
