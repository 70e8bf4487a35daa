"""
The Fermi-Pasta-Ulam recurrence: the energy returns to the lowest mode
======================================================================

A chain of ``N = 31`` unit masses joined by 32 nonlinear springs, ends fixed (:math:`q_0 = q_{N+1} = 0`), the
FPU-:math:`\\alpha` chain (dimensionless units):

.. math::

    H = \\sum_{n=1}^{N} \\frac{p_n^2}{2} + \\sum_{n=0}^{N} \\left(\\frac{(q_{n+1} - q_n)^2}{2}
    + \\frac{\\alpha}{3}(q_{n+1} - q_n)^3\\right), \\qquad \\alpha = 0.25 .

Its normal coordinates and linear frequencies are

.. math::

    Q_k = \\sqrt{\\frac{2}{N+1}} \\sum_n q_n \\sin\\frac{n k \\pi}{N+1}, \\qquad
    \\omega_k = 2\\sin\\frac{k\\pi}{2(N+1)}, \\qquad E_k = \\tfrac12 (\\dot Q_k^2 + \\omega_k^2 Q_k^2) .

Started in mode 1 with unit amplitude, the energy spreads to a few low modes and, instead of sharing
itself out evenly, comes back almost entirely to mode 1 after about 150 periods
:math:`T_1 = 2\\pi/\\omega_1` — the recurrence. There is no closed form for the recurrence time: the
reference is a convergence study (the same run at half the step, and with a different integrator, must give
the same recurrence; ``tests/test_fpu_recurrence.py``), and FPU's observation of a near-complete return.

Reference: E. Fermi, J. Pasta and S. Ulam, "Studies of nonlinear problems", Los Alamos report LA-1940 (1955),
the experiment recalled by the seed paper (V. Chiroiu, C. Rugina, D. Dumitriu, L. Munteanu, "On the acoustics
and friction", SISOM 2012).

mechgen runs the shipped scene ``scenes/fpu_recurrence.toml`` (model ``fpu_chain``, the symplectic ABA864
integrator in a compiled loop, dt = 0.1) through :func:`mechgen.run`, and the same chain at dt = 0.2 through
:func:`mechgen.compile` and :func:`mechgen.symplectic`.
"""
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mechgen

SCENES = Path(mechgen.__file__).resolve().parents[1] / "scenes"
run = mechgen.run(str(SCENES / "fpu_recurrence.toml"))
fine = {analysis["name"]: analysis["outputs"] for analysis in run["analyses"]}["recurrence"]

chain = mechgen.compile("fpu_chain", {"N": 31, "alpha": 0.25, "beta": 0.0, "ends": "fixed"})
coarse = mechgen.symplectic(chain, integrator="aba864", dt=0.2, t_end=11000.0, modes=5)

print(f"recurrence at dt = 0.1: {fine['recurrence_periods']:.6f} T_1, {100 * fine['recurrence_fraction']:.4f} % "
      f"of the energy back in mode 1 (energy error {fine['energy_error']:.1e})")
print(f"recurrence at dt = 0.2: {coarse['recurrence_periods']:.6f} T_1, {100 * coarse['recurrence_fraction']:.4f} %")
dT = abs(fine["recurrence_periods"] - coarse["recurrence_periods"])
dF = abs(fine["recurrence_fraction"] - coarse["recurrence_fraction"])
print(f"difference between the steps: {dT:.1e} T_1 and {dF:.1e} of the energy")
# ABA864 is of order 8: halving dt = 0.2 changes the recurrence by far less than the sampling of the modal
# energies (T_1 / 40 apart, interpolated); tests/test_fpu_recurrence.py asserts the same bounds
assert dT < 1e-4 and dF < 1e-5
assert 140 < fine["recurrence_periods"] < 155 and fine["recurrence_fraction"] > 0.95  # a near-complete return

# %%
# The modal energies, as FPU plotted them:
N = 31
T1 = 2 * np.pi / (2 * np.sin(np.pi / (2 * (N + 1))))
t = np.asarray(fine["t"]) / T1
E = np.asarray(fine["mode_energies_series"])
fig, ax = plt.subplots(figsize=(8, 4))
for k in range(E.shape[1]):
    ax.plot(t, E[:, k], lw=0.8, label=f"mode {k + 1}")
ax.axvline(fine["recurrence_periods"], color="k", ls=":", label="recurrence (mechgen)")
ax.set_xlabel("t / T_1 [-]")
ax.set_ylabel("modal energy E_k [-]")
ax.set_title("FPU-alpha chain, N = 31, alpha = 0.25, started in mode 1")
ax.legend(fontsize=7, loc="upper right")
fig.tight_layout()
plt.show()
