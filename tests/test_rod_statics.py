"""Statics of the geometrically exact (Cosserat) rod on SE(3) (issue 15 items 3 and 5).

References, each independent of the solvers:

* End torque tau on a cantilever: the exact shape is the circular arc of curvature tau/EI,
  r(s) = (sin(k s), 1 - cos(k s), 0)/k, k = tau/EI, tip turned by k L (seed 001, Grazioso, Exercise 1),
  including several full turns (k L up to 4.4 pi).
* Tip point load P on a cantilever (dead, perpendicular to the rod), inextensible elastica: Bisshopp &
  Drucker, Q. Appl. Math. 3 (1945) 272: sqrt(P L^2/EI) = K(k) - F(psi0, k), k^2 = (1 + sin phi)/2,
  sin psi0 = 1/(k sqrt 2), x/L = sqrt(2 sin phi/alpha), y/L = 1 - 2 (E(k) - E(psi0, k))/sqrt(alpha), computed
  here with scipy.special (ellipk, ellipkinc, ellipe, ellipeinc; scipy's parameter m = k^2); and the
  table of Mattiasson, Int. J. Numer. Meth. Eng. 17 (1981) 145, table 1 ((L - x)/L, y/L to 5 decimals).
* Observed orders of convergence: 4 for the RKMK4 shooting, 2 for the midpoint collocation.
* Timoshenko cantilever at small load: tip deflection P L^3/(3 EI) + P L/GA; extension P L/EA.
* Simply supported beam under a uniform load q at small load: midspan 5 q L^4/(384 EI) + q L^2/(8 GA).
* Beam rotating at omega in its own plane (seed 001, Exercise 2), extensible rod, linear law N = EA (x' - 1):
  EA x'' + rhoA omega^2 x = 0, x(0) = 0, N(L) = 0, so x(s) = sin(k s)/(k cos(k L)), k^2 = rhoA omega^2/EA, and
  N(s) = EA (cos(k s)/cos(k L) - 1) = rhoA omega^2 (L^2 - s^2)/2 (1 + O(k^2 L^2)).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

import mechgen
from mechgen.cli import main
from mechgen.errors import ConvergenceError
from mechgen.runtime.rods.liegroup import orthonormality_error
from mechgen.runtime.rods.statics import Rod, solve_statics, turning_angle

SCENES = __import__("pathlib").Path(__file__).resolve().parents[1] / "scenes"

# Mattiasson (1981), table 1: PL^2/EI -> ((L - x)/L, y/L)
MATTIASSON = {1: (0.05643, 0.30172), 2: (0.16064, 0.49346), 3: (0.25442, 0.60325), 4: (0.32894, 0.66996),
              5: (0.38763, 0.71379), 6: (0.43459, 0.74457), 7: (0.47293, 0.76737), 8: (0.50483, 0.78498),
              9: (0.53182, 0.79906), 10: (0.55500, 0.81061)}


def elastica(alpha: float) -> tuple[float, float, float]:
    """Bisshopp & Drucker's cantilever: ((L - x)/L, y/L, tip angle phi) at alpha = P L^2/EI."""
    def gap(phi):
        m = (1 + math.sin(phi)) / 2
        return ellipk(m) - ellipkinc(math.asin(1 / math.sqrt(2 * m)), m) - math.sqrt(alpha)

    phi = brentq(gap, 1e-12, math.pi / 2 - 1e-13, xtol=1e-15)
    m = (1 + math.sin(phi)) / 2
    psi0 = math.asin(1 / math.sqrt(2 * m))
    x = math.sqrt(2 * math.sin(phi) / alpha)
    y = 1 - 2 / math.sqrt(alpha) * (ellipe(m) - ellipeinc(psi0, m))
    return 1 - x, y, phi


def stiffness(EA=1e8, GA=1e8, GJ=1.0, EI=1.0):  # noqa: N803
    return np.diag([EA, GA, GA, GJ, EI, EI])


def tip_error(alpha: float, method: str, n: int, K=None) -> float:
    u, v, phi = elastica(alpha)
    rod = Rod(1.0, stiffness() if K is None else K, tip_force=np.array([0.0, -alpha, 0.0]))
    final = solve_statics(rod, method=method, elements=n, steps=5).final
    x, y = final.H[-1, :2, 3]
    return max(abs(1 - x - u), abs(-y - v), abs(-turning_angle(final.H, (0, 0, 1)) - phi))


# --------------------------------------------------------------------------- end torque: the circular arc

