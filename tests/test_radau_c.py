"""The compiled Radau IIA loop (mechgen.runtime.integration.radau_c): scipy's Radau step for step, in C.

Each model is integrated by the compiled loop and by scipy.integrate.Radau stepped here on the same right-hand
side and Jacobian (the system's own rhs and jacobian, or hand-derived equations), with the samples taken from
each step's dense output as mechgen.runtime.core.integrate takes them: the same steps, Newton iterations and
factorisations, and samples equal to rounding. Rounding is all that differs (the C loop's LU against LAPACK's),
so samples are compared at 1e-10 relative to the state's size at rtol 1e-10 (observed: ~1e-13).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si
import sympy as sp

import mechgen
from mechgen.models import load_model
from mechgen.runtime.core.budget import BudgetExceeded
from mechgen.runtime.integration.radau_c import integrate_radau_c, radau_loop_problem
from mechgen.runtime.integration.run_options import RunOptions
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

#: samples agree to rounding amplified over the run (observed ~1e-13 of the state's size)
SAME = 1e-10


def two_rates() -> Model:
    """x'' + c1 x' + k1 x = 0, y'' + c2 y' + k2 y = 0 (tests/test_compiled_flow.py's model)."""
    model = Model("two_rates", doc="two decoupled damped coordinates")
    model.params(Param("c1", 1.0), Param("k1", 1.0), Param("c2", 1e6), Param("k2", 1e4))
    model.coordinates("x", "y")
    model.kinetic(lambda v: v.x**2 / 2 + v.y**2 / 2)
    model.potential(lambda q, p: p.k1 * q.x**2 / 2 + p.k2 * q.y**2 / 2)
    model.dissipation(lambda v, p: p.c1 * v.x**2 / 2 + p.c2 * v.y**2 / 2)
    return model


def sls() -> Model:
    """m x'' + k1 x + k2 (x - s) = 0, c s' = k2 (x - s) (tests/test_internal_variables.py), stiff: c = 1e-4."""
    model = Model("sls_stiff", doc="mass on a standard linear solid")
    model.params(Param("m", 2.0), Param("k1", 3.0), Param("k2", 5.0), Param("c", 1e-4))
    model.coordinates("x")
    model.internal("s", rate=lambda q, z, p: p.k2 * (q.x - z.s) / p.c)
    model.kinetic(lambda v, p: p.m / 2 * v.x**2)
    model.potential(lambda q, z, p: p.k1 / 2 * q.x**2 + p.k2 / 2 * (q.x - z.s) ** 2)
    return model


def compiled(model: Model, **params):
    system = mechgen.compile(model, params)
    why = radau_loop_problem(system)
    if why is not None:
        pytest.skip(f"no compiled Radau loop here: {why}")
    return system


def scipy_radau(fun, jac, x0, t_end: float, t_eval: np.ndarray, rtol: float, atol: float):
    """(samples, counts) of scipy's Radau stepped to t_end, sampled at t_eval from each step's dense output."""
    solver = si.Radau(fun, 0.0, np.asarray(x0, float), t_end, rtol=rtol, atol=atol, jac=jac)
    rows, i, steps = [], 0, 0
    while solver.status == "running":
        solver.step()
        steps += 1
        j = int(np.searchsorted(t_eval, solver.t, side="right"))
        if j > i:
            rows.append(solver.dense_output()(t_eval[i:j]).T)
            i = j
    counts = {"steps": steps, "nfev": solver.nfev, "njev": solver.njev, "nlu": solver.nlu}
    return np.vstack(rows), counts


def same_run(system, fun, jac, x0, t_end: float, samples: int = 201, rtol: float = 1e-10, atol=1e-12):
    """Run both loops; assert the same counts and samples; return (t, samples)."""
    t_eval = np.linspace(0.0, t_end, samples)
    t, X, counts = integrate_radau_c(system, x0, t_end, RunOptions(rtol=rtol, atol=atol, t_eval=t_eval))
    ref, ref_counts = scipy_radau(fun, jac, x0, t_end, t_eval, rtol, atol)
    assert counts == ref_counts
    np.testing.assert_array_equal(t, t_eval)
    np.testing.assert_allclose(X, ref, rtol=0, atol=SAME * np.max(np.abs(ref)))
    return t, X


def test_stiff_two_rates_step_for_step_and_closed_form():
    """c2 = 1e6, k2 = 1e4: rates ~1e6/s and ~1e-2/s in y, (1 -+ i sqrt 3)/2 in x. The same steps as scipy's Radau
    on the system's rhs and Jacobian, and both coordinates against their closed forms: x = e^{-t/2}(cos wd t +
    sin wd t / (2 wd)), y = (l1 e^{l2 t} - l2 e^{l1 t}) / (l1 - l2) (1e-8: the integrator's error at rtol 1e-10)."""
    system = compiled(two_rates())
    x0 = np.array([1.0, 1.0, 0.0, 0.0])
    t, X = same_run(system, system.rhs, system.jacobian, x0, 1.0)
    wd = math.sqrt(3) / 2
    np.testing.assert_allclose(X[:, 0], np.exp(-t / 2) * (np.cos(wd * t) + np.sin(wd * t) / (2 * wd)), atol=1e-8)
    disc = math.sqrt(1e12 - 4e4)
    l1, l2 = (-1e6 + disc) / 2, (-1e6 - disc) / 2
    y = (l1 * np.exp(l2 * t) - l2 * np.exp(l1 * t)) / (l1 - l2)
    np.testing.assert_allclose(X[:, 1], y, atol=1e-8)


def pendulum_rhs(t, x, m=1.0, k=40.0, l0=1.0, g=9.81):
    """The spring pendulum by hand (mechgen/models/spring_pendulum.py's T and V): r'' = r th'^2 - k/m (r - l0)
    + g cos th, th'' = -(2 r' th' + g sin th) / r."""
    r, th, vr, vth = x
    return np.array([vr, vth, r * vth**2 - k / m * (r - l0) + g * math.cos(th), -(2 * vr * vth + g * math.sin(th)) / r])


def pendulum_jac(t, x, m=1.0, k=40.0, l0=1.0, g=9.81):
    """d(pendulum_rhs)/dx by hand."""
    r, th, vr, vth = x
    return np.array([[0, 0, 1, 0], [0, 0, 0, 1],
                     [vth**2 - k / m, -g * math.sin(th), 0, 2 * r * vth],
                     [(2 * vr * vth + g * math.sin(th)) / r**2, -g * math.cos(th) / r, -2 * vth / r, -2 * vr / r]])


def test_spring_pendulum_state_dependent_mass_against_the_hand_derived_equations():
    """M = diag(m, m r^2) depends on the state: the compiled loop on the generated kernels takes the same steps as
    scipy's Radau on the equations and Jacobian derived by hand, over 5 s of a large swing. At rtol 1e-8: at 1e-10
    the Newton test's decisions on this model sit at rounding (scipy's own Radau on the hand-derived and on the
    generated equations then differ by 2 steps in 3805)."""
    system = compiled(load_model("spring_pendulum"))
    x0 = np.array([1.3, 1.2, 0.0, 0.5])
    same_run(system, pendulum_rhs, pendulum_jac, x0, 5.0, rtol=1e-8)


def test_internal_variable_rates_and_their_jacobian():
    """A stiff Maxwell arm (relaxation k2/c = 5e4/s): the internal variable's rate and its rows g_q, g_v, g_z of J.
    The same steps as scipy's Radau on the linear y' = A y, and x(t_end) against expm(A t_end) (1e-8)."""
    from scipy.linalg import expm

    system = compiled(sls())
    m, k1, k2, c = 2.0, 3.0, 5.0, 1e-4
    A = np.array([[0, 1, 0], [-(k1 + k2) / m, 0, k2 / m], [k2 / c, 0, -k2 / c]])
    x0 = np.array([1.0, 0.0, 1.0])
    t, X = same_run(system, lambda t, y: A @ y, lambda t, y: A, x0, 2.0)
    np.testing.assert_allclose(X[-1], expm(A * 2.0) @ x0, atol=1e-8)


def first_order_van_der_pol() -> Model:
    """x' = y, y' = mu (1 - x^2) y - x, declared with internal variables only (n = 0: dx/dt is the rates)."""
    model = Model("van_der_pol_rates_only", doc="first-order van der Pol, internal variables only")
    model.params(Param("mu", 1.0))
    model.internal("x", lambda z: z.y)
    model.internal("y", lambda z, p: p.mu * (1 - z.x**2) * z.y - z.x)
    return model


def test_a_model_of_internal_variables_only():
    """n = 0 (no coordinates, no mass matrix): the loop steps the rates alone, the same steps as scipy's Radau on
    the equations and Jacobian written by hand, over a period at mu = 1 (rtol 1e-8) (a stiff model of internal variables
    only: the rate-and-state slider below; at mu = 1000 the Newton test's decisions sit at rounding, as for the
    spring pendulum above at rtol 1e-10)."""
    mu = 1.0
    system = compiled(first_order_van_der_pol(), mu=mu)
    assert system.n == 0 and system.m == 2

    def fun(t, z):
        return np.array([z[1], mu * (1 - z[0] ** 2) * z[1] - z[0]])

    def jac(t, z):
        return np.array([[0.0, 1.0], [-2 * mu * z[0] * z[1] - 1, mu * (1 - z[0] ** 2)]])

    same_run(system, fun, jac, np.array([2.0, 0.0]), 7.0, rtol=1e-8)


def test_an_absolute_tolerance_per_state_as_scipys():
    """atol given per state (scipy's array atol; the periodic-orbit guess scales it by each state's range): the stiff
    pair above, the same steps, counts and samples as scipy's Radau with that array at three rtol, and not those of
    a scalar atol; a wrong length is refused (the loop's problem says why)."""
    system = compiled(two_rates())
    x0 = np.array([1.0, 1.0, 0.0, 0.0])
    for atol in ([1e-6, 1e-12, 1e-9, 1e-12], [1e-12, 1e-6, 1e-12, 1e-8]):
        for rtol in (1e-10, 1e-8, 1e-6):
            same_run(system, system.rhs, system.jacobian, x0, 1.0, rtol=rtol, atol=np.array(atol))
    t_eval = np.linspace(0.0, 1.0, 11)
    steps = {a: integrate_radau_c(system, x0, 1.0, RunOptions(rtol=1e-10, atol=np.array(a) if a[1:] else a[0],
                                                              t_eval=t_eval))[2]["steps"]
             for a in ((1e-12, 1e-6, 1e-12, 1e-8), (1e-12,), (1e-6,))}
    assert len(set(steps.values())) == 3, steps
    assert "one per state" in radau_loop_problem(system, 1e-6, np.ones(3))


def test_the_rate_state_slider_runs_compiled_and_agrees_with_scipys():
    """The inertial rate-and-state slider of scenes/rate_state_stick_slip.toml (three internal variables, no
    coordinate), 60 s (three slips) from the load-point step: simulate's Radau runs in the compiled loop and
    agrees with scipy's Radau on the same kernels (loop "python": the same method, its own rounding) to the
    tolerance's size, 1e-6 of ln(V/V_ref) (measured 3e-9 at rtol 1e-8)."""
    import tomllib

    scene = Path(__file__).resolve().parents[1] / "scenes" / "rate_state_stick_slip.toml"
    system = compiled(load_model("rate_state_inertial"), **tomllib.loads(scene.read_text())["params"])
    options = dict(t_end=60.0, method="Radau", rtol=1e-8, atol=1e-12, samples=121)
    c = mechgen.simulate(system, **options)
    py = mechgen.simulate(system, loop="python", **options)
    assert (c["loop"], py["loop"]) == ("c", "python")
    for name in ("phi", "psi", "f"):
        np.testing.assert_allclose(c["trajectory"][name], py["trajectory"][name], rtol=0, atol=1e-6)


def test_simulate_runs_it_for_auto_and_radau_with_the_energy_integrals():
    """simulate: auto's stiff choice is Radau, run compiled (loop "c"); loop "python" runs scipy's on the
    augmented flow (the energy balance's integrals appended): the same trajectory and dissipated energy."""
    system = compiled(two_rates())
    options = dict(t_end=1.0, q0={"x": 1.0, "y": 1.0}, rtol=1e-10, atol=1e-12, samples=51)
    c = mechgen.simulate(system, **options)
    py = mechgen.simulate(system, method="Radau", loop="python", **options)
    assert (c["method"], c["loop"], py["method"], py["loop"]) == ("Radau", "c", "Radau", "python")
    scale = max(1.0, float(np.max(np.abs(py["trajectory"]["x"]))))
    np.testing.assert_allclose(c["trajectory"]["x"], py["trajectory"]["x"], rtol=0, atol=SAME * scale)
    np.testing.assert_allclose(c["dissipated"], py["dissipated"], rtol=SAME)


def test_a_parameter_change_reaches_the_compiled_loop():
    """with_params copies share the kernels; each run reads its own parameters: k1 = 4 gives x = e^{-t/2}(cos wd t
    + sin wd t / (2 wd)) with wd = sqrt(k1 - 1/4) (1e-8: the integrator's error at rtol 1e-10)."""
    system = compiled(two_rates())
    for k1 in (1.0, 4.0):
        r = mechgen.simulate(system.with_params(k1=k1), t_end=1.0, q0={"x": 1.0, "y": 1.0}, method="Radau",
                             rtol=1e-10, atol=1e-12, samples=21)
        assert r["loop"] == "c"
        t, wd = r["t"], math.sqrt(k1 - 0.25)
        np.testing.assert_allclose(r["trajectory"]["x"], np.exp(-t / 2) * (np.cos(wd * t) + np.sin(wd * t) / (2 * wd)),
                                   rtol=0, atol=1e-8)


def test_refused_where_it_cannot_run():
    """The numpy backend: loop 'c' with method Radau is an InputError at the key; 'auto' runs scipy's. A hybrid
    model (its modes: the event loops run it) is refused too."""
    system = mechgen.compile(two_rates(), backend="numpy")
    assert "numpy" in radau_loop_problem(system)
    with pytest.raises(mechgen.InputError, match="loop"):
        mechgen.simulate(system, t_end=1.0, q0={"x": 1.0}, method="Radau", loop="c")
    assert mechgen.simulate(system, t_end=0.1, q0={"x": 1.0}, method="Radau", samples=3)["loop"] == "python"
    hybrid = mechgen.compile(str(Path(__file__).resolve().parent / "models" / "bouncing_ball.py"))
    assert "modes" in radau_loop_problem(hybrid)


def test_without_a_compiler_radau_falls_back_to_scipys(monkeypatch, tmp_path):
    """No C compiler for the loop's library: auto / Radau run scipy's Radau (loop "python"), loop "c" is refused."""
    from mechgen.codegen import build
    from mechgen.runtime.integration import radau_c

    system = compiled(two_rates())  # built while the compiler works
    monkeypatch.setenv("CC", "/nonexistent/cc")
    monkeypatch.setenv("MECHGEN_CACHE", str(tmp_path))  # an empty cache: the loop library is not there built
    build.reset_compiler_cache()
    radau_c.forget_library()
    try:
        assert "cannot be built" in radau_loop_problem(system)
        options = dict(t_end=0.1, q0={"x": 1.0, "y": 1.0}, method="Radau", samples=3)
        assert mechgen.simulate(system, **options)["loop"] == "python"
        with pytest.raises(mechgen.InputError, match="cannot be built"):
            mechgen.simulate(system, loop="c", **options)
    finally:
        monkeypatch.undo()
        build.reset_compiler_cache()
        radau_c.forget_library()
    assert radau_loop_problem(system) is None


def test_step_budget():
    """max_steps bounds the compiled loop's accepted steps as it bounds scipy's (the Python path's message)."""
    system = compiled(two_rates())
    with pytest.raises(BudgetExceeded, match="max_steps"):
        mechgen.simulate(system, t_end=1.0, q0={"x": 1.0, "y": 1.0}, method="Radau", max_steps=20)


def blow_up() -> Model:
    """x'' = a / (2 sqrt x) (V = -a sqrt x): thrown towards x < 0, where sqrt(x) and dx/dt are NaN."""
    model = Model("sqrt_well", doc="a well that ends at x = 0")
    model.params(Param("a", 1.0))
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(lambda q, p: -p.a * sp.sqrt(q.x))
    return model


def test_nan_right_hand_side_names_t():
    system = compiled(blow_up())
    with pytest.raises(mechgen.KernelError, match=r"NaN/Inf at t = .*Radau at t = "):
        integrate_radau_c(system, [1.0, -10.0], 1.0, RunOptions(rtol=1e-8, atol=1e-10, t_eval=np.linspace(0, 1, 11)))


def test_singular_mass_is_named():
    """m = 0 in x'' of the two-rate model (T = m x'^2 / 2): M = dr/da is singular at the start."""
    model = two_rates()
    model.params(Param("mx", 0.0))
    model.kinetic(lambda v, p: p.mx * v.x**2 / 2 + v.y**2 / 2)
    system = compiled(model)
    with pytest.raises(mechgen.errors.ConvergenceError, match=r"Radau failed at t = 0 .*Singular matrix: the mass"):
        integrate_radau_c(system, [1.0, 1.0, 0.0, 0.0], 1.0, RunOptions(t_eval=np.linspace(0, 1, 3)))
