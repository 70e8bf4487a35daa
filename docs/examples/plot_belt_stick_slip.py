"""
An autonomous stick-slip cycle: a mass on a moving belt
=======================================================

The built-in ``belt_stick_slip``: a mass m on a spring k, pressed with the normal force N on a belt moving at
v_b (Leine, van Campen & van de Vrande, *Nonlinear Dyn.* 23, 2000; di Bernardo et al., *Piecewise-smooth
Dynamical Systems*, 2008),

.. math::

    m \\ddot x + k x = F(v_{rel}), \\qquad v_{rel} = v_b - \\dot x ,

sticks (:math:`\\dot x = v_b`, the friction force holding the spring, F = k x) while :math:`|k x| < \\mu_s N`, and
slips with :math:`F = \\mu(v_{rel}) N`, :math:`\\mu = \\mu_k + s (\\mu_s - \\mu_k) e^{-|v_{rel}|/v_s}` (s = 0:
Coulomb friction with a static coefficient above the kinetic one; s = 1: a Stribeck curve). Its stick-slip limit
cycle has no forcing, so its period is unknown: :func:`mechgen.periodic_orbit` without ``frequency`` fixes the
phase by a **Poincare section at an event**, the stick -> slip transition (``section = "breakaway"``), and solves
the return map :math:`P(x_0) = x_0` to it by Newton, the Jacobian

.. math::

    P_x = S \\Phi + f^+ \\frac{\\partial \\tau}{\\partial x_0}, \\qquad
    \\frac{\\partial \\tau}{\\partial x_0} = -\\frac{g_x \\Phi}{\\dot g},

from the modes' transition matrices and the events' saltation matrices S (generated from the guards and resets).
The monodromy :math:`M = S \\Phi` has the trivial multiplier 1, and 0: the catch (slip -> stick) resets
:math:`\\dot x` to :math:`v_b`, so the stick phase forgets the state.

**Reference.** For Coulomb friction (s = 0) the cycle is known in closed form, with
:math:`\\omega = \\sqrt{k/m}`, :math:`D = (\\mu_s - \\mu_k) N / k`, :math:`x_k = \\mu_k N / k`: the slip is the
harmonic arc :math:`x = x_k + R \\sin(\\omega t + \\theta_0)`, :math:`R = \\sqrt{D^2 + (v_b/\\omega)^2}`,
:math:`\\theta_0 = \\operatorname{atan2}(D, v_b/\\omega)`, from the breakaway at :math:`x_k + D` back to
:math:`\\dot x = v_b` at :math:`x_k - D`; the stick carries the mass from :math:`x_k - D` to :math:`x_k + D` at
v_b. So

.. math::

    T = \\frac{2\\pi - 2\\theta_0}{\\omega} + \\frac{2D}{v_b}, \\qquad \\max |x| = x_k + R .

(With :math:`\\mu_s = \\mu_k` the stick phase shrinks to a point and the cycle only grazes :math:`v_{rel} = 0`: the
slip orbits about :math:`x_k` form a family, and no isolated cycle exists.) The branch in v_b is compared with the
same closed form point by point.
"""
import math

import matplotlib.pyplot as plt
import numpy as np

import mechgen

p = dict(m=1.0, k=1.0, N=1.0, mu_s=0.4, mu_k=0.3, stribeck=0.0, v_b=0.5)
belt = mechgen.compile("belt_stick_slip", {"m": p["m"], "k": p["k"], "N": p["N"], "mu_s": p["mu_s"],
                                           "mu_k": p["mu_k"], "stribeck": p["stribeck"]}, free=["v_belt"])
belt = belt.with_params(v_belt=p["v_b"])
cycle = mechgen.periodic_orbit(belt, period=6.0, section="breakaway", samples=801)


def closed_form(v_b):
    """(period, max |x|) of the Coulomb cycle (above)."""
    w = math.sqrt(p["k"] / p["m"])
    D, xk = (p["mu_s"] - p["mu_k"]) * p["N"] / p["k"], p["mu_k"] * p["N"] / p["k"]
    R, theta0 = math.hypot(D, v_b / w), math.atan2(D, v_b / w)
    return (2 * math.pi - 2 * theta0) / w + 2 * D / v_b, xk + R


T, peak = closed_form(p["v_b"])
err_T, err_peak = abs(cycle["period"] - T) / T, abs(cycle["amplitude"]["x"] - peak) / peak
print(f"period {cycle['period']:.12f} (closed form {T:.12f}, relative error {err_T:.1e})")
print(f"max x  {cycle['amplitude']['x']:.12f} (closed form {peak:.12f}, relative error {err_peak:.1e})")
print(f"multipliers {np.round(cycle['multipliers'], 12).tolist()}, {cycle['stability']}; events "
      f"{[(e['guard'], round(e['t'], 9)) for e in cycle['events']]}")
assert err_T < 1e-8 and err_peak < 1e-8

# %%
# The cycle in the belt speed: ``continuation`` about the autonomous orbit, each point against the closed form.
branch = mechgen.continuation(belt, about=cycle, parameter="v_belt", stop=1.0, max_step=0.05)
speeds = np.array([b["v_belt"] for b in branch["branch"]])
periods = np.array([b["period"] for b in branch["branch"]])
exact = np.array([closed_form(v)[0] for v in speeds])
err_branch = float(np.max(np.abs(periods - exact) / exact))
print(f"{len(speeds)} orbits for v_b in [{speeds.min():.2f}, {speeds.max():.2f}]: largest period error "
      f"{err_branch:.1e}")
assert err_branch < 1e-8

# %%
# The cycle in the phase plane (stick on the line x' = v_b) and the period along the branch.
traj = cycle["trajectory"]
stick = np.array(traj["mode_series"]) == belt.modes.index("stick")
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9.5, 3.8))
ax1.plot(traj["x"], traj["x_dot"], label="mechgen (slip)")
ax1.plot(np.array(traj["x"])[stick], np.array(traj["x_dot"])[stick], "r", lw=3, label="stick")
w = math.sqrt(p["k"] / p["m"])
D, xk = (p["mu_s"] - p["mu_k"]) * p["N"] / p["k"], p["mu_k"] * p["N"] / p["k"]
theta = np.linspace(math.atan2(D, p["v_b"] / w), 2 * math.pi - math.atan2(D, p["v_b"] / w), 200)
R = math.hypot(D, p["v_b"] / w)
ax1.plot(xk + R * np.sin(theta), R * w * np.cos(theta), "k:", label="closed-form slip arc")
ax1.set_xlabel("x (m)")
ax1.set_ylabel("x' (m/s)")
ax1.legend(fontsize="small")
ax2.plot(speeds, periods, "o", label="mechgen")
fine = np.linspace(speeds.min(), speeds.max(), 200)
ax2.plot(fine, [closed_form(v)[0] for v in fine], "k-", label="closed form")
ax2.set_xlabel("belt speed v_b (m/s)")
ax2.set_ylabel("period T (s)")
ax2.legend(fontsize="small")
fig.suptitle(f"Stick-slip cycle on a moving belt: T = {cycle['period']:.6f} s, multipliers 1 and 0")
fig.tight_layout()
plt.show()
