"""Branches of periodic orbits (issue 27, items 2 and 3): continuation about a periodic_orbit, with cyclic folds.

References:

* The forced Duffing oscillator x'' + c x' + x + k3 x^3 = F cos(w t) (c = 0.1, k3 = 1, F = 0.3): its
  frequency-response curve bends right and folds twice. At a cyclic fold (LPC) the monodromy matrix has the
  eigenvalue 1 exactly (the shooting Jacobian Phi - I is singular there) - a property, not a fitted number; the
  orbits between the folds are unstable (one multiplier above 1), those outside stable. Points of the curve are
  checked against an independent shooting written here (scipy's solve_ivp DOP853 at rtol 1e-12 on the hand-written
  equation, scipy.optimize.fsolve on x(T) - x0).
* The van der Pol oscillator x'' - mu (1 - x^2) x' + x = 0: the period 6.6632868593 at mu = 1 (Andersen & Geer,
  SIAM J. Appl. Math. 42, 1982) and T = 2 pi (1 + mu^2/16 - 5 mu^4/3072 + O(mu^6)) for small mu.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

import mechgen
from mechgen.cli import main

C, K3, F = 0.1, 1.0, 0.3

DUFFING = f'''"""x'' + c x' + x + k3 x^3 = F cos(w t)."""
import sympy as sp
from mechgen import Model, Param

model = Model("frc_duffing", doc=__doc__)
model.params(Param("c", {C}), Param("k3", {K3}), Param("F", {F}), Param("w", 0.6))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q, p: q.x**2 / 2 + p.k3 * q.x**4 / 4)
model.dissipation(lambda v, p: p.c * v.x**2 / 2)


@model.forces
def drive(p, t):
    return {{"x": p.F * sp.cos(p.w * t)}}
'''


def frc_scene(tmp_path, method: str, extra: str = "") -> str:
    (tmp_path / "duffing.py").write_text(DUFFING)
    path = tmp_path / f"frc_{method}.toml"
    path.write_text(f'''model = "duffing.py"
