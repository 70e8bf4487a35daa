"""Forced harmonic response (issue 27, item 5): force patterns and unbalance over a speed range
(mechgen/analyses/response.py, forcing.py, runtime/linear/harmonic.py), against independent references.

References, each computed here without mechgen:

* the Jeffcott rotor (disk mass M on an isotropic shaft of stiffness k, damping c) under an unbalance m e:
  x + i y = r exp(i Omega t) with r = m e Omega^2 / (k - M Omega^2 + i c Omega), i.e.
  |r| = m e Omega^2 / sqrt((k - M Omega^2)^2 + (c Omega)^2), lagging the unbalance by
  atan2(c Omega, k - M Omega^2); a forward circle (equal semi-axes);
* the anisotropic Jeffcott (k_x != k_y), per axis X = m e Omega^2 / (k_x - M Omega^2 + i c Omega),
  Y = -i m e Omega^2 / (k_y - M Omega^2 + i c Omega): without damping the ellipse x = A_x cos(Omega t),
  y = A_y sin(Omega t) has semi-axes |A_x|, |A_y| and angular momentum x y' - y x' = Omega A_x A_y, negative
  (backward whirl) between the two critical speeds sqrt(k_x / M) < Omega < sqrt(k_y / M); with damping the
  semi-axes and the sign of the angular momentum come from the ellipse sampled at 20001 points;
* a 4-dof overhung rotor (translations coupled to the tilts, gyroscopic G = Ip Omega [[0, 1], [-1, 0]] on
  the tilts): numpy.linalg.solve of (K - w^2 M + i w (D + G)) X = f on the matrices written out here.
"""
from __future__ import annotations

import numpy as np
import pytest

import mechgen
from mechgen.errors import InputError

JEFFCOTT = '''\
"""Jeffcott rotor on supports of stiffness k_x, k_y (a disk of mass M at mid-span, no tilt)."""
from mechgen import Model, Param

model = Model("user_jeffcott", doc=__doc__)
model.params(Param("M", 2.0), Param("k_x", 800.0), Param("k_y", 1800.0), Param("c", 4.0), Param("Omega", 0.0),
             Param("kappa", 0.0))
model.coordinates("x", "y")
model.whirl_pair("x", "y")


@model.kinetic
def kinetic(q, v, p):
    return p.M / 2 * (v.x**2 + v.y**2)


@model.potential
def potential(q, p):  # kappa: a stiffness that grows with the speed, k + kappa Omega^2 (K depends on Omega)
    return ((p.k_x + p.kappa * p.Omega**2) * q.x**2 + (p.k_y + p.kappa * p.Omega**2) * q.y**2) / 2


@model.dissipation
def dissipation(v, p):
    return p.c / 2 * (v.x**2 + v.y**2)
'''

OVERHUNG = '''\
"""An overhung disk: translations x, y coupled to the tilts a, b; gyroscopic moment Ip Omega."""
from mechgen import Model, Param

model = Model("user_overhung", doc=__doc__)
model.params(Param("M", 3.0), Param("Id", 0.05), Param("Ip", 0.08), Param("k11", 2.0e4), Param("k12", -3.0e3),
             Param("k22", 1.5e3), Param("c", 6.0), Param("Omega", 100.0))
model.coordinates("x", "y", "a", "b")


@model.kinetic
def kinetic(q, v, p):
    return p.M / 2 * (v.x**2 + v.y**2) + p.Id / 2 * (v.a**2 + v.b**2) + p.Ip * p.Omega * v.a * q.b


@model.potential
def potential(q, p):
    return (p.k11 * (q.x**2 + q.y**2) + 2 * p.k12 * (q.x * q.a - q.y * q.b) + p.k22 * (q.a**2 + q.b**2)) / 2


@model.dissipation
def dissipation(v, p):
    return p.c / 2 * (v.x**2 + v.y**2)
'''

UNB = {"coordinates": ["x", "y"], "mass": 0.01, "eccentricity": 0.05}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    path = tmp_path_factory.mktemp("forced_models")
    for name, text in {"jeffcott": JEFFCOTT, "overhung": OVERHUNG}.items():
        (path / f"{name}.py").write_text(text)
    return path


