"""Backbone curves (issue 27, item 2): the free orbits of a conservative model (periodic_orbit without frequency) and
their family continued in its amplitude (continuation, parameter = "amplitude").

References, all computed here:

* First-order harmonic balance of x'' + k x + k3 x^3 = 0 with x = A cos(omega t): the projection of x^3 onto
  cos(omega t) is 3/4 A^3, so omega^2 = k + 3/4 k3 A^2 exactly (Nayfeh & Mook, Nonlinear Oscillations, 1979,
  sec. 4.1). With ``harmonics = 1`` mechgen's backbone must be that curve to the corrector's tolerance.
* The exact period of the undamped Duffing oscillator of amplitude A: x = A cn(omega t, m), omega^2 = k + k3 A^2,
  m = k3 A^2 / (2 omega^2), T = 4 K(m) / omega (K the complete elliptic integral of the first kind,
  scipy.special.ellipk; m < 0 for a softening spring).
* The weak limit: Lindstedt-Poincare gives omega = w0 (1 + 3/8 e A^2 - 21/256 e^2 A^4 + O(A^6)), e = k3 / k, while
  the first-order curve expands as w0 (1 + 3/8 e A^2 - 18/256 e^2 A^4 + ...): at small amplitude the exact backbone
  lies below the first-order one by 3/256 e^2 A^4 w0 (checked here against the elliptic period too).
"""
import math

import numpy as np
import pytest
from scipy.special import ellipk

import mechgen
from mechgen.cli import main


def exact_period(A: np.ndarray, k: float, k3: float) -> np.ndarray:
    """T = 4 K(m) / omega, omega^2 = k + k3 A^2, m = k3 A^2 / (2 omega^2) (module doc)."""
    w2 = k + k3 * np.asarray(A) ** 2
    return 4 * ellipk(k3 * np.asarray(A) ** 2 / (2 * w2)) / np.sqrt(w2)


def backbone_scene(tmp_path, k3: float, stop: float, method: str = "harmonic_balance", extra: str = "harmonics = 15",
                   name: str = "bb") -> str:
    path = tmp_path / f"{name}.toml"
    path.write_text(f'''model = "duffing"
backend = "c"
[params]
c = 0.0
F = 0.0
k = 1.0
k3 = {k3}
[[analysis]]
name = "free"
kind = "periodic_orbit"
method = "{method}"
{extra}
period = 6.2
q0 = {{ x = 0.05 }}
[[analysis]]
name = "backbone"
kind = "continuation"
about = "free"
parameter = "amplitude"
stop = {stop}
max_step = 0.1
''')
    return str(path)


def backbone_of(path: str) -> tuple[dict, dict]:
    analyses = mechgen.run(path)["analyses"]
    return analyses[0]["outputs"], analyses[1]["outputs"]


@pytest.mark.parametrize("k3, stop", [(1.0, 2.0), (-1.0, 0.8)])
def test_first_order_backbone_is_the_closed_form(tmp_path, k3, stop):
    """harmonics = 1: omega = sqrt(k + 3/4 k3 A^2) at every point, to 1e-9 (the corrector stops at ||F|| <= 1e-10, and
    dR/domega = 2 omega A >= 0.1 at the smallest A = 0.05); the unfolding is zero to 1e-12 and the energy is
    k A^2 / 2 + k3 A^4 / 4."""
    free, out = backbone_of(backbone_scene(tmp_path, k3, stop, extra="harmonics = 1"))
    b = out["backbone"]
    A, w = np.array(b["amplitude"]["x"]), np.array(b["frequency"])
    assert out["status"] == ("lam_max" if stop > 0.05 else "lam_min") and A[-1] == pytest.approx(stop, abs=1e-12)
    assert np.max(np.abs(w - np.sqrt(1.0 + 0.75 * k3 * A**2))) < 1e-9
    assert np.max(np.abs(b["unfolding"])) < 1e-12
    assert np.max(np.abs(np.array(b["energy"]) - (A**2 / 2 + k3 * A**4 / 4))) < 1e-12
    assert free["unfolding"] == pytest.approx(0.0, abs=1e-12) and free["amplitude"]["x"] == pytest.approx(0.05)


