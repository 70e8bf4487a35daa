"""The continua scenes as shipped: converged defaults and the verdicts their docstrings promise."""
from pathlib import Path

import numpy as np

from mechgen.scene.run import run_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def test_beam_modes_scene_is_converged_to_1e_6():
    """First five frequencies of each end condition against beta_n L (roots recomputed in test_field_beam)."""
    from test_field_beam import exact_roots

    res = run_scene(SCENES / "beam_modes.toml")
    sweep = res["analyses"][1]["outputs"]
    for point, freqs in zip(sweep["grid"], sweep["frequencies"]):
        exact = exact_roots(point["bc"]) ** 2
        assert np.abs(np.array(freqs) / exact - 1).max() < 1e-6, point


def test_moving_string_scene_verdicts_through_the_critical_speed():
    res = run_scene(SCENES / "moving_string.toml")
    at_half = res["analyses"][0]["outputs"]
    assert at_half["verdict"] == "stable"
    assert np.allclose(at_half["frequencies"], np.arange(1, 6) * np.pi * (1 - 0.25), rtol=1e-10)
    sweep = res["analyses"][1]["outputs"]
    for point, verdict in zip(sweep["grid"], sweep["verdict"]):
        # at c = c0 the effective tension P - rhoA c^2 vanishes: K = 0, every static shape is an equilibrium
        # (neutral, the divergence boundary), not "stable"
        expected = "stable" if point["c"] < 1.0 else "neutral" if point["c"] == 1.0 else "unconverged"
        assert verdict == expected, point