@pytest.mark.parametrize("method", ["shooting", "collocation"])
@pytest.mark.parametrize("turns", [0.25, 1.1, 2.2])
def test_end_torque_rolls_the_rod_into_the_exact_circular_arc(method, turns):
    EI, L = 2.0, 1.5
    k = 2 * math.pi * turns / L            # curvature tau/EI; tip angle k L = 2 pi turns (up to 4.4 pi)
    rod = Rod(L, stiffness(EA=1e4, GA=1e4, GJ=1.0, EI=EI), tip_torque=np.array([0.0, 0.0, k * EI]))
    # Newton to 1e-12 (scaled): both discretisations are exact on the arc, so what is left is the solve's
    # convergence, which at the default 1e-10 sits at the 1e-10 L asserted below (2.3e-10 seen on one kernel)
    path = solve_statics(rod, method=method, elements=24, steps=8, tol=1e-12)
    st = path.final
    exact = np.stack([np.sin(k * st.s), 1 - np.cos(k * st.s), 0 * st.s], axis=1) / k
    assert np.max(np.abs(st.H[:, :3, 3] - exact)) < 1e-10 * L
    assert abs(turning_angle(st.H, (0, 0, 1)) - k * L) < 1e-10
    assert np.max(np.abs(st.f[:, 5] - k)) < 1e-10 * k and np.max(np.abs(st.f[:, :3] - [1, 0, 0])) < 1e-12
    assert orthonormality_error(st.H[:, :3, :3]) < 1e-12
    if turns > 2:  # continuation really went round: the branch passes a full turn before the last step
        assert any(abs(turning_angle(p.H, (0, 0, 1))) > 2 * math.pi for p in path.states[:-1])


def test_near_zero_curvature_keeps_the_series_exact():
    """tau L/EI = 1e-9: tip angle and the small deflection y = k L^2/2 to relative 1e-6 (series of the maps)."""
    k = 1e-9
    rod = Rod(1.0, stiffness(EA=1e4, GA=1e4), tip_torque=np.array([0.0, 0.0, k]))
    for method in ("shooting", "collocation"):
        st = solve_statics(rod, method=method, elements=8, steps=1).final
        assert abs(turning_angle(st.H, (0, 0, 1)) / k - 1) < 1e-6
        assert abs(st.H[-1, 1, 3] / (k / 2) - 1) < 1e-6 and abs(st.H[-1, 0, 3] - 1) < 1e-15


# --------------------------------------------------------------------------- tip load: the elastica

def test_the_elliptic_reference_reproduces_mattiasson_table():
    for alpha, (u, v) in MATTIASSON.items():
        uu, vv, _ = elastica(alpha)
        assert abs(uu - u) < 6e-6 and abs(vv - v) < 6e-6


@pytest.mark.parametrize("alpha", [1, 2, 5, 10])
def test_tip_load_large_deflection_matches_the_elastica_by_shooting(alpha):
    """RKMK4, 40 steps, EA/EI = GA/EI = 1e8 (nearly inextensible): within 2e-7 of Bisshopp-Drucker."""
    assert tip_error(alpha, "shooting", 40) < 2e-7


def test_tip_load_by_collocation_matches_the_table_for_every_load():
    """Midpoint collocation, 160 elements: every Mattiasson entry PL^2/EI = 1..10 to its 5 decimals (+ O(h^2))."""
    K = stiffness()
    for alpha, (u, v) in MATTIASSON.items():
        rod = Rod(1.0, K, tip_force=np.array([0.0, -float(alpha), 0.0]))
        x, y = solve_statics(rod, method="collocation", elements=160, steps=4).final.H[-1, :2, 3]
        assert abs(1 - x - u) < 2e-5 and abs(-y - v) < 2e-5


def test_observed_orders_of_convergence():
    """Errors against the elastica at PL^2/EI = 10 as N doubles: order 4 (shooting), 2 (collocation)."""
    shoot = [tip_error(10.0, "shooting", n) for n in (5, 10, 20)]
    coll = [tip_error(10.0, "collocation", n) for n in (10, 20, 40)]
    p_shoot = np.log2(np.array(shoot[:-1]) / shoot[1:])
    p_coll = np.log2(np.array(coll[:-1]) / coll[1:])
    assert np.all(p_shoot > 3.8), p_shoot
    assert np.all(np.abs(p_coll - 2) < 0.05), p_coll


# --------------------------------------------------------------------------- Timoshenko limits, pinned ends