def _jeffcott_axis(W, k, M=2.0, c=4.0, me=0.01 * 0.05):
    """X = m e W^2 / (k - M W^2 + i c W): one axis of the Jeffcott rotor's unbalance response."""
    return me * W**2 / (k - M * W**2 + 1j * c * W)


def test_isotropic_jeffcott_unbalance_against_the_closed_form(files):
    """|r|, the lag atan2(c W, k - M W^2) and a forward circle; 80 speeds through the critical sqrt(k/M) = 20.
    Tolerances: a 2 x 2 complex solve per speed, round-off only (1e-12 relative, 1e-12 rad)."""
    system = mechgen.compile(str(files / "jeffcott.py"), {"k_y": 800.0}, backend="numpy")
    r = mechgen.response(system, unbalance=UNB, over={"Omega": {"start": 1.0, "stop": 60.0, "num": 80}})
    W = np.linspace(1.0, 60.0, 80)
    k, M, c, me = 800.0, 2.0, 4.0, 0.01 * 0.05
    closed = me * W**2 / np.sqrt((k - M * W**2) ** 2 + (c * W) ** 2)
    np.testing.assert_allclose(r["omega"], W, rtol=1e-15)
    np.testing.assert_allclose(r["speeds"], W, rtol=1e-15)
    np.testing.assert_allclose(r["amplitude"]["x"], closed, rtol=1e-12)
    np.testing.assert_allclose(r["amplitude"]["y"], closed, rtol=1e-12)
    np.testing.assert_allclose(r["phase"]["x"], -np.arctan2(c * W, k - M * W**2), atol=1e-12)
    np.testing.assert_allclose(np.unwrap(np.array(r["phase"]["y"]) - r["phase"]["x"]), -np.pi / 2, atol=1e-12)
    orbit = r["orbit"]["x,y"]
    np.testing.assert_allclose(orbit["major"], closed, rtol=1e-12)
    np.testing.assert_allclose(orbit["minor"], closed, rtol=1e-12)
    assert set(orbit["whirl"]) == {"forward"}
    assert r["parameter"] == "Omega" and r["forcing"] == "unbalance"


def test_anisotropic_jeffcott_whirls_backward_between_its_critical_speeds(files):
    """Undamped: semi-axes |A_x|, |A_y| of x = A_x cos, y = A_y sin, and the whirl the sign of A_x A_y: forward
    below sqrt(k_x/M) = 20 and above sqrt(k_y/M) = 30, backward between (speeds off both criticals)."""
    system = mechgen.compile(str(files / "jeffcott.py"), {"c": 0.0}, backend="numpy")
    W = np.array([5.0, 12.0, 18.0, 22.0, 25.0, 28.0, 33.0, 45.0])
    r = mechgen.response(system, unbalance=UNB, over={"Omega": W.tolist()})
    Ax, Ay = _jeffcott_axis(W, 800.0, c=0.0).real, _jeffcott_axis(W, 1800.0, c=0.0).real
    orbit = r["orbit"]["x,y"]
    np.testing.assert_allclose(orbit["major"], np.maximum(abs(Ax), abs(Ay)), rtol=1e-12)
    np.testing.assert_allclose(orbit["minor"], np.minimum(abs(Ax), abs(Ay)), rtol=1e-12)
    expected = ["forward" if a * b > 0 else "backward" for a, b in zip(Ax, Ay)]
    assert orbit["whirl"] == expected
    assert expected[3:6] == ["backward"] * 3 and expected[:3] == ["forward"] * 3  # the known result
    np.testing.assert_allclose(r["amplitude"]["x"], abs(Ax), rtol=1e-12)
    np.testing.assert_allclose(r["amplitude"]["y"], abs(Ay), rtol=1e-12)


