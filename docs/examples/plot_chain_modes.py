"""
Modes of a three-mass spring chain against scipy.linalg.eigh
============================================================

Three masses :math:`m_1, m_2, m_3` (kg) on a line, displacements :math:`x_1, x_2, x_3` (m); a spring
:math:`k_1` holds the first mass to a wall, :math:`k_2` joins masses 1 and 2, :math:`k_3` masses 2 and 3
(N/m); the last mass is free:

.. math::

    T = \\tfrac12 \\sum_i m_i \\dot x_i^2, \\qquad
    V = \\tfrac12 k_1 x_1^2 + \\tfrac12 k_2 (x_2 - x_1)^2 + \\tfrac12 k_3 (x_3 - x_2)^2 .

The natural frequencies :math:`\\omega` (rad/s) solve :math:`K \\phi = \\omega^2 M \\phi` with

.. math::

    M = \\operatorname{diag}(m_1, m_2, m_3), \\qquad
    K = \\begin{pmatrix} k_1 + k_2 & -k_2 & 0 \\\\ -k_2 & k_2 + k_3 & -k_3 \\\\ 0 & -k_3 & k_3 \\end{pmatrix}.

Reference: M and K written by hand and solved by :func:`scipy.linalg.eigh` (any vibration text, e.g.
Rao, *Mechanical Vibrations*, ch. 6). mechgen derives M and K from the energies and solves the same
problem in :func:`mechgen.modes`, which also returns the mass-normalised shapes (``shapes``, one
``{coordinate: value}`` per mode), ``modal_mass`` and ``modal_stiffness``.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.linalg import eigh

import mechgen

MODEL = '''\
"""Three masses in a line: a wall spring k1, couplings k2 and k3; the last mass free."""
from mechgen import Model, Param

model = Model("gallery_chain3", doc=__doc__)
model.params(Param("m1", 1.0, "kg", positive=True), Param("m2", 2.0, "kg", positive=True),
             Param("m3", 0.5, "kg", positive=True), Param("k1", 100.0, "N/m", positive=True),
             Param("k2", 50.0, "N/m", positive=True), Param("k3", 80.0, "N/m", positive=True))
model.coordinates("x1", "x2", "x3")


@model.kinetic
def kinetic(v, p):
    return (p.m1 * v.x1**2 + p.m2 * v.x2**2 + p.m3 * v.x3**2) / 2


@model.potential
def potential(q, p):
    return (p.k1 * q.x1**2 + p.k2 * (q.x2 - q.x1)**2 + p.k3 * (q.x3 - q.x2)**2) / 2
'''

folder = Path(tempfile.mkdtemp())
(folder / "chain3.py").write_text(MODEL)
chain = mechgen.compile(str(folder / "chain3.py"))
result = mechgen.modes(chain)
print(result)

# %%
# The reference: M and K by hand, the generalised symmetric eigenproblem by scipy.
m1, m2, m3, k1, k2, k3 = 1.0, 2.0, 0.5, 100.0, 50.0, 80.0
M = np.diag([m1, m2, m3])
K = np.array([[k1 + k2, -k2, 0.0], [-k2, k2 + k3, -k3], [0.0, -k3, k3]])
eigenvalues, shapes = eigh(K, M)
reference = np.sqrt(eigenvalues)
frequencies = result["frequencies"]
relative = np.max(np.abs(frequencies - reference) / reference)
for i, (a, b) in enumerate(zip(frequencies, reference), start=1):
    print(f"mode {i}: mechgen {a:.10f} rad/s, scipy {b:.10f} rad/s")
print(f"max relative error of the frequencies: {relative:.2e}")
# the same 3 x 3 eigenproblem solved twice: agreement to 1e-10 (the solvers' round-off on well-separated modes)
assert relative < 1e-10

# %%
# Mode shapes: mechgen's are mass-normalised (phi^T M phi = 1, the largest entry positive), as scipy's eigh
# returns them up to sign.
names = ["x1", "x2", "x3"]
ours = np.array([[shape[n] for n in names] for shape in result["shapes"]]).T
signs = np.sign(np.sum(ours * shapes, axis=0))
shape_error = np.max(np.abs(ours - shapes * signs))
print(f"max error of the mass-normalised shapes: {shape_error:.2e}; modal masses {result['modal_mass']}")
assert shape_error < 1e-10  # the same well-separated eigenproblem: round-off

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 4))
modes_axis = np.arange(1, 4)
left.plot(modes_axis, frequencies, "o", ms=9, label="mechgen.modes")
left.plot(modes_axis, reference, "x", ms=9, label="scipy.linalg.eigh")
left.set_xticks(modes_axis)
left.set_xlabel("mode")
left.set_ylabel("natural frequency [rad/s]")
left.legend()
left.set_title("Frequencies")
for j in range(3):
    line, = right.plot(modes_axis, ours[:, j], "o-", label=f"mode {j + 1}, {frequencies[j]:.2f} rad/s")
    right.plot(modes_axis, shapes[:, j] * signs[j], "x", ms=9, color=line.get_color())
right.set_xticks(modes_axis, names)
right.set_ylabel("mass-normalised amplitude [kg^-1/2]")
right.legend()
right.set_title("Mode shapes: mechgen (o) and scipy (x)")
fig.tight_layout()
plt.show()