@pytest.mark.parametrize("method, extra, tol", [
    # harmonic balance, 15 harmonics: the truncation at A = 2 (measured 8.2e-13; 2.5e-8 with 9 harmonics)
    ("harmonic_balance", "harmonics = 15", 1e-10),
    # collocation, 40 intervals of degree 4: its O(mesh^-8) error, measured 1.4e-11 at A = 2
    ("collocation", "mesh = 40", 1e-9),
    # shooting: DOP853 at 1e-11 relative and the corrector's 1e-10 (measured 2.7e-11)
    ("shooting", "", 1e-9),
])
def test_hardening_backbone_against_the_elliptic_period(tmp_path, method, extra, tol):
    """The family continued from A = 0.05 to 2 (k = k3 = 1): the period at each point against 4 K(m) / omega; the
    orbits are neutrally stable (the two trivial multipliers set aside) and the unfolding is zero."""
    _, out = backbone_of(backbone_scene(tmp_path, 1.0, 2.0, method, extra))
    b = out["backbone"]
    A, T = np.array(b["amplitude"]["x"]), np.array(b["period"])
    assert A[0] == pytest.approx(0.05, rel=1e-9) and A[-1] == pytest.approx(2.0, rel=1e-9) and len(A) > 10
    assert np.max(np.abs(T / exact_period(A, 1.0, 1.0) - 1.0)) < tol
    assert np.max(np.abs(b["unfolding"])) < 1e-9
    assert {p["stability"] for p in out["branch"]} == {"stable"}
    assert [s["type"] for s in out["special_points"]] == []


def test_softening_backbone_and_its_weak_limit(tmp_path):
    """k3 = -1 (the separatrix at A = 1): the period grows with A as 4 K(m) / omega (m < 0) up to A = 0.8 (to 1e-9:
    25 harmonics, measured 4.2e-14); at A <= 0.1 the backbone lies 3/256 e^2 A^4 below the first-order curve, to 5 %
    of that gap (the next term is O(A^6): 2 % at A = 0.1)."""
    _, out = backbone_of(backbone_scene(tmp_path, -1.0, 0.8, extra="harmonics = 25"))
    b = out["backbone"]
    A, T, w = np.array(b["amplitude"]["x"]), np.array(b["period"]), np.array(b["frequency"])
    assert np.all(np.diff(T) > 0) and A[-1] == pytest.approx(0.8, rel=1e-9)
    assert np.max(np.abs(T / exact_period(A, 1.0, -1.0) - 1.0)) < 1e-9
    weak = A <= 0.1
    assert weak.sum() >= 2
    gap = w[weak] - np.sqrt(1.0 - 0.75 * A[weak] ** 2)
    assert gap == pytest.approx(-3 / 256 * A[weak] ** 4, rel=0.05)


def test_free_orbit_in_a_model_parameter(tmp_path):
    """parameter = a model parameter: the orbit of the earlier level q(0) = 0.05 followed in k3; first-order HB
    gives omega^2 = 1 + 3/4 k3 A^2 at each k3 (to 1e-9, as above)."""
    text = open(backbone_scene(tmp_path, 1.0, 2.0, extra="harmonics = 1")).read()
    path = tmp_path / "k3.toml"
    path.write_text(text.replace('parameter = "amplitude"', 'parameter = "k3"').replace("stop = 2.0", "stop = 3.0"))
    out = mechgen.run(str(path))["analyses"][1]["outputs"]
    k3 = np.array([p["k3"] for p in out["branch"]])
    w = np.array([p["frequency"] for p in out["branch"]])
    assert k3[-1] == pytest.approx(3.0) and np.max(np.abs(w - np.sqrt(1.0 + 0.75 * k3 * 0.05**2))) < 1e-9