def _extreme_radius(X, Y, sign: float) -> float:
    """The largest (sign = 1) or smallest (sign = -1) radius of x = Re(X e^{i t}), y = Re(Y e^{i t}): the best
    of 2001 samples of a period, refined by scipy's bounded Brent search within one sample spacing."""
    from scipy.optimize import minimize_scalar

    def radius(t):
        return np.hypot((X * np.exp(1j * t)).real, (Y * np.exp(1j * t)).real)

    t = np.linspace(0.0, 2 * np.pi, 2001)
    i = int(np.argmax(sign * radius(t)))
    h = t[1] - t[0]
    best = minimize_scalar(lambda u: -sign * radius(u), bounds=(t[i] - h, t[i] + h), method="bounded",
                           options={"xatol": 1e-12})
    return float(radius(best.x))


def test_damped_anisotropic_orbit_against_the_sampled_ellipse(files):
    """With damping the ellipse is tilted: its semi-axes are the largest and smallest radius of the orbit
    (sampled, then refined by a bounded search: the radius is flat at its extremes, so a position error of
    1e-6 rad is 1e-12 relative in the radius; tolerance 1e-9) and its whirl the sign of the angular momentum
    x y' - y x' averaged over 2000 samples of a period (exact for a trigonometric polynomial of degree 2)."""
    system = mechgen.compile(str(files / "jeffcott.py"), backend="numpy")
    W = np.array([10.0, 19.0, 21.0, 24.0, 27.0, 29.5, 31.0, 50.0])
    r = mechgen.response(system, unbalance=UNB, over={"Omega": W.tolist()})
    theta = np.linspace(0.0, 2 * np.pi, 2000, endpoint=False)
    orbit = r["orbit"]["x,y"]
    for j, w in enumerate(W):
        X, Y = _jeffcott_axis(w, 800.0), -1j * _jeffcott_axis(w, 1800.0)
        assert orbit["major"][j] == pytest.approx(_extreme_radius(X, Y, 1.0), rel=1e-9)
        assert orbit["minor"][j] == pytest.approx(_extreme_radius(X, Y, -1.0), rel=1e-9)
        x, y = (X * np.exp(1j * theta)).real, (Y * np.exp(1j * theta)).real
        xd, yd = (1j * w * X * np.exp(1j * theta)).real, (1j * w * Y * np.exp(1j * theta)).real
        momentum = np.mean(x * yd - y * xd)
        assert orbit["whirl"][j] == ("forward" if momentum > 0 else "backward")
    assert "backward" in orbit["whirl"] and "forward" in orbit["whirl"]


def test_speed_dependent_stiffness_is_relinearised_at_every_speed(files):
    """K(Omega) = k + kappa Omega^2: |r| = m e W^2 / |k + kappa W^2 - M W^2 + i c W|, through the polynomial
    fit of the matrices (more than four speeds) and through assembly at each speed (three speeds)."""
    system = mechgen.compile(str(files / "jeffcott.py"), {"k_y": 800.0, "kappa": 0.5}, backend="numpy")
    for W in (np.linspace(2.0, 50.0, 40), np.array([3.0, 17.0, 41.0])):
        r = mechgen.response(system, unbalance=UNB, over={"Omega": W.tolist()})
        closed = abs(_jeffcott_axis(W, 800.0 + 0.5 * W**2))
        np.testing.assert_allclose(r["amplitude"]["x"], closed, rtol=1e-10)  # the fit's probe check is 1e-12


def _overhung_matrices(w, Omega, p):
    M = np.diag([p["M"], p["M"], p["Id"], p["Id"]])
    K = np.array([[p["k11"], 0, p["k12"], 0], [0, p["k11"], 0, -p["k12"]],
                  [p["k12"], 0, p["k22"], 0], [0, -p["k12"], 0, p["k22"]]])
    D = np.diag([p["c"], p["c"], 0.0, 0.0])
    G = np.zeros((4, 4))
    G[2, 3], G[3, 2] = p["Ip"] * Omega, -p["Ip"] * Omega
    return K - w**2 * M + 1j * w * (D + G)


OVER = {"M": 3.0, "Id": 0.05, "Ip": 0.08, "k11": 2.0e4, "k12": -3.0e3, "k22": 1.5e3, "c": 6.0}


