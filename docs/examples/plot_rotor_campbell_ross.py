"""
A rotor's Campbell diagram against ROSS
=======================================

A shaft of length ``L`` (m) spinning at :math:`\\Omega` (rad/s), with disks and bearings, modelled by Timoshenko
beam elements (shear and rotary inertia) in its two lateral directions. Linearised about the straight shaft,

.. math::

    M \\ddot q + \\left(C + \\Omega G\\right) \\dot q + K q = 0,

with ``M`` the shaft's and disks' mass (translational and diametral inertia), ``G`` the skew gyroscopic matrix
of the polar inertia, ``C`` and ``K`` the bearings' damping and stiffness (here :math:`k_{xx} = 10^6`,
:math:`k_{yy} = 0.8\\times10^6` N/m, no damping) plus the shaft's bending stiffness. The damped natural
frequencies :math:`\\omega_d` are the imaginary parts of the eigenvalues of this quadratic problem; with spin
each pair splits into a backward and a forward whirl, and the Campbell diagram follows them with
:math:`\\Omega`.

Reference: ROSS (ross-rotordynamics 2.3.0, the open-source rotordynamics package), its documented example rotor
``ross.rotor_example()``: a 1.5 m steel shaft of 50 mm diameter in six elements, two disks, two bearings. ROSS
is not needed to build this page: its numbers are stored in ``benchmarks/ross_data/ross_reference.json``
(written by ``benchmarks/ross_reference.py`` with ROSS 2.3.0; ``tests/test_rotor_ross.py`` compares the same
numbers): the lowest eight lateral damped frequencies at 0, 500, 1000 and 2000 rad/s for the rotor as given,
and ROSS's own Campbell diagram (50 speeds, 0 to 1000 rad/s) of the rotor with every element split in eight.

The seed paper, Y. Yu and W. L. Cleghorn, "Free vibration of a spinning stepped Timoshenko beam", J. Appl.
Mech. 67 (December 2000), lost its tables in the text extraction; its stepped shaft is the scene
``scenes/stepped_rotor.toml`` (no reference numbers), while ROSS's example checks the same elements, disks,
bearings and gyroscopic terms against an independent code.

mechgen runs the shipped scene ``scenes/ross_example_rotor.toml`` (model ``spinning_shaft`` with the two-node
Timoshenko element ROSS uses; a ``sweep`` of modes at ROSS's four speeds and a ``campbell`` analysis) through
:func:`mechgen.run`.
"""
import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

ROOT = Path(mechgen.__file__).resolve().parents[1]
run = mechgen.run(str(ROOT / "scenes" / "ross_example_rotor.toml"))
outputs = {analysis["name"]: analysis["outputs"] for analysis in run["analyses"]}
ross = json.loads((ROOT / "benchmarks" / "ross_data" / "ross_reference.json").read_text())["rotors"]

# %%
# The damped frequencies at ROSS's four speeds, the same element on the same mesh:
speeds = [point["Omega"] for point in outputs["speeds"]["grid"]]
worst = 0.0
for speed, ours in zip(speeds, outputs["speeds"]["frequencies"]):
    theirs = np.array(ross["example"]["modal"][f"{speed:.1f}"]["lateral_only"]["wd"][:8])
    relative = np.max(np.abs(np.array(ours) / theirs - 1))
    worst = max(worst, relative)
    print(f"Omega = {speed:6.0f} rad/s: max |w_mechgen / w_ROSS - 1| over 8 modes = {relative:.1e}")
# the same matrices up to assembly order: round-off of an eigenvalue problem with K / M ~ 1e6 (tests assert 1e-6)
assert worst < 1e-8

# %%
# The Campbell diagram against ROSS's, computed on the rotor with every element split in eight (its column
# with no lateral whirl is the torsional mode of ROSS's 6-dof nodes, left out): the two meshes differ by the
# discretisation error of the six-element mesh.
campbell = outputs["campbell"]
omega = np.array(campbell["speeds"])
ours = np.array(campbell["frequencies"])
refined = ross["example_refined"]["campbell"]
their_speeds = np.array(refined["speed_range"])
lateral = ~np.isnan(np.array(refined["whirl_values"], dtype=float)).all(axis=0)
theirs = np.sort(np.array(refined["wd"])[:, lateral], axis=1)
assert np.allclose(their_speeds, omega)
count = min(theirs.shape[1], ours.shape[1])
relative = np.abs(np.sort(ours, axis=1)[:, :count] / theirs[:, :count] - 1)
print(f"Campbell, {len(omega)} speeds: max |w_mechgen (6 elements) / w_ROSS (48 elements) - 1| = {relative.max():.1e}")
# 7 lateral modes on both meshes; the six-element mesh's discretisation error at 1000 rad/s is below 1e-3
assert relative.max() < 1e-3

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 7), gridspec_kw={"height_ratios": [3, 1]})
for j in range(ours.shape[1]):
    top.plot(omega, ours[:, j], "-", color="C0", lw=1, label="mechgen" if j == 0 else None)
for j in range(theirs.shape[1]):
    top.plot(their_speeds[::3], theirs[::3, j], "o", color="C1", ms=3, label="ROSS (refined mesh)" if j == 0 else None)
for speed in speeds[:-1]:
    theirs_here = ross["example"]["modal"][f"{speed:.1f}"]["lateral_only"]["wd"][:8]
    top.plot([speed] * 8, theirs_here, "kx", label="ROSS (same mesh)" if speed == 0 else None)
top.plot(omega, omega, "k:", lw=1, label="1x spin")
top.set_ylabel("damped frequency [rad/s]")
top.set_title("ROSS example rotor: Campbell diagram")
top.legend(fontsize=7)
bottom.semilogy(omega, relative.max(axis=1))
bottom.set_xlabel("spin speed Omega [rad/s]")
bottom.set_ylabel("max |w / w_ROSS,refined - 1|")
fig.tight_layout()
plt.show()