def test_a_damped_model_is_not_a_conservative_family(tmp_path, capsys):
    """With damping the free orbit is a limit-cycle problem (no unfolding reported), and parameter = "amplitude"
    about it is refused at the key (exit 2); about a steady state it is refused at load (exit 2)."""
    text = open(backbone_scene(tmp_path, 1.0, 2.0, extra="harmonics = 1")).read()
    forced = tmp_path / "forced.toml"
    forced.write_text(text.replace("c = 0.0\nF = 0.0", "c = 0.1\nF = 0.3\nw = 0.5")
                      .replace("period = 6.2", 'frequency = "w"'))
    assert main(["run", str(forced)]) == 2
    err = capsys.readouterr().err
    assert "parameter" in err and "conservative" in err
    steady = tmp_path / "steady.toml"
    steady.write_text(text.split("[[analysis]]")[0] + '''[[analysis]]
name = "rest"
kind = "steady"
[[analysis]]
name = "backbone"
kind = "continuation"
about = "rest"
parameter = "amplitude"
stop = 1.0
''')
    assert main(["run", str(steady)]) == 2
    err = capsys.readouterr().err
    assert "analysis[2].parameter" in err and "periodic_orbit" in err


TWO = '''"""Two unit masses, springs to ground and a coupling kc, a cubic spring k3 on the first: conservative."""
from mechgen import Model, Param

model = Model("two_duffing", doc=__doc__)
model.params(Param("kc", 0.5), Param("k3", 1.0))
model.coordinates("x1", "x2")
model.kinetic(lambda v: (v.x1**2 + v.x2**2) / 2)
model.potential(lambda q, p: q.x1**2 / 2 + q.x2**2 / 2 + p.kc * (q.x1 - q.x2)**2 / 2 + p.k3 * q.x1**4 / 4)
'''


@pytest.mark.parametrize("method, extra", [("harmonic_balance", "harmonics = 15"), ("collocation", "mesh = 40"),
                                           ("shooting", "")])
def test_two_coordinate_backbone_closes_under_a_hand_written_flow(tmp_path, method, extra):
    """A conservative model of two coordinates (its in-phase nonlinear normal mode from q0 = (0.01, 0.01)): the first
    orbit's frequency is the linear mode's, 1 rad/s, to 1e-4 (the O(A^2) shift, 3/8 k3 A^2 / 2 ~ 2e-5 at A = 0.01);
    the family continued to x1(0) = 0.8: at every fourth point the hand-written flow (scipy DOP853 at 1e-12) maps the
    orbit's start onto itself over its period to 1e-8 (the methods' errors: 15 harmonics, mesh^-8, DOP853 at
    1e-11), and the frequency rises with the amplitude (hardening)."""
    (tmp_path / "two.py").write_text(TWO)
    path = tmp_path / "two.toml"
    path.write_text(f'''model = "two.py"
backend = "c"
[[analysis]]
name = "free"
kind = "periodic_orbit"
method = "{method}"
{extra}
period = 6.3
q0 = {{ x1 = 0.01, x2 = 0.01 }}
[[analysis]]
name = "family"
kind = "continuation"
about = "free"
parameter = "amplitude"
stop = 0.8
max_step = 0.1
''')
    free, out = backbone_of(str(path))
    assert free["frequency"] == pytest.approx(1.0, abs=1e-4) and abs(free["unfolding"]) < 1e-9

    def rhs(t, y):
        x1, x2 = y[0], y[1]
        return [y[2], y[3], -x1 - 0.5 * (x1 - x2) - x1**3, -x2 + 0.5 * (x1 - x2)]

    from scipy.integrate import solve_ivp

    points = out["branch"]
    assert points[-1]["start"]["x1"] == pytest.approx(0.8, rel=1e-9)
    for p in points[::4] + [points[-1]]:
        s = p["start"]
        x0 = np.array([s["x1"], s["x2"], s["x1_dot"], s["x2_dot"]])
        end = solve_ivp(rhs, (0.0, p["period"]), x0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
        assert np.max(np.abs(end - x0)) < 1e-8
    assert np.all(np.diff(out["backbone"]["frequency"]) > 0)
