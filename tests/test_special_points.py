"""Special points of equilibrium branches (issue 27, item 3): folds (LP), branch points (BP, with switching) and
Hopf points (H, with the first Lyapunov coefficient), on models the tests write.

References (closed forms):

* Pitchfork: x'' + c x' + (k - P) x + a x^3 = 0. The trivial branch x = 0 meets the side branch
  x^2 = (P - k) / a at P = k (a BP). Along the side branch F_y = k - P + 3 a x^2 = 2 a x^2 >= 0 never changes
  sign, so a test that counts unstable eigenvalues misses the BP there (BifurcationKit #223); the bordered
  determinant does not.
* Hopf: the Rayleigh oscillator x'' + w0^2 x = (mu + beta x^2) x'. Its equilibrium x = 0 loses stability at
  mu = 0 through the pair +-i w0. Averaging (x = r cos phi, x' = -r w0 sin phi) gives dr/dt = mu r / 2 +
  beta r^3 / 8, so the cycle is born supercritically for beta < 0 and subcritically for beta > 0. The first
  Lyapunov coefficient with Kuznetsov's normalisation (<q, q> = 1, q = (1, i w0) / sqrt(1 + w0^2), so that
  x's amplitude is r = 2 |z| / sqrt(1 + w0^2)) is l1 = Re c1 / w0 = beta / (2 w0 (1 + w0^2)).
* Rotor with internal (rotating) damping: the Jeffcott rotor m r'' + (c_e + c_i) r' + k r - i c_i W r = 0 in
  complex form (r = x + i y) becomes unstable at the onset speed W = w_n (1 + c_e / c_i), w_n = sqrt(k / m)
  (Crandall; Genta, Dynamics of Rotating Systems, sec. 8.3): a Hopf point in the speed with the whirl frequency
  w_n.
"""
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.runtime.steady.special_points import first_lyapunov, hopf_sign

PITCHFORK = '''"""x'' + c x' + (k - P) x + a x^3 = 0."""
from mechgen import Model, Param

model = Model("pitchfork", doc=__doc__)
model.params(Param("P", 0.5), Param("k", 1.0), Param("a", 2.0), Param("c", 0.1))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: (p.k - p.P) * q.x**2 / 2 + p.a * q.x**4 / 4)
model.dissipation(lambda v, p: p.c * v.x**2 / 2)
'''

RAYLEIGH = '''"""x'' + w0^2 x = (mu + beta x^2) x'."""
from mechgen import Model, Param

model = Model("rayleigh", doc=__doc__)
model.params(Param("mu", -0.5), Param("w0", 1.5), Param("beta", -1.0))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: p.w0**2 * q.x**2 / 2)


@model.forces
def forces(q, v, p):
    return {"x": (p.mu + p.beta * q.x**2) * v.x}
'''

ROTOR = '''"""Jeffcott rotor with external damping c_e and internal (rotating) damping c_i at speed W."""
from mechgen import Model, Param

model = Model("jeffcott_internal", doc=__doc__)
model.params(Param("m", 2.0), Param("k", 800.0), Param("c_e", 0.4), Param("c_i", 1.6), Param("W", 5.0))
model.coordinates("x", "y")
model.kinetic(lambda v, p: p.m * (v.x**2 + v.y**2) / 2)
model.potential(lambda q, p: p.k * (q.x**2 + q.y**2) / 2)


@model.dissipation
def dissipation(q, v, p):
    # external damping on the absolute velocity, internal damping on the velocity seen in the rotating frame
    return p.c_e * (v.x**2 + v.y**2) / 2 + p.c_i * ((v.x + p.W * q.y)**2 + (v.y - p.W * q.x)**2) / 2
'''


def scene(tmp_path, model: str, name: str, guess: str, parameter: str, stop: float, extra: str = "") -> str:
    (tmp_path / f"{name}.py").write_text(model)
    path = tmp_path / f"{name}.toml"
    path.write_text(f'''model = "{name}.py"
backend = "numpy"
[[analysis]]
name = "eq"
kind = "steady"
guess = {{ {guess} }}
[[analysis]]
name = "cont"
kind = "continuation"
about = "eq"
parameter = "{parameter}"
stop = {stop}
{extra}
''')
    return str(path)