backend = "c"
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "{method}"
frequency = "w"
{"mesh = 40" if method == "collocation" else "harmonics = 9"}
[[analysis]]
name = "frc"
kind = "continuation"
about = "orbit"
parameter = "w"
stop = 2.5
max_step = 0.05
max_points = 400
{extra}
''')
    return str(path)


def hand_orbit(w: float, x0: np.ndarray) -> tuple[np.ndarray, float]:
    """(x0, max |x|) of the forced orbit at w by hand-written shooting from the guess x0."""
    T = 2 * math.pi / w

    def rhs(t, y):
        return [y[1], F * math.cos(w * t) - C * y[1] - y[0] - K3 * y[0] ** 3]

    def flow(x, times=None):
        sol = solve_ivp(rhs, (0.0, T), x, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=times)
        return sol.y

    start = fsolve(lambda x: flow(x)[:, -1] - x, x0, xtol=1e-13)
    dense = solve_ivp(rhs, (0.0, T), start, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True).sol
    grid = np.linspace(0.0, T, 4001)
    k = int(np.argmax(np.abs(dense(grid)[0])))
    from scipy.optimize import minimize_scalar

    best = minimize_scalar(lambda t: -abs(dense(t)[0]), bounds=(grid[max(k - 1, 0)], grid[min(k + 1, 4000)]),
                           method="bounded", options={"xatol": 1e-12})
    return start, float(-best.fun)


@pytest.fixture(scope="module")
def curves(tmp_path_factory):
    folder = tmp_path_factory.mktemp("frc")
    return {m: mechgen.run(frc_scene(folder, m))["analyses"][1]["outputs"]
            for m in ("shooting", "harmonic_balance", "collocation")}


def test_duffing_response_curve_folds(curves):
    """Two cyclic folds on each method's curve; at shooting's the largest multiplier is 1 (to 1e-6: the monodromy
    by central differences of the compiled flow, ~1e-10, at a fold located by Brent to ~1e-14 in arclength); the
    three methods' folds agree to 1e-6 in w (harmonic balance with H = 9: its truncation, measured 5e-10;
    collocation on 40 intervals)."""
    folds = {m: [s for s in out["special_points"] if s["type"] == "LPC"] for m, out in curves.items()}
    assert all(len(f) == 2 for f in folds.values())
    for fold in folds["shooting"]:
        assert max(abs(complex(*mu)) for mu in fold["multipliers"]) == pytest.approx(1.0, abs=1e-6)
    for a, b, c in zip(folds["shooting"], folds["harmonic_balance"], folds["collocation"]):
        assert a["w"] == pytest.approx(b["w"], abs=1e-6)
        assert a["w"] == pytest.approx(c["w"], abs=1e-6)  # collocation, 40 intervals of degree 4 (order 8)
    assert sorted(f["w"] for f in folds["shooting"]) == pytest.approx([1.3242362, 1.7797195], abs=1e-6)


def test_duffing_response_curve_points_and_stability(curves):
    """Every shooting point between the folds (in branch order) is unstable and every other stable; three points'
    amplitudes equal the hand-written shooting's at the same w (to 1e-8; measured 1e-11), and harmonic balance's
    (H = 9) to 1e-6 (its truncation, largest near the resonance: measured 3e-8)."""
    out = curves["shooting"]
    points = out["branch"]
    folds = [s["w"] for s in out["special_points"]]
    index = [min(range(len(points)), key=lambda i: abs(points[i]["w"] - f) + 10 * (i < j))
             for j, f in enumerate(folds)]
    first, last = sorted(index)
    for i, p in enumerate(points):
        if i < first - 1 or i > last + 1:
            assert p["stability"] == "stable", p
        elif first + 1 < i < last - 1:
            assert p["stability"] == "unstable", p
    hb = curves["harmonic_balance"]["branch"]
    for k in (10, len(points) // 2, len(points) - 10):
        p = points[k]
        start, amplitude = hand_orbit(p["w"], np.array([p["start"]["x"], p["start"]["x_dot"]]))
        assert [p["start"]["x"], p["start"]["x_dot"]] == pytest.approx(start, abs=1e-8)
        assert p["amplitude"]["x"] == pytest.approx(amplitude, abs=1e-8)
    for k in (10, len(hb) // 2, len(hb) - 10):
        q = hb[k]
        _, amplitude = hand_orbit(q["w"], np.array([q["start"]["x"], q["start"]["x_dot"]]))
        assert q["amplitude"]["x"] == pytest.approx(amplitude, abs=1e-6)


def test_van_der_pol_period_along_mu(tmp_path):
    """The limit cycle continued in mu from 1 down to 0.2 by shooting: T(1) = 6.6632868593 (to 1e-8) and
    T(0.2) = 2 pi (1 + mu^2/16 - 5 mu^4/3072) (to 1e-6: the next term, O(mu^6) ~ 1e-6)."""
    scene = tmp_path / "vdp.toml"
    scene.write_text('''model = "van_der_pol"
