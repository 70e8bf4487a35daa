"""
A forced, damped Duffing oscillator: a time history against scipy
==================================================================

The model, written below as energies (mass ``m``, damping ``c``, stiffnesses ``k`` and ``k3``, forcing
amplitude ``F`` at frequency ``w``; SI units, x in m, t in s):

.. math::

    T = \\tfrac12 m \\dot x^2, \\quad V = \\tfrac12 k x^2 + \\tfrac14 k_3 x^4, \\quad
    R = \\tfrac12 c \\dot x^2, \\quad Q_x = F \\cos(w t),

so that Lagrange's equation is the Duffing equation

.. math::

    m \\ddot x + c \\dot x + k x + k_3 x^3 = F \\cos(w t).

Reference: the same equation written by hand and integrated by :func:`scipy.integrate.solve_ivp`
(DOP853, rtol 1e-12). mechgen derives the equation from the energies, generates its kernels and
integrates with :func:`mechgen.simulate`; its time history is ``result["trajectory"]``.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mechgen

MODEL = '''\
"""Forced, damped Duffing oscillator: m x'' + c x' + k x + k3 x^3 = F cos(w t)."""
import sympy as sp
from mechgen import Model, Param

model = Model("gallery_duffing", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("c", 0.1, "N s/m"), Param("k", 1.0, "N/m"),
             Param("k3", 0.5, "N/m^3"), Param("F", 0.5, "N"), Param("w", 1.2, "rad/s"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2 + p.k3 * q.x**4 / 4


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def forces(p, t):
    return {"x": p.F * sp.cos(p.w * t)}
'''

folder = Path(tempfile.mkdtemp())
(folder / "duffing.py").write_text(MODEL)
system = mechgen.compile(str(folder / "duffing.py"))

T_END = 20.0
result = mechgen.simulate(system, t_end=T_END, q0={"x": 1.0}, method="DOP853", rtol=1e-11, atol=1e-13,
                          samples=401)
t = result["t"]
x = result["trajectory"]["x"]

# %%
# The reference: the Duffing equation written by hand.
m, c, k, k3, F, w = 1.0, 0.1, 1.0, 0.5, 0.5, 1.2


def duffing(time, state):
    """x' = v, v' = (F cos(w t) - c v - k x - k3 x^3) / m."""
    pos, vel = state
    return [vel, (F * np.cos(w * time) - c * vel - k * pos - k3 * pos**3) / m]


reference = solve_ivp(duffing, (0.0, T_END), [1.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t)
error = np.max(np.abs(x - reference.y[0]))
print(f"max |x_mechgen - x_scipy| over {T_END} s: {error:.2e} m")
# both integrators run at rtol ~1e-11..1e-12 on a non-chaotic orbit of size 1: their difference stays below 1e-8
assert error < 1e-8

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
top.plot(t, x, label="mechgen.simulate")
top.plot(t, reference.y[0], "--", label="scipy solve_ivp (hand-written)")
top.set_ylabel("x [m]")
top.legend()
top.set_title("Forced, damped Duffing oscillator")
bottom.semilogy(t, np.abs(x - reference.y[0]) + 1e-18)
bottom.set_xlabel("t [s]")
bottom.set_ylabel("|difference| [m]")
fig.tight_layout()

# %%
# The phase portrait, from the velocity that the trajectory also holds (``x_dot``):
fig, ax = plt.subplots(figsize=(5, 4))
ax.plot(x, result["trajectory"]["x_dot"])
ax.set_xlabel("x [m]")
ax.set_ylabel("x' [m/s]")
ax.set_title("Phase portrait")
fig.tight_layout()
plt.show()