def continuation_outputs(path: str) -> dict:
    return mechgen.run(path)["analyses"][1]["outputs"]


def test_pitchfork_found_on_the_trivial_branch_and_switched(tmp_path):
    """The BP at P = k to 1e-8 (bisection to 1e-10 of a segment of length <= 0.1); switching follows the side
    branch, whose every point satisfies x^2 = (P - k) / a to the corrector's 1e-10."""
    out = continuation_outputs(scene(tmp_path, PITCHFORK, "pitchfork", "x = 0.0", "P", 2.0,
                                     "switch_branches = true\nmax_step = 0.1"))
    bps = [s for s in out["special_points"] if s["type"] == "BP"]
    assert len(bps) == 1 and bps[0]["P"] == pytest.approx(1.0, abs=1e-8)
    # the other branch leaves the BP perpendicular to the parameter (a pitchfork: dP/dx = 0 at x = 0)
    assert abs(bps[0]["direction"]["x"]) == pytest.approx(1.0, abs=1e-6)
    halves = out["switched_branches"]
    assert [h["half"] for h in halves] == ["+", "-"]
    for h in halves:
        xs = np.array([p["coordinates"]["x"] for p in h["branch"]])
        P = np.array([p["P"] for p in h["branch"]])
        assert len(xs) > 5 and np.all(np.sign(xs) == np.sign(xs[0]))
        assert np.max(np.abs(xs**2 - (P - 1.0) / 2.0)) < 1e-9
    assert not [s for s in out["special_points"] if s["type"] in ("H", "LP")]


def test_pitchfork_found_along_the_side_branch_where_no_eigenvalue_changes_sign(tmp_path):
    """Starting on the side branch at P = 2 and going down, F_y = 2 a x^2 >= 0 all along (no eigenvalue changes
    sign), yet the bordered determinant finds the BP at P = k, x = 0 (to 1e-6 in x: it is a point of the side
    branch where P - k = a x^2, so P is met to a x^2 ~ 1e-12)."""
    out = continuation_outputs(scene(tmp_path, PITCHFORK.replace('Param("P", 0.5)', 'Param("P", 2.0)'),
                                     "side", "x = 0.7", "P", 0.5, "max_points = 80\nmax_step = 0.1"))
    xs = [p["coordinates"]["x"] for p in out["branch"]]
    assert min(xs) < 0 < max(xs)   # the branch passed through the BP onto the other half
    assert [s["type"] for s in out["special_points"]] == ["BP"]   # the turn of P at the BP is no fold
    bps = out["special_points"]
    assert bps[0]["coordinates"]["x"] == pytest.approx(0.0, abs=1e-6)
    assert bps[0]["P"] == pytest.approx(1.0, abs=1e-8)


@pytest.mark.parametrize("beta", [-1.0, 0.5])
def test_hopf_point_and_its_first_lyapunov_coefficient(tmp_path, beta):
    """H at mu = 0 (to 1e-8), omega = w0 (to 1e-8), l1 = beta / (2 w0 (1 + w0^2)) (to 1e-6: central differences
    of the exact Jacobian with step 1e-3; the field is cubic, so they are exact up to round-off ~1e-10) and its
    criticality from the sign."""
    model = RAYLEIGH.replace('Param("beta", -1.0)', f'Param("beta", {beta})')
    out = continuation_outputs(scene(tmp_path, model, "rayleigh", "x = 0.0", "mu", 0.5))
    (h,) = [s for s in out["special_points"] if s["type"] == "H"]
    w0 = 1.5
    assert h["mu"] == pytest.approx(0.0, abs=1e-8)
    assert h["frequency"] == pytest.approx(w0, rel=1e-8)
    assert h["lyapunov"] == pytest.approx(beta / (2 * w0 * (1 + w0**2)), rel=1e-6)
    assert h["criticality"] == ("supercritical" if beta < 0 else "subcritical")
    change = out["stability_changes"][0]
    assert change["mu"] == pytest.approx(0.0, abs=1e-7) and change["to"] == "flutter"


