"""
A rotor from scratch: a Jeffcott rotor's Campbell diagram and critical speeds
=============================================================================

A rigid disk (mass ``m``, kg; polar and diametral moments of inertia ``Ip``, ``Id``, kg m^2) on a massless,
flexible shaft with translational stiffness ``k_t`` (N/m) and tilt stiffness ``k_r`` (N m/rad), spinning at the
imposed speed :math:`\\Omega` (rad/s). Coordinates: the centre's translations ``x, y`` (m) and the tilts
:math:`\\theta_x, \\theta_y` (rad); the disk's angular velocity in its tilted frame is
:math:`\\omega = (\\dot\\theta_x \\cos\\theta_y,\\ \\dot\\theta_y,\\ \\Omega + \\dot\\theta_x \\sin\\theta_y)`, and

.. math::

    T = \\tfrac m2 (\\dot x^2 + \\dot y^2) + \\tfrac{I_d}2 (\\omega_1^2 + \\omega_2^2) + \\tfrac{I_p}2 \\omega_3^2,
    \\qquad V = \\tfrac{k_t}2 (x^2 + y^2) + \\tfrac{k_r}2 (\\theta_x^2 + \\theta_y^2).

Reference: the closed forms of the linearised rotor (Genta, *Dynamics of Rotating Systems*, 2005, ch. 3-4;
Friswell et al., *Dynamics of Rotating Machines*, 2010, ch. 3). The translations vibrate at
:math:`\\sqrt{k_t/m}` at every speed; the gyroscopic moment splits the tilt into a forward and a backward whirl,

.. math::

    \\omega_{f,b} = \\frac{\\pm I_p \\Omega + \\sqrt{I_p^2 \\Omega^2 + 4 I_d k_r}}{2 I_d},

and a whirl meets the 1x line :math:`\\omega = \\Omega` (a critical speed, where unbalance excites it) at
:math:`\\Omega = \\sqrt{k_t/m}` (translation), :math:`\\Omega_b = \\sqrt{k_r / (I_d + I_p)}` (backward tilt) and,
for a long rotor (:math:`I_d > I_p`), :math:`\\Omega_f = \\sqrt{k_r / (I_d - I_p)}` (forward tilt).

``model.whirl_pair`` names the coordinates whose orbit says forward or backward; :func:`mechgen.campbell`
requires one.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

MODEL = '''\
"""Jeffcott rotor with disk tilt: T = m/2 (x'^2 + y'^2) + Id/2 (w1^2 + w2^2) + Ip/2 w3^2,
V = k_t/2 (x^2 + y^2) + k_r/2 (tx^2 + ty^2), w = (tx' cos ty, ty', Omega + tx' sin ty). SI units."""
import sympy as sp
from mechgen import Model, Param

model = Model("gallery_jeffcott", doc=__doc__)
model.params(Param("m", 10.0, "kg", positive=True), Param("Ip", 0.05, "kg m^2", positive=True),
             Param("Id", 0.1, "kg m^2", positive=True), Param("k_t", 4.0e5, "N/m"), Param("k_r", 1.0e3, "N m/rad"),
             Param("Omega", 0.0, "rad/s", "spin speed"))
model.coordinates("x", "y", "theta_x", "theta_y")
model.whirl_pair("x", "y")
model.whirl_pair("theta_x", "theta_y")


@model.kinetic
def kinetic(q, v, p):
    w1 = v.theta_x * sp.cos(q.theta_y)
    w2 = v.theta_y
    w3 = p.Omega + v.theta_x * sp.sin(q.theta_y)
    return p.m / 2 * (v.x**2 + v.y**2) + p.Id / 2 * (w1**2 + w2**2) + p.Ip / 2 * w3**2


@model.potential
def potential(q, p):
    return p.k_t / 2 * (q.x**2 + q.y**2) + p.k_r / 2 * (q.theta_x**2 + q.theta_y**2)
'''

folder = Path(tempfile.mkdtemp())
(folder / "jeffcott.py").write_text(MODEL)
rotor = mechgen.compile(str(folder / "jeffcott.py"))
speeds = np.linspace(0.0, 300.0, 31)
diagram = mechgen.campbell(rotor, over={"Omega": speeds}, count=4)

# %%
# The closed forms at every speed, and the frequency error.
m, Ip, Id, k_t, k_r = 10.0, 0.05, 0.1, 4.0e5, 1.0e3
root = np.sqrt(Ip**2 * speeds**2 + 4 * Id * k_r)
forward, backward = (Ip * speeds + root) / (2 * Id), (-Ip * speeds + root) / (2 * Id)
translation = np.full_like(speeds, np.sqrt(k_t / m))
expected = np.sort(np.column_stack([translation, translation, forward, backward]), axis=1)
found = np.sort(np.asarray(diagram["frequencies"]), axis=1)
error = np.max(np.abs(found - expected) / expected)
print(f"max relative error of the whirl frequencies over {len(speeds)} speeds: {error:.1e}")
assert error < 1e-9  # 4 x 4 gyroscopic eigenproblems: round-off

# %%
# Each tilt branch's whirl label against the closed form (forward: the frequency that rises with speed).
labels = np.asarray(diagram["whirl"])
frequencies = np.asarray(diagram["frequencies"])
for i, speed in enumerate(speeds[1:], start=1):
    for f, label in zip(frequencies[i], labels[i]):
        if not np.isclose(f, np.sqrt(k_t / m), rtol=1e-6):
            assert np.isclose(f, forward[i] if label == "forward" else backward[i], rtol=1e-9), (speed, f, label)
print("whirl labels: each tilt branch is forward or backward as the closed form says")

# %%
# Critical speeds (1x crossings) against the closed forms.
closed = {"translation": np.sqrt(k_t / m), "backward tilt": np.sqrt(k_r / (Id + Ip)),
          "forward tilt": np.sqrt(k_r / (Id - Ip))}
critical = sorted(c["speed"] for c in diagram["critical_speeds"])
print("critical speeds found [rad/s]:", np.round(critical, 6))
worst = 0.0
for name, value in closed.items():
    nearest = min(critical, key=lambda c: abs(c - value))
    worst = max(worst, abs(nearest - value) / value)
    print(f"{name:>13}: closed form {value:.6f} rad/s, mechgen {nearest:.6f} rad/s")
print(f"max relative error of the critical speeds: {worst:.1e}")
# the crossings are located between the grid's speeds by mechgen's own root finding on the branches
assert worst < 1e-6

fig, ax = plt.subplots(figsize=(7, 5))
for j in range(frequencies.shape[1]):
    ax.plot(speeds, frequencies[:, j], "o", ms=4, color="C0", label="mechgen.campbell" if j == 0 else None)
ax.plot(speeds, forward, "-", color="C1", lw=1, label="forward tilt (closed form)")
ax.plot(speeds, backward, "-", color="C2", lw=1, label="backward tilt (closed form)")
ax.plot(speeds, translation, "-", color="C3", lw=1, label="translation (closed form)")
ax.plot(speeds, speeds, "k--", lw=0.8, label="1x")
ax.plot(list(closed.values()), list(closed.values()), "kx", ms=10, mew=2, label="critical speeds (closed form)")
ax.set_xlabel("spin speed Omega [rad/s]")
ax.set_ylabel("whirl frequency [rad/s]")
ax.set_title("Jeffcott rotor: Campbell diagram")
ax.legend(loc="upper left", fontsize="small")
fig.tight_layout()
plt.show()
