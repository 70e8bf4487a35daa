"""
A model of your own in five minutes: a damped oscillator against its closed form
================================================================================

A model is a Python file of your own: parameters, coordinates and energies. Here a mass ``m`` (kg) on a
spring ``k`` (N/m) with a dashpot ``c`` (N s/m), displacement ``x`` (m):

.. math::

    T = \\tfrac12 m \\dot x^2, \\qquad V = \\tfrac12 k x^2, \\qquad R = \\tfrac12 c \\dot x^2
    \\quad\\Longrightarrow\\quad m \\ddot x + c \\dot x + k x = 0 .

Reference: the closed form of the underdamped free vibration (any vibration text, e.g. Rao, *Mechanical
Vibrations*, section 2.6). With :math:`\\omega_0 = \\sqrt{k/m}`, :math:`\\zeta = c / (2 \\sqrt{k m})` and
:math:`\\omega_d = \\omega_0 \\sqrt{1 - \\zeta^2}`, the eigenvalues are :math:`-\\zeta\\omega_0 \\pm i\\omega_d`, the
logarithmic decrement is :math:`\\delta = 2\\pi\\zeta / \\sqrt{1 - \\zeta^2}`, and released from :math:`x_0` at rest

.. math::

    x(t) = x_0 e^{-\\zeta \\omega_0 t} \\left( \\cos \\omega_d t + \\frac{\\zeta \\omega_0}{\\omega_d}
    \\sin \\omega_d t \\right).

The three steps below are all a new model takes: write the file, compile it, call the analyses.
"""
import math
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

# %%
# 1. The model file. It only declares; mechgen derives the equation of motion from it.
MODEL = '''\
"""A damped oscillator: T = m x'^2/2, V = k x^2/2, R = c x'^2/2 (SI units)."""
from mechgen import Model, Param

model = Model("my_oscillator", doc=__doc__)
model.params(Param("m", 1.0, "kg", "mass", positive=True), Param("k", 4.0, "N/m", "stiffness", positive=True),
             Param("c", 0.4, "N s/m", "damping"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def potential(q, p):
    return p.k / 2 * q.x**2


@model.dissipation
def dissipation(v, p):
    return p.c / 2 * v.x**2
'''
folder = Path(tempfile.mkdtemp())
(folder / "oscillator.py").write_text(MODEL)

# %%
# 2. Compile it (derive, generate, build; cached for the next run), at values of our choosing.
system = mechgen.compile(str(folder / "oscillator.py"), {"m": 1.0, "k": 4.0, "c": 0.4})

# %%
# 3. The analyses: modes about rest, and a time history from x0 = 0.1 m.
modes = mechgen.modes(system)
print(modes)
x0, t_end = 0.1, 15.0
run = mechgen.simulate(system, t_end=t_end, q0={"x": x0}, rtol=1e-10, atol=1e-12, samples=601)

# %%
# The closed forms.
m, k, c = 1.0, 4.0, 0.4
w0, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
wd = w0 * math.sqrt(1 - zeta**2)
delta = 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
t = run["t"]
closed = x0 * np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))

frequency_error = abs(modes["frequencies"][0] - wd) / wd
decrement_error = abs(modes["log_dec"][0] - delta) / delta
history_error = np.max(np.abs(run["trajectory"]["x"] - closed))
print(f"damped frequency: mechgen {modes['frequencies'][0]:.12f} rad/s, closed form {wd:.12f} rad/s "
      f"(relative error {frequency_error:.1e})")
print(f"log decrement:    mechgen {modes['log_dec'][0]:.12f}, closed form {delta:.12f} "
      f"(relative error {decrement_error:.1e})")
print(f"x(t): max |mechgen - closed form| over {t_end} s = {history_error:.1e} m")
# a 2 x 2 eigenproblem: round-off; the integrator runs at rtol 1e-10 on an amplitude of 0.1 m
assert frequency_error < 1e-10 and decrement_error < 1e-10
assert history_error < 1e-9

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
top.plot(t, run["trajectory"]["x"], label="mechgen.simulate")
top.plot(t, closed, "--", label="closed form")
top.plot(t, x0 * np.exp(-zeta * w0 * t), ":", color="gray", label=r"envelope $x_0 e^{-\zeta\omega_0 t}$")
top.set_ylabel("x [m]")
top.set_title(f"Damped oscillator: omega_d = {wd:.4f} rad/s, zeta = {zeta:.2f}")
top.legend(loc="upper right")
bottom.semilogy(t, np.abs(run["trajectory"]["x"] - closed) + 1e-18)
bottom.set_xlabel("t [s]")
bottom.set_ylabel("|mechgen - closed form| [m]")
fig.tight_layout()
plt.show()