def test_rotor_onset_speed_of_internal_damping_is_a_hopf_point(tmp_path):
    """The whirl instability's onset W = w_n (1 + c_e / c_i) = 20 * 1.25 = 25 rad/s (to 1e-7 relative) with the
    frequency w_n = 20 rad/s (the forward whirl that loses its damping)."""
    out = continuation_outputs(scene(tmp_path, ROTOR, "rotor", "x = 0.0, y = 0.0", "W", 40.0, "max_step = 2.0"))
    hopf = [s for s in out["special_points"] if s["type"] == "H"]
    assert len(hopf) == 1
    assert hopf[0]["W"] == pytest.approx(25.0, rel=1e-7)
    assert hopf[0]["frequency"] == pytest.approx(20.0, rel=1e-7)


def test_lyapunov_coefficient_of_the_normal_form():
    """x' = -w y + s x r^2, y' = w x + s y r^2 is z' = i w z + s z |z|^2 (z = x + i y); with <q, q> = 1 the
    state's z is sqrt(2) times Kuznetsov's, so l1 = 2 s / w exactly (a cubic field: the differences are exact)."""
    s, w = -0.3, 1.7

    def jacobian(v):
        x, y = v
        r2 = x * x + y * y
        return np.array([[s * (r2 + 2 * x * x), -w + 2 * s * x * y], [w + 2 * s * x * y, s * (r2 + 2 * y * y)]])

    omega, l1 = first_lyapunov(jacobian, np.zeros(2))
    assert omega == pytest.approx(w, rel=1e-12)
    assert l1 == pytest.approx(2 * s / w, rel=1e-8)


def test_hopf_test_function_ignores_a_neutral_saddle():
    """The bialternate product's sign: a pair crossing the axis flips it; +-mu real keeps the product of the
    others' sign but vanishes (a neutral saddle is a zero, told apart by is_hopf at the located point)."""
    assert hopf_sign([-0.1 + 1j, -0.1 - 1j, -2.0]) == -hopf_sign([0.1 + 1j, 0.1 - 1j, -2.0])
    assert hopf_sign([1.0, -1.0, -3.0]) == 0


def test_switch_branches_is_refused_for_a_boundary_value_branch():
    """switch_branches about a boundary-value steady state: a SceneError (exit 2) at the key, before any work."""
    from mechgen.analyses.continuation import run_continuation
    from mechgen.errors import SceneError

    with pytest.raises(SceneError) as err:
        run_continuation(None, {"about": "start", "parameter": "lambda0", "stop": 0.2, "switch_branches": True},
                         {"start": {"_bvp": object(), "_result": object()}})
    assert err.value.key == "switch_branches" and "Newton steady states only" in str(err.value)


def test_folds_are_special_points_and_nothing_else_is(tmp_path):
    """The snap-through branch lam = x^3 - x (tests/test_newton_continuation.py): two LP at lam = +-2/(3 sqrt 3)
    (to 1e-10, the folds' own accuracy), no BP and no H (the spectrum is real on this undamped branch: +-i w or
    +-mu pairs, whose sums never change sign except through the folds' zero eigenvalue, no pair +-i w there)."""
    from test_newton_continuation import snap_scene

    out = mechgen.run(snap_scene(tmp_path))["analyses"][1]["outputs"]
    assert [s["type"] for s in out["special_points"]] == ["LP", "LP"]
    fold = 2 / 3**1.5
    assert [s["lam"] for s in out["special_points"]] == pytest.approx([fold, -fold], abs=1e-10)


def test_shipped_rotor_scene_reports_the_onset_speed():
    """scenes/rotor_internal_damping.toml (the built-in laval_rotor with c_i): H at Omega = sqrt(k_t/m)(1 + c/c_i)
    = 250 rad/s with the whirl frequency 200 rad/s (to 1e-8 relative: bisection to 1e-10 of a segment, then the
    secant on Re of the critical pair); the hardening shaft (k_t3 > 0) makes it supercritical (l1 < 0: the bounded
    whirl of scenes/rotor_whirl_limit_cycle.toml is born there)."""
    from pathlib import Path

    scene = Path(__file__).resolve().parents[1] / "scenes" / "rotor_internal_damping.toml"
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    (h,) = out["special_points"]
    assert h["type"] == "H" and h["Omega"] == pytest.approx(250.0, rel=1e-8)
    assert h["frequency"] == pytest.approx(200.0, rel=1e-8)
    assert h["criticality"] == "supercritical" and h["lyapunov"] < 0
    curve = mechgen.run(str(scene))["analyses"][2]["outputs"]["curve"]
    c_i = np.array([p["c_i"] for p in curve])
    assert c_i[-1] == 320.0
    assert np.max(np.abs(np.array([p["Omega"] for p in curve]) / (200.0 * (1 + 20.0 / c_i)) - 1)) < 1e-8


