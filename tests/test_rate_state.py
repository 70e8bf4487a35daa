"""Rate-and-state friction on a spring-slider (mechgen/models/rate_state_slider.py, scenes/rate_state_slider.toml).

mu = mu0 + a ln(V/V*) + b ln(V* theta/D_c) (Dieterich 1979, J. Geophys. Res. 84, 2161; Ruina 1983, J. Geophys.
Res. 88, 10359), aging law theta' = 1 - V theta/D_c, slip law theta' = -(V theta/D_c) ln(V theta/D_c); the model
integrates phi = ln(V/V*), psi = ln(V* theta/D_c).

References derived here (independent of mechgen):

* Velocity step V1 -> V2 at infinite stiffness (V imposed), from steady sliding at V1 (theta0 = D_c/V1):
  aging law (linear in theta): theta(t) = D_c/V2 + (theta0 - D_c/V2) exp(-V2 t/D_c);
  slip law (linear in Omega = ln(V2 theta/D_c) with slip d = V2 t): Omega = ln(V2/V1) exp(-d/D_c), so
  mu - mu_ss(V2) = b ln(V2/V1) exp(-d/D_c) (the slip law's exponential decay with slip, Ruina 1983);
  steady change mu_ss(V2) - mu_ss(V1) = (a - b) ln(V2/V1).
* Quasi-static spring-slider k (V2 - V) = sigma mu'. With u = phi - ln(V2/V*), w = psi + ln(V2/V*),
  w0 = V2/D_c and kappa = k V2/sigma, both laws linearise about steady sliding to
      w' = -w0 (u + w),   u' = (-kappa u - b w')/a,
  A = [[(b w0 - kappa)/a, b w0/a], [-w0, -w0]], tr A = (b w0 - kappa)/a - w0, det A = w0 kappa/a > 0.
  tr A = 0 gives k_c = sigma (b - a)/D_c, and there s = +- i sqrt(det A): omega = (V2/D_c) sqrt((b - a)/a)
  (derived here; the critical stiffness is Ruina 1983's and Rice & Ruina 1983's, J. Appl. Mech. 50, 343,
  where the neutral oscillation's period is 2 pi (D_c/V) sqrt(a/(b - a))). Stable (tr A < 0) for k > k_c.
"""
import math

import numpy as np
import pytest

import mechgen
from mechgen.errors import ConvergenceError
from mechgen.runtime.core.integrate import integrate_first_order

SCENE = "scenes/rate_state_slider.toml"
BASE = {"a": 0.01, "b": 0.015, "D_c": 1e-5, "sigma": 1e7, "mu0": 0.6, "V1": 1e-6, "V2": 1e-4, "V_ref": 3e-6}


def compiled(**params):
    return mechgen.compile("rate_state_slider", {**BASE, **params}, backend="c")


def mu_ss(p: dict, V: float) -> float:
    return p["mu0"] + (p["a"] - p["b"]) * math.log(V / p["V_ref"])


def mu_imposed(p: dict, law: str, t: float) -> float:
    """mu(t) after the step V1 -> V2 at imposed velocity (module doc)."""
    a, b, Dc, V1, V2, Vr = (p[k] for k in ("a", "b", "D_c", "V1", "V2", "V_ref"))
    if law == "aging":
        theta = Dc / V2 + (Dc / V1 - Dc / V2) * math.exp(-V2 * t / Dc)
        return p["mu0"] + a * math.log(V2 / Vr) + b * math.log(Vr * theta / Dc)
    return mu_ss(p, V2) + b * math.log(V2 / V1) * math.exp(-V2 * t / Dc)


def linear_eigenvalues(p: dict, k: float) -> np.ndarray:
    w0, kappa = p["V2"] / p["D_c"], k * p["V2"] / p["sigma"]
    A = np.array([[(p["b"] * w0 - kappa) / p["a"], p["b"] * w0 / p["a"]], [-w0, -w0]])
    return A, np.linalg.eigvals(A)


