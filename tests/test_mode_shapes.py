"""Mode shapes of lumped models (issue 25, item 2): real, complex and rotor orbits, against independent references.

Every model here is written in the test; its M, C, K are written out by hand beside it, and the reference is
scipy on those matrices or a closed form:

* a 3-dof spring-mass chain (non-uniform masses, springs between the masses: non-diagonal K) and a double
  pendulum linearised at rest (non-diagonal M): frequencies and shapes against ``scipy.linalg.eigh(K, M)``,
  phi^T M phi = 1 and phi^T K phi = omega^2;
* a damped 2-dof system: proportional damping C = a M + b K keeps the undamped (real) shapes with
  zeta_i = a / (2 w_i) + b w_i / 2 (Rayleigh damping; Inman, "Engineering Vibration", 4th ed., sect. 4.5),
  non-proportional damping against ``scipy.linalg.eig`` of the first-order matrix [[0, I], [-M^-1 K, -M^-1 C]];
* rotors (Friswell, Penny, Garvey, Lees, "Dynamics of Rotating Machines", CUP 2010, sect. 3.5-3.6): a point-mass
  Jeffcott rotor on anisotropic supports (kx != ky) whose modes are x-only and y-only straight lines at every
  speed (whirl ``linear``, also at the Campbell diagram's critical speeds Omega = sqrt(kx/m), sqrt(ky/m)); a
  Laval disk's tilt (Id theta_x'' + Ip Omega theta_y' + kx theta_x = 0, Id theta_y'' - Ip Omega theta_x' +
  ky theta_y = 0): with theta_x = Re(e^{i w t}) the second equation gives theta_y = Re(i r e^{i w t}),
  r = (kx - Id w^2) / (Ip Omega w), an ellipse of semi-axes 1 and |r| whose signed minor/major ratio is -r
  (|r| <= 1) or -1/r; isotropic (kx = ky = k) the whirl frequencies solve Id w^2 -+ Ip Omega w - k = 0, so
  r = -+1: circles, forward and backward.
"""
import numpy as np
import pytest
import scipy.linalg as sla

import mechgen
# ------------------------------------------------------------------------------------------- models
# Model files written by the tests (a system that mechgen.modes accepts is compiled from a reference it can
# look up again: a file path), each with its matrices by hand.

CHAIN3 = '''"""Wall - k1 - m1 - k2 - m2 - k3 - m3 - k4 - wall: T = sum m_i x_i'^2 / 2, V = sum k_j stretch_j^2 / 2."""
from mechgen import Model, Param

model = Model("chain3", doc=__doc__)
model.params(Param("m1", 1.0), Param("m2", 2.0), Param("m3", 0.5),
             Param("k1", 100.0), Param("k2", 50.0), Param("k3", 80.0), Param("k4", 30.0))
model.coordinates("x1", "x2", "x3")
model.kinetic(lambda v, p: (p.m1 * v.x1**2 + p.m2 * v.x2**2 + p.m3 * v.x3**2) / 2)
model.potential(lambda q, p: (p.k1 * q.x1**2 + p.k2 * (q.x2 - q.x1)**2 + p.k3 * (q.x3 - q.x2)**2
                              + p.k4 * q.x3**2) / 2)
'''


def chain3_matrices(m1=1.0, m2=2.0, m3=0.5, k1=100.0, k2=50.0, k3=80.0, k4=30.0):
    """M and K of CHAIN3, by hand."""
    M = np.diag([m1, m2, m3])
    K = np.array([[k1 + k2, -k2, 0.0], [-k2, k2 + k3, -k3], [0.0, -k3, k3 + k4]])
    return M, K


DOUBLE_PENDULUM = '''"""Planar double pendulum: point masses on rigid rods, angles a, b from the vertical."""
import sympy as sp
from mechgen import Model, Param

model = Model("double_pendulum", doc=__doc__)
model.params(Param("m1", 1.5), Param("m2", 0.7), Param("l1", 1.2), Param("l2", 0.8), Param("g", 9.81))
model.coordinates("a", "b")
model.kinetic(lambda q, v, p: (p.m1 + p.m2) / 2 * p.l1**2 * v.a**2 + p.m2 / 2 * p.l2**2 * v.b**2
              + p.m2 * p.l1 * p.l2 * v.a * v.b * sp.cos(q.a - q.b))
model.potential(lambda q, p: -(p.m1 + p.m2) * p.g * p.l1 * sp.cos(q.a) - p.m2 * p.g * p.l2 * sp.cos(q.b))
'''