CUSP = '''"""x'' + c x' + x^3 - mu x - lam = 0: V = x^4/4 - mu x^2/2 - lam x."""
from mechgen import Model, Param

model = Model("cusp", doc=__doc__)
model.params(Param("lam", -1.0), Param("mu", 1.0), Param("c", 0.2))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: q.x**4 / 4 - p.mu * q.x**2 / 2 - p.lam * q.x)
model.dissipation(lambda v, p: p.c * v.x**2 / 2)
'''


def curve_scene(tmp_path, model: str, name: str, guess: str, first: str, first_stop: float, second: str,
                second_stop: float, extra: str = "") -> str:
    path = scene(tmp_path, model, name, guess, first, first_stop, extra)
    with open(path, "a") as f:
        f.write(f'''[[analysis]]
name = "curve"
kind = "continuation"
about = "cont"
special_point = 1
parameter = "{second}"
stop = {second_stop}
max_step = 0.2
''')
    return path


def test_fold_curve_of_the_cusp(tmp_path):
    """The fold curve of x^3 - mu x - lam = 0 in (lam, mu): 3 x^2 = mu and lam = -2 x^3 (so lam^2 = 4 (mu/3)^3),
    every point to 1e-9 (the corrector's 1e-10 on the augmented residual, whose g is a bordered solve)."""
    out = mechgen.run(curve_scene(tmp_path, CUSP, "cusp", "x = -1.3", "lam", 1.0, "mu", 3.0))["analyses"][2]["outputs"]
    assert out["type"] == "LP" and out["parameters"] == ["lam", "mu"] and out["status"] == "lam_max"
    x = np.array([p["coordinates"]["x"] for p in out["curve"]])
    mu = np.array([p["mu"] for p in out["curve"]])
    lam = np.array([p["lam"] for p in out["curve"]])
    assert mu[-1] == 3.0 and len(mu) > 5
    assert np.max(np.abs(3 * x**2 - mu)) < 1e-9
    assert np.max(np.abs(lam + 2 * x**3)) < 1e-9


def test_hopf_curve_of_the_rotor_onset_speed(tmp_path):
    """The onset speed W = w_n (1 + c_e / c_i) of a Jeffcott rotor with internal damping, followed in c_i from 1.6
    to 4 (to 1e-8 relative at every point), the whirl frequency w_n = 20 rad/s all along."""
    path = curve_scene(tmp_path, ROTOR, "rotor", "x = 0.0, y = 0.0", "W", 40.0, "c_i", 4.0, "max_step = 2.0")
    out = mechgen.run(path)["analyses"][2]["outputs"]
    assert out["type"] == "H" and out["status"] == "lam_max"
    c_i = np.array([p["c_i"] for p in out["curve"]])
    W = np.array([p["W"] for p in out["curve"]])
    assert c_i[-1] == 4.0 and len(c_i) > 3
    assert np.max(np.abs(W / (20.0 * (1 + 0.4 / c_i)) - 1)) < 1e-8
    assert np.max(np.abs(np.array([p["frequency"] for p in out["curve"]]) - 20.0)) < 1e-7


def test_special_point_curve_refuses_a_branch_point_and_a_missing_index(tmp_path, capsys):
    """special_point naming a BP, or past the list: exit 2 at the key; special_point about a steady: exit 2."""
    from mechgen.cli import main

    path = curve_scene(tmp_path, PITCHFORK, "pitchfork", "x = 0.0", "P", 2.0, "a", 3.0)
    assert main(["run", path]) == 2
    err = capsys.readouterr().err
    assert "special_point" in err and "BP" in err and "Traceback" not in err
    text = open(path).read()
    open(path, "w").write(text.replace('about = "cont"\nspecial_point = 1', 'about = "eq"\nspecial_point = 1'))
    assert main(["run", path]) == 2
    assert "special_point" in capsys.readouterr().err


