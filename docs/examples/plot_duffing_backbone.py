"""
The backbone curve of the Duffing oscillator: free orbits continued in their amplitude
======================================================================================

Without damping and forcing the Duffing oscillator (the built-in model ``duffing`` with :math:`c = F = 0`)

.. math::

    m \\ddot x + k x + k_3 x^3 = 0

keeps its energy :math:`E = \\tfrac12 m \\dot x^2 + \\tfrac12 k x^2 + \\tfrac14 k_3 x^4`, and its periodic orbits
form a one-parameter family: the *backbone curve*, the frequency of the free oscillation against its amplitude,
round which the forced frequency-response curves of the damped oscillator bend. A ``periodic_orbit`` without
``frequency`` on such a conservative model finds the member through :math:`x(0) = q_0` (an extremum there), its
frequency found; the family, whose orbits are not isolated, is regularised by the unfolding parameter
:math:`\\varepsilon` of Muñoz-Almaraz et al. (*Physica D* 181, 2003), an unknown added to the equations
(:math:`r + \\varepsilon \\dot x = 0` for harmonic balance) whose energy balance
:math:`\\varepsilon \\int_0^T \\dot x^2 \\, dt = 0` forces :math:`\\varepsilon = 0` on the orbit. ``continuation``
with ``parameter = "amplitude"`` follows the family (the shipped scene ``scenes/duffing_backbone.toml``: harmonic
balance with 15 harmonics and shooting, from :math:`A = 0.05` to 2 m).

**References.** The exact motion is :math:`x = A\\,\\mathrm{cn}(\\omega t, \\mu)` with
:math:`\\omega^2 = (k + k_3 A^2)/m` and :math:`\\mu = k_3 A^2 / (2 (k + k_3 A^2))`, so the period is

.. math::

    T(A) = \\frac{4 K(\\mu)}{\\omega}

(:math:`K` the complete elliptic integral of the first kind, ``scipy.special.ellipk``). First-order harmonic
balance, :math:`x \\approx A \\cos \\omega t`, gives the classical backbone (Nayfeh & Mook, *Nonlinear
Oscillations*, 1979, sec. 4.1)

.. math::

    \\omega^2 = \\left(k + \\tfrac34 k_3 A^2\\right) / m ,

exact as :math:`A \\to 0` and about 1.2 % high at :math:`A = 2` here. Both are printed against mechgen's
backbone below, which is then drawn over the damped, forced oscillator's frequency-response curve
(:math:`c = 0.1`, :math:`F = 0.3`: ``scenes/duffing_frequency_response.toml``).
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.special import ellipk

import mechgen

root = Path(mechgen.__file__).resolve().parents[1]
scene = mechgen.run(str(root / "scenes" / "duffing_backbone.toml"))
outputs = {a["name"]: a["outputs"] for a in scene["analyses"]}
m, k, k3 = 1.0, 1.0, 1.0

# %%
# The exact period at each point's amplitude, and the first-order frequency.
for name in ("backbone_hb", "backbone_shooting"):
    table = outputs[name]["backbone"]
    A = np.array(table["amplitude"]["x"])
    T = np.array(table["period"])
    w2 = (k + k3 * A**2) / m
    exact = 4 * ellipk(k3 * A**2 / (2 * (k + k3 * A**2))) / np.sqrt(w2)
    error = np.max(np.abs(T / exact - 1.0))
    first = np.sqrt((k + 0.75 * k3 * A**2) / m)
    print(f"{name}: {len(A)} orbits from A = {A[0]:.3g} to {A[-1]:.3g} m; largest |T / T_exact - 1| = {error:.2e}; "
          f"largest |unfolding| = {np.max(np.abs(table['unfolding'])):.1e}; first-order frequency off by "
          f"{np.max(np.abs(np.array(table['frequency']) / first - 1.0)):.2%} at most")
    assert error < 1e-9  # measured 8e-13 (harmonic balance, 15 harmonics) and 2.7e-11 (shooting, DOP853 at 1e-11)

# %%
# The damped, forced oscillator's frequency-response curve (the shipped scene's harmonic balance part) and the
# backbone over it, with the first-order curve.
forced = mechgen.compile("duffing", {"m": m, "c": 0.1, "k": k, "k3": k3, "F": 0.3, "w": 0.5})
orbit = mechgen.periodic_orbit(forced, method="harmonic_balance", harmonics=9, frequency="w", start="linear")
frc = mechgen.continuation(forced, about=orbit, parameter="w", stop=2.5, max_step=0.05, max_points=400)
w_frc = np.array([p["w"] for p in frc["branch"]])
A_frc = np.array([p["amplitude"]["x"] for p in frc["branch"]])
stable = np.array([p["stability"] == "stable" for p in frc["branch"]])

table = outputs["backbone_hb"]["backbone"]
A = np.array(table["amplitude"]["x"])
fig, ax = plt.subplots(figsize=(7, 5))
ax.plot(np.where(stable, w_frc, np.nan), A_frc, "b-", lw=1.2, label="forced response (c = 0.1, F = 0.3), stable")
ax.plot(np.where(~stable, w_frc, np.nan), A_frc, "b--", lw=1.2, label="forced response, unstable")
ax.plot(table["frequency"], A, "k-", lw=2.0, label="backbone, mechgen (harmonic balance)")
shot = outputs["backbone_shooting"]["backbone"]
ax.plot(shot["frequency"], shot["amplitude"]["x"], "o", mfc="none", color="tab:orange", ms=4,
        label="backbone, mechgen (shooting)")
grid = np.linspace(0.0, A.max(), 200)
ax.plot(np.sqrt((k + 0.75 * k3 * grid**2) / m), grid, "k:", lw=1.0, label="first-order harmonic balance")
exact_w = 2 * np.pi * np.sqrt((k + k3 * grid**2) / m) / (4 * ellipk(k3 * grid**2 / (2 * (k + k3 * grid**2))))
ax.plot(exact_w, grid, color="tab:red", lw=0.8, ls="-.", label="exact, 2 pi / T(A) (elliptic integral)")
ax.set_xlabel("frequency (rad/s)")
ax.set_ylabel("amplitude max |x| (m)")
ax.set_title("Duffing oscillator: backbone curve over the frequency-response curve", fontsize=9)
ax.legend(fontsize=7, loc="upper left")
fig.tight_layout()
plt.show()
