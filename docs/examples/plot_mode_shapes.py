"""
Mode shapes: a triple pendulum's shapes, modal masses and MAC against scipy.linalg.eigh
=======================================================================================

Three equal bobs of mass ``m`` (kg) on three massless links of length ``l`` (m) under gravity ``g``, link
angles :math:`\\theta_1, \\theta_2, \\theta_3` (rad) from the vertical. The bobs sit at
:math:`x_i = l \\sum_{j \\le i} \\sin\\theta_j`, :math:`y_i = -l \\sum_{j \\le i} \\cos\\theta_j`, and

.. math::

    T = \\tfrac12 m \\sum_i (\\dot x_i^2 + \\dot y_i^2), \\qquad V = m g \\sum_i y_i .

Unlike a chain of springs, the mass matrix is full. Linearised about the hanging state (Rao, *Mechanical
Vibrations*, the triple pendulum of chapter 6; any n-link pendulum: :math:`M_{ij} = m l^2 (n + 1 - \\max(i, j))`,
:math:`K = m g l \\operatorname{diag}(n + 1 - i)`),

.. math::

    M = m l^2 \\begin{pmatrix} 3 & 2 & 1 \\\\ 2 & 2 & 1 \\\\ 1 & 1 & 1 \\end{pmatrix}, \\qquad
    K = m g l \\operatorname{diag}(3, 2, 1), \\qquad K \\phi = \\omega^2 M \\phi .

Reference: M and K above written by hand and solved by :func:`scipy.linalg.eigh`. :func:`mechgen.modes` derives
M and K from the energies and returns the frequencies, the mass-normalised shapes (``shapes``: one
``{coordinate: value}`` per mode, :math:`\\phi^T M \\phi = 1`), ``modal_mass`` and ``modal_stiffness``. The
shapes are compared by the modal assurance criterion,
:math:`\\mathrm{MAC}_{ij} = (\\phi_i^T \\psi_j)^2 / ((\\phi_i^T \\phi_i)(\\psi_j^T \\psi_j))`: 1 for the same shape,
below 1 for different ones.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.linalg import eigh

import mechgen

MODEL = '''\
"""A triple pendulum of equal bobs m on links of length l (SI units)."""
import sympy as sp
from mechgen import Model, Param

model = Model("gallery_triple_pendulum", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("l", 0.5, "m", positive=True), Param("g", 9.81, "m/s^2"))
model.coordinates("theta1", "theta2", "theta3")


def bobs(q, p):
    """(x_i, y_i) of the three bobs."""
    angles = [q.theta1, q.theta2, q.theta3]
    return [(p.l * sum(sp.sin(a) for a in angles[:i + 1]), -p.l * sum(sp.cos(a) for a in angles[:i + 1]))
            for i in range(3)]


@model.kinetic
def kinetic(q, v, p):
    rates = [v.theta1, v.theta2, v.theta3]
    angles = [q.theta1, q.theta2, q.theta3]
    total = 0
    for i in range(3):
        vx = p.l * sum(sp.cos(a) * w for a, w in zip(angles[:i + 1], rates[:i + 1]))
        vy = p.l * sum(sp.sin(a) * w for a, w in zip(angles[:i + 1], rates[:i + 1]))
        total += p.m / 2 * (vx**2 + vy**2)
    return total


@model.potential
def potential(q, p):
    return p.m * p.g * sum(y for _, y in bobs(q, p))
'''

folder = Path(tempfile.mkdtemp())
(folder / "triple.py").write_text(MODEL)
pendulum = mechgen.compile(str(folder / "triple.py"))
result = mechgen.modes(pendulum)
print(result)

# %%
# The reference: M and K by hand, scipy's generalised symmetric eigenproblem.
m, l, g = 1.0, 0.5, 9.81
M = m * l**2 * np.array([[3.0, 2.0, 1.0], [2.0, 2.0, 1.0], [1.0, 1.0, 1.0]])
K = m * g * l * np.diag([3.0, 2.0, 1.0])
eigenvalues, psi = eigh(K, M)
reference = np.sqrt(eigenvalues)
frequency_error = np.max(np.abs(result["frequencies"] - reference) / reference)
for i, (a, b) in enumerate(zip(result["frequencies"], reference), start=1):
    print(f"mode {i}: mechgen {a:.10f} rad/s, scipy {b:.10f} rad/s")
print(f"max relative error of the frequencies: {frequency_error:.1e}")
# the same 3 x 3 eigenproblem with well-separated eigenvalues, solved twice: round-off
assert frequency_error < 1e-10

# %%
# Modal masses and stiffnesses of mechgen's shapes, computed with the hand-written M and K: 1 and omega^2.
names = ["theta1", "theta2", "theta3"]
phi = np.array([[shape[n] for n in names] for shape in result["shapes"]]).T
modal_mass = np.einsum("ik,ij,jk->k", phi, M, phi)
modal_stiffness = np.einsum("ik,ij,jk->k", phi, K, phi)
print(f"modal masses (hand-written M): {modal_mass}; mechgen reports {result['modal_mass']}")
print(f"modal stiffnesses / omega^2:   {modal_stiffness / reference**2}")
assert np.allclose(modal_mass, 1.0, rtol=0, atol=1e-10)  # mass-normalised shapes: round-off of a 3 x 3 product
assert np.allclose(modal_stiffness, reference**2, rtol=1e-10, atol=0)

# %%
# The modal assurance criterion between mechgen's shapes and scipy's: its diagonal is 1 (the same shapes, up
# to sign), its off-diagonal entries those of three different shapes that are M-orthogonal, not orthogonal.
mac = (phi.T @ psi) ** 2 / np.outer(np.sum(phi**2, axis=0), np.sum(psi**2, axis=0))
mac_scipy = (psi.T @ psi) ** 2 / np.outer(np.sum(psi**2, axis=0), np.sum(psi**2, axis=0))
print("MAC(mechgen, scipy):\n", np.array2string(mac, precision=6))
diagonal_error = np.max(np.abs(np.diag(mac) - 1.0))
print(f"max |MAC_ii - 1| = {diagonal_error:.1e}; max |MAC - MAC(scipy, scipy)| = {np.max(np.abs(mac - mac_scipy)):.1e}")
assert diagonal_error < 1e-10 and np.max(np.abs(mac - mac_scipy)) < 1e-10  # round-off, as above

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2), gridspec_kw={"width_ratios": [1.6, 1]})
for j in range(3):
    angles = 0.25 * phi[:, j] / np.max(np.abs(phi[:, j]))  # the shape drawn at a visible amplitude (rad)
    x = np.concatenate([[0.0], l * np.cumsum(np.sin(angles))]) + 1.2 * j
    y = np.concatenate([[0.0], -l * np.cumsum(np.cos(angles))])
    ref = 0.25 * psi[:, j] * np.sign(psi[:, j] @ phi[:, j]) / np.max(np.abs(psi[:, j]))
    xr = np.concatenate([[0.0], l * np.cumsum(np.sin(ref))]) + 1.2 * j
    yr = np.concatenate([[0.0], -l * np.cumsum(np.cos(ref))])
    left.plot(x, y, "o-", lw=2, label="mechgen" if j == 0 else None)
    left.plot(xr, yr, "k+--", ms=10, lw=0.8, label="scipy.linalg.eigh" if j == 0 else None)
    left.text(1.2 * j, 0.12, f"mode {j + 1}\n{result['frequencies'][j]:.3f} rad/s", ha="center")
left.set_xlabel("x [m] (modes side by side)")
left.set_ylabel("y [m]")
left.set_ylim(-1.75, 0.5)
left.set_yticks([-1.5, -1.0, -0.5, 0.0])
left.set_aspect("equal")
left.legend(loc="lower right", fontsize="small")
left.set_title("Mode shapes")
image = right.imshow(mac, vmin=0, vmax=1, cmap="viridis")
right.set_xticks(range(3), [f"scipy {j + 1}" for j in range(3)])
right.set_yticks(range(3), [f"mechgen {i + 1}" for i in range(3)])
for i in range(3):
    for j in range(3):
        right.text(j, i, f"{mac[i, j]:.3f}", ha="center", va="center", color="w" if mac[i, j] < 0.5 else "k")
fig.colorbar(image, ax=right, label="MAC")
right.set_title("Modal assurance criterion")
fig.tight_layout()
plt.show()
