"""
A nonlinear frequency-response curve: the Duffing oscillator through its folds
==============================================================================

The forced, damped Duffing oscillator (the built-in model ``duffing``)

.. math::

    m \\ddot x + c \\dot x + k x + k_3 x^3 = F \\cos(w t)

responds, near its resonance, with an amplitude that depends on the frequency through a curve that bends over
(to the right for a hardening spring, :math:`k_3 > 0`) and folds twice: between the two cyclic folds (LPC) three
orbits coexist, the middle one unstable. :func:`mechgen.periodic_orbit` finds one orbit (here by harmonic balance
with 9 harmonics) and :func:`mechgen.continuation` about it follows the branch in :math:`w` by pseudo-arclength,
through both folds, with the Floquet multipliers of every orbit.

**References.** First-order harmonic balance, :math:`x \\approx A \\cos(w t - \\varphi)`, gives the classical
frequency-amplitude relation (Nayfeh & Mook, *Nonlinear Oscillations*, 1979, sec. 4.1)

.. math::

    \\left[\\left(k - m w^2 + \\tfrac34 k_3 A^2\\right)^2 + (c w)^2\\right] A^2 = F^2 ,

close to the converged curve when the nonlinearity is weak (its error, of the order of the third harmonic, is
printed below). Exactly, at a cyclic fold the monodromy matrix has the eigenvalue 1: the largest multiplier there
is printed too.
"""
import matplotlib.pyplot as plt
import numpy as np

import mechgen

m, c, k, k3, F = 1.0, 0.05, 1.0, 0.1, 0.1
duffing = mechgen.compile("duffing", {"m": m, "c": c, "k": k, "k3": k3, "F": F, "w": 0.6})
orbit = mechgen.periodic_orbit(duffing, method="harmonic_balance", harmonics=9, frequency="w")
curve = mechgen.continuation(duffing, about=orbit, parameter="w", stop=1.6, max_step=0.02, max_points=600)

# %%
# The first-order harmonic balance at every branch point's amplitude: the frequencies w with
# ((k - m w^2 + 3/4 k3 A^2)^2 + (c w)^2) A^2 = F^2, the one nearest the branch's w.
w = np.array([p["w"] for p in curve["branch"]])
A = np.array([p["amplitude"]["x"] for p in curve["branch"]])


def first_order_w(amplitude, near):
    """The root w of the first-order relation (a quadratic in w^2) nearest ``near``."""
    s = k + 0.75 * k3 * amplitude**2
    # m^2 w^4 + (c^2 - 2 m s) w^2 + s^2 - F^2 / A^2 = 0
    roots = np.roots([m * m, c * c - 2 * m * s, s * s - (F / amplitude) ** 2])
    roots = np.sqrt(roots[(np.abs(roots.imag) < 1e-12) & (roots.real > 0)].real)
    return roots[np.argmin(np.abs(roots - near))] if roots.size else np.nan


reference = np.array([first_order_w(a, wi) for a, wi in zip(A, w)])
error = np.nanmax(np.abs(reference - w))
print(f"{len(w)} orbits; largest |w - w_first_order| at equal amplitude: {error:.2e} rad/s")
assert error < 5e-3  # the first order neglects terms of second order in 3/4 k3 A^2 / k (<= 0.24 here): 3.1e-3 measured

folds = [s for s in curve["special_points"] if s["type"] == "LPC"]
for s in folds:
    largest = max(abs(complex(*mu)) for mu in s["multipliers"])
    print(f"LPC at w = {s['w']:.8f} rad/s, amplitude {s['amplitude']['x']:.6f} m, largest |multiplier| "
          f"{largest:.8f} (exactly 1 at a fold)")
assert len(folds) == 2

# %%
# The curve, its unstable middle branch (dashed) and the first-order relation.
stable = np.array([p["stability"] == "stable" for p in curve["branch"]])
fig, ax = plt.subplots(figsize=(7, 5))
ax.plot(np.where(stable, w, np.nan), A, "b-", lw=1.5, label="mechgen, stable")
ax.plot(np.where(~stable, w, np.nan), A, "r--", lw=1.5, label="mechgen, unstable")
ax.plot(reference, A, "k:", lw=1.0, label="first-order harmonic balance")
ax.plot([s["w"] for s in folds], [s["amplitude"]["x"] for s in folds], "kx", ms=9, label="cyclic folds (LPC)")
backbone = np.linspace(0.0, A.max(), 100)
ax.plot(np.sqrt((k + 0.75 * k3 * backbone**2) / m), backbone, color="0.6", lw=0.8, label="backbone")
ax.set_xlabel("forcing frequency w (rad/s)")
ax.set_ylabel("amplitude max |x| (m)")
ax.set_title("Duffing oscillator: frequency-response curve (harmonic balance, 9 harmonics)", fontsize=9)
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