def test_small_tip_load_gives_the_timoshenko_deflection_and_the_extension():
    EI, GA, EA, L = 1.0, 20.0, 50.0, 1.0
    P = 1e-5 * EI / L**2
    K = stiffness(EA=EA, GA=GA, EI=EI)
    for method, n in (("shooting", 10), ("collocation", 200)):
        st = solve_statics(Rod(L, K, tip_force=np.array([0.0, -P, 0.0])), method=method, elements=n, steps=1).final
        expect = P * L**3 / (3 * EI) + P * L / GA
        tol = 1e-6 if method == "shooting" else 3e-5  # collocation: O(h^2) = 2.5e-5
        assert abs(-st.H[-1, 1, 3] / expect - 1) < tol
        st = solve_statics(Rod(L, K, tip_force=np.array([P, 0.0, 0.0])), method=method, elements=n, steps=1).final
        assert abs((st.H[-1, 0, 3] - L) / (P * L / EA) - 1) < 1e-6


def test_pinned_pinned_beam_under_a_uniform_load():
    EI, GA, L, q = 1.0, 30.0, 2.0, 1e-6

    def load(r):
        return np.tile([0.0, -q, 0.0, 0.0, 0.0, 0.0], (len(r), 1))

    rod = Rod(L, stiffness(EA=1e6, GA=GA, EI=EI), load=load, base="pinned", tip="pinned")
    expect = 5 * q * L**4 / (384 * EI) + q * L**2 / (8 * GA)
    st = solve_statics(rod, method="shooting", elements=20, steps=1).final
    assert abs(-st.H[10, 1, 3] / expect - 1) < 1e-5
    assert np.max(np.abs(st.sigma[[0, -1], 4:])) < 1e-12  # no bending moment at the pins


def test_free_base_with_a_clamped_tip_is_the_mirrored_cantilever():
    EI, L, q = 1.0, 1.0, 1e-6

    def load(r):
        return np.tile([0.0, -q, 0.0, 0.0, 0.0, 0.0], (len(r), 1))

    rod = Rod(L, stiffness(EA=1e8, GA=1e8, EI=EI), load=load, base="free", tip="clamped")
    st = solve_statics(rod, method="shooting", elements=10, steps=1).final
    assert abs(-st.H[0, 1, 3] / (q * L**4 / (8 * EI)) - 1) < 1e-6


def test_a_path_that_cannot_converge_names_the_last_load():
    rod = Rod(1.0, stiffness(), tip_force=np.array([0.0, -1.0, 0.0]))
    with pytest.raises(ConvergenceError, match="beyond load factor 0"):
        solve_statics(rod, method="shooting", elements=4, steps=2, tol=1e-300, min_step=0.1)


# --------------------------------------------------------------------------- the model, the kind, the scenes

def test_rotating_beam_axial_force_against_the_closed_form(tmp_path, capsys):
    target = tmp_path / "out.json"
    assert main(["run", str(SCENES / "rotating_beam.toml"), "--json", str(target)]) == 0
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    rhoA, omega, EA, L = 1.0, 10.0, 1e3, 1.0
    k = math.sqrt(rhoA * omega**2 / EA)
    s = np.array(out["s"])
    N = np.array(out["stress_resultant"])[:, 0]
    exact = EA * (np.cos(k * s) / math.cos(k * L) - 1)
    assert np.max(np.abs(N - exact)) < 1e-7 * np.max(exact)
    x = np.array(out["shape"])[:, 0]
    assert np.max(np.abs(x - np.sin(k * s) / (k * math.cos(k * L)))) < 1e-9
    small = rhoA * omega**2 * (L**2 - s**2) / 2     # the small-strain form: agrees to O(k^2 L^2) = 0.1
    assert np.max(np.abs(N - small)) < 0.5 * (k * L) ** 2 * np.max(small)
    strain = np.array(out["strain"])[:, 0]
    assert np.max(np.abs(strain - exact / EA)) < 1e-10
    eta = np.array(out["velocity"])       # section velocity omega x r: (0, omega x(s), 0), spin (0, 0, omega)
    assert np.max(np.abs(eta[:, 1] - omega * np.sin(k * s) / (k * math.cos(k * L)))) < 1e-8
    assert np.max(np.abs(eta[:, [0, 2, 3, 4]])) < 1e-12 and np.allclose(eta[:, 5], omega, rtol=1e-14)


def test_end_torque_scene_and_python_function_agree(tmp_path, capsys):
    target = tmp_path / "out.json"
    assert main(["run", str(SCENES / "rod_end_torque.toml"), "--json", str(target), "--plot", str(tmp_path)]) == 0
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    assert np.max(np.abs(out["tip_position"])) < 1e-12                   # two full turns: back at the base
    assert abs(out["tip_rotation"] - 4 * math.pi) < 1e-10
    assert out["orthonormality_error"] < 1e-12
    assert [p["load"] for p in out["branch"]][-1] == 1.0 and np.allclose(out["branch"][0]["tip_position"], [1, 0, 0])
    assert list(tmp_path.glob("*.png"))
    system = mechgen.compile("cosserat_rod", params={"EI": 1.0, "L": 1.0}, backend="numpy")
    res = mechgen.rod_statics(system, tip_torque=[0.0, 0.0, math.pi], N=12, method="collocation")
    assert np.allclose(res["tip_position"], [0.0, 2 / math.pi, 0.0], atol=1e-10)
    assert abs(res["tip_rotation"] - math.pi) < 1e-10