def double_pendulum_matrices(m1=1.5, m2=0.7, l1=1.2, l2=0.8, g=9.81):
    """M and K of the double pendulum at rest, by hand (M is not diagonal)."""
    M = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2**2]])
    K = np.diag([(m1 + m2) * g * l1, m2 * g * l2])
    return M, K


DAMPED2 = '''"""Two masses, three springs, a dashpot matrix: R = (c11 x1'^2 + 2 c12 x1' x2' + c22 x2'^2) / 2."""
from mechgen import Model, Param

model = Model("damped2", doc=__doc__)
model.params(Param("c11", 0.0), Param("c12", 0.0), Param("c22", 0.0))
model.coordinates("x1", "x2")
model.kinetic(lambda v: (2.0 * v.x1**2 + 1.0 * v.x2**2) / 2)
model.potential(lambda q: (300.0 * q.x1**2 + 120.0 * (q.x2 - q.x1)**2 + 200.0 * q.x2**2) / 2)
model.dissipation(lambda v, p: (p.c11 * v.x1**2 + 2 * p.c12 * v.x1 * v.x2 + p.c22 * v.x2**2) / 2)
'''

M_D2 = np.diag([2.0, 1.0])
K_D2 = np.array([[420.0, -120.0], [-120.0, 320.0]])

JEFFCOTT = '''"""Point mass on anisotropic supports, spinning (no gyroscopic term): x and y decouple."""
from mechgen import Model, Param

model = Model("jeffcott_aniso", doc=__doc__)
model.params(Param("m", 2.0), Param("kx", 800.0), Param("ky", 1250.0), Param("Omega", 0.0))
model.coordinates("x", "y")
model.whirl_pair("x", "y")
model.kinetic(lambda v, p: p.m / 2 * (v.x**2 + v.y**2))
model.potential(lambda q, p: (p.kx * q.x**2 + p.ky * q.y**2) / 2)
'''

LAVAL_TILT = '''"""A disk's tilts on a shaft of tilt stiffnesses kx, ky at spin Omega: G = Ip Omega [[0, 1], [-1, 0]]."""
from mechgen import Model, Param

model = Model("laval_tilt", doc=__doc__)
model.params(Param("Id", 1.0), Param("Ip", 0.8), Param("kx", 4.0), Param("ky", 6.0), Param("Omega", 0.0))
model.coordinates("tx", "ty")
model.whirl_pair("tx", "ty")
model.kinetic(lambda q, v, p: p.Id / 2 * (v.tx**2 + v.ty**2) + p.Ip * p.Omega / 2 * (v.tx * q.ty - q.tx * v.ty))
model.potential(lambda q, p: (p.kx * q.tx**2 + p.ky * q.ty**2) / 2)
'''

SOURCES = {"chain3": CHAIN3, "double_pendulum": DOUBLE_PENDULUM, "damped2": DAMPED2, "jeffcott": JEFFCOTT,
           "laval_tilt": LAVAL_TILT}


@pytest.fixture(scope="module")
def model_files(tmp_path_factory):
    """The model files above, written once: {name: path}."""
    folder = tmp_path_factory.mktemp("models")
    paths = {}
    for name, text in SOURCES.items():
        paths[name] = folder / f"{name}.py"
        paths[name].write_text(text)
    return paths


# ------------------------------------------------------------------------------------------- helpers


def as_matrix(shapes: list[dict], names) -> np.ndarray:
    """Columns phi_k from the ``shapes`` output (one {coordinate: value} per mode)."""
    return np.array([[s[n] for n in names] for s in shapes]).T


def complex_matrix(shapes: list[dict], names) -> np.ndarray:
    """Columns X_k from the complex ``shapes`` output ({coordinate: {amplitude, phase}} per mode)."""
    return np.array([[s[n]["amplitude"] * np.exp(1j * s[n]["phase"]) for n in names] for s in shapes]).T


def normalised(X: np.ndarray) -> np.ndarray:
    """Each column divided by its largest-magnitude entry (the documented normalisation: that entry 1)."""
    return X / X[np.argmax(np.abs(X), axis=0), np.arange(X.shape[1])][None, :]


# ------------------------------------------------------------------------------------------- real shapes


@pytest.mark.parametrize("name, matrices, names", [("chain3", chain3_matrices, ("x1", "x2", "x3")),
                                                   ("double_pendulum", double_pendulum_matrices, ("a", "b"))])
