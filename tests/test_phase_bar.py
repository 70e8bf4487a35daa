"""Phase boundaries in a bar (issue 28, items 7-9): Maxwell stress, two-phase equilibria, driving traction.

References (Abeyaratne & Knowles, J. Mech. Phys. Solids 38, 1990; "Evolution of Phase Transitions", CUP 2006):

* cubic law sigma = mu (gamma - beta gamma^2 + c gamma^3): a cubic is point-symmetric about its inflection
  gamma_i = beta/(3 c) (sigma(gamma_i + u) - sigma(gamma_i) = sigma'(gamma_i) u + mu c u^3 is odd in u), so the
  horizontal line through (gamma_i, sigma(gamma_i)) cuts equal areas: sigma_M = sigma(gamma_i)
  = mu (beta/(3 c) - 2 beta^3/(27 c^2)), phase strains gamma_i -+ sqrt((beta^2 - 3 c)/(3 c^2)) (the roots of
  sigma'(gamma_i) + mu c u^2 = 0);
* trilinear law: an equal-area solve written here with scipy (quad of a hand-written sigma, brentq), independent
  of the model's kernels and of mechgen.runtime.steady.phases; with both phases of modulus mu the driving
  traction is f = gamma_T (sigma - sigma_M) in closed form;
* a convex law (beta^2 < 3 c) has no phase boundary.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import mechgen
from mechgen.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _boundary(params: dict, strain_range, **options):
    system = mechgen.compile("phase_bar", params, backend="c")
    return mechgen.analysis("phase_boundary", system, strain_range=strain_range, **options)


@pytest.mark.parametrize("beta, c", [(3.0, 2.2), (2.0, 1.0)])
def test_cubic_maxwell_stress_is_the_stress_at_the_inflection(beta, c):
    mu = 2.5
    r = _boundary({"law": "cubic", "mu": mu, "beta": beta, "c": c}, [-1.0, 3.0])
    gi = beta / (3 * c)
    sigma_m = mu * (beta / (3 * c) - 2 * beta**3 / (27 * c**2))
    u = np.sqrt((beta**2 - 3 * c) / (3 * c**2))
    assert r["phase_boundary"]
    # Brent's method to 1e-15 of the stress scale on a kernel evaluated in double precision
    assert abs(r["maxwell_stress"] - sigma_m) <= 1e-11 * mu
    np.testing.assert_allclose(r["phase_strains"], [gi - u, gi + u], rtol=0, atol=1e-9)  # sigma' ~ 1: same digits


def _trilinear(g, gM, gm, gT):
    """sigma/mu of the trilinear law, written out here."""
    if g <= gM:
        return g
    if g < gm:
        return gM + ((gm - gT) - gM) * (g - gM) / (gm - gM)
    return g - gT


def test_trilinear_maxwell_stress_against_an_independent_equal_area_solve():
    gM, gm, gT = 0.02, 0.07, 0.06
    r = _boundary({"law": "trilinear", "gamma_M": gM, "gamma_m": gm, "gamma_T": gT}, [-0.01, 0.12])

    def area(sigma):  # int_{g1}^{g2} (sigma(g) - sigma) dg with g1 = sigma, g2 = sigma + gT (mu = 1)
        return quad(lambda g: _trilinear(g, gM, gm, gT) - sigma, sigma, sigma + gT, points=[gM, gm],
                    epsabs=1e-15, epsrel=1e-13)[0]

    reference = brentq(area, gm - gT, gM, xtol=1e-15)
    assert abs(r["maxwell_stress"] - reference) <= 1e-12  # quad's and brentq's tolerances, stresses ~ 0.02
    np.testing.assert_allclose(r["phase_strains"], [reference, reference + gT], rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["spinodal_strains"], [gM, gm], rtol=0, atol=1e-12)  # the kinks, by Brent


def test_two_phase_equilibria_fractions_and_driving_traction():
    gM, gm, gT, L = 0.02, 0.06, 0.05, 2.0
    r = _boundary({"law": "trilinear", "gamma_M": gM, "gamma_m": gm, "gamma_T": gT, "L": L}, [-0.01, 0.1],
                  elongation=[0.08, 0.01], equilibrium_samples=9)
    sigma_m = r["maxwell_stress"]
    w0 = gM**2 / 2 + gM * (gm - gM) + ((gm - gT) - gM) / (gm - gM) * (gm - gM)**2 / 2 - (gm - gT)**2 / 2
    assert abs(sigma_m - w0 / gT) <= 1e-13  # sigma_M = w0/gamma_T (the model's docstring)
    inside, outside = r["equilibria"]
    nu = (0.08 / L - sigma_m) / gT  # phase strains sigma_M and sigma_M + gamma_T
    assert abs(inside["phase_fraction"] - nu) <= 1e-12 and abs(inside["boundary_position"] - nu * L) <= 1e-12
    assert abs(inside["driving_traction"]) <= 1e-15  # f = 0 at the Maxwell stress (stresses ~ 0.02)
    assert outside["phase_fraction"] is None  # mean strain 0.005 < gamma_1: one phase
    fam = inside["family"]
    assert len(fam["stress"]) > 3
    np.testing.assert_allclose(fam["driving_traction"], gT * (np.array(fam["stress"]) - sigma_m), rtol=0, atol=1e-15)
    np.testing.assert_allclose(fam["phase_fraction"], (0.08 / L - np.array(fam["stress"])) / gT, rtol=0, atol=1e-12)


def test_a_convex_energy_has_no_phase_boundary_and_says_so():
    r = _boundary({"law": "cubic", "beta": 1.0, "c": 1.0}, [-1.0, 2.0], elongation=[0.5])
    assert r["phase_boundary"] is False and r["maxwell_stress"] is None
    assert r["phase_strains"] == [] and r["equilibria"] == []
    assert "convex" in r["note"] and "no phase boundary" in r["note"]


def _scene(tmp_path, *edits) -> Path:
    text = (ROOT / "scenes" / "phase_bar.toml").read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "bar.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("edit, words", [
    (('law = "trilinear"', 'law = "quartic"'), ["law", "cubic", "trilinear"]),
    (("strain_range = [-0.01, 0.1]", "strain_range = [0.0, 0.05]"), ["strain_range", "wider"]),
    (("gamma_m = 0.06", "gamma_m = 0.01"), ["params", "gamma_M < gamma_m"]),
    (("strain_range = [-0.01, 0.1]", "strain_range = [0.1, -0.01]"), ["strain_range", "increasing"]),
])
def test_bad_input_is_refused_naming_file_and_key(tmp_path, capsys, edit, words):
    path = _scene(tmp_path, edit)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert "bar.toml" in err or words[0] == "params"
    for word in words:
        assert word in err, err
