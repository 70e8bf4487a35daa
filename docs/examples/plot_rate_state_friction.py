"""
Rate-and-state friction: the velocity step and the stick-slip cycle of a spring-slider
======================================================================================

The friction coefficient of rate-and-state friction depends on the slip rate ``V`` (m/s) and a state
:math:`\\theta` (s), with the aging or the slip law for the state:

.. math::

    \\mu = \\mu_0 + a \\ln\\frac{V}{V_*} + b \\ln\\frac{V_*\\theta}{D_c}, \\qquad
    \\dot\\theta = 1 - \\frac{V\\theta}{D_c}\\ \\text{(aging)}, \\qquad
    \\dot\\theta = -\\frac{V\\theta}{D_c}\\ln\\frac{V\\theta}{D_c}\\ \\text{(slip)} .

**The velocity step.** Sliding steadily at :math:`V_1` (:math:`\\theta_0 = D_c/V_1`), the velocity is
stepped to :math:`V_2` and held (infinite stiffness). The aging law is linear in :math:`\\theta`, the slip law
linear in :math:`\\Omega = \\ln(V_2\\theta/D_c)` with slip :math:`d = V_2 t`:

.. math::

    \\theta(t) = \\frac{D_c}{V_2} + \\left(\\frac{D_c}{V_1} - \\frac{D_c}{V_2}\\right) e^{-V_2 t/D_c}
    \\ \\text{(aging)}, \\qquad
    \\mu - \\mu_{ss}(V_2) = b \\ln\\frac{V_2}{V_1}\\, e^{-d/D_c}\\ \\text{(slip)},

with the steady change :math:`\\mu_{ss}(V_2) - \\mu_{ss}(V_1) = (a - b)\\ln(V_2/V_1)`.

**The stick-slip cycle.** A block (mass per area ``m``, kg/m²) pulled through a spring ``k`` (Pa/m) at
:math:`V_2` under normal stress :math:`\\sigma` (Pa): :math:`m\\dot V = F - \\sigma\\mu`,
:math:`\\dot F = k (V_2 - V)`. Linearised about steady sliding, its oscillation is neutral at

.. math::

    k_c = \\frac{\\sigma (b - a)}{D_c}\\left(1 + \\frac{m V_2^2}{\\sigma a D_c}\\right), \\qquad
    \\omega_c = \\frac{V_2}{D_c}\\sqrt{\\frac{b - a}{a}},

and below :math:`k_c` the step grows into a stick-slip limit cycle.

Reference: J. H. Dieterich, J. Geophys. Res. 84 (1979) 2161; A. Ruina, "Slip instability and state variable
friction laws", J. Geophys. Res. 88 (1983) 10359; J. R. Rice and A. Ruina, J. Appl. Mech. 50 (1983) 343 —
the friction law of the seed paper (V. Chiroiu, C. Rugina, D. Dumitriu, L. Munteanu, "On the acoustics and
friction", SISOM 2012, which discusses the friction stress's evolution for such a slip history). The
closed forms above are derived in ``tests/test_rate_state.py`` and ``tests/test_rate_state_inertial.py``.

mechgen: the built-in model ``rate_state_slider`` with ``loading = "imposed"`` through
:func:`mechgen.compile` and :func:`mechgen.simulate` for the step; the shipped scene
``scenes/rate_state_stick_slip.toml`` (model ``rate_state_inertial``) through :func:`mechgen.run` for the cycle.
"""
import math
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

p = {"a": 0.01, "b": 0.015, "D_c": 1e-5, "sigma": 1e7, "mu0": 0.6, "V1": 1e-6, "V2": 1e-4, "V_ref": 3e-6}


def mu_steady(V):
    """mu_ss(V) = mu0 + (a - b) ln(V/V_ref)."""
    return p["mu0"] + (p["a"] - p["b"]) * math.log(V / p["V_ref"])


def mu_step(law, t):
    """mu(t) after the step V1 -> V2 at imposed velocity (closed forms above)."""
    a, b, Dc, V1, V2, Vr = (p[k] for k in ("a", "b", "D_c", "V1", "V2", "V_ref"))
    if law == "aging":
        theta = Dc / V2 + (Dc / V1 - Dc / V2) * np.exp(-V2 * t / Dc)
        return p["mu0"] + a * math.log(V2 / Vr) + b * np.log(Vr * theta / Dc)
    return mu_steady(V2) + b * math.log(V2 / V1) * np.exp(-V2 * t / Dc)


