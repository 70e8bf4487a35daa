"""No silent wrong answers from the linear analyses (issue 12, section 3).

Each case once returned exit 0 with a wrong or misleading result; each is checked against a reference of
its own: a closed form, a published criterion evaluated independently (Routh-Hurwitz on the characteristic
polynomial), or the textbook matrices of the model. The models are test-local (tests/models/).

* modes/stability about a point that is not an equilibrium: V = k x^2/2 + b x^4/4 - F x (m = 1, k = 4,
  b = 2, F = 3) has its equilibrium at k x + b x^3 = F, x* = 0.626845..., and omega^2 = (k + 3 b x*^2)/m,
  omega = 2.52143 (the origin gave sqrt(k/m) = 2);
* rigid-body modes: a free chain of three masses (omega^2 = k/m, 3k/m and one rigid mode), the free-free
  Euler-Bernoulli beam (two rigid modes, then beta_n L = 4.7300, 7.8532, 10.9956, 14.1372);
* light damping: Ziegler's column with dashpots of 1e-3, the flutter onset against the Routh-Hurwitz
  condition of its characteristic polynomial (and the undamped onset (7/2 - sqrt 2) c/l);
* refinement near a boundary: an Euler column just above P_E = pi^2 EI/L^2, growth rate
  (pi/L) sqrt((P - P_E)/rhoA);
* counts: stability's eigenvalues trimmed with its frequencies; campbell's default count on two dofs.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import numpy.polynomial.polynomial as npoly
import pytest
from scipy.optimize import brentq

import mechgen
from mechgen.cli import main
from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.linear.modes import modes as solve_modes
from mechgen.runtime.linear.stability import stability as solve_stability

MODELS = Path(__file__).resolve().parent / "models"


def _compiled(name: str, **values):
    return mechgen.compile(str(MODELS / f"{name}.py"), values or None)


def _one_paragraph(err: str) -> str:
    return " ".join(err.split())


# ----------------------------------------------------------------------------- 1. the operating point

M_, K_, B_, F_ = 1.0, 4.0, 2.0, 3.0


def _duffing_equilibrium() -> tuple[float, float]:
    """x* (the real root of b x^3 + k x - F) and omega = sqrt((k + 3 b x*^2) / m)."""
    roots = np.roots([B_, 0.0, K_, -F_])
    x = float(roots[np.abs(roots.imag) < 1e-12].real[0])
    return x, math.sqrt((K_ + 3 * B_ * x * x) / M_)


def test_modes_about_a_non_equilibrium_find_the_equilibrium_through_the_api():
    x_star, omega = _duffing_equilibrium()
    assert omega == pytest.approx(2.5214, abs=1e-4)  # the number
    system = _compiled("loaded_duffing")
    for out in (mechgen.modes(system).outputs, mechgen.modes(system, at={"x": 0.5}).outputs):
        assert out["frequencies"] == pytest.approx([omega], rel=1e-12)
        point = out["operating_point"]
        assert point["found"] == "newton"
        assert point["coordinates"]["x"] == pytest.approx(x_star, rel=1e-12)
        assert point["residual_norm"] <= 1e-10 * K_
    # the start's residual is reported: r(0) = -F, r(0.5) = k 0.5 + b 0.125 - F
    assert mechgen.modes(system).outputs["operating_point"]["start_residual_norm"] == pytest.approx(F_)
    assert mechgen.modes(system, at={"x": 0.5}).outputs["operating_point"]["start_residual_norm"] == \
        pytest.approx(abs(K_ * 0.5 + B_ * 0.125 - F_))
    stab = mechgen.stability(system).outputs
    assert stab["verdict"] == "stable" and stab["frequencies"] == pytest.approx([omega], rel=1e-12)
    assert stab["operating_point"]["coordinates"]["x"] == pytest.approx(x_star, rel=1e-12)


def test_an_equilibrium_given_is_used_as_is():
    """At x* itself (or with F = 0 at the origin) nothing is searched and nothing extra is reported."""
    x_star, omega = _duffing_equilibrium()
    system = _compiled("loaded_duffing")
    out = mechgen.modes(system, at={"x": x_star}).outputs
    assert "operating_point" not in out and out["frequencies"] == pytest.approx([omega], rel=1e-12)
    unloaded = mechgen.modes(system.with_params(F=0.0)).outputs
    assert "operating_point" not in unloaded
    assert unloaded["frequencies"] == pytest.approx([math.sqrt(K_ / M_)], rel=1e-12)


def _scene(tmp_path: Path, model: str, analyses: str) -> Path:
    scene = tmp_path / "scene.toml"
    scene.write_text(f'model = "{MODELS / (model + ".py")}"\nbackend = "numpy"\n{analyses}')
    return scene


def test_a_scene_reports_the_equilibrium_it_linearised_about(tmp_path, capsys):
    x_star, omega = _duffing_equilibrium()
    scene = _scene(tmp_path, "loaded_duffing", '[[analysis]]\nname = "small"\nkind = "modes"\n'
                                                '[[analysis]]\nname = "verdict"\nkind = "stability"\n')
    target = tmp_path / "out.json"
    assert main(["run", str(scene), "--json", str(target)]) == 0
    printed = capsys.readouterr().out
    assert "operating_point" in printed and "newton" in printed
    out = {a["name"]: a["outputs"] for a in json.loads(target.read_text())["analyses"]}
    assert out["small"]["frequencies"] == pytest.approx([omega], rel=1e-12)
    assert out["small"]["operating_point"]["coordinates"]["x"] == pytest.approx(x_star, rel=1e-12)
    assert out["verdict"]["frequencies"] == pytest.approx([omega], rel=1e-12)


def test_no_equilibrium_refuses_with_exit_1_naming_the_residual_and_steady(tmp_path, capsys):
    """V = -F x: the residual is -F everywhere (no rest point); modes must not linearise anyway."""
    system = _compiled("pushed_mass")
    with pytest.raises(ConvergenceError, match="residual norm 3"):
        mechgen.modes(system)
    scene = _scene(tmp_path, "pushed_mass", '[[analysis]]\nname = "small"\nkind = "stability"\n')
    assert main(["run", str(scene)]) == 1
    err = _one_paragraph(capsys.readouterr().err)
    assert "not an equilibrium" in err and "residual norm 3" in err and "steady" in err


# ----------------------------------------------------------------------------- 2. rigid-body modes

def test_free_chain_has_one_rigid_mode_apart_from_its_frequencies():
    m, k = 2.0, 50.0
    system = _compiled("free_chain", m=m, k=k)
    out = mechgen.modes(system).outputs
    assert out["rigid_modes"] == 1
    assert out["frequencies"] == pytest.approx([math.sqrt(k / m), math.sqrt(3 * k / m)], rel=1e-12)
    assert out["rigid_shapes"] == [pytest.approx({"x1": 1.0, "x2": 1.0, "x3": 1.0}, rel=1e-10)]
    stab = mechgen.stability(system).outputs
    assert stab["verdict"] == "neutral" and stab["rigid_modes"] == 1
    assert stab["frequencies"] == pytest.approx([math.sqrt(k / m), math.sqrt(3 * k / m)], rel=1e-12)
    # count counts elastic modes
    assert mechgen.modes(system, count=1).outputs["frequencies"] == pytest.approx([math.sqrt(k / m)], rel=1e-12)


def test_a_soft_mode_is_not_taken_for_a_rigid_one():
    """Ground springs g = 1e-8 k under the chain: K + g I has the chain's eigenvalues shifted by g, so the
    lowest omega^2 is g/m exactly -- small, but about 1e7 times the rigid threshold 10 eps max|lambda|."""
    m, k = 2.0, 50.0
    chain = np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]) * k
    for g, rigid in ((1e-8 * k, 0), (0.0, 1)):
        res = solve_modes(m * np.eye(3), chain + g * np.eye(3))
        assert res.rigid == rigid
        expected = [g / m, (k + g) / m, (3 * k + g) / m][rigid:]
        assert res.eigenvalues[rigid:] == pytest.approx(expected, rel=1e-7)


BETA_L = [4.730040744862704, 7.853204624095838, 10.995607838001671, 14.137165491257464]


def test_free_free_beam_has_two_rigid_modes_then_the_closed_form():
    """Free-free Euler-Bernoulli beam: omega_n = (beta_n L)^2 sqrt(EI / (rhoA L^4)), cos cosh = 1 (the
    clamped-clamped roots), and two rigid modes (translation, rotation)."""
    beam = mechgen.compile("euler_bernoulli_beam", {"bc": "free-free", "discretisation": "quintic", "N": 16})
    out = mechgen.modes(beam, count=4).outputs
    assert out["rigid_modes"] == 2
    assert out["frequencies"] == pytest.approx([b * b for b in BETA_L], rel=1e-7)
    stab = mechgen.stability(beam).outputs
    assert stab["verdict"] == "neutral" and stab["rigid_modes"] == 2
    assert stab["refinement"]["verdicts"] == ["neutral", "neutral"]
    assert stab["frequencies"][:4] == pytest.approx([b * b for b in BETA_L], rel=1e-7)
    # supported, the same beam has none and is stable
    pinned = mechgen.stability(beam.with_params(bc="pinned-pinned"))
    assert pinned.outputs["verdict"] == "stable" and pinned.outputs["rigid_modes"] == 0


def test_a_fine_free_free_beam_keeps_its_first_elastic_mode():
    """512 hermite elements: Lambda = 2.5e14, the rigid eigenvalues come out near 1e-2 and the first elastic
    lambda = (beta_1 L)^4 = 500.56; the threshold 10 eps Lambda = 0.55 separates them (a factor n would not)."""
    from mechgen.runtime.linear.modes import AccuracyWarning

    beam = mechgen.compile("euler_bernoulli_beam", {"bc": "free-free", "N": 512})
    mats = beam.linear(np.zeros(beam.n))
    with pytest.warns(AccuracyWarning):  # the spectrum spans 5e11: the low modes are good to about 1e-4
        res = solve_modes(*(x.toarray() if hasattr(x, "toarray") else x for x in (mats["M"], mats["K"])))
    assert res.rigid == 2
    assert res.eigenvalues[2:4] == pytest.approx([b**4 for b in BETA_L[:2]], rel=1e-4)


# ----------------------------------------------------------------------------- 3. light damping

def _ziegler(P: float, d1: float, d2: float, c: float = 1.0, m: float = 1.0, l: float = 1.0):
    """The linearised Ziegler column (module doc of tests/models/ziegler_column.py)."""
    M = m * l * l * np.array([[3.0, 1.0], [1.0, 1.0]])
    C = np.array([[d1 + d2, -d2], [-d2, d2]])
    K = np.array([[2 * c - P * l, P * l - c], [-c, c]])
    return M, C, K


def _hurwitz(P: float, d1: float, d2: float) -> float:
    """The Routh-Hurwitz determinant a1 a2 a3 - a1^2 a4 - a0 a3^2 of det(s^2 M + s C + K) = a0 s^4 + ... + a4:
    with every a_i > 0 the column is stable exactly while it is positive (flutter onset where it vanishes)."""
    M, C, K = _ziegler(P, d1, d2)
    entry = [[[K[i, j], C[i, j], M[i, j]] for j in range(2)] for i in range(2)]
    a = npoly.polysub(npoly.polymul(entry[0][0], entry[1][1]), npoly.polymul(entry[0][1], entry[1][0]))
    a4, a3, a2, a1, a0 = a
    return a1 * a2 * a3 - a1 * a1 * a4 - a0 * a3 * a3


def _onset(verdict_at, lo: float, hi: float) -> float:
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if verdict_at(mid) == "stable":
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("d1, d2", [(1e-3, 1e-3), (1e-3, 0.0)])
def test_flutter_onset_of_lightly_damped_ziegler_column_is_not_shifted_by_the_tolerance(d1, d2):
    """The verdict's threshold is each eigenvalue's own error bound, so the onset agrees with the
    Routh-Hurwitz one to about the eigen-solve's accuracy (measured 1.4e-10 and 4e-11; a fixed 1e-8 * scale
    put it 3.9e-5 and 5e-6 high). Equal dashpots: near 41/28 c/l, the vanishing-damping limit."""
    grid = np.linspace(1.0, 3.0, 2001)
    h = np.array([_hurwitz(P, d1, d2) for P in grid])
    i = int(np.flatnonzero(np.diff(np.sign(h)))[0])
    reference = brentq(lambda P: _hurwitz(P, d1, d2), grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15)
    onset = _onset(lambda P: solve_stability(*_ziegler(P, d1, d2)).verdict, 1.0, 3.0)
    assert abs(onset - reference) <= 1e-9 * reference
    if d1 == d2:
        assert reference == pytest.approx(41 / 28, abs=1e-5)


def test_flutter_onset_through_the_api_and_undamped():
    """The same through mechgen.stability on the model; undamped, the onset is (7/2 - sqrt 2) c/l."""
    system = _compiled("ziegler_column", d1=1e-3, d2=1e-3)
    grid = np.linspace(1.0, 2.0, 1001)
    h = np.array([_hurwitz(P, 1e-3, 1e-3) for P in grid])
    i = int(np.flatnonzero(np.diff(np.sign(h)))[0])
    reference = brentq(lambda P: _hurwitz(P, 1e-3, 1e-3), grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15)
    onset = _onset(lambda P: mechgen.stability(system.with_params(P=P)).outputs["verdict"], 1.0, 2.0)
    assert abs(onset - reference) <= 1e-9 * reference
    undamped = _onset(lambda P: solve_stability(*_ziegler(P, 0.0, 0.0)).verdict, 1.0, 3.0)
    assert undamped == pytest.approx(3.5 - math.sqrt(2.0), rel=1e-9)
    past = mechgen.stability(system.with_params(P=1.01 * reference)).outputs
    assert past["verdict"] == "flutter" and past["unstable"] == {"real": 0, "complex": 1}


def test_an_explicit_tolerance_keeps_its_meaning():
    """tolerance = 1e-8: the fixed threshold 1e-8 * max|s| (the old rule), so the onset moves up by it."""
    d = 1e-3
    reference = brentq(lambda P: _hurwitz(P, d, d), 1.4, 1.5, xtol=1e-15, rtol=1e-15)
    fixed = _onset(lambda P: solve_stability(*_ziegler(P, d, d), tolerance=1e-8).verdict, 1.0, 3.0)
    # at the fixed onset the growth rate equals the threshold it was given
    res = solve_stability(*_ziegler(fixed, d, d), tolerance=1e-8)
    assert res.growth_rate == pytest.approx(1e-8 * res.scale, rel=1e-3)
    assert fixed > reference * (1 + 1e-6)


# ----------------------------------------------------------------------------- 4. refinement near a boundary

def test_a_column_just_above_its_euler_load_diverges_under_refinement():
    """P = 1.001 P_E: both meshes see one real growing eigenvalue (divergence); the growth rates differ
    by far more than 1 % (the coarse mesh's error on a small growth rate), which no longer decides."""
    column = _compiled("euler_column")
    P_E = math.pi**2
    out = mechgen.stability(column.with_params(P=1.001 * P_E)).outputs
    assert out["verdict"] == "divergence"
    ref = out["refinement"]
    assert ref["verdicts"] == ["divergence", "divergence"]
    assert ref["unstable"] == [{"real": 1, "complex": 0}] * 2
    assert "sign structure" in ref["compared"] and ref["growth_rate_converged"] is False
    exact = math.pi * math.sqrt(0.001 * P_E)
    g0, g1 = ref["growth_rates"]
    assert abs(g1 - exact) < abs(g0 - exact) and abs(g1 / exact - 1) < 0.05
    # converged with the mesh: hermite N = 32 against the closed form
    fine = mechgen.stability(column.with_params(P=1.001 * P_E, N=32), refine=False).outputs
    assert fine["growth_rate"] == pytest.approx(exact, rel=1e-4)
    below = mechgen.stability(column.with_params(P=0.999 * P_E)).outputs
    assert below["verdict"] == "stable"


# ----------------------------------------------------------------------------- 5. counts

def test_stability_count_trims_eigenvalues_with_frequencies():
    system = _compiled("ziegler_column", P=0.5)
    full = mechgen.stability(system).outputs
    one = mechgen.stability(system, count=1).outputs
    assert len(full["eigenvalues"]) == 4 and len(one["eigenvalues"]) == 2
    assert one["frequencies"] == pytest.approx(full["frequencies"][:1], rel=1e-12)
    assert sorted(abs(s[1]) for s in one["eigenvalues"]) == pytest.approx([one["frequencies"][0]] * 2, rel=1e-12)


def test_campbell_default_count_on_two_dofs_and_an_explicit_too_large_one(tmp_path, capsys):
    """The rotating frame sees the Jeffcott rotor's whirls at |w0 - Omega| and w0 + Omega (w0 = 10)."""
    speeds = "over = { Omega = [0.0, 2.0, 4.0] }\n"
    scene = _scene(tmp_path, "rotating_jeffcott", f'[[analysis]]\nname = "diagram"\nkind = "campbell"\n{speeds}')
    target = tmp_path / "out.json"
    assert main(["run", str(scene), "--json", str(target)]) == 0
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    for omega, row in zip(out["speeds"], out["frequencies"]):
        assert sorted(row) == pytest.approx(sorted([abs(10.0 - omega), 10.0 + omega]), rel=1e-12)
    scene.write_text(scene.read_text() + "count = 3\n")
    assert main(["run", str(scene)]) == 2
    err = _one_paragraph(capsys.readouterr().err)
    assert "count" in err and "at most 2" in err
    with pytest.raises(InputError, match="at most 2"):
        mechgen.campbell(_compiled("rotating_jeffcott"), over={"Omega": [0.0, 1.0]}, count=3)