def test_force_pattern_on_several_coordinates_against_numpy(files):
    """f = (1, 2 e^{i 90 deg}, 0.5 e^{-i 30 deg}, 0) at Omega = 100 rad/s: X = numpy.linalg.solve(A, f) on the
    hand-written matrices (A well conditioned off resonance: 1e-9 relative to the largest entry)."""
    system = mechgen.compile(str(files / "overhung.py"), backend="numpy")
    W = np.linspace(5.0, 200.0, 30)
    force = {"x": 1.0, "y": {"amplitude": 2.0, "phase": 90.0}, "a": {"amplitude": 0.5, "phase": -30.0}}
    r = mechgen.response(system, force=force, omega=W.tolist())
    f = np.array([1.0, 2.0j, 0.5 * np.exp(-1j * np.pi / 6), 0.0])
    X = np.array([np.linalg.solve(_overhung_matrices(w, 100.0, OVER), f) for w in W]).T
    for i, name in enumerate("xyab"):
        got = np.array(r["amplitude"][name]) * np.exp(1j * np.array(r["phase"][name]))
        np.testing.assert_allclose(got, X[i], rtol=0, atol=1e-9 * abs(X[i]).max())
    assert r["forcing"] == "force" and "input" not in r.outputs
    assert "orbit" not in r.outputs  # no whirl pair declared, no orbits asked for


def test_unbalance_on_a_gyroscopic_rotor_against_numpy(files):
    """The overhung rotor's unbalance response over speeds, G = Ip Omega re-evaluated at every speed (and the
    driving frequency the speed): numpy.linalg.solve of the hand-written A(Omega) X = (m e W^2)(1, -i, 0, 0)."""
    system = mechgen.compile(str(files / "overhung.py"), backend="numpy")
    W = np.linspace(10.0, 400.0, 25)
    r = mechgen.response(system, unbalance=dict(UNB, phase=45.0), over={"Omega": W.tolist()},
                         orbits=[["x", "y"], ["a", "b"]])
    me = 0.01 * 0.05
    X = np.array([np.linalg.solve(_overhung_matrices(w, w, OVER), me * w**2 * np.exp(1j * np.pi / 4)
                                  * np.array([1.0, -1j, 0.0, 0.0])) for w in W]).T
    for i, name in enumerate("xyab"):
        got = np.array(r["amplitude"][name]) * np.exp(1j * np.array(r["phase"][name]))
        np.testing.assert_allclose(got, X[i], rtol=0, atol=1e-9 * abs(X[i]).max())
    assert set(r["orbit"]) == {"x,y", "a,b"}


def test_speed_unit_converts_the_given_speeds(files):
    """rpm = 60 / (2 pi) rad/s and Hz = 1 / (2 pi) rad/s: the same speeds written in each unit give the same
    response; ``omega`` stays in rad/s, ``omega_in_unit`` holds the values as written."""
    system = mechgen.compile(str(files / "jeffcott.py"), backend="numpy")
    rad = [5.0, 21.0, 40.0]
    base = mechgen.response(system, unbalance=UNB, over={"Omega": rad})
    for unit, factor in (("rpm", 60.0 / (2 * np.pi)), ("Hz", 1.0 / (2 * np.pi))):
        written = [w * factor for w in rad]
        r = mechgen.response(system, unbalance=UNB, over={"Omega": written}, speed_unit=unit)
        np.testing.assert_allclose(r["omega"], rad, rtol=1e-14)
        np.testing.assert_allclose(r["omega_in_unit"], written, rtol=1e-14)
        np.testing.assert_allclose(r["amplitude"]["x"], base["amplitude"]["x"], rtol=1e-12)
        assert r["speed_unit"] == unit
    f = mechgen.response(system, input="x", omega=[1.0, 3.0], speed_unit="Hz")
    np.testing.assert_allclose(f["omega"], [2 * np.pi, 6 * np.pi], rtol=1e-15)
    np.testing.assert_allclose(f["amplitude"]["x"], abs(1.0 / (800.0 - 2.0 * np.array(f["omega"]) ** 2
                                                              + 4.0j * np.array(f["omega"]))), rtol=1e-12)


