"""continuation about a Newton steady state (issue 25, item 8): pseudo-arclength on the generated residual.

* A snap-through oscillator x'' + x^3 - x = lam (V = x^4/4 - x^2/2 - lam x): its equilibria lam = x^3 - x fold at
  x = -+1/sqrt(3), lam = +-2/(3 sqrt 3) (d lam/dx = 3x^2 - 1 = 0), and K = 3x^2 - 1 makes the middle branch
  unstable (divergence) and the outer ones stable; at lam = 1 the last branch point solves x^3 - x - 1 = 0,
  x = 1.324717957244746 (the plastic number).
* A pinned-pinned Euler-Bernoulli beam under a uniform load q (a continuum's Newton steady state): the static
  problem is linear, so the potential energy at equilibrium is -q^2 c with one constant c along the branch
  (c -> L^5 / (240 EI) as the mesh is refined: Timoshenko & Gere, or any beam table, w = q x (L^3 - 2 L x^2 +
  x^3) / (24 EI) and V = -1/2 int q w = -q^2 L^5 / (240 EI)).
"""
import numpy as np
import pytest

import mechgen
from mechgen.cli import main

SNAP = '''"""x'' + x^3 - x = lam: V = x^4/4 - x^2/2 - lam x."""
from mechgen import Model, Param

model = Model("snap", doc=__doc__)
model.params(Param("lam", -1.0))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: q.x**4 / 4 - q.x**2 / 2 - p.lam * q.x)
'''


def snap_scene(tmp_path, extra: str = "") -> str:
    (tmp_path / "snap.py").write_text(SNAP)
    scene = tmp_path / "snap.toml"
    scene.write_text(f'''model = "snap.py"
backend = "numpy"
[[analysis]]
name = "eq"
kind = "steady"
guess = {{ x = -1.3 }}
[[analysis]]
name = "cont"
kind = "continuation"
about = "eq"
parameter = "lam"
stop = 1.0
{extra}
''')
    return str(scene)


def test_snap_through_branch_folds_and_stability(tmp_path):
    """Folds at lam = +-2/(3 sqrt 3), x = -+1/sqrt(3) to 1e-10 (Brent on the tangent's lam component: the fold's
    lam is accurate to the square of its location error; measured 1e-16); the verdict changes there (to 1e-8 in
    x: bisection along the branch to 1e-9 of a segment; measured 4e-11); every point's verdict is the sign of
    3x^2 - 1."""
    out = mechgen.run(snap_scene(tmp_path))["analyses"][1]["outputs"]
    fold = 2 / 3**1.5
    assert [f["lam"] for f in out["folds"]] == pytest.approx([fold, -fold], abs=1e-10)
    assert [f["coordinates"]["x"] for f in out["folds"]] == pytest.approx([-1 / 3**0.5, 1 / 3**0.5], abs=1e-10)
    changes = out["stability_changes"]
    assert [(c["from"], c["to"]) for c in changes] == [("stable", "divergence"), ("divergence", "stable")]
    assert [c["coordinates"]["x"] for c in changes] == pytest.approx([-1 / 3**0.5, 1 / 3**0.5], abs=1e-8)
    for p in out["branch"]:
        x = p["coordinates"]["x"]
        assert abs(x**3 - x - p["lam"]) < 1e-10  # every point is an equilibrium
        if abs(3 * x * x - 1) > 1e-6:
            assert p["verdict"] == ("stable" if 3 * x * x > 1 else "divergence")
    assert out["status"] == "lam_max" and out["branch"][-1]["lam"] == 1.0
    assert out["branch"][-1]["coordinates"]["x"] == pytest.approx(1.324717957244746, abs=1e-10)


def test_beam_branch_of_a_newton_steady_state(tmp_path):
    """The energy at equilibrium is -q^2 c along the branch: c constant to 1e-10 (the static problem is linear),
    and within 1e-4 of L^5/(240 EI) at 8 cubic elements (measured 4e-5: the discretisation error)."""
    scene = tmp_path / "beam.toml"
    scene.write_text('''model = "euler_bernoulli_beam"
backend = "numpy"
[params]
q = 1.0
N = 8
[[analysis]]
name = "eq"
kind = "steady"
[[analysis]]
name = "cont"
kind = "continuation"
about = "eq"
parameter = "q"
stop = 3.0
''')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    c = np.array([-p["potential_energy"] / p["q"] ** 2 for p in out["branch"]])
    assert len(c) > 3 and out["branch"][-1]["q"] == 3.0
    assert np.abs(c / c[0] - 1).max() < 1e-10
    assert c[0] == pytest.approx(1 / 240, rel=1e-4)  # EI = L = 1
    assert all(p["verdict"] == "stable" for p in out["branch"]) and out["folds"] == []


def test_boundary_value_keys_are_refused_on_a_newton_branch(tmp_path, capsys):
    assert main(["run", snap_scene(tmp_path, 'minimize = "energy"')]) == 2
    err = capsys.readouterr().err
    assert "key 'minimize'" in err and "Newton steady state" in err and "Traceback" not in err