backend = "c"
[params]
mu = 1.0
[[analysis]]
name = "cycle"
kind = "periodic_orbit"
method = "shooting"
period = 6.5
q0 = { x = 2.0 }
[[analysis]]
name = "branch"
kind = "continuation"
about = "cycle"
parameter = "mu"
stop = 0.2
max_step = 0.1
''')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    points = out["branch"]
    assert points[0]["mu"] == 1.0 and points[-1]["mu"] == 0.2 and out["status"] == "lam_min"
    assert points[0]["period"] == pytest.approx(6.6632868593, abs=1e-8)
    mu = 0.2
    assert points[-1]["period"] == pytest.approx(2 * math.pi * (1 + mu**2 / 16 - 5 * mu**4 / 3072), abs=1e-6)
    assert all(p["stability"] == "stable" for p in points)


def test_orbit_branch_refuses_equilibrium_keys(tmp_path, capsys):
    """A key of equilibrium branches (minimize) on an orbit branch: exit 2 naming it."""
    assert main(["run", frc_scene(tmp_path, "shooting", 'minimize = "x"')]) == 2
    err = capsys.readouterr().err
    assert "minimize" in err and "Traceback" not in err


def test_fold_curve_of_the_response_in_frequency_and_forcing(tmp_path):
    """The upper cyclic fold of the Duffing curve followed in (w, F) by harmonic balance (H = 9): at every point a
    multiplier is 1 (to 1e-5: harmonic balance's truncation at the largest amplitudes; a fold of a converged orbit
    has one exactly); F has a minimum along the curve, the cusp where the two folds are born, near first-order
    harmonic balance's cusp F = 0.0516, w = 1.0904 (d^2 = 3 c^2 w^2 with d = 1 - w^2, Nayfeh & Mook sec. 4.1;
    to 6 %: the first order's neglected terms at A ~ 0.4); past it the curve returns along the lower fold, which
    at F = 0.3 lies at the lower fold of the response curve (w = 1.3242362, to 1e-3: linear interpolation
    between curve points)."""
    scene = tmp_path / "cusp.toml"
    (tmp_path / "duffing.py").write_text(DUFFING)
    scene.write_text('''model = "duffing.py"
backend = "c"
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "harmonic_balance"
harmonics = 9
frequency = "w"
[[analysis]]
name = "frc"
kind = "continuation"
about = "orbit"
parameter = "w"
stop = 2.5
max_step = 0.05
max_points = 400
[[analysis]]
name = "fold_curve"
kind = "continuation"
about = "frc"
special_point = 1
parameter = "F"
stop = 0.0
max_step = 0.02
max_points = 130
''')
    out = mechgen.run(str(scene))["analyses"][2]["outputs"]
    assert out["type"] == "LPC" and out["parameters"] == ["w", "F"]
    curve = out["curve"]
    F = np.array([p["F"] for p in curve])
    w = np.array([p["w"] for p in curve])
    for p in curve:
        assert max(abs(complex(*mu)) for mu in p["multipliers"]) == pytest.approx(1.0, abs=1e-5)
    k = int(np.argmin(F))
    assert 0 < k < len(F) - 1 and F[-1] > 0.3
    assert F[k] == pytest.approx(0.0516, rel=0.06) and w[k] == pytest.approx(1.0904, rel=0.01)
    back = slice(k, None)
    assert np.interp(0.3, F[back], w[back]) == pytest.approx(1.3242362, abs=1e-3)


FORCED_VDP = '''"""x'' - mu (1 - x^2) x' + x = F cos(w t)."""
import sympy as sp
from mechgen import Model, Param

model = Model("forced_vdp", doc=__doc__)
model.params(Param("mu", 0.2), Param("F", 0.5), Param("w", 1.1))
model.coordinates("x")
model.kinetic(lambda v: v.x**2 / 2)
model.potential(lambda q: q.x**2 / 2)


@model.forces
def forces(q, v, p, t):
    return {"x": p.mu * (1 - q.x**2) * v.x + p.F * sp.cos(p.w * t)}
'''


def test_torus_point_of_the_forced_van_der_pol_oscillator(tmp_path):
    """The entrained orbit of x'' - mu (1 - x^2) x' + x = F cos(w t) (mu = 0.2, w = 1.1), followed down in F, loses
    stability through a Neimark-Sacker point: a complex pair of multipliers on the unit circle. Liouville's formula
    det Phi = exp(mu int (1 - x^2) dt) makes |mu_1 mu_2| = 1 there exactly when the orbit's mean of x^2 is 1: checked
    on the orbit integrated here by scipy from the point's start state (to 1e-6), and the pair's modulus from a
    hand-written monodromy (central differences of scipy's flow) to 1e-6."""
    (tmp_path / "fvdp.py").write_text(FORCED_VDP)
    scene = tmp_path / "ns.toml"
    scene.write_text('''model = "fvdp.py"