@pytest.mark.parametrize("options, key", [
    ({"input": "x", "force": {"x": 1.0}, "omega": [1.0]}, "force"),
    ({"force": {"z": 1.0}, "omega": [1.0]}, "force.z"),
    ({"force": {"x": {"amplitude": 1.0, "phaze": 3}}, "omega": [1.0]}, "force.x.phaze"),
    ({"unbalance": dict(UNB, coordinates=["x", "z"]), "over": {"Omega": [1.0]}}, "unbalance.coordinates[2]"),
    ({"unbalance": dict(UNB, eccentricity=-0.1), "over": {"Omega": [1.0]}}, "unbalance.eccentricity"),
    ({"unbalance": dict(UNB, mass=-1.0), "over": {"Omega": [1.0]}}, "unbalance.mass"),
    ({"unbalance": UNB}, "over"),
    ({"unbalance": UNB, "over": {"Omega": [1.0]}, "omega": [1.0]}, "omega"),
    ({"unbalance": UNB, "over": {"spin": [1.0]}}, "over.spin"),
    ({"unbalance": UNB, "over": {"Omega": [-1.0]}}, "over.Omega"),
    ({"input": "x", "omega": [1.0], "over": {"Omega": [1.0]}}, "over"),
    ({"force": {"x": 1.0}}, "omega"),
    ({"input": "x", "omega": [1.0], "speed_unit": "rps"}, "speed_unit"),
    ({"omega": [1.0]}, "input"),
])
def test_bad_input_names_the_key(files, options, key):
    system = mechgen.compile(str(files / "jeffcott.py"), backend="numpy")
    with pytest.raises(InputError) as err:
        mechgen.response(system, **options)
    assert f"'response.{key}'" in str(err.value)


def test_unbalance_on_a_model_without_the_speed_parameter(tmp_path):
    """The spring pendulum has no spin speed: an unbalance over 'Omega' is refused naming over.Omega."""
    system = mechgen.compile("spring_pendulum", backend="numpy")
    with pytest.raises(InputError) as err:
        mechgen.response(system, unbalance={"coordinates": ["r", "theta"], "mass": 1.0, "eccentricity": 0.1},
                         over={"Omega": [1.0, 2.0]})
    assert "'response.over.Omega'" in str(err.value) and "no parameter" in str(err.value)


def test_the_scene_draws_a_bode_plot_and_orbits(tmp_path):
    """scenes/jeffcott_unbalance.toml (the laval rotor's translations, speeds in rpm): the closed form of the
    isotropic Jeffcott rotor at every speed (1e-12 relative: round-off of a 4 x 4 solve), and both figures."""
    pytest.importorskip("matplotlib")
    from pathlib import Path

    from mechgen.cli import main

    scene = Path(__file__).resolve().parents[1] / "scenes" / "jeffcott_unbalance.toml"
    out = mechgen.run(str(scene))["analyses"][0]["outputs"]
    W = np.linspace(0.0, 6000.0, 301) * 2 * np.pi / 60
    np.testing.assert_allclose(out["omega"], W, rtol=1e-14)
    closed = 1e-4 * W**2 / np.sqrt((4.0e5 - 10.0 * W**2) ** 2 + (200.0 * W) ** 2)
    np.testing.assert_allclose(out["amplitude"]["x"], closed, rtol=1e-12, atol=1e-300)
    assert set(out["orbit"]["x,y"]["whirl"][1:]) == {"forward"} and out["orbit"]["x,y"]["whirl"][0] == "none"
    assert main(["run", str(scene), "--plot", str(tmp_path)]) == 0
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == ["jeffcott_unbalance_unbalance.png", "jeffcott_unbalance_unbalance_orbits.png"]


def test_a_scene_with_a_bad_unbalance_exits_2_naming_the_file_and_key(tmp_path, capsys):
    """From the command line: a negative eccentricity, and input beside force, are exit 2 with the key."""
    from mechgen.cli import main

    for table, key in (('unbalance = { coordinates = ["x", "y"], mass = 0.01, eccentricity = -0.01 }\n'
                        'over = { Omega = [100.0, 200.0] }\n', "analysis[1].unbalance.eccentricity"),
                       ('input = "x"\nforce = { x = 1.0 }\nomega = [1.0]\n', "analysis[1].force")):
        scene = tmp_path / "bad.toml"
        scene.write_text(f'model = "laval_rotor"\n\n[[analysis]]\nname = "u"\nkind = "response"\n{table}')
        assert main(["run", str(scene)]) == 2
        err = capsys.readouterr().err
        assert "bad.toml" in err and key in err, err