t_end = 8 * p["D_c"] / p["V2"]  # 8 D_c of slip
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
for law in ("aging", "slip"):
    slider = mechgen.compile("rate_state_slider", {**p, "law": law, "loading": "imposed"}, backend="c")
    step = mechgen.simulate(slider, t_end=t_end, method="Radau", rtol=1e-12, atol=1e-14, samples=401)
    t = np.asarray(step["t"])
    mu = np.asarray(step["trajectory"]["mu"])
    error = np.max(np.abs(mu - mu_step(law, t)))
    print(f"velocity step, {law} law: max |mu_mechgen - mu_closed form| over {len(t)} samples: {error:.1e}")
    # Radau at rtol 1e-12 on a friction coefficient of order 0.6: 1e-10 (tests/test_rate_state.py asserts the same)
    assert error < 1e-10
    top.plot(t * p["V2"] / p["D_c"], mu, label=f"{law} law (mechgen)")
    top.plot(t * p["V2"] / p["D_c"], mu_step(law, t), "k--", lw=1)
    bottom.semilogy(t * p["V2"] / p["D_c"], np.abs(mu - mu_step(law, t)) + 1e-18, label=law)
top.axhline(mu_steady(p["V2"]), color="grey", ls=":", label="steady mu at V2")
top.plot([], [], "k--", lw=1, label="closed forms")
top.set_ylabel("friction coefficient mu [-]")
top.set_title("Velocity step V1 -> V2 = 100 V1 at imposed velocity")
top.legend()
bottom.set_xlabel("slip since the step d / D_c [-]")
bottom.set_ylabel("|mu - closed form| [-]")
bottom.legend()
fig.tight_layout()

# %%
# The stick-slip cycle: the scene's stability boundary in the spring stiffness against :math:`k_c` and
# :math:`\omega_c`, then its 300 s time history at k = 4e9 Pa/m < k_c.
# The scene as shipped, with the time history sampled every 5 ms instead of 0.5 s (a slip lasts a few tens of
# ms): a scene is a dict too.
SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
scene = tomllib.loads((SCENES / "rate_state_stick_slip.toml").read_text())
# the scene's cycle by collocation and its branch in k have their own page (plot_stick_slip_cycle.py)
scene["analysis"] = [a for a in scene["analysis"] if a["kind"] not in ("periodic_orbit", "continuation")]
for analysis in scene["analysis"]:
    if analysis["name"] == "cycles":
        analysis["samples"] = 60001
run = mechgen.run(scene)
outputs = {analysis["name"]: analysis["outputs"] for analysis in run["analyses"]}
q = run["params"]
k_c = q["sigma"] * (q["b"] - q["a"]) / q["D_c"] * (1 + q["m"] * q["V2"] ** 2 / (q["sigma"] * q["a"] * q["D_c"]))
omega_c = q["V2"] / q["D_c"] * math.sqrt((q["b"] - q["a"]) / q["a"])
boundary = outputs["stiffness"]
print(f"critical stiffness: mechgen {boundary['k_critical']:.6e} Pa/m, closed form {k_c:.6e} Pa/m, "
      f"relative difference {abs(boundary['k_critical'] / k_c - 1):.1e}")
print(f"neutral frequency:  mechgen {boundary['frequency_critical']:.10f} rad/s, closed form {omega_c:.10f} rad/s, "
      f"relative difference {abs(boundary['frequency_critical'] / omega_c - 1):.1e}; verdict at k = {q['k']:.1e}: "
      f"{boundary['verdict']}")
# the crossing is solved to round-off of the eigenvalues' real part (tests/test_rate_state_inertial.py asserts 1e-10)
assert abs(boundary["k_critical"] / k_c - 1) < 1e-10 and abs(boundary["frequency_critical"] / omega_c - 1) < 1e-10

cycle = outputs["cycles"]
t = np.asarray(cycle["t"])
stress = np.asarray(cycle["trajectory"]["spring_stress"])
velocity = np.asarray(cycle["trajectory"]["velocity"])
level = outputs["sliding"]["spring_stress"]
up = np.flatnonzero((stress[:-1] < level) & (stress[1:] >= level))
crossings = t[up] + (level - stress[up]) / (stress[up + 1] - stress[up]) * (t[up + 1] - t[up])
periods = np.diff(crossings)
# no closed form for the nonlinear cycle: its period is read off the samples (crossings of the steady stress,
# linearly interpolated between samples), and it settles: the last periods agree
print(f"limit cycle: {len(periods)} periods, the last three {np.round(periods[-3:], 4)} s (read off samples "
      f"{t[1] - t[0]:.3f} s apart)")
assert np.ptp(periods[-3:]) < 1e-3 * periods[-1]  # settled (measured: a few 1e-6 relative)

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 4))
left.plot(t, stress / 1e6)
left.axhline(level / 1e6, color="grey", ls=":", label="steady sliding")
left.set_xlabel("t [s]")
left.set_ylabel("spring stress F [MPa]")
left.set_title("Stick-slip at k = 0.79 k_c")
left.legend()
late = t >= crossings[-3]
right.semilogx(velocity[late], stress[late] / 1e6)
right.axvline(q["V2"], color="grey", ls=":", label="load-point velocity V2")
right.set_xlabel("slip rate V [m/s]")
right.set_ylabel("spring stress F [MPa]")
right.set_title("The limit cycle (last two periods)")
right.legend()
fig.tight_layout()
plt.show()