def test_lumped_shapes_match_scipy_eigh(model_files, name, matrices, names):
    """Frequencies to 1e-12 relative and shapes to 1e-10 (eigenvectors of well separated eigenvalues: their
    error is eps ||K|| / gap; measured 1.1e-16), phi^T M phi = 1 and phi^T K phi = omega^2 to 1e-12."""
    system = mechgen.compile(str(model_files[name]), backend="numpy")
    res = mechgen.modes(system)
    M, K = matrices()
    lam, ref = sla.eigh(K, M)
    np.testing.assert_allclose(res["frequencies"], np.sqrt(lam), rtol=1e-12)
    phi = as_matrix(res["shapes"], names)
    signs = np.sign(np.sum(phi * ref, axis=0))  # scipy's sign is arbitrary: compare up to it
    np.testing.assert_allclose(phi, ref * signs[None, :], atol=1e-10 * np.abs(ref).max())
    # the documented sign: the largest |entry| of each shape is positive
    assert np.all(phi[np.argmax(np.abs(phi), axis=0), np.arange(phi.shape[1])] > 0)
    # mass normalisation and modal stiffness, on the hand-written matrices and as reported
    np.testing.assert_allclose(phi.T @ M @ phi, np.eye(len(names)), atol=1e-12)
    np.testing.assert_allclose(np.diag(phi.T @ K @ phi), lam, rtol=1e-12)
    np.testing.assert_allclose(res["modal_mass"], 1.0, rtol=1e-12)
    np.testing.assert_allclose(res["modal_stiffness"], lam, rtol=1e-12)


def test_count_keeps_the_lowest_shapes(model_files):
    system = mechgen.compile(str(model_files["chain3"]), backend="numpy")
    full, two = mechgen.modes(system), mechgen.modes(system, count=2)
    assert len(two["shapes"]) == len(two["modal_mass"]) == len(two["modal_stiffness"]) == 2
    assert two["shapes"] == full["shapes"][:2]


# ------------------------------------------------------------------------------------------- complex shapes


def test_proportional_damping_keeps_the_real_shapes(model_files):
    """C = a M + b K: the undamped shapes (phases 0 or pi), zeta_i = a / (2 w_i) + b w_i / 2 (Rayleigh damping),
    wd_i = w_i sqrt(1 - zeta_i^2); to 1e-10 (the first-order eigenproblem's round-off; measured 4e-16)."""
    a, b = 0.8, 0.002
    C = a * M_D2 + b * K_D2
    res = mechgen.modes(mechgen.compile(str(model_files["damped2"]), {"c11": C[0, 0], "c12": C[0, 1], "c22": C[1, 1]},
                                        backend="numpy"))
    lam, phi = sla.eigh(K_D2, M_D2)
    w = np.sqrt(lam)
    zeta = a / (2 * w) + b * w / 2
    np.testing.assert_allclose(res["frequencies"], w * np.sqrt(1 - zeta**2), rtol=1e-10)
    X = complex_matrix(res["shapes"], ("x1", "x2"))
    np.testing.assert_allclose(X, normalised(phi), atol=1e-10)
    for shape in res["shapes"]:
        for v in shape.values():
            assert min(abs(v["phase"]), abs(abs(v["phase"]) - np.pi)) < 1e-10
        assert max(v["amplitude"] for v in shape.values()) == pytest.approx(1.0, abs=1e-15)


def test_nonproportional_damping_shapes_match_scipy_eig(model_files):
    """A dashpot on mass 1 only: complex shapes. Reference: scipy.linalg.eig of [[0, I], [-M^-1 K, -M^-1 C]]
    written here, the q-part of each eigenvector with Im s > 0, normalised to its largest entry; 1e-10
    (round-off of two eigen-solves; measured 1.0e-15)."""
    C = np.array([[6.0, 0.0], [0.0, 0.0]])
    res = mechgen.modes(mechgen.compile(str(model_files["damped2"]), {"c11": 6.0}, backend="numpy"))
    Minv = np.linalg.inv(M_D2)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K_D2, -Minv @ C]])
    s, V = sla.eig(A)
    up = np.flatnonzero(s.imag > 0)
    up = up[np.argsort(s[up].imag)]
    np.testing.assert_allclose(res["frequencies"], s[up].imag, rtol=1e-12)
    np.testing.assert_allclose(np.array(res["eigenvalues"]), np.c_[s[up].real, s[up].imag], rtol=1e-12)
    X = complex_matrix(res["shapes"], ("x1", "x2"))
    np.testing.assert_allclose(X, normalised(V[:2, up]), atol=1e-10)
    assert np.abs(np.angle(X)).max() > 1e-3  # genuinely complex: not a real shape with phases 0 and pi


