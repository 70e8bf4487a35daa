"""The curved-beam section stiffness on the user path: model, ``cross_section`` analysis, scene, JSON, bad input.

Reference: seed 001 (Grazioso, slides 20-25), the closed form of K for a circular arc of radius r with a
square section of side b, beta = b/r (the model's docstring, tests/test_cross_section.py):
c1 = 4/(4 - beta^2), c2 = 12/beta^3 (2 ln((2-beta)/(2+beta)) + (1+c1) beta), c3 = (ln((2-beta)/(2+beta))
+ c1 beta)/beta^2, evaluated with mpmath at 50 digits; and the straight rod diag(EA, mu A, mu A, mu Ip,
EI2, EI3) for a user's own model declared the same way.
"""
from __future__ import annotations

import json
import textwrap
from pathlib import Path

import mpmath
import numpy as np
import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError
from mechgen.scene.run import run_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "curved_beam_stiffness.toml"


def seed_K(r, b, lam, mu) -> np.ndarray:
    """K of the curved square at 50 digits (seed 001, slides 24-25)."""
    with mpmath.workdps(50):
        r, b, lam, mu = (mpmath.mpf(x) for x in (r, b, lam, mu))
        beta = b / r
        E = mu * (3 * lam + 2 * mu) / (lam + mu)
        L = mpmath.log((2 - beta) / (2 + beta))
        c1 = 4 / (4 - beta**2)
        c2 = 12 / beta**3 * (2 * L + (1 + c1) * beta)
        c3 = (L + c1 * beta) / beta**2
        K = mpmath.diag([c1 * E * b**2, c1 * mu * b**2, c1 * mu * b**2, mu * b**4 * (c1 + c2) / 12,
                         c1 * E * b**4 / 12, c2 * E * b**4 / 12])
        K[0, 5] = K[5, 0] = -c3 * E * b**3
        K[2, 3] = K[3, 2] = c3 * mu * b**3
        return np.array(K.tolist(), dtype=float)


def _close(got, ref, rel=1e-13):
    got, ref = np.asarray(got, dtype=float), np.asarray(ref, dtype=float)
    scale = np.sqrt(np.outer(np.diag(ref), np.diag(ref)))
    assert np.all(np.abs(got - ref) <= rel * scale), np.max(np.abs(got - ref) / scale)


def test_scene_reports_the_seed_K_and_the_cli_writes_it_as_json(tmp_path, capsys):
    results = run_scene(str(SCENE))
    entry = results["analyses"][0]
    assert entry["kind"] == "cross_section"
    _close(entry["outputs"]["K"], seed_K(0.5, 0.1, 2.0e6, 1.0e6))
    target = tmp_path / "k.json"
    assert main(["run", str(SCENE), "--json", str(target)]) == 0
    out = capsys.readouterr().out
    assert "K[u1]" in out and "26936" in out           # c1 E b^2 = 2.6936e4 N at beta = 0.2
    K = json.loads(target.read_text())["analyses"][0]["outputs"]["K"]
    assert len(K) == 6 and all(len(row) == 6 for row in K)
    _close(K, seed_K(0.5, 0.1, 2.0e6, 1.0e6))


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_free_parameters_give_a_kernel_accurate_from_a_straight_to_a_tight_arc(backend):
    # r and b kept free: the kernel holds the section functions F_mn(b/(2r)) as series | closed-form branches
    system = mechgen.compile("curved_beam_stiffness", free=["r", "b", "lam", "mu"], backend=backend)
    for beta in (1e-9, 1e-4, 0.05, 0.25, 0.4999, 0.5001, 0.7, 1.0, 1.99):
        s = system.with_params(r=0.1 / beta, b=0.1, lam=3.0e6, mu=1.5e6)
        got = mechgen.cross_section(s).outputs["K"]
        # below beta = 1/2 the 64-term series (truncation < 1e-30); above it the closed form, whose brackets
        # cancel like 16 eps/(beta/2)^2 <= 6e-14 (measured: 3e-16 below, 2.1e-14 at beta = 0.5001)
        _close(got, seed_K(0.1 / beta, 0.1, 3.0e6, 1.5e6), rel=1e-15 if beta < 0.5 else 6e-14)


def test_a_section_reaching_the_centre_of_curvature_or_unstable_material_is_refused(capsys):
    for setting, key in (("b=1.0", "params.r"), ("b=1.2", "params.r"), ("lam=-0.9e6", "params"),
                         ("mu=-1e6", "mu")):
        assert main(["run", str(SCENE), "--set", setting]) == 2
        err = capsys.readouterr().err
        assert f"key '{key}'" in err or f"key '--set {key}'" in err, err
    system = mechgen.compile("curved_beam_stiffness", free=["r", "b"], backend="numpy")
    with pytest.raises(InputError, match="not finite") as info:
        mechgen.cross_section(system.with_params(r=0.5, b=1.2))
    assert info.value.key == "params"
    with pytest.raises(InputError, match="not positive definite"):
        mechgen.cross_section(mechgen.compile("curved_beam_stiffness", params={"lam": -0.9e6}, backend="numpy"))


def test_a_users_own_model_declares_its_section_the_same_way(tmp_path):
    model = tmp_path / "my_rod.py"
    model.write_text(textwrap.dedent('''
        """A straight rod with a rectangular section w2 x w3."""
        from mechgen import Model, Param
        from mechgen.symbolic.cross_section import Rectangle, cross_section_stiffness

        model = Model("my_rod", doc=__doc__)
        model.params(Param("w2", 0.02, "m"), Param("w3", 0.05, "m"), Param("lam", 1.0e9, "Pa"),
                     Param("mu", 5.0e8, "Pa"))

        @model.section_stiffness
        def section(p):
            return cross_section_stiffness(p.lam, p.mu, Rectangle(p.w2, p.w3))
    '''))
    scene = tmp_path / "my_rod.toml"
    scene.write_text(f'model = "{model}"\nbackend = "numpy"\n[[analysis]]\nname = "K"\nkind = "cross_section"\n')
    K = np.array(run_scene(str(scene))["analyses"][0]["outputs"]["K"])
    lam, mu, w2, w3 = 1.0e9, 5.0e8, 0.02, 0.05
    E, A, I2, I3 = mu * (3 * lam + 2 * mu) / (lam + mu), w2 * w3, w2 * w3**3 / 12, w3 * w2**3 / 12
    np.testing.assert_allclose(K, np.diag([E * A, mu * A, mu * A, mu * (I2 + I3), E * I2, E * I3]), rtol=1e-15,
                               atol=0)


def test_a_model_without_a_section_is_told_what_the_analysis_needs(tmp_path, capsys):
    scene = tmp_path / "no_section.toml"
    scene.write_text('model = "spring_pendulum"\n[[analysis]]\nname = "K"\nkind = "cross_section"\n')
    assert main(["run", str(scene)]) == 2
    assert "section_stiffness" in capsys.readouterr().err