def test_tip_load_scene_matches_the_elastica(tmp_path):
    target = tmp_path / "out.json"
    assert main(["run", str(SCENES / "rod_tip_load.toml"), "--json", str(target)]) == 0
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    u, v, phi = elastica(10.0)
    x, y, z = out["tip_position"]
    # 80 collocation elements: O(h^2) = 3e-4 (test_observed_orders_of_convergence); EA/EI = 1e6
    assert abs(1 - x - u) < 3e-4 and abs(-y - v) < 3e-4 and abs(-out["tip_rotation"] - phi) < 3e-4 and z == 0.0


@pytest.mark.parametrize("setting, key", [("GA=-1.0", "params"), ("EI=0.0", "params"), ("L=0.0", "L")])
def test_bad_sections_and_lengths_are_refused_naming_the_key(setting, key, capsys):
    assert main(["run", str(SCENES / "rod_end_torque.toml"), "--set", setting]) == 2
    err = capsys.readouterr().err
    assert key in err and "Traceback" not in err


def test_unconstrained_ends_and_a_failed_path(tmp_path, capsys):
    text = (SCENES / "rod_end_torque.toml").read_text()
    for ends in ('base = "pinned"', 'base = "free"\ntip = "free"', 'base = "free"\ntip = "pinned"'):
        scene = tmp_path / "loose.toml"
        scene.write_text(text + ends + "\n")
        assert main(["run", str(scene)]) == 2
        assert "analysis[1].tip" in capsys.readouterr().err
    scene = tmp_path / "stuck.toml"
    scene.write_text(text.replace('tip_torque = [0.0, 0.0, "4 * pi * EI / L"]', "tip_force = [0.0, -1.0, 0.0]")
                     .replace("steps = 10", "steps = 2\ntol = 1e-300\nmin_step = 0.1")
                     .replace("elements = 40", "elements = 4"))
    assert main(["run", str(scene)]) == 1
    assert "last load reached" in capsys.readouterr().err


# --------------------------------------------------------------------------- 3D, many turns, the declaration

@pytest.mark.parametrize("method", ["shooting", "collocation"])
def test_oblique_end_torque_on_an_isotropic_rod_gives_the_exact_helix(method):
    """GJ = EI, no force: the spatial moment M is constant and the section turns about it at M/EI, so
    f = (e1, M/EI) everywhere and H(L) = exp(L hat6 f) (the body moment R^T M = M)."""
    from mechgen.runtime.rods.liegroup import exp_se3

    EI, L = 1.5, 2.0
    M = np.array([2.0, 0.5, -3.0])
    st = solve_statics(Rod(L, stiffness(EA=1e3, GA=1e3, GJ=EI, EI=EI), tip_torque=M), method=method, elements=16,
                       steps=4).final
    expect = exp_se3(st.s[:, None] * np.concatenate([[1.0, 0.0, 0.0], M / EI]))
    assert np.max(np.abs(st.H - expect)) < 1e-10


@pytest.mark.parametrize("method", ["shooting", "collocation"])
def test_twenty_full_turns_keep_the_rotations_orthonormal(method):
    """tau L/EI = 40 pi (issue 15 item 6): the arc closes on itself 20 times; R^T R = I to 1e-12 at every node."""
    k = 40 * math.pi
    rod = Rod(1.0, stiffness(EA=1e4, GA=1e4), tip_torque=np.array([0.0, 0.0, k]))
    st = solve_statics(rod, method=method, elements=400, steps=1).final
    assert orthonormality_error(st.H[:, :3, :3]) < 1e-12
    assert abs(turning_angle(st.H, (0, 0, 1)) - k) < 1e-9 and np.max(np.abs(st.H[-1, :3, 3])) < 1e-10


CURVED = '''"""A curved rod in a few lines: the arc of radius r with the curved-beam section (seed 001)."""
from mechgen.symbolic.cross_section import Square, cross_section_stiffness
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("curved_rod", doc=__doc__, file=__file__)
model.params(Param("r", 0.5, "m"), Param("b", 0.1, "m"), Param("lam", 2.0e6, "Pa"), Param("mu", 1.0e6, "Pa"),
             Param("L", 1.0, "m"))


@model.section_stiffness
def stiffness(p):
    return cross_section_stiffness(p.lam, p.mu, Square(p.b), kappa0=1 / p.r)


model.rod(length=lambda p: p.L, f0=lambda p: (1, 0, 0, 0, 0, 1 / p.r))
'''