def test_rotor_whirl_limit_cycle_beyond_the_onset():
    """scenes/rotor_whirl_limit_cycle.toml: at Omega = 300 rad/s the whirl is the circle r = R exp(i w t) with
    w = c_i Omega / (c + c_i) = 240 rad/s and R^2 = (m w^2 - k_t) / k_t3 = 1e-4 m^2 (closed form: the damping
    forces and the elastic and centripetal forces balance on the circle), to 1e-8 relative (shooting at Newton rtol
    1e-9); the tilts stay at rest and the whirl is stable."""
    from pathlib import Path

    scene = Path(__file__).resolve().parents[1] / "scenes" / "rotor_whirl_limit_cycle.toml"
    out = mechgen.run(str(scene))["analyses"][0]["outputs"]
    assert out["frequency"] == pytest.approx(240.0, rel=1e-8)
    assert out["amplitude"]["x"] == pytest.approx(0.01, rel=1e-8)
    assert out["amplitude"]["y"] == pytest.approx(0.01, rel=1e-8)
    assert out["amplitude"]["theta_x"] < 1e-12 and out["stability"] == "stable"


def test_limit_cycles_born_at_a_hopf_point(tmp_path):
    """The Rayleigh oscillator x'' + x = (mu + beta x^2) x' (beta = -1): continuing its Hopf point in mu itself
    starts the branch of limit cycles from the normal form and follows it to mu = 0.5. Averaging gives the cycle
    x = 2 sqrt(-mu/beta) cos t + O(mu) with the period 2 pi (1 + mu^2/16 + O(mu^4)): the amplitudes to
    1e-2 mu^2 relative (the next averaging order, measured 5e-3 mu^2) and the periods to 2 pi mu^4 / 100
    (measured 2 pi 1.1e-4 at mu = 0.5 = 2 pi 1.7e-3 mu^4); all stable (a supercritical point: l1 = -1/4). On the
    C backend, as a user runs orbits (shooting's flow in the compiled loop; on numpy's it runs in Python)."""
    model = RAYLEIGH.replace('Param("w0", 1.5)', 'Param("w0", 1.0)')
    path = scene(tmp_path, model, "rayleigh", "x = 0.0", "mu", 0.5)
    Path(path).write_text(Path(path).read_text().replace('backend = "numpy"', 'backend = "c"'))
    with open(path, "a") as f:
        f.write('''[[analysis]]
name = "cycles"
kind = "continuation"
about = "cont"
special_point = 1
parameter = "mu"
stop = 0.5
max_step = 0.05
''')
    out = mechgen.run(path)["analyses"][2]["outputs"]
    assert out["hopf"]["lyapunov"] == pytest.approx(-0.25, rel=1e-6) and out["status"] == "lam_max"
    for p in out["branch"]:
        mu = p["mu"]
        assert p["amplitude"]["x"] / (2 * mu**0.5) - 1 == pytest.approx(0.0, abs=1e-2 * mu**2 + 1e-7)
        assert p["period"] == pytest.approx(2 * np.pi * (1 + mu**2 / 16), abs=2 * np.pi * mu**4 / 100 + 1e-8)
        assert p["stability"] == "stable"


def test_no_cycles_from_a_degenerate_hopf_point(tmp_path, capsys):
    """The linear rotor's Hopf point (l1 = 0: no cycle is born) cannot start a branch of cycles: exit 2 at
    special_point."""
    from mechgen.cli import main

    path = scene(tmp_path, ROTOR, "rotor", "x = 0.0, y = 0.0", "W", 40.0, "max_step = 2.0")
    with open(path, "a") as f:
        f.write('''[[analysis]]
name = "cycles"
kind = "continuation"
about = "cont"
special_point = 1
parameter = "W"
stop = 40.0
''')
    assert main(["run", path]) == 2
    err = capsys.readouterr().err
    assert "special_point" in err and "degenerate" in err and "Traceback" not in err


