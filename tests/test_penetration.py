"""Ogive-nose penetration (ogive_penetration) against the closed form, and the fit of the target resistance.

Reference: Frew, Forrestal & Hanchak (2000), "Penetration experiments with limestone targets and ogive-nose
steel projectiles", J. Appl. Mech. 67 (December 2000; the seed file), eqs. 1a-1b (after Forrestal, Altman, Cargile & Hanchak 1994):
P = m/(2 pi a^2 rho N) ln(1 + N rho V1^2/R) + 4a, V1^2 = (m Vs^2 - 4 pi a^3 R)/(m + 4 pi a^3 N rho),
N = (8 psi - 1)/(24 psi^2); the projectile stops in the crater when m Vs^2 < 4 pi a^3 R, at
P = Vs sqrt(m/c), c = pi a R / 4 (derived in tests/impact_reference.py). Eq. 3: R = K + k (2a0/2a),
K = 607 MPa, k = 86 MPa, 2a0 = 25.4 mm, from R = 913, 787, 693 MPa at 2a = 7.1, 12.7, 25.4 mm.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechgen

sys.path.insert(0, str(Path(__file__).parent))
import impact_reference as ref  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCALES = ((7.1e-3, 0.020, 913e6), (12.7e-3, 0.117, 787e6), (25.4e-3, 0.931, 693e6))
INNER = {"kind": "simulate", "t_end": 0.05, "method": "DOP853", "rtol": 1e-12, "atol": 1e-15, "outputs": ["depth"]}


@pytest.fixture(scope="module")
def system():
    return mechgen.compile("ogive_penetration", {"rho": ref.LIMESTONE_DENSITY}, free=["m", "a", "R", "Vs"])


@pytest.mark.parametrize("method", ["DOP853", "Radau"])
@pytest.mark.parametrize("scale", SCALES)
def test_depth_meets_the_closed_form(system, scale, method):
    two_a, m, R = scale
    for Vs in (400.0, 1000.0, 1900.0):
        s = system.with_params(m=m, a=two_a / 2, R=R, Vs=Vs)
        out = mechgen.simulate(s, t_end=0.05, method=method, rtol=1e-12, atol=1e-15).outputs
        expected = ref.penetration_depth(m, two_a / 2, 3.0, ref.LIMESTONE_DENSITY, R, Vs)
        assert out["depth"] == pytest.approx(expected, rel=1e-8)
        assert out["final_mode"] == "tunnel"
        assert [e["guard"] for e in out["events"]] == ["tunnel_entry", "at_rest"]
        assert out["events"][-1]["to"] is None and abs(out["velocity"]) < 1e-9 * Vs


def test_slow_projectile_stops_in_the_crater(system):
    """m Vs^2 < 4 pi a^3 R: rest before x = 4a, at P = Vs sqrt(m/c), c = pi a R / 4."""
    m, a, R, Vs = 0.931, 0.0127, 693e6, 60.0
    assert m * Vs**2 < 4 * np.pi * a**3 * R
    out = mechgen.simulate(system.with_params(m=m, a=a, R=R, Vs=Vs), t_end=0.05, rtol=1e-12, atol=1e-15,
                           method="DOP853").outputs
    assert out["final_mode"] == "crater" and [e["guard"] for e in out["events"]] == ["at_rest"]
    assert out["depth"] == pytest.approx(Vs * np.sqrt(m / (np.pi * a * R / 4)), rel=1e-9)
    assert out["depth"] < 4 * a


def test_fit_recovers_a_known_resistance_with_noise(system):
    """Depths simulated at R = 787 MPa with 1 % seeded Gaussian noise: the fitted R lies within 3 of its
    reported standard errors of the truth, and that error is near the linearised one, sigma / |dP/dR|."""
    two_a, m, R = SCALES[1]
    Vs = np.linspace(400.0, 1800.0, 12)
    clean = np.array([ref.penetration_depth(m, two_a / 2, 3.0, ref.LIMESTONE_DENSITY, R, v) for v in Vs])
    noisy = clean * (1 + 0.01 * np.random.default_rng(7).standard_normal(len(Vs)))
    data = {"m": [m] * len(Vs), "a": [two_a / 2] * len(Vs), "Vs": list(Vs), "P": list(noisy)}
    out = mechgen.fit(system, parameters=["R"], start={"R": 500e6}, data=data, observed="P", inputs=["m", "a", "Vs"],
                      analysis=INNER, output="depth", diff_step=1e-4).outputs
    assert abs(out["R"] - R) < 3 * out["R_stderr"]
    h = 1e-6 * R
    slope = np.array([(ref.penetration_depth(m, two_a / 2, 3.0, ref.LIMESTONE_DENSITY, R + h, v)
                       - ref.penetration_depth(m, two_a / 2, 3.0, ref.LIMESTONE_DENSITY, R - h, v)) / (2 * h)
                      for v in Vs])
    linearised = np.sqrt(np.sum(np.asarray(out["residuals"]) ** 2) / (len(Vs) - 1) / np.sum(slope**2))
    assert out["R_stderr"] == pytest.approx(linearised, rel=0.05)


@pytest.mark.slow
def test_scene_reproduces_the_papers_resistances_and_scale_law(tmp_path):
    """scenes/penetration_limestone.toml: depths per striking velocity (closed form), R per projectile scale
    recovered from the synthetic depths to 1e-8, and the paper's K and k inside one standard error of the
    fit of eq. 3 to the paper's three R values."""
    out = tmp_path / "p.json"
    proc = subprocess.run([sys.executable, "-m", "mechgen", "run", str(ROOT / "scenes" / "penetration_limestone.toml"),
                           "--json", str(out)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    analyses = {a["name"]: a["outputs"] for a in json.loads(out.read_text())["analyses"]}
    depth = analyses["depth"]
    for point, P in zip(depth["grid"], depth["depth"]):
        assert P == pytest.approx(ref.penetration_depth(0.931, 0.0127, 3.0, 2300.0, 693e6, point["Vs"]), rel=1e-8)
    fitted = analyses["resistance"]
    assert fitted["R"] == pytest.approx([913e6, 787e6, 693e6], rel=1e-8)
    assert len(fitted["R_stderr"]) == 3
    law = analyses["scale_law"]
    assert abs(law["K"] - 607e6) < law["K_stderr"] and abs(law["k"] - 86e6) < law["k_stderr"]


def test_synthetic_data_file_is_the_closed_form():
    """scenes/data/limestone_synthetic.csv holds eq. (1) at the paper's R (made by its script, reproducible)."""
    rows = [line.split(",") for line in (ROOT / "scenes" / "data" / "limestone_synthetic.csv").read_text().splitlines()
            if line and not line.startswith("#")][1:]
    R_of = {two_a: R for two_a, _, R in SCALES}
    for two_a, m, a, Vs, P in ([float(v) for v in row] for row in rows):
        assert P == pytest.approx(ref.penetration_depth(m, a, 3.0, 2300.0, R_of[two_a], Vs), rel=1e-14)
