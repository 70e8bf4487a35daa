"""
Periodic orbits: a forced Duffing orbit by harmonic balance and shooting, the van der Pol limit cycle
=====================================================================================================

The analysis kind ``periodic_orbit`` finds a periodic orbit of a smooth lumped model directly, without
integrating until the transient dies out, and reports its period, its harmonics, its Floquet multipliers and
its stability.

**A forced orbit.** The Duffing oscillator (x in m, t in s)

.. math::

    \\ddot x + c \\dot x + x + k_3 x^3 = F \\cos(\\omega t),
    \\qquad c = 0.05,\\ k_3 = 0.5,\\ F = 0.3,\\ \\omega = 1.2,

has, from a start near its resonant orbit, a periodic response of period T = 2π/ω. Harmonic balance writes x as
a Fourier series of H harmonics and solves for the coefficients (the model's generated residual evaluated at
8 (H + 1) phases in one batched call, its exact Jacobian from the generated tangent); shooting solves
x(T) − x(0) = 0 with the monodromy matrix from the variational equations. Reference: the same equation written
by hand, shot with :func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-13) and :func:`scipy.optimize.fsolve`.
By Liouville's formula the product of the two Floquet multipliers is exp(−c T) exactly.

**An autonomous orbit.** The van der Pol oscillator

.. math::

    \\ddot x - \\mu (1 - x^2) \\dot x + x = 0

(the built-in model ``van_der_pol``; ``scenes/van_der_pol_limit_cycle.toml``) has a limit cycle whose period is
unknown: it is found beside the orbit, with a phase condition, here by shooting, harmonic balance and orthogonal
collocation (degree-4 polynomials at Gauss points on 40 intervals). References: T = 6.6632868593231 at μ = 1 and
the small-μ expansion T = 2π (1 + μ²/16 − 5μ⁴/3072 + …), amplitude 2 + O(μ²) (Andersen & Geer, SIAM J. Appl.
Math. 42, 1982); the non-trivial multiplier is exp(μ ∮ (1 − x²) dt) (the trace of the Jacobian integrated over the
orbit), computed here by scipy beside the state.
"""
import math
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

import mechgen

MODEL = '''\
"""Forced Duffing: x'' + c x' + x + k3 x^3 = F cos(w t)."""
import sympy as sp
from mechgen import Model, Param

model = Model("gallery_orbit_duffing", doc=__doc__)
model.params(Param("c", 0.05), Param("k3", 0.5), Param("F", 0.3), Param("w", 1.2, "rad/s"))
model.coordinates("x")


@model.kinetic
def kinetic(v):
    return v.x**2 / 2


@model.potential
def potential(q, p):
    return q.x**2 / 2 + p.k3 * q.x**4 / 4


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def forces(p, t):
    return {"x": p.F * sp.cos(p.w * t)}
'''

folder = Path(tempfile.mkdtemp())
(folder / "duffing.py").write_text(MODEL)
duffing = mechgen.compile(str(folder / "duffing.py"))

hb = mechgen.periodic_orbit(duffing, frequency="w", harmonics=7, q0={"x": 1.3}, v0={"x": 0.5})
shot = mechgen.periodic_orbit(duffing, frequency="w", method="shooting", q0={"x": 1.3}, v0={"x": 0.5})

# %%
# The reference: the Duffing equation by hand, shot by scipy.
c, k3, F, w = 0.05, 0.5, 0.3, 1.2
T = 2 * math.pi / w


def rhs(t, x):
    """x' = v, v' = F cos(w t) - c v - x - k3 x^3."""
    return [x[1], F * math.cos(w * t) - c * x[1] - x[0] - k3 * x[0] ** 3]


def flow(x0, t_eval=None):
    return solve_ivp(rhs, (0.0, T), x0, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=t_eval)