@pytest.mark.parametrize("law", ["aging", "slip"])
def test_velocity_step_at_imposed_velocity_follows_the_closed_forms(law):
    """mu(t) after V1 -> V2 = 100 V1 (module doc: aging theta(t), slip law exp(-d/D_c)) to 1e-10, and the
    steady change (a - b) ln(V2/V1) to 1e-10 after 60 D_c of slip."""
    p = dict(BASE)
    system = compiled(law=law, loading="imposed")
    Dc_over_V = p["D_c"] / p["V2"]
    for slips in (0.1, 0.5, 1.0, 2.0, 5.0):
        out = mechgen.simulate(system, t_end=slips * Dc_over_V, method="Radau", rtol=1e-12, atol=1e-14)
        assert abs(out["mu"] - mu_imposed(p, law, slips * Dc_over_V)) < 1e-10
    late = mechgen.simulate(system, t_end=60 * Dc_over_V, method="Radau", rtol=1e-12, atol=1e-14)
    change = (p["a"] - p["b"]) * math.log(p["V2"] / p["V1"])
    assert abs(late["mu"] - mu_ss(p, p["V1"]) - change) < 1e-10
    assert abs(late["velocity"] / p["V2"] - 1) < 1e-12 and abs(late["slip_rate_ratio"] - 1) < 1e-10


@pytest.mark.parametrize("law", ["aging", "slip"])
def test_hard_case_tiny_D_c_and_a_step_of_a_million(law):
    """D_c = 1e-6 of the slip V2 t_end, V2/V1 = 1e6: the closed forms at 3 D_c of slip and the steady change
    (a - b) ln(1e6) at the end, to 1e-10."""
    p = {**BASE, "D_c": 1e-9, "V1": 1e-9, "V2": 1e-3, "V_ref": 1e-6}
    system = mechgen.compile("rate_state_slider", {**p, "law": law, "loading": "imposed"}, backend="c")
    t3 = 3 * p["D_c"] / p["V2"]
    early = mechgen.simulate(system, t_end=t3, method="Radau", rtol=1e-12, atol=1e-14)
    assert abs(early["mu"] - mu_imposed(p, law, t3)) < 1e-10
    end = mechgen.simulate(system, t_end=1.0, method="Radau", rtol=1e-12, atol=1e-14)  # slip 1e6 D_c
    assert abs(end["mu"] - mu_ss(p, p["V1"]) - (p["a"] - p["b"]) * math.log(1e6)) < 1e-10


def test_generated_jacobian_at_steady_sliding_is_the_hand_linearisation():
    """d(phi', psi')/d(phi, psi) at V = V2 equals A of the module doc (both laws), to 1e-12 relative."""
    for law in ("aging", "slip"):
        for k in (1e9, 7.3e9, 4e10):
            system = compiled(law=law, k=k)
            steady = mechgen.steady(system)
            x = np.asarray(steady.state["_z"], float)
            A, _ = linear_eigenvalues(BASE, k)
            J = system.jacobian(0.0, x)
            assert np.max(np.abs(J - A)) < 1e-12 * np.max(np.abs(A))
            assert abs(steady["velocity"] / BASE["V2"] - 1) < 1e-12


@pytest.mark.parametrize("law", ["aging", "slip"])
@pytest.mark.parametrize("a, b, D_c, V2", [(0.01, 0.015, 1e-5, 1e-4), (0.005, 0.02, 1e-6, 3e-7)])
def test_critical_stiffness_and_neutral_frequency(law, a, b, D_c, V2):
    """k_c = sigma (b - a)/D_c and omega = (V2/D_c) sqrt((b - a)/a) (Ruina 1983; Rice & Ruina 1983) to 1e-10,
    the verdict stable above k_c and stick_slip below."""
    p = {**BASE, "a": a, "b": b, "D_c": D_c, "V2": V2}
    k_c = p["sigma"] * (b - a) / D_c
    omega = V2 / D_c * math.sqrt((b - a) / a)
    for factor, verdict in ((1.25, "stable"), (0.8, "stick_slip")):
        system = mechgen.compile("rate_state_slider", {**p, "law": law, "k": factor * k_c}, backend="c")
        out = mechgen.analysis("stability_boundary", system, parameter="k", bracket=[1e-3 * k_c, 1e3 * k_c],
                               labels={"flutter": "stick_slip", "divergence": "stick_slip"})
        assert abs(out["k_critical"] / k_c - 1) < 1e-10
        assert abs(out["frequency_critical"] / omega - 1) < 1e-10 and out["crossing"] == "complex"
        assert out["verdict"] == verdict
        expected = np.sort_complex(linear_eigenvalues(p, factor * k_c)[1])
        found = np.sort_complex(np.array([complex(*e) for e in out["eigenvalues"]]))
        assert np.max(np.abs(found - expected)) < 1e-10 * np.max(np.abs(expected))