# ------------------------------------------------------------------------------------------- rotors


def test_anisotropic_jeffcott_modes_are_linear(model_files):
    """x-only and y-only modes, w = sqrt(kx/m), sqrt(ky/m) = 20, 25 rad/s: straight lines along x and y."""
    system = mechgen.compile(str(model_files["jeffcott"]), {"Omega": 300.0}, backend="numpy")
    res = mechgen.modes(system)
    np.testing.assert_allclose(res["frequencies"], [20.0, 25.0], rtol=1e-12)
    assert res["whirl"] == ["linear", "linear"]
    assert np.array_equal(res["whirl_ratio"], [0.0, 0.0])
    assert [o["major"] for o in res["orbits"]] == pytest.approx([1.0, 1.0], abs=1e-15)
    assert [o["minor"] for o in res["orbits"]] == [0.0, 0.0]
    assert [o["angle"] for o in res["orbits"]] == pytest.approx([0.0, np.pi / 2], abs=1e-12)  # along x, along y


def test_anisotropic_jeffcott_critical_speeds_are_linear(model_files):
    """Campbell over Omega: the flat curves cross Omega at sqrt(kx/m) = 20 and sqrt(ky/m) = 25 (to 1e-9: the
    refined crossings' tolerance), both straight-line orbits at every speed."""
    system = mechgen.compile(str(model_files["jeffcott"]), backend="numpy")
    camp = mechgen.campbell(system, over={"Omega": {"start": 0.0, "stop": 40.0, "num": 9}}, count=2)
    assert all(row == ["linear", "linear"] for row in camp["whirl"])
    crit = camp["critical_speeds"]
    assert [c["whirl"] for c in crit] == ["linear", "linear"]
    np.testing.assert_allclose([c["speed"] for c in crit], [20.0, 25.0], rtol=1e-9)


def test_anisotropic_laval_tilt_orbits_match_closed_form(model_files):
    """At rest x-only and y-only (linear); spinning, ellipses with whirl_ratio -r or -1/r (module docstring),
    r = (kx - Id w^2) / (Ip Omega w): to 1e-9 (the ratio of two eigenvector entries; measured 4e-16)."""
    Id, Ip, kx, ky, speed = 1.0, 0.8, 4.0, 6.0, 2.5
    system = mechgen.compile(str(model_files["laval_tilt"]), {"kx": kx, "ky": ky}, backend="numpy")
    rest = mechgen.modes(system)
    np.testing.assert_allclose(rest["frequencies"], np.sqrt([kx / Id, ky / Id]), rtol=1e-12)
    assert rest["whirl"] == ["linear", "linear"] and np.array_equal(rest["whirl_ratio"], [0.0, 0.0])
    spin = mechgen.modes(system.with_params(Omega=speed))
    w = np.sqrt(np.sort(np.roots([Id**2, -(Id * (kx + ky) + Ip**2 * speed**2), kx * ky]).real))
    np.testing.assert_allclose(spin["frequencies"], w, rtol=1e-12)
    r = (kx - Id * w**2) / (Ip * speed * w)
    kappa = np.where(np.abs(r) <= 1, -r, -1 / r)
    np.testing.assert_allclose(spin["whirl_ratio"], kappa, rtol=1e-9)
    assert spin["whirl"] == ["backward", "forward"] and kappa[0] < 0 < kappa[1]
    for o, rk in zip(spin["orbits"], r):  # the normalised shape: semi-axes 1 and |r| (or 1/|r| and 1)
        assert o["major"] == pytest.approx(1.0, rel=1e-12)
        assert o["minor"] == pytest.approx(min(abs(rk), 1 / abs(rk)), rel=1e-9)


