"""
The stick-slip limit cycle of a rate-and-state slider by collocation, and its branch to the Hopf point
======================================================================================================

A block (mass per area ``m``, kg/m²) under normal stress :math:`\\sigma` (Pa), pulled through a spring ``k`` (Pa/m)
whose far end moves at :math:`V_2`, slides with rate-and-state friction (aging law). In the model's internal
variables :math:`\\phi = \\ln(V/V_*)`, :math:`\\psi = \\ln(V_*\\theta/D_c)`, :math:`f = F/\\sigma - \\mu_0`
(``mechgen/models/rate_state_inertial.py``):

.. math::

    \\dot\\phi = \\frac{\\sigma (f - a\\phi - b\\psi)}{m V_* e^{\\phi}}, \\qquad
    \\dot\\psi = \\frac{V_*}{D_c}\\left(e^{-\\psi} - e^{\\phi}\\right), \\qquad
    \\dot f = \\frac{k (V_2 - V_* e^{\\phi})}{\\sigma} .

Steady sliding at :math:`V_2` loses stability as k falls through
:math:`k_c = \\sigma (b - a)/D_c\\,(1 + m V_2^2/(\\sigma a D_c))` with the neutral frequency
:math:`\\omega_c = (V_2/D_c)\\sqrt{(b - a)/a}` (Rice & Ruina 1983); below it the slider sticks and slips on a limit
cycle whose slip lasts a few hundredths of its period — a stiff cycle, which shooting does not converge on.

mechgen: the shipped scene ``scenes/rate_state_stick_slip.toml`` through :func:`mechgen.run`: ``cycle`` is a
``periodic_orbit`` by ``collocation`` (100 intervals, adapted twice) started ``from`` the simulate ``cycles`` (its
last cycle: one period re-integrated from its state and closed by a Poincaré section, the first mesh adapted to that
guess, AUTO's integral phase condition); ``cycle_in_k`` continues it in k.

Reference: the same three equations written out here and run by scipy's LSODA (ODEPACK's Adams/BDF switching, rtol
1e-13) from the velocity step for 15 cycles; the period is Aitken's limit of the distances between successive upward
crossings of :math:`\\phi = \\ln(V_2/V_*)`, and the ratio of their successive differences is the non-trivial Floquet
multiplier (the transient shrinks by it each cycle). J. R. Rice and A. Ruina, J. Appl. Mech. 50 (1983) 343; A. Ruina,
J. Geophys. Res. 88 (1983) 10359. The tests: ``tests/test_stick_slip_cycle.py``.
"""
import math
import time
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import scipy.integrate as si
import scipy.optimize as so

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
scene = tomllib.loads((SCENES / "rate_state_stick_slip.toml").read_text())
p = scene["params"]


def rhs(t, x):
    """The slider's equations above, aging law."""
    phi, psi, f = x
    V = p["V_ref"] * math.exp(phi)
    return [p["sigma"] * (f - p["a"] * phi - p["b"] * psi) / (p["m"] * V),
            p["V_ref"] / p["D_c"] * (math.exp(-psi) - math.exp(phi)), p["k"] * (p["V2"] - V) / p["sigma"]]


# %%
# The reference: a long LSODA run from the step V1 -> V2 and the period read off its crossings.
start = time.perf_counter()
before = math.log(p["V1"] / p["V_ref"])
run = si.solve_ivp(rhs, (0.0, 330.0), [before, -before, (p["a"] - p["b"]) * before], method="LSODA",
                   rtol=1e-13, atol=1e-14, dense_output=True)
level = math.log(p["V2"] / p["V_ref"])
grid = np.linspace(0.0, 330.0, 200_001)
above = run.sol(grid)[0] - level
up = np.flatnonzero((above[:-1] < 0) & (above[1:] >= 0))
crossings = np.array([so.brentq(lambda s: run.sol(s)[0] - level, grid[i], grid[i + 1], xtol=1e-14) for i in up])
periods = np.diff(crossings)
d = np.diff(periods)
T_ref = periods[-1] - d[-1] ** 2 / (d[-1] - d[-2])  # Aitken's limit
mu_ref = d[-1] / d[-2]
print(f"reference (scipy LSODA, {time.perf_counter() - start:.1f} s): period {T_ref:.10f} s, last periods "
      f"{np.round(periods[-3:], 9)}, multiplier from the transient {mu_ref:.6f}")

# %%
# mechgen: the scene's simulate, its cycle by collocation and the branch in k.
start = time.perf_counter()
result = mechgen.run(scene)
outputs = {analysis["name"]: analysis["outputs"] for analysis in result["analyses"]}
cycle, branch = outputs["cycle"], outputs["cycle_in_k"]
mu = np.array([complex(*m) for m in cycle["multipliers"]])
trivial = int(np.argmin(np.abs(mu - 1)))
mu2 = np.delete(mu, trivial)[0].real
error = abs(cycle["period"] - T_ref) / T_ref
print(f"mechgen (the whole scene, {time.perf_counter() - start:.1f} s): period {cycle['period']:.10f} s, relative "
      f"error {error:.1e}; multipliers {np.round(mu.real, 6)}: trivial |mu - 1| = {abs(mu[trivial] - 1):.1e}, "
      f"mu_2 {mu2:.6f} against the transient's {mu_ref:.6f}")
