"""Dynamics of the geometrically exact (Cosserat) rod (issue 15 items 4 and 6; mechgen.runtime.rods.dynamics).

References, each independent of the integrator:

* The discrete forces are the exact gradient of the discrete strain energy (central differences of V).
* Euler-Bernoulli cantilever: omega_n = lambda_n^2 sqrt(EI/(rhoA L^4)), lambda_n = 1.87510407, 4.69409113,
  7.85475744 (roots of cos x cosh x = -1), approached at O(h^2) by the linearised elements.
* A suddenly applied small tip load P on that cantilever: with the modes normalised to int phi^2 = L
  (|phi_n(L)| = 2), y_tip(t) = sum_n 4 P/(rhoA L omega_n^2) (1 - cos omega_n t) (modal superposition; its
  static limit is P L^3/(3 EI) since sum 1/lambda_n^4 = 1/12).
* Energy of a free undamped rod conserved to the integrator's order 2 (observed order from three steps).
* Free flight under gravity: the undeformed rod's nodes follow x0 + v0 t + g t^2/2 exactly; a rod spinning
  about its axis at w turns rigidly: R(t) = exp(w t e1), and its rotations stay orthonormal to 1e-12 over
  100 turns.
* Damped motion under its own weight settles on the static solution (rod_statics collocation, 160 elements).
* A stiff rod (EA/EI = 1e8) stepped far above the explicit limit h sqrt(rhoA/EA).
* Newton's refresh rule on the bench's stiff rod: no split steps, bounded solves per step (counts), and the
  trajectory of plain Newton (a Jacobian at every iterate) to tol 1e-13.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import mechgen
from mechgen.cli import main
from mechgen.runtime.rods.dynamics import Discrete, RodBody, linear_frequencies, reference_state, simulate
from mechgen.runtime.rods.liegroup import exp_so3, orthonormality_error
from mechgen.runtime.rods.statics import Rod

SCENES = Path(__file__).resolve().parents[1] / "scenes"
LAMBDA = (1.8751040687119611, 4.6940911329741745, 7.8547574382376126) + tuple((2 * n - 1) * math.pi / 2 for n in range(4, 12))
# lambda_n = (2n - 1) pi/2 + O(e^-lambda_n) for n >= 4 (cos x cosh x = -1): 10.9955407 vs 10.9955743 (3e-6)


def body(EA=1e8, GA=1e8, GJ=1.0, EI=1.0, rhoA=1.0, rhoI=1e-5, rhoJ=2e-5, load=None, tip_force=(0, 0, 0),
         damping=0.0, L=1.0):  # noqa: N803
    K = np.diag([EA, GA, GA, GJ, EI, EI])
    rod = Rod(L, K, load=load, tip_force=np.array(tip_force, dtype=float))
    return RodBody(rod, np.diag([rhoA, rhoA, rhoA, rhoJ, rhoI, rhoI]), damping)


def test_internal_forces_are_the_exact_gradient_of_the_strain_energy():
    b = body(EA=3e2, GA=2e2, GJ=0.7, EI=1.3)
    d = Discrete(b, 7, "free", "free")
    rng = np.random.default_rng(3)
    st = reference_state(b, 7)
    x = st.x + 0.05 * rng.normal(size=st.x.shape)
    R = st.R @ exp_so3(0.8 * rng.normal(size=(8, 3)))          # large relative rotations
    F, Mb, _ = d.internal(x, R)
    e, worst = 1e-6, 0.0
    for i in range(8):
        for k in range(3):
            dx = np.zeros_like(x)
            dx[i, k] = e
            g = (d.elastic_energy(x + dx, R) - d.elastic_energy(x - dx, R)) / (2 * e)
            worst = max(worst, abs(-g - F[i, k]) / np.max(np.abs(F)))
            w = np.zeros((8, 3))
            w[i, k] = e
            g = (d.elastic_energy(x, R @ exp_so3(w)) - d.elastic_energy(x, R @ exp_so3(-w))) / (2 * e)
            worst = max(worst, abs(-g - Mb[i, k]) / np.max(np.abs(Mb)))
    assert worst < 1e-8          # central differences: O(e^2) + round-off/e


def rayleigh(k: int, rho_ratio: float) -> float:
    """omega_k (EI = rhoA = L = 1) with the rotary inertia rhoI = rho_ratio rhoA to first order (Rayleigh
    quotient at the Euler-Bernoulli mode phi = cosh bx - cos bx - s (sinh bx - sin bx)):
    omega^2 = omega_EB^2 / (1 + rho_ratio int phi'^2 / int phi^2)."""
    from scipy.integrate import quad

    lam = LAMBDA[k]
    sig = (math.cosh(lam) + math.cos(lam)) / (math.sinh(lam) + math.sin(lam))
    phi = lambda x: math.cosh(lam * x) - math.cos(lam * x) - sig * (math.sinh(lam * x) - math.sin(lam * x))  # noqa: E731
    dphi = lambda x: lam * (math.sinh(lam * x) + math.sin(lam * x) - sig * (math.cosh(lam * x) - math.cos(lam * x)))  # noqa: E731
    ratio = quad(lambda x: dphi(x) ** 2, 0, 1, epsabs=1e-14)[0] / quad(lambda x: phi(x) ** 2, 0, 1, epsabs=1e-14)[0]
    return lam**2 / math.sqrt(1 + rho_ratio * ratio)


def test_linearised_cantilever_frequencies_converge_to_euler_bernoulli_at_order_two():
    errors = []
    exact = [rayleigh(k, 1e-5) for k in range(3)]          # rhoI/rhoA = 1e-5: shifts of 1.7e-5 .. 3e-4
    for n in (10, 20, 40):
        w = linear_frequencies(Discrete(body(), n), 6)
        # two equal bending planes: each frequency twice (both members checked against the closed form)
        errors.append([abs(w[j] / exact[j // 2] - 1) for j in range(6)])
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(orders[1] > 1.9) and np.all(orders[1] < 2.1), orders     # 20 -> 40 elements
    assert np.all(orders[0] > 1.8) and np.all(orders[0] < 2.3), orders     # mode 3 pre-asymptotic at 10
    assert errors[-1, 0] < 1e-3


def modal_tip(P, t, count=11):
    """y_tip(t) of the Euler-Bernoulli cantilever (EI = rhoA = L = 1) under a tip load P from t = 0, the
    lowest three frequencies with the rotary inertia rhoI = 1e-5 rhoA (:func:`rayleigh`)."""
    omega = [rayleigh(k, 1e-5) if k < 3 else LAMBDA[k] ** 2 for k in range(count)]
    return sum(4 * P / lam**4 * (1 - np.cos(w * t)) for lam, w in zip(LAMBDA[:count], omega))


def test_suddenly_applied_tip_load_follows_the_modal_solution():
    P = 1e-4                                            # linear regime: tip deflection 3e-5 L
    T1 = 2 * math.pi / LAMBDA[0] ** 2
    errs = []
    for n, steps in ((20, 300), (40, 600)):
        b = body(tip_force=(0.0, P, 0.0))
        tr = simulate(Discrete(b, n), reference_state(b, n), dt=T1 / steps, t_end=1.5 * T1, save_every=4)
        t, y = np.array(tr.t), np.array(tr.tip)[:, 1]
        errs.append(np.max(np.abs(y - modal_tip(P, t))) / (P / 3))
        # the dt = T1/200 step is ~1800 times the explicit limit h sqrt(rhoA/EA) = 2.5e-6 s at n = 40
        assert T1 / steps > 1000 * (1 / n) * math.sqrt(1 / 1e8)
    # modes above the 11th carry < 2e-6 of the static deflection; the rest is O(h^2, dt^2), with modes 3-5
    # pre-asymptotic at 20 elements (measured 0.0117 -> 0.0043, a factor 0.37 rather than 0.25)
    assert errs[1] < 0.4 * errs[0] and errs[1] < 5e-3, errs


def free_rod_state(b, n):
    st = reference_state(b, n)
    s = st.x[:, 0]
    st.v = np.stack([0.1 + 0 * s, np.sin(math.pi * s), 0.3 * np.cos(2 * math.pi * s)], axis=1)
    st.w = np.stack([2.0 + 0 * s, 0.5 * np.cos(math.pi * s), 0.2 + 0 * s], axis=1)
    return st


def test_free_undamped_rod_conserves_energy_to_second_order_and_momentum_exactly():
    b = body(EA=400.0, GA=300.0, GJ=0.8, EI=1.0, rhoI=1e-3, rhoJ=2e-3)
    d = Discrete(b, 12, "free", "free")
    errs = []
    for dt in (0.02, 0.01, 0.005):
        tr = simulate(d, free_rod_state(b, 12), dt=dt, t_end=2.0, save_every=int(round(0.02 / dt)))
        E = np.array(tr.energy)
        errs.append(np.max(np.abs(E - E[0])) / E[0])
        fin, st0 = tr.final, free_rod_state(b, 12)
        p0 = np.sum(d.weights[:, None] * st0.v, axis=0)
        assert np.allclose(np.sum(d.weights[:, None] * fin.v, axis=0), p0, atol=1e-12)
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    # pre-asymptotic at dt = 0.02 (2.31), approaching 2 (2.20 at dt = 0.01)
    assert np.all(orders > 1.8) and np.all(orders < 2.4) and abs(orders[1] - 2) < abs(orders[0] - 2), (errs, orders)
    assert errs[0] > 1e-7          # the energy is really exchanged (not a trivially rigid motion)


def test_free_flight_under_gravity_is_an_exact_parabola():
    g = np.array([0.0, -9.81, 0.0])

    def load(r):
        out = np.zeros((len(r), 6))
        out[:, :3] = 2.0 * g
        return out

    b = body(EA=1e3, GA=1e3, rhoA=2.0, load=load)
    d = Discrete(b, 10, "free", "free")
    st = reference_state(b, 10)
    v0 = np.array([1.0, 3.0, -0.5])
    st.v[:] = v0
    tr = simulate(d, st, dt=0.01, t_end=1.0, tol=1e-14)
    exact = reference_state(b, 10).x + v0 * 1.0 + 0.5 * g * 1.0**2
    assert np.max(np.abs(tr.final.x - exact)) < 1e-11          # 100 steps, Newton to 1e-14 L each
    assert np.max(np.abs(tr.final.R - np.eye(3))) < 1e-12


def test_spin_about_the_axis_for_one_hundred_turns_stays_rigid_and_orthonormal():
    b = body(EA=1e3, GA=1e3, GJ=1.0, EI=1.0, rhoI=1e-3, rhoJ=2e-3)
    d = Discrete(b, 8, "free", "free")
    st = reference_state(b, 8)
    w = 2 * math.pi * 10.0                                   # 10 turns per second, for 10 s
    st.w[:, 0] = w
    tr = simulate(d, st, dt=0.004, t_end=10.0, save_every=250)
    assert orthonormality_error(tr.final.R) < 1e-12
    exact = exp_so3(np.array([w * 10.0, 0.0, 0.0]))
    assert np.max(np.abs(tr.final.R - exact)) < 1e-9        # 2500 products: round-off grows ~ steps * eps
    assert np.max(np.abs(tr.final.x - reference_state(b, 8).x)) < 1e-12


def test_dynamic_relaxation_settles_on_the_static_solution_at_order_two():
    """A cantilever under its own weight, q L^3/EI = 3 (large deflection), released from straight, damped
    (c = 4/s) and stepped by backward Euler (alpha = 1, which also damps the stiff modes the sudden load
    rings): at rest it is the static equilibrium, here the rod_statics collocation with 160 elements
    (itself checked against closed forms in tests/test_rod_statics.py: error < 1e-5 here)."""
    from mechgen.runtime.rods.statics import solve_statics

    def load(r):
        out = np.zeros((len(r), 6))
        out[:, 1] = -3.0
        return out

    ref = solve_statics(Rod(1.0, np.diag([1e6, 1e6, 1e6, 1.0, 1.0, 1.0]), load=load), method="collocation",
                        elements=160, steps=5).final.H[-1, :3, 3]
    errs = []
    for n in (10, 20):
        b = body(EA=1e6, GA=1e6, load=load, rhoI=1e-3, rhoJ=2e-3)
        b = RodBody(b.rod, b.M, 4.0, 1.0)
        tr = simulate(Discrete(b, n), reference_state(b, n), dt=0.05, t_end=12.0, save_every=240)
        errs.append(np.max(np.abs(tr.final.x[-1] - ref)))
        assert np.max(np.abs(tr.final.v)) < 1e-9              # at rest
    assert 3.0 < errs[0] / errs[1] < 5.0 and errs[1] < 3e-5, errs


def test_midpoint_rule_keeps_the_stiff_modes_ringing_and_alpha_damps_them():
    """The documented limit of the midpoint rule: a sudden self-weight load on a stiff rod excites shear modes
    with omega dt >> 1, which it does not damp (the mass-proportional damping cannot reach them either);
    alpha = 1 does."""
    def load(r):
        out = np.zeros((len(r), 6))
        out[:, 1] = -3.0
        return out

    speeds = []
    for alpha in (0.5, 1.0):
        b = body(EA=1e6, GA=1e6, load=load, rhoI=1e-3, rhoJ=2e-3)
        b = RodBody(b.rod, b.M, 4.0, alpha)
        tr = simulate(Discrete(b, 10), reference_state(b, 10), dt=0.05, t_end=6.0, save_every=120)
        speeds.append(float(np.max(np.abs(tr.final.w))))
    assert speeds[0] > 1e-3 and speeds[1] < 1e-2 * speeds[0], speeds


def test_scene_runs_and_the_python_function_agrees(tmp_path):
    out = tmp_path / "r.json"
    assert main(["run", str(SCENES / "rod_dynamics.toml"), "--json", str(out)]) == 0
    a = json.loads(out.read_text())["analyses"][0]["outputs"]
    assert a["orthonormality_error"] < 1e-12 and a["energy_error"] < 1e-2
    assert len(a["t"]) == len(a["tip_trajectory"]) and a["t"][-1] == pytest.approx(2.0)
    tip = np.array(a["tip_trajectory"])
    assert np.min(tip[:, 1]) < -0.5 and np.all(tip[:, 2] == 0.0)   # large sag, in the plane of gravity
    s = mechgen.compile("cosserat_rod", params=dict(json.loads(out.read_text())["params"]))
    b = mechgen.rod_dynamics(s, elements=40, dt=0.005, t_end=2.0, save_every=2).outputs
    assert b["tip_trajectory"] == a["tip_trajectory"]


@pytest.mark.parametrize("setting, key", [("rhoA=0.0", "params"), ("rhoI=0.0", "params"), ("GA=-1.0", "params")])
def test_a_rod_without_mass_or_stiffness_is_refused_naming_the_key(setting, key, capsys):
    assert main(["run", str(SCENES / "rod_dynamics.toml"), "--set", setting]) == 2
    err = capsys.readouterr().err
    assert key in err and "Traceback" not in err


@pytest.mark.parametrize("line, key", [("dt = 5.0", "dt"), ("dt = -1.0", "dt"), ("damping = -1.0", "damping"),
                                       ("tip = \"glued\"", "tip"), ("speed = 1.0", "speed")])
def test_bad_dynamics_keys_exit_2_naming_the_key(tmp_path, capsys, line, key):
    text = (SCENES / "rod_dynamics.toml").read_text()
    name = line.split(" =")[0]
    lines = [ln for ln in text.splitlines() if not ln.startswith(f"{name} =")]
    scene = tmp_path / "bad.toml"
    scene.write_text("\n".join(lines) + f"\n{line}\n")
    assert main(["run", str(scene)]) == 2
    err = capsys.readouterr().err
    assert key in err and "Traceback" not in err and "bad.toml" in err


def test_same_run_twice_gives_the_same_numbers():
    s = mechgen.compile("cosserat_rod", params={"rhoA": 1.0, "rhoI": 1e-3, "rhoJ": 2e-3, "g_y": -1.0})
    a = mechgen.rod_dynamics(s, elements=6, dt=0.05, t_end=0.5).outputs
    b = mechgen.rod_dynamics(s, elements=6, dt=0.05, t_end=0.5).outputs
    assert a["tip_trajectory"] == b["tip_trajectory"] and a["energy"] == b["energy"]


def test_compiled_elements_match_the_numpy_reference_including_near_pi(monkeypatch):
    """runtime/csrc/rod_elements.c against Discrete.internal (numpy): the same operations, so equal to
    round-off; a relative rotation of 3.1 rad takes log's near-pi branch. And a whole run without the library
    (no compiler) gives the compiled run's numbers to rounding."""
    from mechgen.runtime.rods import dynamics

    b = body(EA=3e2, GA=2e2, GJ=0.7, EI=1.3)
    d = Discrete(b, 8, "free", "free")
    st = reference_state(b, 8)
    rng = np.random.default_rng(2)
    st.x = st.x + 0.05 * rng.normal(size=st.x.shape)
    st.R = st.R @ exp_so3(0.9 * rng.normal(size=(9, 3)))
    st.R[3] = st.R[2] @ exp_so3(np.array([0.0, 3.1, 0.2]))
    z = 0.3 * rng.normal(size=(5, 9, 6))
    assert dynamics.element_library() is not None
    for c, n in zip(d.weighted_internal(st, z), d.weighted_internal(st, z, compiled=False)):
        assert np.max(np.abs(c - n)) <= 1e-13 * np.max(np.abs(n))
    bb = body(tip_force=(0.0, 1e-2, 0.0), EA=1e4, GA=1e4, rhoI=1e-4, rhoJ=2e-4)
    run = lambda: simulate(Discrete(bb, 10), reference_state(bb, 10), dt=0.01, t_end=0.3).final.x  # noqa: E731
    compiled = run()
    monkeypatch.setattr(dynamics, "element_library", lambda: None)
    assert np.max(np.abs(run() - compiled)) < 1e-12


def stiff_bench_body():
    """mechgen bench rods' stiff rod (bench.rods.base_section(100), PyElastica's mapping): r = 1 cm, EI = 100 N m^2,
    rhoA = 1 kg/m, G = E/3, shear coefficient 27/28; a step tip load P L^2/EI = 2 across it."""
    r = 0.01
    A, I = math.pi * r * r, math.pi * r**4 / 4
    E, rho = 100.0 / I, 1.0 / A
    G = E / 3
    K = np.diag([E * A, 27 / 28 * G * A, 27 / 28 * G * A, G * 2 * I, E * I, E * I])
    M = np.diag([rho * A] * 3 + [rho * 2 * I, rho * I, rho * I])
    return RodBody(Rod(1.0, K, tip_force=np.array([0.0, -200.0, 0.0])), M)


def test_stiff_steps_converge_in_a_handful_of_newton_solves_without_splitting(monkeypatch):
    """The refresh rule (dynamics._Solver.attempt, issue 30): on the bench's stiff rod at N = 5 and dt = 2.5e-3 s
    (280 x PyElastica's explicit limit there; the rod swings through 0.78 L in 0.2 s) every step converges
    without being split, in a bounded number of linear solves (counts, not times). Before the rule (a Jacobian
    taken at the predictor never taken again within the step) the same run split 28 steps and its worst
    attempt took 104 solves. Reference: plain Newton (REFRESH = 0: the Jacobian taken at every iterate) to
    tol = 1e-13, the same equations by another path of iterates."""
    from mechgen.runtime.rods import dynamics

    b = stiff_bench_body()
    steps, tol = 80, 1e-10
    run = lambda tol: simulate(Discrete(b, 5), reference_state(b, 5), dt=0.2 / steps, t_end=0.2, tol=tol)  # noqa: E731
    tr = run(tol)
    assert tr.splits == 0
    # measured 18 solves in the worst step, 801 solves and 125 Jacobians in all (10.0 and 1.6 a step)
    assert tr.most_step_iterations <= 20
    assert tr.newton_iterations <= 12 * steps and tr.jacobians <= 2.5 * steps, (tr.newton_iterations, tr.jacobians)
    monkeypatch.setattr(dynamics, "REFRESH", 0.0)
    ref = run(1e-13)
    assert ref.splits == 0 and ref.most_step_iterations <= 20          # measured 15: Newton's few iterations
    tip, tip_ref = np.array(tr.tip), np.array(ref.tip)
    assert np.max(np.abs(tip_ref - tip_ref[0])) > 0.5                 # geometrically nonlinear (0.78 L)
    # each step's increments lie within tol (units of L) of the step's root, so the positions within
    # steps x tol = 8e-9 L where the errors merely add; a factor 2 for their propagation (measured 4.1e-9 L)
    assert np.max(np.abs(tip - tip_ref)) < 2 * steps * tol


def random_step_state(b, n, rng):
    """A deformed, moving state of ``n`` elements with a relative rotation of 3.1 rad (log's near-pi branch)."""
    st = reference_state(b, n)
    st.x = st.x + 0.05 * rng.normal(size=st.x.shape)
    st.R = st.R @ exp_so3(0.9 * rng.normal(size=(n + 1, 3)))
    st.R[3] = st.R[2] @ exp_so3(np.array([0.0, 3.1, 0.2]))
    st.v, st.w = rng.normal(size=(n + 1, 3)), 3.0 * rng.normal(size=(n + 1, 3))
    return st


@pytest.mark.parametrize("ends,load,uniform,alpha", [
    (("clamped", "free"), None, False, 0.5),
    (("free", "free"), "gravity", True, 0.5),
    (("pinned", "clamped"), "field", False, 0.75),
    (("clamped", "pinned"), "torque", True, 1.0),
])
def test_compiled_step_residual_matches_the_numpy_reference(ends, load, uniform, alpha):
    """rod_elements.c's mgr_residual (the whole midpoint residual, one call) against Discrete.residual_numpy:
    the same operations in another order, so equal to round-off (1e-12 of the largest entry: a few hundred ulps
    of sums of terms up to that size); at random states with a near-pi relative rotation, fixed and free ends,
    a tip wrench, damping, a uniform load (force and torque) or a position-dependent one, alpha 1/2 .. 1; single
    and batched increments; the saved point's energies and turning angle, and the step's rotations, against
    the numpy ones."""
    from mechgen.runtime.rods import compiled, dynamics

    loads = {None: None,
             "gravity": lambda r: np.tile([0.0, -9.81, 0.0, 0.0, 0.0, 0.0], (len(r), 1)),
             "field": lambda r: np.concatenate([-r * [1.0, 2.0, 0.5], 0.1 * np.sin(r)], axis=1),
             "torque": lambda r: np.tile([0.3, -2.0, 0.1, 0.2, -0.4, 0.5], (len(r), 1))}
    K = np.diag([3e2, 2e2, 2e2, 0.7, 1.3, 1.1]) + 0.05 * np.ones((6, 6))
    rod = Rod(1.0, K, load=loads[load], tip_force=np.array([0.1, -0.3, 0.2]), tip_torque=np.array([0.02, 0.0, -0.01]),
              load_uniform=uniform)
    M = np.diag([1.0, 1.0, 1.0, 2e-3, 1e-3, 1.5e-3])
    M[4, 5] = M[5, 4] = 2e-4
    b = RodBody(rod, M, damping=0.7, alpha=alpha)
    d = Discrete(b, 8, *ends)
    rng = np.random.default_rng(5)
    st = random_step_state(b, 8, rng)
    assert dynamics.element_library() is not None
    for z in (0.3 * rng.normal(size=(9, 6)), 0.3 * rng.normal(size=(4, 9, 6))):
        for dt in (0.01, 0.2):
            got, ref = d.residual(st, z, dt), d.residual_numpy(st, z, dt)
            for c, n in zip(got, ref):
                assert c.shape == n.shape
                assert np.max(np.abs(c - n)) <= 1e-12 * max(np.max(np.abs(n)), 1.0)
    energy, turn = d.saved_point(st, np.array([0.0, 0.6, 0.8]))
    e_ref, t_ref = d.saved_point(st, np.array([0.0, 0.6, 0.8]), compiled=False)
    assert abs(energy - e_ref) <= 1e-13 * abs(e_ref) and abs(turn - t_ref) <= 1e-13 * max(abs(t_ref), 1.0)
    # the step's new rotations R exp(theta) (mgr_rotate), angles from 0 over the series' 1 rad switch to 3
    theta = rng.normal(size=(9, 3)) * np.linspace(0.0, 3.0, 9)[:, None] / np.sqrt(3.0)
    rotated = compiled.rotate(dynamics.element_library(), st.R, theta)
    assert np.max(np.abs(rotated - st.R @ exp_so3(theta))) <= 1e-14      # entries of size <= 1: ulps


def test_compiled_band_solve_matches_lapack():
    """rod_elements.c's mgr_band_solve (a Newton correction with dgbtrf's factors of the step Jacobian) against
    scipy's LAPACK dgbtrs on the rod's step Jacobian at a random state (pivoting happens there: alpha = 1 with a
    large dt) and its residual: the same operations in another order, so equal to round-off (1e-12 of the
    largest entry); the correction solves J dz = -r (checked against the dense product) and its size is
    max |dz_i| / scale_i."""
    from scipy.linalg import lapack

    from mechgen.runtime.rods import compiled, dynamics
    from mechgen.runtime.rods.dynamics import BAND

    b = body(EA=3e2, GA=2e2, GJ=0.7, EI=1.3, damping=0.3)
    d = Discrete(b, 8, "clamped", "free")
    rng = np.random.default_rng(7)
    st = random_step_state(b, 8, rng)
    z = 0.1 * rng.normal(size=(9, 6))
    r = d.residual(st, z, 0.3)[0]
    ab = d.jacobian_band(st, z, 0.3)
    lu, piv, info = lapack.dgbtrf(ab, BAND, BAND)
    assert info == 0 and np.any(piv != np.arange(len(piv)))
    scale = np.tile([2.0, 2.0, 2.0, 1.0, 1.0, 1.0], 9)
    solve = compiled.BandSolve.of(dynamics.element_library(), lu, piv, BAND, scale)
    dz, size = solve(r)
    ref = lapack.dgbtrs(lu, BAND, BAND, -r.ravel(), piv)[0]
    assert np.max(np.abs(dz - ref)) <= 1e-12 * np.max(np.abs(ref))
    assert size == np.max(np.abs(dz) / scale)
    dense = np.zeros((54, 54))
    for j in range(54):
        for i in range(max(0, j - BAND), min(54, j + BAND + 1)):
            dense[i, j] = ab[2 * BAND + i - j, j]
    # a backward-stable solve: residual a few eps |J| |dz| (measured 4e-15 |r|; J's condition number is 2e9)
    assert np.max(np.abs(dense @ dz + r.ravel())) <= 1e-10 * np.max(np.abs(r))


def test_a_run_without_the_library_gives_the_compiled_run(monkeypatch):
    """The whole step with every compiled piece (residual, correction, new rotations, saved points) against the
    numpy/scipy path (no compiler): a damped rod under gravity and a tip torque, alpha = 0.6, saved at every
    step. The Newton iterates differ by round-off only, so the saved tip path, energies and turning angles agree
    far below the Newton tolerance (1e-10 L, rad): to 1e-12 (measured ~1e-15)."""
    from mechgen.runtime.rods import dynamics

    g = lambda r: np.tile([0.0, -9.81, 0.0, 0.0, 0.0, 0.0], (len(r), 1))  # noqa: E731
    rod = Rod(1.0, np.diag([1e4, 1e4, 1e4, 0.7, 1.0, 1.0]), load=g, load_uniform=True,
              tip_torque=np.array([0.0, 0.0, 0.05]))
    b = RodBody(rod, np.diag([1.0, 1.0, 1.0, 2e-4, 1e-4, 1e-4]), damping=0.2, alpha=0.6)

    def run():
        tr = simulate(Discrete(b, 10), reference_state(b, 10), dt=0.01, t_end=0.3, save_every=1)
        return np.asarray(tr.tip), np.asarray(tr.energy), np.asarray(tr.tip_rotation), tr.newton_iterations

    compiled = run()
    monkeypatch.setattr(dynamics, "element_library", lambda: None)
    numpy_ = run()
    assert compiled[3] == numpy_[3]
    for c, n in zip(compiled[:3], numpy_[:3]):
        assert np.max(np.abs(c - n)) <= 1e-12 * max(np.max(np.abs(n)), 1.0)
    assert np.max(np.abs(compiled[2])) > 0.1 and np.ptp(compiled[1]) > 0.0      # it turned and moved


@pytest.mark.parametrize("rate,size", [(0.1, 1e-3), (0.3, 1e-5), (0.5, 1e-4), (0.9, 1e-6)])
def test_stale_corrections_counts_the_geometric_series(rate, size):
    """dynamics.stale_corrections (the refresh rule's cost of keeping a Jacobian): the corrections of a kept
    Jacobian shrink geometrically, |dz_k| = size rate^k, and Newton stops at the first k whose error estimate
    |dz_k| rate / (1 - rate) is below tol; counting them one by one gives the ceiling of the closed form."""
    from mechgen.runtime.rods.dynamics import stale_corrections

    tol, k = 1e-10, 0
    while size * rate ** k * rate / (1.0 - rate) >= tol:
        k += 1
    assert math.ceil(stale_corrections(rate, size, tol)) == k
    assert stale_corrections(1.0, size, tol) == math.inf and stale_corrections(rate, 1e-20, tol) == 0.0


@pytest.mark.parametrize("gravity", [False, True])
def test_compiled_corrections_take_the_python_loops_iterates_bit_for_bit(monkeypatch, gravity):
    """rod_elements.c's mgr_corrections (attempt's loop between two Jacobians in one C call) against the Python loop,
    its reference: the same operations in the same order, so the same trajectory bit for bit and the same counts.
    On the bench's stiff rod at N = 5 with steps 8 x the stiff test's (dt = 0.02 s: measured 1,879 solves, 420
    Jacobians, 31 split steps: every branch of the loop, damping, refreshes and failures, is taken), and with a
    uniform load (gravity, lumped once: the compiled path) at dt = 5 ms (970 solves, 200 Jacobians, 12 splits;
    at 10 ms and more this rod under gravity fails with the split limit's ConvergenceError, on either loop). A
    position-dependent load keeps the Python loop."""
    from mechgen.runtime.rods import dynamics

    b = stiff_bench_body()
    if gravity:
        rod = b.rod
        b = RodBody(Rod(rod.L, rod.K, load=lambda r: np.tile([0.0, -9.81 * b.rhoA, 0.0, 0.0, 0.0, 0.0], (len(r), 1)),
                        tip_force=rod.tip_force, load_uniform=True), b.M)

    def run():
        return simulate(Discrete(b, 5), reference_state(b, 5), dt=0.005 if gravity else 0.02, t_end=0.2, tol=1e-10)

    assert dynamics.element_library() is not None
    fast = run()
    monkeypatch.setattr(dynamics, "COMPILED_CORRECTIONS", False)
    slow = run()
    assert fast.splits > 10 and fast.jacobians > 100                  # the hard case it is meant to be
    assert (fast.newton_iterations, fast.jacobians, fast.splits, fast.most_step_iterations) == \
        (slow.newton_iterations, slow.jacobians, slow.splits, slow.most_step_iterations)
    np.testing.assert_array_equal(np.array(fast.tip), np.array(slow.tip))
    np.testing.assert_array_equal(fast.final.R, slow.final.R)
    np.testing.assert_array_equal(np.array(fast.energy), np.array(slow.energy))
