"""Continua in the compiled DOP853 loop (issue 25, item 3; mechgen.runtime.fields.flow_c, field_flow.c).

References: FieldSystem.rhs itself (numpy assembly of the pointwise residual, end and part terms, reduction,
penalty, mass solve), to rounding; scipy's DOP853 stepping FieldSystem.rhs in Python (the compiled loop takes
its steps: the same number of steps, states equal to rounding); the closed-form free vibration of a string
fixed at one end and free at the other, w = sin(pi s / 2L) cos(omega_1 t), omega_1 = (pi / 2L) sqrt(T / rho).
The continuum is declared here (a user model), with segments, placed parts, end terms, damping and a
time-dependent load, so that every block of the operators is exercised.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

import mechgen
from mechgen.analyses import simulate_flow
from mechgen.runtime.integration.augmented import INTEGRALS as EXTRA
from mechgen.runtime.integration.augmented import AugmentedFlow
from mechgen.errors import InputError
from mechgen.runtime.core.integrate import integrate_first_order
from mechgen.runtime.integration.run_options import RunOptions
from mechgen.runtime.fields.flow_c import compiled_rhs, field_loop_problem, integrate_field_c

STRING = '''\
"""A taut string on a viscous foundation, fixed at s = 0, with a spring and a mass at s = L, beads placed along
it (parts) and a distributed harmonic load:

    rho w_tt + c w_t - T w_ss = f0 sin(Omega t) s / L   on (0, L),   w(0) = 0,
    T w_s(L) + k_e w(L) + m_e w_tt(L) = 0,   a bead of mass m at s_b.