assert error < 1e-9 and abs(mu[trivial] - 1) < 1e-6 and abs(mu2 - mu_ref) < 5e-3  # tests/test_stick_slip_cycle.py

# %%
# The branch in k. The Hopf point is subcritical: the stable cycle outlives k_c up to a cyclic fold (LPC), turns
# back unstable there and shrinks onto steady sliding at k_c, where the branch ends (status ``equilibrium``).
k_c = p["sigma"] * (p["b"] - p["a"]) / p["D_c"] * (1 + p["m"] * p["V2"] ** 2 / (p["sigma"] * p["a"] * p["D_c"]))
omega_c = p["V2"] / p["D_c"] * math.sqrt((p["b"] - p["a"]) / p["a"])
points = branch["branch"]
fold = branch["special_points"][0]
last = points[-1]
print(f"branch: {len(points)} orbits, status {branch['status']}; {fold['type']} at k = {fold['k']:.6e} Pa/m = "
      f"{fold['k'] / k_c:.5f} k_c (period {fold['period']:.4f} s)")
print(f"its last orbit: k = {last['k']:.6e} Pa/m against k_c = {k_c:.6e} (relative {abs(last['k'] / k_c - 1):.1e}); "
      f"period {last['period']:.5f} s against 2 pi / omega_c = {2 * math.pi / omega_c:.5f} s "
      f"(relative {abs(last['period'] * omega_c / (2 * math.pi) - 1):.1e})")
assert branch["status"] == "equilibrium" and abs(last["k"] / k_c - 1) < 1e-4
assert abs(last["period"] * omega_c / (2 * math.pi) - 1) < 1e-3

# %%
# Mesh convergence: the period on adapted meshes against 200 intervals (order 8 at the mesh points).
system = mechgen.compile("rate_state_inertial", {**p}, backend="c")
meshes = (50, 70, 100, 140)
best = mechgen.periodic_orbit(system, method="collocation", period=21.0, z0={"phi": 2.0, "psi": -2.0}, mesh=200,
                              adapt=2)["period"]
mesh_errors = [abs(mechgen.periodic_orbit(system, method="collocation", period=21.0, z0={"phi": 2.0, "psi": -2.0},
                                          mesh=m, adapt=2)["period"] - best) for m in meshes]
print("period error against 200 intervals: " + ", ".join(f"{m}: {e:.1e}" for m, e in zip(meshes, mesh_errors)))

fig, axes = plt.subplots(1, 3, figsize=(13, 4))
t = np.asarray(cycle["t"])
V = np.asarray(cycle["trajectory"]["velocity"])
shift = t[int(np.argmax(V))]
ref_t = np.linspace(crossings[-2], crossings[-1], 4001)
ref_V = p["V_ref"] * np.exp(run.sol(ref_t)[0])
ref_shift = ref_t[int(np.argmax(ref_V))]
axes[0].semilogy(t - shift, V, label="mechgen (collocation)")
axes[0].semilogy(ref_t - ref_shift, ref_V, "k--", lw=1, label="scipy LSODA, last cycle")
axes[0].set_xlabel("t - t(V max) [s]")
axes[0].set_ylabel("slip rate V [m/s]")
axes[0].set_title(f"The cycle: T = {cycle['period']:.6f} s (error {error:.0e})")
axes[0].legend(fontsize=8)
k = np.array([q["k"] for q in points])
phi_max = np.array([q["amplitude"]["phi"] for q in points])
stable = np.array([q["stability"] == "stable" for q in points])
axes[1].plot(k[stable], phi_max[stable], "-", label="stable cycles")
axes[1].plot(k[~stable], phi_max[~stable], "--", label="unstable cycles")
axes[1].plot(fold["k"], fold["amplitude"]["phi"], "kx", label="LPC")
axes[1].axvline(k_c, color="grey", ls=":", label="k_c (Hopf)")
axes[1].axhline(level, color="grey", lw=0.8, label="steady sliding ln(V2/V*)")
axes[1].set_xlabel("spring stiffness k [Pa/m]")
axes[1].set_ylabel("max phi = ln(V_max/V*) [-]")
axes[1].set_title("The branch in k")
axes[1].legend(fontsize=8)
axes[2].loglog(meshes, mesh_errors, "o-", label="mechgen")
axes[2].loglog(meshes, mesh_errors[0] * (np.array(meshes) / meshes[0]) ** -8.0, "k:", label="slope -8")
axes[2].set_xlabel("collocation intervals")
axes[2].set_ylabel("|T - T(200)| [s]")
axes[2].set_title("Mesh convergence (adapted meshes)")
axes[2].legend(fontsize=8)
fig.tight_layout()
plt.show()