backend = "c"
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "shooting"
frequency = "w"
q0 = { x = 2.0 }
[[analysis]]
name = "branch"
kind = "continuation"
about = "orbit"
parameter = "F"
stop = 0.1
max_step = 0.02
''')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    (ns,) = [s for s in out["special_points"] if s["type"] == "NS"]
    F_ns, T = ns["F"], ns["period"]
    assert T == pytest.approx(2 * math.pi / 1.1, rel=1e-14)

    def rhs(t, y):
        return [y[1], 0.2 * (1 - y[0] ** 2) * y[1] - y[0] + F_ns * math.cos(1.1 * t)]

    x0 = np.array([ns["start"]["x"], ns["start"]["x_dot"]])
    sol = solve_ivp(rhs, (0.0, T), x0, method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True)
    assert np.max(np.abs(sol.y[:, -1] - x0)) < 1e-8  # a periodic orbit of the hand-written equation
    t = np.linspace(0.0, T, 20001)
    x = sol.sol(t)[0]
    from scipy.integrate import simpson

    mean_square = simpson(x**2, x=t) / T
    assert mean_square == pytest.approx(1.0, abs=1e-6)
    h = 1e-6
    J = np.column_stack([(solve_ivp(rhs, (0.0, T), x0 + h * e, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
                          - solve_ivp(rhs, (0.0, T), x0 - h * e, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1])
                         / (2 * h) for e in np.eye(2)])
    mu = np.linalg.eigvals(J)
    assert abs(mu[0].imag) > 1e-3 and np.abs(mu) == pytest.approx([1.0, 1.0], abs=1e-6)


def test_period_doubling_of_the_double_well_duffing_and_a_closed_branch(tmp_path):
    """x'' + 0.3 x' - x + x^3 = F cos(1.2 t) (Holmes 1979's double-well oscillator), its orbit in one well followed
    up in F: a PD point (a multiplier -1) near F = 0.2656, checked by a hand-written shooting and monodromy at the
    located F (the real multiplier -1 to 1e-6); the branch, an isola symmetric in F -> -F, closes on itself and the
    continuation says so (status 'closed') instead of running to max_points."""
    scene = tmp_path / "well.toml"
    scene.write_text('''model = "duffing"
backend = "c"
[params]
c = 0.3
k = -1.0
k3 = 1.0
F = 0.05
w = 1.2
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "shooting"
frequency = "w"
q0 = { x = 1.0 }
[[analysis]]
name = "branch"
kind = "continuation"
about = "orbit"
parameter = "F"
stop = 3.0
max_step = 0.05
max_points = 400
''')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    assert out["status"] == "closed" and out["points"] < 400
    pd = min((s for s in out["special_points"] if s["type"] == "PD" and s["F"] > 0), key=lambda s: s["F"])
    F_pd, T = pd["F"], 2 * math.pi / 1.2
    assert F_pd == pytest.approx(0.2656, abs=1e-3)

    def rhs(t, y):
        return [y[1], F_pd * math.cos(1.2 * t) - 0.3 * y[1] + y[0] - y[0] ** 3]

    def flow(x):
        return solve_ivp(rhs, (0.0, T), x, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]

    x0 = fsolve(lambda x: flow(x) - x, [pd["start"]["x"], pd["start"]["x_dot"]], xtol=1e-13)
    h = 1e-6
    J = np.column_stack([(flow(x0 + h * e) - flow(x0 - h * e)) / (2 * h) for e in np.eye(2)])
    mu = np.linalg.eigvals(J)
    assert np.min(mu.real) == pytest.approx(-1.0, abs=1e-6) and np.all(np.abs(mu.imag) < 1e-9)


def test_doubled_orbit_past_the_period_doubling(tmp_path):
    """switch_branches on the double-well Duffing branch: past its first PD point the doubled orbit has period 2T,
    and the hand-written flow maps its start onto itself over 2T (to 1e-8) but not over T."""
    scene = tmp_path / "well2.toml"
    scene.write_text('''model = "duffing"