def test_isotropic_laval_whirls_in_circles(model_files):
    """kx = ky: circles (whirl_ratio -1, +1), backward below forward, at w = (-+Ip Omega + sqrt(Ip^2 Omega^2 +
    4 Id k)) / (2 Id); at rest the double frequency's pair is re-chosen as the two circles."""
    Id, Ip, k, speed = 1.0, 0.8, 5.0, 3.0
    system = mechgen.compile(str(model_files["laval_tilt"]), {"kx": k, "ky": k}, backend="numpy")
    spin = mechgen.modes(system.with_params(Omega=speed))
    root = np.sqrt(Ip**2 * speed**2 + 4 * Id * k)
    np.testing.assert_allclose(spin["frequencies"], [(-Ip * speed + root) / 2, (Ip * speed + root) / 2], rtol=1e-12)
    assert spin["whirl"] == ["backward", "forward"]
    np.testing.assert_allclose(spin["whirl_ratio"], [-1.0, 1.0], rtol=1e-12)
    rest = mechgen.modes(system)
    np.testing.assert_allclose(rest["frequencies"], [np.sqrt(k / Id)] * 2, rtol=1e-12)
    assert rest["whirl"] == ["backward", "forward"]
    np.testing.assert_allclose(rest["whirl_ratio"], [-1.0, 1.0], rtol=1e-12)
    X = complex_matrix(rest["shapes"], ("tx", "ty"))
    np.testing.assert_allclose(X[1] / X[0], [1j, -1j], atol=1e-12)  # Y = i X backward, Y = -i X forward


def test_scene_path_reports_shapes_and_orbits(model_files):
    """The same outputs through a scene (a TOML dict given to mechgen.run) and its JSON."""
    path = model_files["jeffcott"]
    out = mechgen.run({"model": str(path), "backend": "numpy", "params": {"kx": 450.0},
                       "analysis": [{"name": "free", "kind": "modes"}]})
    modes = out["analyses"][0]["outputs"]
    np.testing.assert_allclose(modes["frequencies"], [15.0, 25.0], rtol=1e-12)  # sqrt(450/2), sqrt(1250/2)
    assert modes["whirl"] == ["linear", "linear"]
    np.testing.assert_allclose(as_matrix([{n: v["amplitude"] for n, v in s.items()} for s in modes["shapes"]],
                                         ("x", "y")), np.eye(2), atol=1e-15)


def test_shapes_and_orbits_plots(model_files, tmp_path):
    """The plots write the bar and orbit figures beside the spectrum (labelled panels, one per mode)."""
    pytest.importorskip("matplotlib")
    chain = mechgen.modes(mechgen.compile(str(model_files["chain3"]), backend="numpy"))
    written = chain.plot(tmp_path / "chain")
    assert any(p.name.endswith("_shapes.png") for p in written)
    rotor = mechgen.modes(mechgen.compile(str(model_files["laval_tilt"]), {"Omega": 2.5}, backend="numpy"))
    written = rotor.plot(tmp_path / "rotor")
    assert {p.name.rsplit("_", 1)[-1] for p in written} >= {"shapes.png", "orbits.png"}


def test_laval_rotor_judges_tilt_modes_at_its_tilt_station():
    """The built-in Laval rotor declares two whirl stations (centre x, y and tilts theta_x, theta_y): its tilt
    modes, which leave x, y at rest, whirl backward at w_b and forward at w_f = (-+Ip Omega + sqrt(Ip^2 Omega^2
    + 4 Id k_r)) / (2 Id) (model docstring), circles (whirl_ratio -+1); the translation pair at sqrt(k_t/m)
    stays (backward, forward). Frequencies to 1e-12 relative."""
    m, Ip, Id, k_t, k_r, speed = 10.0, 0.2, 0.1, 4.0e5, 2.0e4, 600.0
    res = mechgen.modes(mechgen.compile("laval_rotor", {"Omega": speed}, backend="numpy"))
    root = np.sqrt(Ip**2 * speed**2 + 4 * Id * k_r)
    wb, wf, wt = (-Ip * speed + root) / (2 * Id), (Ip * speed + root) / (2 * Id), np.sqrt(k_t / m)
    np.testing.assert_allclose(res["frequencies"], [wb, wt, wt, wf], rtol=1e-12)
    assert res["whirl"] == ["backward", "backward", "forward", "forward"]
    np.testing.assert_allclose(res["whirl_ratio"], [-1.0, -1.0, 1.0, 1.0], rtol=1e-12)


def test_whirl_pair_adds_stations_and_refuses_a_repeated_name():
    from mechgen import Model
    from mechgen.errors import ModelError

    model = Model("pairs", doc="two stations")
    model.coordinates("x", "y", "u", "v")
    model.whirl_pair("x", "y")
    model.whirl_pair("u", "v")
    assert model.whirl == ("x", "y", "u", "v")
    with pytest.raises(ModelError, match="repeats a name"):
        model.whirl_pair("x", "v")