def test_scene_outputs_and_verdicts():
    """The scene's contract outputs: mu_steady_before/after ((a - b) ln(V2/V1) apart, to 1e-10), k_critical,
    verdict stable above k_c = 5e9 Pa/m and stick_slip below, for both laws."""
    def outputs(*overrides):
        res = mechgen.run(SCENE, overrides=list(overrides))
        merged = {}
        for entry in res["analyses"]:
            merged.update(entry["outputs"])
        return merged

    out = outputs("V_ref=3e-6")
    assert abs(out["mu_steady_after"] - out["mu_steady_before"] - (0.01 - 0.015) * math.log(10.0)) < 1e-10
    assert abs(out["mu_steady_before"] - (0.6 + (0.01 - 0.015) * math.log(1e-6 / 3e-6))) < 1e-12
    assert abs(out["k_critical"] / 5e9 - 1) < 1e-10 and out["verdict"] == "stick_slip"
    assert outputs("k=6e9")["verdict"] == "stable"
    assert outputs("law=slip", "k=5.5e9")["verdict"] == "stable"
    assert outputs("law=slip", "k=4.5e9")["verdict"] == "stick_slip"


def _trajectory_at(system, times):
    x0 = np.asarray(system.call("initial")["x"], float).ravel()
    traj = integrate_first_order(system.rhs, x0, times[-1], jac=system.jacobian, method="Radau", rtol=1e-9,
                                 atol=1e-16, t_eval=np.array(times))
    return traj.x if traj.x.shape[0] == len(traj.t) else traj.x.T


@pytest.mark.parametrize("law", ["aging", "slip"])
@pytest.mark.parametrize("factor", [0.9, 1.1])
def test_simulated_oscillation_grows_below_k_c_and_decays_above(law, factor):
    """From steady sliding at V1 = V2 exp(-1e-7) the oscillation of u = ln(V/V2) grows (k < k_c) or decays
    (k > k_c) as the linearisation says (module doc): u(t + n T)/u(t) = exp(n T Re s), T = 2 pi/Im s, to 1e-5
    (the nonlinear terms are of the order of the amplitude: measured 4e-7 at k = 0.9 k_c, 5e-8 at 1.1 k_c)."""
    p = {**BASE, "V2": 1e-5, "V1": 1e-5 * math.exp(-1e-7), "V_ref": 1e-5}  # phi = u, psi = w: small numbers
    k_c = p["sigma"] * (p["b"] - p["a"]) / p["D_c"]
    s = linear_eigenvalues(p, factor * k_c)[1]
    s = s[np.argmax(s.imag)]
    T = 2 * math.pi / s.imag
    system = mechgen.compile("rate_state_slider", {**p, "law": law, "k": factor * k_c}, backend="c")
    t0, n = 2.3, 6
    traj_x = _trajectory_at(system, [t0, t0 + n * T])
    u = traj_x[:, 0] - math.log(p["V2"] / p["V_ref"])
    ratio = u[1] / u[0]
    assert abs(ratio / math.exp(n * T * s.real) - 1) < 1e-5
    assert (ratio > 1) == (factor < 1)


def test_large_step_below_k_c_runs_away_and_the_run_says_when():
    """Without inertia a growing stick-slip oscillation has nothing to bound its slip velocity: the step
    V1 -> 10 V1 at k = 0.8 k_c ends with exit 1 naming the time reached and the fastest rate (dphi/dt), never
    a hang; above k_c (k = 2 k_c, aging law) the same step settles to steady sliding at V2."""
    p = {**BASE, "V1": 1e-6, "V2": 1e-5, "V_ref": 1e-6}
    with pytest.raises(ConvergenceError, match=r"t = [0-9.]+ of t_end = 100.*dphi/dt"):
        mechgen.simulate(compiled(**p, k=4e9), t_end=100.0, method="Radau", rtol=1e-10, atol=1e-12)
    out = mechgen.simulate(compiled(**p, k=1e10), t_end=300.0, method="Radau", rtol=1e-10, atol=1e-12)
    assert abs(out["velocity"] / p["V2"] - 1) < 1e-6
    assert abs(out["mu"] - mu_ss(p, p["V2"])) < 1e-8


