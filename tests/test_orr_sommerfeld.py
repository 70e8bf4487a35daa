"""Orr-Sommerfeld stability of plane Poiseuille flow (issue 28 item 4, the Newtonian limit of the JS channel).

References: Orszag, S. A. (1971) "Accurate solution of the Orr-Sommerfeld stability equation", J. Fluid Mech.
50:689-703: the least stable wave speed c = 0.23752649 + 0.00373967 i at alpha = 1, Re = 10^4 (8 decimals) and
the critical point Re_c = 5772.22, alpha_c = 1.02056. Chebyshev differentiation checked on polynomials, whose
derivatives are known exactly; the critical point's alpha also from a quartic fit of Im c(alpha) (no
eigenvector derivatives).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mechgen.errors import SceneError
from mechgen.runtime.spectral import chebyshev as cb
from mechgen.runtime.spectral.orr_sommerfeld import critical_point, least_stable, operators, spectrum, wave_speeds
from mechgen.scene.run import run_scene

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "orr_sommerfeld.toml"
ORSZAG_C = 0.23752649 + 0.00373967j
# half a unit in the last of Orszag's 8 decimals (his rounding) plus our N = 64 vs 96 change (6e-10)
ORSZAG_TOL = 5e-9 + 1e-9


def test_chebyshev_matrices_exact_on_polynomials():
    """D and the clamped D^4 differentiate polynomials of degree <= N exactly (to round-off x N^2, N^8)."""
    D, y = cb.differentiation(16)
    assert np.max(np.abs(D @ y**5 - 5 * y**4)) < 1e-11  # round-off of D grows as N^2 eps
    D4 = cb.clamped_fourth(16)
    yi = y[1:16]
    v = (1 - yi**2) ** 2 * yi**3  # clamped at both ends: v = y^3 - 2 y^5 + y^7
    exact = -2 * 120 * yi + 7 * 6 * 5 * 4 * yi**3
    assert np.max(np.abs(D4 @ v - exact)) < 1e-7  # round-off of D^4 grows as N^8 eps (1e-5 at N = 16, relative 1e-9)


def test_orszag_least_stable_eigenvalue():
    """Orszag (1971): c = 0.23752649 + 0.00373967 i at alpha = 1, Re = 1e4, to his 8 decimals."""
    kept, rejected = spectrum(1.0, 1e4, 64, 96, 1e-6)
    c = kept[0]
    assert abs(c.real - ORSZAG_C.real) < ORSZAG_TOL and abs(c.imag - ORSZAG_C.imag) < ORSZAG_TOL
    assert rejected.size > 0  # the high, unresolved part of the discrete spectrum is dropped, not reported


def test_resolution_filter_rejects_unresolved():
    """Every kept eigenvalue reappears at both resolutions; the rejected ones move between N = 64 and 96."""
    coarse = wave_speeds(operators(64), 1.0, 1e4)
    fine = wave_speeds(operators(96), 1.0, 1e4)
    kept, rejected = cb.resolved(coarse, fine, 1e-6)
    assert all(np.min(np.abs(coarse - c)) <= 1e-6 * max(1, abs(c)) for c in kept)
    assert all(np.min(np.abs(fine - c)) > 1e-6 * max(1, abs(c)) for c in rejected)
    assert kept.size + rejected.size == coarse.size


def test_orszag_critical_point():
    """Re_c = 5772.22 (Orszag's 6 digits) and alpha_c within one unit of his last digit (1.02056): we get
    1.0205474 at N = 48 and 64 alike, also from a quartic fit of Im c(alpha) at Re_c."""
    a48, R48, c48, _ = critical_point(operators(48), 1.0, 6000.0)
    a64, R64, _, _ = critical_point(operators(64), 1.0, 6000.0)
    assert round(R48, 2) == 5772.22 and round(R64, 2) == 5772.22
    assert abs(R48 - R64) < 1e-3  # the round-off floor of Im c (1e-10) over d Im c / d Re (5e-7)
    assert abs(a48 - a64) < 1e-7 and abs(a48 - 1.02056) < 1.5e-5  # one unit in Orszag's 6th digit
    assert abs(c48.imag) < 1e-9
    ops = operators(48)
    alphas = np.linspace(a48 - 5e-3, a48 + 5e-3, 9)
    fit = np.polyfit(alphas - a48, [least_stable(ops, a, R48)[0].imag for a in alphas], 4)
    top = np.roots(np.polyder(fit))
    top = top[np.isreal(top)].real
    assert np.min(np.abs(top)) < 1e-6  # the maximum of Im c over alpha lies at alpha_c


def test_scene_outputs():
    """The shipped scene reports the contract's names with the values above."""
    out = run_scene(str(SCENE))["analyses"][0]["outputs"]
    c = complex(*out["least_stable_c"])
    assert abs(c - ORSZAG_C) < 2 * ORSZAG_TOL
    assert out["verdict"] == "unstable" and out["resolution"] == [64, 96]
    assert round(out["critical_Re"], 2) == 5772.22


def test_same_resolutions_refused(tmp_path):
    """N_check = N is no convergence check: refused at load (exit 2) naming the key."""
    scene = tmp_path / "os.toml"
    scene.write_text(SCENE.read_text().replace("N = 64", "N = 64\nN_check = 64"))
    with pytest.raises(SceneError, match="N_check"):
        run_scene(str(scene))


def test_scene_values_reach_the_analysis(tmp_path):
    """The scene's Re is the one solved (alpha, Re kept free in the kernels): Re = 5000 < Re_c is stable at
    alpha = 1 (Orszag 1971: the neutral curve's minimum is Re_c = 5772.22)."""
    scene = tmp_path / "os.toml"
    scene.write_text(SCENE.read_text().replace("Re = 1.0e4", "Re = 5.0e3").replace("count = 8", "critical = false"))
    out = run_scene(str(scene))["analyses"][0]["outputs"]
    assert out["verdict"] == "stable" and out["least_stable_c"][1] < 0 and "critical_Re" not in out