"""
import sympy as sp

from mechgen import Model, Param, fix

model = Model("user_loaded_string", doc=__doc__)
model.params(Param("T", 1.0, "N", positive=True), Param("rho", 1.0, "kg/m", positive=True),
             Param("L", 1.0, "m", positive=True), Param("c", 0.0, "N s/m^2"), Param("f0", 0.0, "N/m"),
             Param("Omega", 1.0, "rad/s"), Param("k_e", 0.0, "N/m"), Param("m_e", 0.0, "kg"))
model.field("w", length="L", discretisation="hermite", N=8)
model.part("bead", Param("m", 0.0, "kg", "mass"))


@model.kinetic_density
def kinetic(u, p):
    return p.rho / 2 * u.w_t**2


@model.potential_density
def potential(u, p, s, t):
    return p.T / 2 * u.w_s**2 - p.f0 * sp.sin(p.Omega * t) * s / p.L * u.w


@model.dissipation_density
def dissipation(u, p):
    return p.c / 2 * u.w_t**2


@model.point_kinetic("end")
def end_mass(u, p):
    return p.m_e / 2 * u.w_t**2


@model.point_potential("end")
def end_spring(u, p):
    return p.k_e / 2 * u.w**2


@model.point_kinetic("bead")
def bead(u, p, part):
    return part.m / 2 * u.w_t**2


@model.boundary
def boundary():
    return [fix("w", "start")]
'''

LOADED = {"N": 6, "c": 0.3, "f0": 2.0, "Omega": 3.0, "k_e": 2.0, "m_e": 0.5}
SEGMENTS = [{"length": 0.4, "elements": 2, "rho": 2.0}, {"length": 0.6, "elements": 4}]
PARTS = [{"kind": "bead", "at": 0.2, "m": 0.2}, {"kind": "bead", "at": 0.7, "m": 0.1}]


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("field_loop_models") / "loaded_string.py"
    path.write_text(STRING)
    return str(path)


@pytest.fixture(scope="module")
def plain(model_file):
    system = mechgen.compile(model_file)
    if field_loop_problem(system) is not None:
        pytest.skip(f"no compiled loop here: {field_loop_problem(system)}")
    return system


@pytest.fixture(scope="module")
def loaded(model_file, plain):
    return mechgen.compile(model_file, LOADED, segments=SEGMENTS, parts=PARTS)


@pytest.mark.parametrize("choices", [{}, {"constraints": "penalty"}, {"discretisation": "legendre"}],
                         ids=["eliminate", "penalty", "global-basis"])
def test_compiled_rhs_is_field_system_rhs(loaded, plain, choices):
    """dx/dt from the precomputed operators and one kernel call a block equals FieldSystem.rhs at random states
    and times, to rounding (1e-13 of its largest entry: sums of a few dozen terms, taken in another order), and
    so do the energy balance's powers (Q.v, v.dR/dv, -dL/dt integrated over the string, its beads and end) that
    the C side appends, against energy_balance.AugmentedFlow's numpy quadrature.
    Cases: segments with their own rho, two beads, an end mass and spring (eliminated w(0) = 0; the penalty
    instead), and a global Legendre basis (a dense null-space reduction)."""
    system = (plain.with_params(**LOADED) if "discretisation" in choices else loaded).with_params(**choices)
    f = compiled_rhs(system, extra=EXTRA)
    rng = np.random.default_rng(7)
    for _ in range(4):
        x, t = rng.standard_normal(2 * system.n + EXTRA), float(rng.uniform(0.0, 3.0))
        expected = AugmentedFlow(system).rhs(t, x)
        got = f(t, x)
        state, powers = slice(0, 2 * system.n), slice(2 * system.n, None)
        assert np.abs(got[state] - expected[state]).max() <= 1e-13 * np.abs(expected[state]).max()
        assert np.abs(got[powers] - expected[powers]).max() <= 1e-13 * np.abs(expected[powers]).max()


def test_outputs_series_is_outputs_at_each_sample(loaded):
    """FieldSystem.outputs_series (each block's points of all samples in one kernel call) equals FieldSystem.outputs
    sample by sample, to rounding (1e-13 of the largest energy: sums over 30 points in another order)."""
    rng = np.random.default_rng(3)
    X, t = rng.standard_normal((5, 2 * loaded.n)), rng.uniform(0.0, 3.0, 5)
    series = loaded.outputs_series(t, X)
    for k in range(len(t)):
        one = loaded.outputs(X[k, :loaded.n], X[k, loaded.n:], None, float(t[k]))
        assert sorted(one) == sorted(series)
        scale = max(abs(v) for v in one.values())
        assert all(abs(series[name][k] - one[name]) <= 1e-13 * scale for name in one)


def test_compiled_loop_is_scipys_dop853_step_for_step(loaded):
    """The forced, damped string with beads from rest over 2 s at rtol 1e-10: the compiled loop takes as many steps
    as scipy's DOP853 on FieldSystem.rhs, and the samples agree to 1e-11 of the largest state (rounding: measured
    2e-13; the residual's sums are taken in another order)."""
    run = RunOptions(method="DOP853", rtol=1e-10, atol=1e-12, t_eval=np.linspace(0.0, 2.0, 21))
    x0 = np.zeros(2 * loaded.n)
    t, X, counts = integrate_field_c(loaded, x0, 2.0, run)
    ref = integrate_first_order(loaded.rhs, x0, 2.0, options=run)
    xs = ref.x if ref.x.shape[0] == len(ref.t) else ref.x.T
    assert counts["steps"] == ref.steps
    np.testing.assert_array_equal(t, ref.t)
    assert np.abs(X - xs).max() <= 1e-11 * np.abs(xs).max()


def test_simulate_runs_a_continuum_in_the_compiled_loop(loaded):
    """simulate (method auto -> DOP853 on the C backend): loop = "c", the same outputs as loop = "python" (names and
    values, to 1e-11 of each series' scale: rounding, as above); the forced, damped run reports its energy balance
    (work and dissipated energy integrated with the state) in place of energy_drift, closed to rounding in both."""
    options = dict(t_end=1.0, rtol=1e-10, atol=1e-12, samples=11)
    c = mechgen.simulate(loaded, **options)
    py = mechgen.simulate(loaded, loop="python", **options)
    assert (c["method"], c["loop"], py["method"], py["loop"]) == ("DOP853", "c", "DOP853", "python")
    assert sorted(c.outputs) == sorted(py.outputs) and list(c["trajectory"]) == list(py["trajectory"])
    for name, series in py["trajectory"].items():
        scale = max(np.abs(series).max(), 1e-300)
        assert np.abs(np.asarray(c["trajectory"][name]) - series).max() <= 1e-11 * scale, name
    assert "energy_drift" not in c.outputs and c["work"] > 0 and c["dissipated"] > 0
    assert c["work"] == pytest.approx(py["work"], rel=1e-10) and c["dissipated"] == pytest.approx(py["dissipated"],
                                                                                                  rel=1e-10)
    assert c["energy_balance_error"] < 1e-12 and py["energy_balance_error"] < 1e-12  # measured 5e-15


def test_free_vibration_of_a_string_at_its_closed_form_frequency(plain):
    """Started in its first mode, the fixed-free string oscillates as q(t) = q(0) cos(omega_1 t) with
    omega_1 = (pi / 2L) sqrt(T / rho) = pi / 2: over one period within 2e-8 of q(0) (the Hermite mesh of 8 elements
    has omega_1 high by 8e-10, a phase error of 2 pi 8e-10 = 5e-9 after a period; integration at rtol 1e-11)."""
    omega = math.pi / 2
    r = mechgen.simulate(plain, t_end=2 * math.pi / omega, initial_mode=1, amplitude=0.1, rtol=1e-11, atol=1e-13,
                         samples=41)
    assert r["loop"] == "c"
    t = np.asarray(r["t"])
    Q = np.column_stack([r["trajectory"][name] for name in plain.coordinates])
    error = np.abs(Q - np.outer(np.cos(omega * t), Q[0])).max() / np.abs(Q[0]).max()
    assert error < 2e-8
    assert "energy_balance_error" not in r.outputs and r["energy_drift"] < 1e-9  # conservative: measured 3e-11


def test_damped_string_loses_its_energy_as_the_closed_form_says(plain):
    """The fixed-free string on a viscous foundation (c = 0.2, rho = T = L = 1) started in mode 1 at rest: each mode
    obeys q'' + (c / rho) q' + omega^2 q = 0 (the damping is proportional to the mass), so with gamma = c / 2 rho,
    omega_d = sqrt(omega^2 - gamma^2) and omega = pi / 2,
    E(t) / E(0) = exp(-2 gamma t) ((omega / omega_d)^2 sin^2 omega_d t
                                   + (cos omega_d t + gamma / omega_d sin omega_d t)^2)
    and the dissipated energy is E(0) - E(t). The run (compiled loop) reports energy_balance_error, work = 0 and
    dissipated, integrated with the state; both series meet the closed form to 3e-9 of E(0) (measured 3e-10: the
    Hermite mesh's omega_1 is high by 8e-10; integration at rtol 1e-11)."""
    omega, gamma = math.pi / 2, 0.1
    damped = math.sqrt(omega**2 - gamma**2)
    r = mechgen.simulate(plain.with_params(c=0.2), t_end=6.0, initial_mode=1, amplitude=0.1, rtol=1e-11, atol=1e-13,
                         samples=31)
    assert r["loop"] == "c" and "energy_drift" not in r.outputs and r["work"] == 0.0
    t, E = np.asarray(r["t"]), np.asarray(r["energy_series"])
    ratio = np.exp(-2 * gamma * t) * ((omega / damped) ** 2 * np.sin(damped * t) ** 2
                                      + (np.cos(damped * t) + gamma / damped * np.sin(damped * t)) ** 2)
    assert np.abs(E - E[0] * ratio).max() < 3e-9 * E[0]
    assert np.abs(np.asarray(r["trajectory"]["dissipated"]) - E[0] * (1 - ratio)).max() < 3e-9 * E[0]
    assert r["dissipated"] == pytest.approx(E[0] * (1 - ratio[-1]), abs=3e-9 * E[0])
    assert r["energy_balance_error"] < 1e-11  # the balance closes to the integration's accuracy


def test_where_the_compiled_loop_cannot_run(model_file, plain):
    """The numpy backend and a state-dependent mass are named; loop = "c" is then an input error, and loop "auto"
    falls back to scipy's DOP853 in Python."""
    numpy_system = mechgen.compile(model_file, backend="numpy")
    assert "numpy ones" in field_loop_problem(numpy_system)
    with pytest.raises(InputError, match="loop 'c' cannot run here"):
        mechgen.simulate(numpy_system, t_end=0.1, method="DOP853", loop="c", initial_mode=1)
    assert mechgen.simulate(numpy_system, t_end=0.1, method="DOP853", initial_mode=1)["loop"] == "python"
    assert "multipliers" in field_loop_problem(plain.with_params(constraints="multiplier"))
    heavy = model_file.replace(".py", "_heavy.py")
    with open(heavy, "w", encoding="utf-8") as out:
        out.write(STRING.replace('"user_loaded_string"', '"user_heavy_string"')
                  .replace("p.rho / 2 * u.w_t**2", "p.rho * (1 + u.w**2) / 2 * u.w_t**2"))
    varying = mechgen.compile(heavy)
    assert field_loop_problem(varying) == "the mass matrix depends on the state"
    assert mechgen.simulate(varying, t_end=0.1, method="DOP853", initial_mode=1)["loop"] == "python"


def test_auto_weighs_a_large_continuums_largest_rates(plain):
    """Above 400 first-order states, auto's estimate is ARPACK's 6 largest eigenvalues of the sparse linearisation:
    against the dense eigenvalues of FieldSystem.jacobian, the fastest rate and (c / 2 rho = 0.15 for every mode of
    the string on its viscous foundation) the fastest decay agree, the rate to 1e-6 and the decay to 1e-5 (ARPACK stops
    at a residual of tol |lambda|max = 1e-10 * 1146, 8e-7 of the decay, which the damped operator's non-normality
    magnifies: random start vectors gave up to 4.3e-6; the fixed start vector gives 6e-10, and auto's threshold
    needs percent); the estimate is the same on every call (a fixed start vector); auto then runs DOP853 in the C
    loop, and
    DOP853 over a t_end whose stability alone needs twice max_steps is refused before the first step."""
    system = plain.with_params(N=120, c=0.3)
    x0 = np.concatenate([0.01 * np.sin(np.arange(system.n)), np.zeros(system.n)])
    assert x0.size > simulate_flow.ESTIMATE_SIZE
    largest = simulate_flow.start_rates(system, x0)
    dense = np.linalg.eigvals(system.jacobian(0.0, x0))
    assert np.abs(largest).max() == pytest.approx(np.abs(dense).max(), rel=1e-6)
    assert np.max(-largest.real) == pytest.approx(np.max(-dense.real), rel=1e-5)
    np.testing.assert_array_equal(simulate_flow.start_rates(system, x0), largest)
    assert np.max(-dense.real) == pytest.approx(0.15, rel=1e-9)
    r = mechgen.simulate(system, t_end=0.01, initial_mode=1, amplitude=0.1, samples=3)
    assert (r["method"], r["loop"]) == ("DOP853", "c")
    fastest = float(np.abs(dense).max())
    # the mesh's fastest modes needing more than STIFF_STEPS explicit steps for stability alone: implicit
    long = 1.01 * simulate_flow.STIFF_STEPS * simulate_flow.DOP853_MESH_STEP / fastest
    assert simulate_flow.chosen_method(system, x0, long, rates=largest) == "Radau"
    assert simulate_flow.chosen_method(system, x0, 0.98 * long, rates=largest) == "DOP853"
    # DOP853 needs >= t_end |lambda|max / 12 steps: refused up front
    with pytest.raises(mechgen.errors.MechgenError, match="needs at least .* steps to stay stable"):
        mechgen.simulate(system, t_end=10.0, method="DOP853", initial_mode=1, max_steps=int(10.0 * fastest / 24))


def test_a_follower_loads_work_is_its_power_integrated_along_the_run():
    """Beck's column (follower_column: a tangential tip load P, a weak form, so no potential) released from the
    unloaded cantilever's first mode shape: the work reported (integrated with the state in the compiled loop)
    equals the follower's power -P w_s(L, t) w_t(L, t) from the sampled trajectory, integrated by Simpson's rule
    over 8001 samples (an independent quadrature: measured 3e-9 of the work; 8e-5 at 2001 samples, where the
    mesh's fast modes are barely sampled; asserted to 1e-7), and the balance E(t) - E(0) - W(t) closes
    (energy_balance_error < 1e-9: measured 5e-14)."""
    from scipy.integrate import simpson

    from mechgen.analyses.simulate import run_simulate

    system = mechgen.compile("follower_column", {"N": 8, "P": 10.0})
    if field_loop_problem(system) is not None:
        pytest.skip(f"no compiled loop here: {field_loop_problem(system)}")
    free = system.with_params(P=0.0).linear(np.zeros(system.n))  # start in the unloaded cantilever's first mode
    shape = sla.eigh(free["K"].toarray(), free["M"].toarray(), subset_by_index=[0, 0])[1][:, 0]
    q0 = dict(zip(system.coordinates, 0.1 * shape / np.abs(shape).max()))
    out = run_simulate(system, {"t_end": 3.0, "q0": q0, "rtol": 1e-10, "atol": 1e-12, "samples": 8001,
                                "progress": False}, {})
    assert out["loop"] == "c" and out["dissipated"] == 0.0 and out["energy_balance_error"] < 1e-9
    n, L, P = system.n, 1.0, 10.0
    X = np.column_stack([out["trajectory"][name] for name in
                         [*system.coordinates, *(f"{c}_dot" for c in system.coordinates)]])
    slope, value = (np.array([system.field_values(e, [L], k)["w"][0] for e in np.eye(n)]) for k in (1, 0))
    power = -P * (X[:, :n] @ slope) * (X[:, n:] @ value)  # w_s(L, t) and w_t(L, t) are linear in (q, v)
    assert out["work"] == pytest.approx(simpson(power, x=out["t"]), rel=1e-7)
