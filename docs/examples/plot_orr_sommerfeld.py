"""
Plane Poiseuille flow: the Orr-Sommerfeld spectrum and the critical Reynolds number
===================================================================================

The Newtonian limit of the Johnson-Segalman channel (seed 002, Khayat & Ashrafi) is the Orr-Sommerfeld problem
of plane Poiseuille flow. The base flow :math:`U = 1 - y^2` between walls at :math:`y = \\pm 1` (velocities in
the centreline velocity, lengths in the half-width) is disturbed by a stream function
:math:`\\psi = v(y)\\,e^{i\\alpha(x - ct)}`:

.. math::

    (U - c)(v'' - \\alpha^2 v) - U'' v = \\frac{1}{i\\alpha Re}\\,(v'''' - 2\\alpha^2 v'' + \\alpha^4 v),
    \\qquad v = v' = 0 \\text{ at } y = \\pm 1 .

The ``orr_sommerfeld`` analysis solves it by Chebyshev collocation (the clamped fourth derivative through
:math:`v = (1 - y^2) f`) as a generalised eigenproblem :math:`A v = c\\,B v`, at two resolutions (N = 64 and 96):
only the eigenvalues found at both within :math:`10^{-6}` are reported, the others (the crowded high part of the
discrete spectrum) are rejected as unresolved. The critical point (Im c = 0 where d Im c / d alpha = 0) is
found by Newton with the eigenvalue's derivatives from its left and right eigenvectors.

**Reference.** Orszag, S. A. (1971), *J. Fluid Mech.* 50:689-703: :math:`c = 0.23752649 + 0.00373967\\,i` at
:math:`\\alpha = 1`, :math:`Re = 10^4`; :math:`Re_c = 5772.22` at :math:`\\alpha_c = 1.02056`.
"""
from pathlib import Path

import matplotlib.pyplot as plt

import mechgen
from mechgen.runtime.spectral.chebyshev import resolved
from mechgen.runtime.spectral.orr_sommerfeld import operators, wave_speeds

scene = Path(mechgen.__file__).resolve().parents[1] / "scenes" / "orr_sommerfeld.toml"
out = mechgen.run(str(scene))["analyses"][0]["outputs"]

c = complex(*out["least_stable_c"])
orszag = 0.23752649 + 0.00373967j
print(f"least stable c = {c.real:.10f} + {c.imag:.10f} i   (Orszag 1971: 0.23752649 + 0.00373967 i)")
print(f"error: {abs(c.real - orszag.real):.1e} (real), {abs(c.imag - orszag.imag):.1e} (imaginary); "
      f"change N = 64 -> 96: {out['least_stable_change']:.1e}")
print(f"critical Re = {out['critical_Re']:.4f} (Orszag 5772.22), alpha = {out['critical_alpha']:.7f} (Orszag 1.02056)")
print(f"resolved eigenvalues: {out['resolved']}, rejected as unresolved: {out['rejected']}")
assert abs(c.real - orszag.real) < 6e-9 and abs(c.imag - orszag.imag) < 6e-9
assert round(out["critical_Re"], 2) == 5772.22

coarse = wave_speeds(operators(64), 1.0, 1e4)
kept, rejected = resolved(coarse, wave_speeds(operators(96), 1.0, 1e4), 1e-6)
fig, ax = plt.subplots(figsize=(6.4, 4.4))
ax.plot(rejected.real, rejected.imag, "x", color="0.6", label="rejected (N = 64 and 96 disagree)")
ax.plot(kept.real, kept.imag, "o", mfc="none", label="resolved")
ax.plot(orszag.real, orszag.imag, "r+", ms=14, label="Orszag (1971)")
ax.axhline(0.0, color="k", lw=0.5)
ax.set(xlim=(0, 1.05), ylim=(-1.0, 0.05), xlabel="Re c", ylabel="Im c",
       title="Orr-Sommerfeld spectrum, alpha = 1, Re = 10^4")
ax.legend(loc="lower left")
plt.show()