x0 = fsolve(lambda x: flow(x).y[:, -1] - x, [1.3, 0.5], xtol=1e-13)
t = np.array(hb["t"])
x_ref = flow(x0, t_eval=t).y[0]
error_hb = np.max(np.abs(np.array(hb["trajectory"]["x"]) - x_ref))
error_shot = np.max(np.abs(np.array(shot["trajectory"]["x"]) - x_ref))
mu = np.array([complex(*m) for m in shot["multipliers"]])
print(f"Duffing orbit, T = {hb['period']:.6f}: max |x - x_ref| harmonic balance (H = 7) {error_hb:.2e}, "
      f"shooting {error_shot:.2e}")
print(f"multipliers {np.round(mu, 8)}, |mu| = {abs(mu[0]):.8f} ({shot['stability']}); "
      f"product {np.prod(mu).real:.12f} vs exp(-c T) = {math.exp(-c * T):.12f}")
assert error_hb < 1e-5 and error_shot < 1e-8
assert abs(np.prod(mu).real - math.exp(-c * T)) < 1e-9

# %%
# The van der Pol limit cycle at mu = 1, and at mu = 0.1 against the small-mu expansion.
vdp = mechgen.compile("van_der_pol")
cycle = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0})
cycle_hb = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0}, harmonics=30)
cycle_col = mechgen.periodic_orbit(vdp, period=6.5, q0={"x": 2.0}, mesh=40)
T_REF = 6.6632868593231
print(f"van der Pol mu = 1: T shooting {cycle['period']:.12f}, harmonic balance (H = 30) "
      f"{cycle_hb['period']:.12f}, collocation (40 intervals) {cycle_col['period']:.12f}, reference {T_REF}; "
      f"amplitude {cycle['amplitude']['x']:.9f}")


def vdp_rhs(t, y, m=1.0):
    """x' = v, v' = m (1 - x^2) v - x, and the trace integrand 1 - x^2."""
    return [y[1], m * (1 - y[0] ** 2) * y[1] - y[0], 1 - y[0] ** 2]


a = cycle["amplitude"]["x"]
trace = solve_ivp(vdp_rhs, (0.0, cycle["period"]), [a, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-14).y[2, -1]
mus = np.array([complex(*m) for m in cycle["multipliers"]])
print(f"multipliers {np.round(mus.real, 10)}; exp(mu int (1 - x^2) dt) = {math.exp(trace):.10f}")
assert abs(cycle["period"] - T_REF) < 1e-9 and abs(cycle_hb["period"] - T_REF) < 1e-8
assert abs(cycle_col["period"] - T_REF) < 1e-8
assert abs(mus[1].real - math.exp(trace)) < 1e-9

small = mechgen.periodic_orbit(vdp.with_params(mu=0.1), period=6.3, q0={"x": 2.0})
expansion = 2 * math.pi * (1 + 0.1**2 / 16)
print(f"van der Pol mu = 0.1: T = {small['period']:.9f}, 2 pi (1 + mu^2/16) = {expansion:.9f} (difference "
      f"{small['period'] - expansion:.2e}; the next term -2 pi 5 mu^4/3072 = {-2 * math.pi * 5e-4 / 3072:.2e})")
assert abs(small["period"] - expansion) < 3e-6

# %%
# The orbits: the Duffing response over one period (both methods on the reference), the limit cycles.
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
axes[0].plot(t, x_ref, "k-", lw=3, alpha=0.3, label="scipy shooting (reference)")
axes[0].plot(t, hb["trajectory"]["x"], "C0--", label="harmonic balance, H = 7")
axes[0].plot(t[::8], np.array(shot["trajectory"]["x"])[::8], "C1o", ms=4, label="shooting")
axes[0].set_xlabel("t (s)")
axes[0].set_ylabel("x (m)")
axes[0].set_title(f"Duffing, omega = {w}: error {max(error_hb, error_shot):.1e}")
axes[0].legend(fontsize="small")
for result, label in ((cycle, "mu = 1"), (small, "mu = 0.1")):
    axes[1].plot(result["trajectory"]["x"], result["trajectory"]["x_dot"], label=f"{label}: T = {result['period']:.5f}")
axes[1].set_xlabel("x")
axes[1].set_ylabel("dx/dt")
axes[1].set_title("van der Pol limit cycles")
axes[1].legend(fontsize="small")
fig.tight_layout()
plt.show()