NEGATIVE_DAMPING = '''"""m x'' + (c - g) x' + k x = 0: the force g x' feeds energy in; unstable for g > c, at g = c it
oscillates at sqrt(k/m)."""
from mechgen import Model, Param

model = Model("negative_damping", doc=__doc__)
model.params(Param("m", 2.0, "kg"), Param("k", 8.0, "N/m"), Param("c", 0.3, "N s/m"), Param("g", 0.1, "N s/m"))
model.coordinates("x")

@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2

@model.potential
def potential(q, p):
    return p.k / 2 * q.x**2

@model.dissipation
def dashpot(v, p):
    return p.c / 2 * v.x**2

@model.forces
def feed(v, p):
    return {"x": p.g * v.x}
'''


def test_stability_boundary_of_a_users_model_without_internal_variables(tmp_path):
    """A user's model (no internal variables): the boundary g_c = c and the frequency sqrt(k/m) = 2 rad/s
    (closed form of m s^2 + (c - g) s + k = 0) to 1e-10."""
    path = tmp_path / "negative_damping.py"
    path.write_text(NEGATIVE_DAMPING)
    system = mechgen.compile(str(path), backend="numpy")
    out = mechgen.analysis("stability_boundary", system, parameter="g", bracket=[0.0, 1.0])
    assert abs(out["g_critical"] - 0.3) < 1e-10 and abs(out["frequency_critical"] - 2.0) < 1e-10
    assert out["verdict"] == "stable" and out["crossing"] == "complex"
    with pytest.raises(ConvergenceError, match="same sign at both ends"):
        mechgen.analysis("stability_boundary", system, parameter="g", bracket=[0.5, 1.0])


def test_steady_newton_takes_its_own_parameter_values_and_aliases():
    """steady (Newton) with params = {V2: V1} is steady sliding at V1: mu = mu0 + (a - b) ln(V1/V*) to 1e-12,
    reported also under its alias; an alias of no output is refused naming the key."""
    system = compiled(k=6e9)
    out = mechgen.steady(system, params={"V2": BASE["V1"]}, aliases={"mu_steady_before": "mu"}, tol=1e-14)
    assert abs(out["mu_steady_before"] - mu_ss(BASE, BASE["V1"])) < 1e-12 and out["mu"] == out["mu_steady_before"]
    assert abs(out["velocity"] / BASE["V1"] - 1) < 1e-12
    with pytest.raises(mechgen.SceneError, match="aliases.friction"):
        mechgen.steady(system, aliases={"friction": "mu_total"})


@pytest.mark.parametrize("options, key", [({"bracket": [2e9, 1e9]}, "bracket"),
                                          ({"bracket": [1e9]}, "bracket"),
                                          ({"bracket": [1e9, 2e10], "labels": {"wobbly": "x"}}, "labels.wobbly"),
                                          ({"bracket": [1e9, 2e10], "parameter": "law"}, "parameter")])
def test_stability_boundary_refuses_bad_options_at_their_key(options, key):
    system = compiled()
    with pytest.raises(mechgen.InputError, match=key.replace(".", r"\.")):
        mechgen.analysis("stability_boundary", system, **{"parameter": "k", **options})


@pytest.mark.parametrize("law, factor, settles", [("aging", 2.0, True), ("aging", 0.5, False),
                                                  ("slip", 2.0, False), ("slip", 0.5, False)])
def test_hard_case_spring_driven_step_of_a_million_settles_or_says_when_it_ran_away(law, factor, settles):
    """D_c = 1e-9 m, V1 = 1e-9 -> V2 = 1e-3 m/s through the spring: at k = 2 k_c the aging law settles to steady
    sliding (mu_ss(V2) to 1e-10); below k_c, and for the slip law even above it at so large a step (the slip law's
    instability to large perturbations, cf. Gu, Rice, Ruina & Tse 1984, J. Mech. Phys. Solids 32, 167), the
    quasi-static slider runs away and the run stops with exit 1 naming the time reached, never a hang."""
    p = {**BASE, "D_c": 1e-9, "V1": 1e-9, "V2": 1e-3, "V_ref": 1e-6}
    k_c = p["sigma"] * (p["b"] - p["a"]) / p["D_c"]
    system = mechgen.compile("rate_state_slider", {**p, "law": law, "k": factor * k_c}, backend="c")
    run = lambda: mechgen.simulate(system, t_end=1e-3, method="Radau", rtol=1e-10, atol=1e-12)  # noqa: E731
    if settles:
        out = run()
        assert abs(out["velocity"] / p["V2"] - 1) < 1e-10 and abs(out["mu"] - mu_ss(p, p["V2"])) < 1e-10
    else:
        with pytest.raises(ConvergenceError, match=r"stopped at t = [0-9.e-]+ of t_end = 0.001 .*dphi/dt"):
            run()
