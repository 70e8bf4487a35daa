"""
Time histories and phase portraits: a damped pendulum against scipy
===================================================================

A pendulum of mass ``m`` (kg) on a massless rod of length ``l`` (m) under gravity ``g`` (m/s^2), with a
viscous moment ``c`` (N m s) at the pivot; angle :math:`\\theta` (rad) from the hanging state:

.. math::

    T = \\tfrac12 m l^2 \\dot\\theta^2, \\quad V = -m g l \\cos\\theta, \\quad R = \\tfrac12 c \\dot\\theta^2
    \\quad\\Longrightarrow\\quad m l^2 \\ddot\\theta + c \\dot\\theta + m g l \\sin\\theta = 0 .

Released at :math:`\\theta_0 = 2.5` rad with :math:`\\dot\\theta_0 = 6` rad/s it first goes over the top, then
swings ever lower: a large, nonlinear motion that no closed form gives.

Reference: the equation above written by hand and integrated by :func:`scipy.integrate.solve_ivp`
(DOP853, rtol 1e-12). :func:`mechgen.simulate` returns the time history as ``result["trajectory"]``
(each coordinate, its velocity ``<name>_dot``, the outputs and energies at the samples ``result["t"]``);
with ``plot="phase"`` its figure (``result.plot(folder)``, or ``mechgen run --plot DIR``) is the phase
portrait.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mechgen

MODEL = '''\
"""A damped pendulum: m l^2 theta'' + c theta' + m g l sin(theta) = 0 (SI units)."""
import sympy as sp
from mechgen import Model, Param

model = Model("gallery_pendulum", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("l", 1.0, "m", positive=True),
             Param("g", 9.81, "m/s^2"), Param("c", 0.25, "N m s"))
model.coordinates("theta")


@model.kinetic
def kinetic(v, p):
    return p.m * p.l**2 / 2 * v.theta**2


@model.potential
def potential(q, p):
    return -p.m * p.g * p.l * sp.cos(q.theta)


@model.dissipation
def dissipation(v, p):
    return p.c / 2 * v.theta**2
'''

folder = Path(tempfile.mkdtemp())
(folder / "pendulum.py").write_text(MODEL)
pendulum = mechgen.compile(str(folder / "pendulum.py"))

T_END, THETA0, OMEGA0 = 20.0, 2.5, 6.0
result = mechgen.simulate(pendulum, t_end=T_END, q0={"theta": THETA0}, v0={"theta": OMEGA0}, method="DOP853",
                          rtol=1e-11, atol=1e-13, samples=2001, plot="phase")
t = result["t"]
theta, omega = result["trajectory"]["theta"], result["trajectory"]["theta_dot"]

# %%
# The reference: the pendulum's equation by hand.
m, l, g, c = 1.0, 1.0, 9.81, 0.25


def pendulum_rhs(time, state):
    """theta' = omega, omega' = -(c omega + m g l sin(theta)) / (m l^2)."""
    angle, rate = state
    return [rate, -(c * rate + m * g * l * np.sin(angle)) / (m * l**2)]


reference = solve_ivp(pendulum_rhs, (0.0, T_END), [THETA0, OMEGA0], method="DOP853", rtol=1e-12, atol=1e-14,
                      t_eval=t)
error = max(np.max(np.abs(theta - reference.y[0])), np.max(np.abs(omega - reference.y[1])))
print(f"max |mechgen - scipy| over {T_END} s, angle and rate: {error:.2e} (rad, rad/s)")
# both integrators run at rtol 1e-11..1e-12 on a damped (contracting) motion of size ~10: below 1e-7
assert error < 1e-7

# the energy the dashpot took, against the energy balance the run reports (dissipated = int c theta'^2 dt)
E = result["trajectory"]["energy"]
print(f"energy lost {E[0] - E[-1]:.9f} J, dissipated (reported) {result['dissipated']:.9f} J")
assert abs((E[0] - E[-1]) - result["dissipated"]) < 1e-7  # rtol 1e-11 on ~20 J, plus the sampling of E

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
top.plot(t, theta, label="mechgen.simulate")
top.plot(t, reference.y[0], "--", label="scipy solve_ivp (hand-written)")
top.set_ylabel("theta [rad]")
top.set_title("Damped pendulum: over the top, then swinging")
top.legend()
bottom.semilogy(t, np.abs(theta - reference.y[0]) + 1e-18)
bottom.set_xlabel("t [s]")
bottom.set_ylabel("|difference| [rad]")
fig.tight_layout()

# %%
# The phase portrait drawn from the trajectory, mechgen's and scipy's, with the separatrix of the undamped
# pendulum (the energy of the upright state, :math:`\dot\theta^2 = 2 g/l\,(1 + \cos\theta)`):
fig, ax = plt.subplots(figsize=(6, 4.5))
ax.plot(theta, omega, lw=1.2, label="mechgen")
ax.plot(reference.y[0], reference.y[1], "--", lw=0.8, label="scipy")
angles = np.linspace(0.0, 5 * np.pi, 400)
ax.plot(angles, np.sqrt(2 * g / l * (1 + np.cos(angles))), ":", color="gray", label="separatrix")
ax.plot(angles, -np.sqrt(2 * g / l * (1 + np.cos(angles))), ":", color="gray")
ax.set_xlabel("theta [rad]")
ax.set_ylabel("theta' [rad/s]")
ax.set_title("Phase portrait")
ax.legend(loc="lower left")
fig.tight_layout()

# %%
# The figure mechgen draws itself for ``plot="phase"`` (``result.plot(folder)`` writes it as a PNG):
written = result.plot(folder)
fig, ax = plt.subplots(figsize=(5, 4.5))
ax.imshow(plt.imread(written[0]))
ax.set_axis_off()
plt.show()