def test_a_folded_speed_parameter_is_refused(files):
    """A system compiled with the speed folded into its kernels cannot be re-linearised at other speeds."""
    system = mechgen.compile(str(files / "jeffcott.py"), free=["M"], backend="numpy")
    with pytest.raises(InputError, match="over"):
        mechgen.response(system, unbalance=UNB, over={"Omega": [1.0, 2.0]})


def test_a_rotating_force_pattern_on_a_whirl_pair_reports_its_orbit():
    """The Laval rotor's translations driven by F_x = cos(w t), F_y = sin(w t) (phase -90 degrees): the pattern
    drives both coordinates of the declared whirl pair (x, y), so its orbit is reported: a forward circle of
    radius |1 / (k_t - m w^2 + i c w)| (x and y decoupled and alike); 1e-12 relative: round-off."""
    p = {"m": 10.0, "k_t": 4.0e5, "c": 40.0}
    rotor = mechgen.compile("laval_rotor", p, backend="numpy")
    W = np.linspace(50.0, 400.0, 15)
    r = mechgen.response(rotor, force={"x": 1.0, "y": {"amplitude": 1.0, "phase": -90.0}}, omega=W.tolist())
    radius = abs(1.0 / (p["k_t"] - p["m"] * W**2 + 1j * p["c"] * W))
    assert list(r["orbit"]) == ["x,y"]  # the tilts are not driven: (theta_x, theta_y) is left out
    np.testing.assert_allclose(r["orbit"]["x,y"]["major"], radius, rtol=1e-12)
    np.testing.assert_allclose(r["orbit"]["x,y"]["minor"], radius, rtol=1e-12)
    assert set(r["orbit"]["x,y"]["whirl"]) == {"forward"}


def test_internal_damping_does_not_change_the_synchronous_unbalance_response():
    """The Laval rotor with internal (rotating) damping c_i: its force c_i (r' - i Omega r) (r = x + i y; a
    damping D = c_i and a circulatory K = c_i Omega [[0, 1], [-1, 0]] that grows with the speed) vanishes on the
    synchronous forward whirl r = R e^{i Omega t} an unbalance drives, so the response is the closed form
    without c_i (Genta, Dynamics of Rotating Systems, 2005, sec. 8.3: rotating damping does no work in
    synchronous whirl). Speeds below the onset sqrt(k_t/m) (1 + c/c_i) = 466.7 rad/s, where the state is stable.
    1e-12 relative: round-off of a 4 x 4 solve; K(Omega) through the speed polynomial (30 speeds)."""
    p = {"m": 10.0, "k_t": 4.0e5, "c": 200.0, "c_i": 150.0}
    rotor = mechgen.compile("laval_rotor", p, backend="numpy")
    W = np.linspace(10.0, 450.0, 30)
    r = mechgen.response(rotor, unbalance={"coordinates": ["x", "y"], "mass": 0.01, "eccentricity": 0.01},
                         over={"Omega": W.tolist()})
    closed = 1e-4 * W**2 / np.sqrt((p["k_t"] - p["m"] * W**2) ** 2 + (p["c"] * W) ** 2)
    np.testing.assert_allclose(r["amplitude"]["x"], closed, rtol=1e-12)
    np.testing.assert_allclose(r["orbit"]["x,y"]["minor"], closed, rtol=1e-12)
    # not vacuous: c_i does enter the matrices, since a non-synchronous drive (omega = 150 at Omega = 300) feels
    # it (here by 7.6 %; any change beyond round-off would do)
    fixed = mechgen.response(rotor.with_params(Omega=300.0), input="x", omega=[150.0])
    alone = mechgen.response(rotor.with_params(Omega=300.0, c_i=0.0), input="x", omega=[150.0])
    assert abs(fixed["amplitude"]["x"][0] / alone["amplitude"]["x"][0] - 1) > 1e-3