backend = "c"
[params]
c = 0.3
k = -1.0
k3 = 1.0
F = 0.05
w = 1.2
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "shooting"
frequency = "w"
q0 = { x = 1.0 }
[[analysis]]
name = "branch"
kind = "continuation"
about = "orbit"
parameter = "F"
stop = 0.5
max_step = 0.02
switch_branches = true
''')
    out = mechgen.run(str(scene))["analyses"][1]["outputs"]
    first = out["doubled"][0]
    F_d, T = first["F"], 2 * math.pi / 1.2
    assert first["period"] == pytest.approx(2 * T, rel=1e-14)

    def flow(x, span):
        def rhs(t, y):
            return [y[1], F_d * math.cos(1.2 * t) - 0.3 * y[1] + y[0] - y[0] ** 3]
        return solve_ivp(rhs, (0.0, span), x, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]

    x0 = np.array([first["start"]["x"], first["start"]["x_dot"]])
    assert np.max(np.abs(flow(x0, 2 * T) - x0)) < 1e-8
    assert np.max(np.abs(flow(x0, T) - x0)) > 1e-4


WELL = """model = "duffing"
backend = "c"
[params]
c = 0.3
k = -1.0
k3 = 1.0
F = 0.05
w = 1.2
[[analysis]]
name = "settle"
kind = "simulate"
t_end = 104.71975511965977
q0 = { x = 1.0 }
series = true
samples = 2001
[[analysis]]
name = "orbit"
kind = "periodic_orbit"
method = "METHOD"
EXTRA
frequency = "w"
from = "settle"
[[analysis]]
name = "branch"
kind = "continuation"
about = "orbit"
parameter = "F"
stop = 0.5
max_step = 0.02
switch_branches = true
"""


@pytest.mark.parametrize("method, extra", [("harmonic_balance", "harmonics = 15"), ("collocation", "mesh = 40")])
def test_doubled_orbit_by_harmonic_balance_and_collocation(tmp_path, method, extra):
    """switch_branches on the double-well Duffing branch (the orbit in one well, from a simulate that settled there)
    by harmonic balance (the doubled orbit: 30 harmonics of w/2) and collocation (80 intervals over 2T): the PD point
    agrees with shooting's F = 0.2655817860716 (measured there; to 1e-9: the methods' errors, measured 5e-12), the
    doubled orbit's period is 2T, and its start is the 2T-periodic orbit of a hand-written shooting (scipy DOP853 at
    1e-12, fsolve over 2T) at its F to 1e-9 (measured 1e-12 for both), and not T-periodic."""
    scene = tmp_path / f"well_{method}.toml"
    scene.write_text(WELL.replace("METHOD", method).replace("EXTRA", extra))
    out = mechgen.run(str(scene))["analyses"][-1]["outputs"]
    pd = [s for s in out["special_points"] if s["type"] == "PD"]
    assert pd and pd[0]["F"] == pytest.approx(0.2655817860716, abs=1e-9)
    first = out["doubled"][0]
    F_d, T = first["F"], 2 * math.pi / 1.2
    assert first["period"] == pytest.approx(2 * T, rel=1e-14) and first["at"] == 1

    def flow(x, span):
        def rhs(t, y):
            return [y[1], F_d * math.cos(1.2 * t) - 0.3 * y[1] + y[0] - y[0] ** 3]
        return solve_ivp(rhs, (0.0, span), x, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]

    x0 = np.array([first["start"]["x"], first["start"]["x_dot"]])
    reference = fsolve(lambda x: flow(x, 2 * T) - x, x0, xtol=1e-13)
    assert np.max(np.abs(reference - x0)) < 1e-9
    assert np.max(np.abs(flow(x0, T) - x0)) > 1e-3