def test_van_der_pol_limit_cycle_from_its_hopf_point():
    """scenes/van_der_pol_from_hopf.toml: x'' - (mu - x^2) x' + x = 0 is van der Pol's equation for y = x / sqrt(mu),
    so the cycle followed from the Hopf point at mu = 0 reaches at mu = 1 van der Pol's period 6.6632868593
    (Andersen & Geer 1982; to 1e-8) and amplitude, the van der Pol cycle's max |y| at mu = 1, computed here by
    scipy (the settled cycle's maximum located on the dense output; to 1e-8)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import minimize_scalar
    from pathlib import Path

    scene = Path(__file__).resolve().parents[1] / "scenes" / "van_der_pol_from_hopf.toml"
    _, onset, cycles = (a["outputs"] for a in mechgen.run(str(scene))["analyses"])
    (h,) = onset["special_points"]
    assert h["type"] == "H" and h["mu"] == pytest.approx(0.0, abs=1e-9) and h["criticality"] == "supercritical"
    last = cycles["branch"][-1]
    assert last["mu"] == 1.0
    assert last["period"] == pytest.approx(6.6632868593, abs=1e-8)
    sol = solve_ivp(lambda t, y: [y[1], (1 - y[0] ** 2) * y[1] - y[0]], (0.0, 120.0), [2.0, 0.0], method="DOP853",
                    rtol=1e-12, atol=1e-14, dense_output=True)
    t = np.linspace(100.0, 100.0 + 6.7, 6701)
    k = int(np.argmax(np.abs(sol.sol(t)[0])))
    best = minimize_scalar(lambda s: -abs(sol.sol(s)[0]), bounds=(t[k - 1], t[k + 1]), method="bounded",
                           options={"xatol": 1e-12})
    assert last["amplitude"]["x"] == pytest.approx(-best.fun, abs=1e-8)


@pytest.mark.parametrize("step", [0.1, 0.3])
def test_a_branch_that_steps_through_the_hopf_point_ends_there_without_a_fold(tmp_path, step):
    """The limit cycles of x'' - (mu - x^2) x' + x = 0 followed from mu = 1 down towards their Hopf point at mu = 0
    with steps large enough to cross it: near it the orbits are A cos(t) + O(A^2) with mu even in A, so a step
    across A = 0 lands on the same orbit half a period on, where mu turns back. The branch must end there (status
    equilibrium, mu decreasing all along, no cyclic fold). Before, it reported an LPC at mu = 0.035 and went back
    up to mu = 85 along the same orbits. Reference: x = sqrt(mu) y with y van der Pol's cycle of parameter mu,
    whose amplitude is 2 + O(mu^2): the last orbit's amplitude is 2 sqrt(mu) to 1e-4 at mu < 0.1."""
    path = tmp_path / "vdp_down.toml"
    path.write_text(f"""model = "van_der_pol_hopf"
backend = "c"
[params]
mu = 1.0
[[analysis]]
name = "cycle"
kind = "periodic_orbit"
method = "collocation"
mesh = 40
period = 6.6
q0 = {{ x = 2.0 }}
[[analysis]]
name = "down"
kind = "continuation"
about = "cycle"
parameter = "mu"
stop = -0.5
step = {step}
max_step = 1.0
""")
    down = mechgen.run(str(path))["analyses"][1]["outputs"]
    assert down["status"] == "equilibrium" and down["special_points"] == [] and down["folds"] == []
    mu = np.array([point["mu"] for point in down["branch"]])
    assert np.all(np.diff(mu) < 0) and 0.0 < mu[-1] < 0.1
    last = down["branch"][-1]
    assert last["amplitude"]["x"] == pytest.approx(2.0 * np.sqrt(last["mu"]), rel=1e-4)
    assert last["period"] == pytest.approx(2 * np.pi, rel=0.01)


def test_bisection_is_bounded_when_corrected_points_leave_the_bracket(monkeypatch):
    """A fold cascade (js_fluid past its first fold) once made the BP bisection loop for minutes: the points corrected
    onto the branch jumped to another sheet, so the bracket's length never shrank. The location now stops after
    BISECT_STEPS halvings and returns the secant point between the last two corrected points."""
    from mechgen.runtime.steady import branch_scan, special_points

    calls = []

    def jumping(eqs, xa, xb, theta):  # every "corrected" point lands a unit away from both ends
        calls.append(theta)
        return np.array([float(len(calls) % 2) + 5.0, 1.0])

    monkeypatch.setattr(branch_scan, "point_between", jumping)
    values = iter([1.0, -1.0] + [1.0] * 1000)
    x = special_points.bisect(None, np.zeros(2), np.ones(2), lambda x: next(values))
    assert len(calls) == special_points.BISECT_STEPS
    assert np.all(np.isfinite(x))