def test_a_user_rod_on_a_declared_curved_section(tmp_path):
    """The rod's K is the section's (with the extension-bending coupling K[u1, w3]); an end torque tau about z
    keeps n = 0 and m = (0, 0, tau), so f = f0 + K^-1 sigma is constant and H(L) = exp(L hat6 f)."""
    from mechgen.runtime.rods.liegroup import exp_se3

    path = tmp_path / "curved_rod.py"
    path.write_text(CURVED)
    system = mechgen.compile(str(path), backend="numpy")
    K = np.asarray(mechgen.cross_section(system)["K"])
    assert K[0, 5] != 0.0
    out = system.call("rod", f=np.array([[1.1, 0.01, 0, 0, 0.02, 2.3]]), r=np.zeros((1, 3)))
    eps = np.array([0.1, 0.01, 0, 0, 0.02, 2.3 - 2.0])
    assert np.allclose(out["sigma"][0], K @ eps, rtol=1e-13) and np.allclose(out["C"][0], K.ravel())
    assert abs(out["W"][0, 0] - eps @ K @ eps / 2) < 1e-12 * abs(eps @ K @ eps)
    tau = -0.3 * K[5, 5]
    for method in ("shooting", "collocation"):
        res = mechgen.rod_statics(system, tip_torque=[0.0, 0.0, tau], elements=10, method=method)
        f = np.array([1.0, 0, 0, 0, 0, 2.0]) + np.linalg.solve(K, [0, 0, 0, 0, 0, tau])
        assert np.allclose(res["tip_position"], exp_se3(f)[:3, 3], atol=1e-11)
        assert np.allclose(np.array(res["strain"]), np.tile(f - [1, 0, 0, 0, 0, 2.0], (11, 1)), atol=1e-12)


def test_rod_declarations_that_cannot_work_are_model_errors():
    from mechgen.errors import ModelError
    from mechgen.symbolic.model import Model
    from mechgen.symbolic.params import Param
    from mechgen.symbolic.rod import rod_stiffness

    model = Model("twice", file=__file__)
    model.params(Param("EI", 1.0, "N m^2"))
    model.rod(stiffness=lambda p: rod_stiffness(1.0, 1.0, 1.0, p.EI))
    with pytest.raises(ModelError, match="declares its rod twice"):
        model.rod()
    bare = Model("bare", file=__file__)
    bare.params(Param("EI", 1.0, "N m^2"))
    bare.rod(length=lambda p: p.EI)
    with pytest.raises(ModelError, match="no 6 x 6 stiffness"):
        mechgen.compile(bare, backend="numpy")


def test_at_pl2_ei_100_the_path_stays_on_the_hanging_branch():
    """PL^2/EI = 100: Newton from a coarse load step can converge to a looped elastica (another equilibrium);
    the continuation refuses such jumps, so the answer is Bisshopp-Drucker's (within O(h^2) = 1e-4 at N = 80)."""
    assert tip_error(100.0, "collocation", 80) < 1.2e-4


@pytest.mark.slow
def test_at_pl2_ei_100_shooting_also_stays_on_the_branch():
    """The same by RKMK4 shooting (ill-conditioned here: ~exp(sqrt(100)) sensitivity, about 12 s)."""
    assert tip_error(100.0, "shooting", 40) < 2e-6


def test_the_model_gravity_load_gives_the_timoshenko_cantilever_under_its_own_weight(capsys):
    """q = rhoA g per length, small: tip deflection q L^4/(8 EI) + q L^2/(2 GA) (Timoshenko beam theory)."""
    EI, GA, L, rhoA, g = 2.0, 40.0, 1.5, 1e-3, 9.81
    system = mechgen.compile("cosserat_rod", params={"EI": EI, "GA": GA, "L": L, "rhoA": rhoA, "g_y": -g,
                                                     "EA": 1e6, "GJ": 1.0}, backend="numpy")
    res = mechgen.rod_statics(system, elements=200, steps=1)
    q = rhoA * g
    expect = q * L**4 / (8 * EI) + q * L**2 / (2 * GA)
    assert abs(-res["tip_position"][1] / expect - 1) < 3e-5     # O(h^2) of the collocation at N = 200
    assert main(["show", "cosserat_rod"]) == 0
    assert "omega**2*r_1*rhoA" in capsys.readouterr().out
