"""
Periodic orbits through impacts: an impact oscillator's period doubling
=======================================================================

The built-in ``impact_oscillator``, a forced, damped oscillator against a rigid stop at its equilibrium
(Shaw & Holmes, *J. Sound Vib.* 90, 1983),

.. math::

    \\ddot x + c \\dot x + x = F \\cos(w t) \\quad (x < 0), \\qquad \\dot x^+ = -e\\, \\dot x^- \\text{ when } x
    \\text{ reaches } 0 ,

has, for c = 0.05, F = 1, e = 0.8, an orbit with one impact per forcing period. :func:`mechgen.periodic_orbit`
finds it by shooting through the impact: Newton on :math:`x(T) - x_0` with the Jacobian
:math:`\\Phi - I`, where the monodromy :math:`\\Phi = \\Phi_1 S \\Phi_0` multiplies the flows between impacts by the
impact's **saltation matrix**

.. math::

    S = R_x + \\frac{(f^+ - R_x f^- - R_t)\\, g_x^T}{\\dot g},

built from the derivatives of the guard g = x and the reset R that mechgen generates from the model. The
continuation in w finds where a Floquet multiplier passes through -1 (a period doubling, PD) and, with
``switch_branches``, the orbit of period 2T with two impacts just past it.

**Reference.** The same PD point computed independently here: a hand-written event-driven flow
(``scipy.integrate.solve_ivp`` with a terminal event at the stop, the reset applied by hand), its orbit by
``scipy.optimize.fsolve``, its multipliers from central differences, and Brent's method on
:math:`\\min \\mu + 1 = 0`. The product of the multipliers is :math:`e^2 \\exp(-cT)` exactly (one impact per
period, Liouville's formula between impacts).
"""
import math

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

import mechgen

c, F, e = 0.05, 1.0, 0.8
oscillator = mechgen.compile("impact_oscillator", {"c": c, "F": F, "cor": e, "d": 0.0, "w": 2.5}, free=["w"])
orbit = mechgen.periodic_orbit(oscillator, frequency="w", q0={"x": -0.6}, v0={"x": 0.04})
flip = mechgen.continuation(oscillator, about=orbit, parameter="w", stop=2.8, max_step=0.05, switch_branches=True)
(pd,) = [s for s in flip["special_points"] if s["type"] == "PD"]
T = 2 * math.pi / 2.5
product = np.prod([complex(*mu) for mu in orbit["multipliers"]]).real
print(f"one-impact orbit at w = 2.5: multipliers' product {product:.12f}, e^2 exp(-cT) = "
      f"{e**2 * math.exp(-c * T):.12f}")
print(f"PD at w = {pd['w']:.9f} rad/s, multipliers {np.round(pd['multipliers'], 9).tolist()}")


# %%
# The independent computation of the PD point.
def hand_flow(x0, t_end, w):
    def rhs(t, y):
        return [y[1], F * math.cos(w * t) - c * y[1] - y[0]]

    def hit(t, y):
        return y[0]

    hit.terminal, hit.direction = True, 1
    t, y = 0.0, np.asarray(x0, float)
    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-14, events=hit)
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1:
            y[0], y[1] = -1e-13, -e * y[1]
    return y


guess = {"x": np.array([orbit["trajectory"]["x"][0], orbit["trajectory"]["x_dot"][0]])}


def lowest_multiplier_plus_one(w):
    period = 2 * math.pi / w
    x0 = fsolve(lambda x: hand_flow(x, period, w) - x, guess["x"], xtol=1e-13)
    guess["x"] = x0
    J = np.column_stack([(hand_flow(x0 + 1e-6 * u, period, w) - hand_flow(x0 - 1e-6 * u, period, w)) / 2e-6
                         for u in np.eye(2)])
    return float(np.min(np.linalg.eigvals(J).real)) + 1.0


w_hand = brentq(lowest_multiplier_plus_one, 2.6, 2.7, xtol=1e-10)
print(f"hand-written event-driven computation: PD at w = {w_hand:.9f} rad/s; difference {abs(pd['w'] - w_hand):.1e}")
assert abs(pd["w"] - w_hand) < 1e-6

# %%
# The branch (amplitude against w: stable solid, unstable dashed), the PD point and the doubled orbit; the two
# orbits' phase portraits just past the PD point.
(doubled,) = flip["doubled"]
fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
branch = flip["branch"]
w = np.array([p["w"] for p in branch])
amplitude = np.array([p["amplitude"]["x"] for p in branch])
stable = np.array([p["stability"] == "stable" for p in branch])
left.plot(np.where(stable, w, np.nan), amplitude, "b-", label="one impact per period, stable")
left.plot(np.where(~stable, w, np.nan), amplitude, "r--", label="one impact per period, unstable")
left.plot(pd["w"], pd["amplitude"]["x"], "ks", mfc="none", ms=9, label="PD")
left.plot(doubled["w"], doubled["amplitude"]["x"], "o", color="tab:purple", label="doubled orbit (2 impacts)")
left.set_xlabel("w (rad/s)")
left.set_ylabel("max |x| over the orbit (m)")
left.legend(fontsize=7)
left.set_title("the branch of one-impact orbits", fontsize=9)
w_d = doubled["w"]
x_d = np.array([doubled["start"]["x"], doubled["start"]["x_dot"]])
times = np.linspace(0.0, doubled["period"], 2000)
states = np.array([hand_flow(x_d, t, w_d) if t > 0 else x_d for t in times[::20]])
right.plot(states[:, 0], states[:, 1], ".", ms=3, color="tab:purple", label="doubled orbit (hand-written flow)")
right.axvline(0.0, color="k", lw=1.5, label="stop")
right.set_xlabel("x (m)")
right.set_ylabel("x' (m/s)")
right.legend(fontsize=7)
right.set_title(f"w = {w_d:.4f} rad/s: period 2T", fontsize=9)
fig.tight_layout()
plt.show()
