"""simulate with method = "cvodes": SUNDIALS' BDF on the CasADi kernels (mechgen.runtime.core.sundials).

References:
* the damped oscillator m x'' + c x' + k x = 0: x(t) = e^(-zeta w t) (x0 cos(w_d t) + (v0 + zeta w x0)/w_d
  sin(w_d t)), w = sqrt(k/m), zeta = c / (2 sqrt(k m)), w_d = w sqrt(1 - zeta^2);
* the standard linear solid with an internal variable (tests/test_internal_variables.py): the matrix
  exponential of its linear first-order system y' = A y;
* the nonlinear spring pendulum: scipy's Radau at a tolerance 100 times tighter (another integrator).
"""
import math

import numpy as np
import pytest

import mechgen
from mechgen.errors import InputError, SceneError
from mechgen.runtime.core.budget import BudgetExceeded


OSCILLATOR = '''"""m x'' + c x' + k x = 0"""
from mechgen import Model, Param

model = Model("damped_oscillator", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("k", 4.0, "N/m"), Param("c", 0.4, "N s/m"))
model.coordinates("x")
model.output("position", lambda q: q.x)


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def potential(q, p):
    return p.k / 2 * q.x**2


@model.dissipation
def dashpot(v, p):
    return p.c / 2 * v.x**2
'''

SLS = '''"""mass on a standard linear solid: m x'' + k1 x + k2 (x - s) = 0, c s' = k2 (x - s)"""
from mechgen import Model, Param

model = Model("sls_oscillator", doc=__doc__)
model.params(Param("m", 2.0, "kg"), Param("k1", 3.0, "N/m"), Param("k2", 5.0, "N/m"), Param("c", 0.7, "N s/m"))
model.coordinates("x")
model.internal("s", rate=lambda q, z, p: p.k2 * (q.x - z.s) / p.c)
model.output("position", lambda q: q.x)


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def potential(q, z, p):
    return p.k1 / 2 * q.x**2 + p.k2 / 2 * (q.x - z.s) ** 2
'''


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("cvodes_models")
    (path / "oscillator.py").write_text(OSCILLATOR)
    (path / "sls.py").write_text(SLS)
    return path


def oscillator(folder) -> str:
    return str(folder / "oscillator.py")


def exact(t, m, k, c, x0=1.0, v0=0.0):
    w, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    wd = w * math.sqrt(1 - zeta**2)
    return math.exp(-zeta * w * t) * (x0 * math.cos(wd * t) + (v0 + zeta * w * x0) / wd * math.sin(wd * t))


def run(system, **options):
    options = {"t_end": 10.0, "method": "cvodes", "q0": {"x": 1.0}, "rtol": 1e-10, "atol": 1e-12, **options}
    return mechgen.simulate(system, **options).outputs


def test_damped_oscillator_meets_the_closed_form_and_converges(folder):
    """Error at t_end against the closed form: below 1e-8 at rtol 1e-10, and falling with the tolerance
    (BDF of variable order: the slope of log error on log rtol is near 1)."""
    system = mechgen.compile(oscillator(folder), backend="casadi")
    assert run(system)["position"] == pytest.approx(exact(10.0, 1.0, 4.0, 0.4), abs=1e-8)
    rtols = [1e-6, 1e-8, 1e-10]
    errors = [abs(run(system, rtol=r, atol=r * 1e-2)["position"] - exact(10.0, 1.0, 4.0, 0.4)) for r in rtols]
    slope = np.polyfit(np.log(rtols), np.log(errors), 1)[0]
    print(f"cvodes damped oscillator: errors {errors}, slope {slope:.2f}")
    assert slope > 0.6 and errors[-1] < errors[0] * 1e-3


def test_stiff_oscillator_k_over_m_1e10(folder):
    """k/m = 1e10 with zeta = 0.5 (w = 1e5 rad/s) over t = 1e-3 s (16 periods, decayed by e^-50): BDF's steps
    are bounded by accuracy, not stability; the closed form is met to 1e-9 of the amplitude."""
    system = mechgen.compile(oscillator(folder), {"k": 1e10, "c": 1e5}, backend="casadi")
    out = run(system, t_end=1e-4, rtol=1e-10, atol=1e-14, max_steps=20000)
    assert out["position"] == pytest.approx(exact(1e-4, 1.0, 1e10, 1e5), abs=1e-9)


def test_internal_variable_meets_the_matrix_exponential(folder):
    from scipy.linalg import expm

    system = mechgen.compile(str(folder / "sls.py"), backend="casadi")
    m, k1, k2, c = 2.0, 3.0, 5.0, 0.7
    A = np.array([[0, 1, 0], [-(k1 + k2) / m, 0, k2 / m], [k2 / c, 0, -k2 / c]])
    ref = (expm(A * 5.0) @ np.array([0.3, 0.0, 0.0]))[0]
    out = mechgen.simulate(system, t_end=5.0, method="cvodes", q0={"x": 0.3}, rtol=1e-11, atol=1e-13).outputs
    assert out["position"] == pytest.approx(ref, abs=1e-9)


def test_nonlinear_pendulum_agrees_with_radau():
    casadi = mechgen.compile("spring_pendulum", backend="casadi")
    numpy = mechgen.compile("spring_pendulum", backend="numpy")
    q0 = {"r": 1.2, "theta": 0.3}
    ours = mechgen.simulate(casadi, t_end=3.0, method="cvodes", q0=q0, rtol=1e-10, atol=1e-12).outputs
    ref = mechgen.simulate(numpy, t_end=3.0, method="Radau", q0=q0, rtol=1e-12, atol=1e-14).outputs
    for name in ("x", "y", "energy"):
        assert ours[name] == pytest.approx(ref[name], abs=1e-7), name
    assert ours["energy_drift"] < 1e-7


def test_same_run_twice_gives_identical_numbers():
    system = mechgen.compile("spring_pendulum", backend="casadi")
    a = mechgen.simulate(system, t_end=2.0, method="cvodes", q0={"r": 1.0, "theta": 0.5}, series=True).outputs
    b = mechgen.simulate(system, t_end=2.0, method="cvodes", q0={"r": 1.0, "theta": 0.5}, series=True).outputs
    assert a == b


def test_other_backends_and_hybrid_models_are_refused_by_name(folder):
    with pytest.raises(InputError, match="backend = \"casadi\""):
        run(mechgen.compile(oscillator(folder), backend="numpy"))
    with pytest.raises(SceneError, match="method.*no event location.*modes"):
        mechgen.simulate(mechgen.compile("viscoelastic_impact", backend="casadi"), t_end=1.0, method="cvodes")


def test_step_budget_ends_the_run_naming_the_key(folder):
    """max_steps = 50 cannot carry 300 periods at rtol 1e-10: BudgetExceeded (exit 1) naming the key and the
    piece of t reached, never a hang."""
    system = mechgen.compile(oscillator(folder), {"c": 0.0}, backend="casadi")
    with pytest.raises(BudgetExceeded) as info:
        run(system, t_end=1000.0, max_steps=50)
    assert info.value.key == "max_steps" and "between t = 0" in str(info.value)


def test_scene_with_cvodes(tmp_path):
    """A scene selects it by name; with backend "c" the run is refused at the key, exit 2."""
    import subprocess
    import sys

    text = ('title = "pendulum"\nmodel = "spring_pendulum"\nbackend = "{}"\n[[analysis]]\nname = "run"\n'
            'kind = "simulate"\nt_end = 2.0\nmethod = "cvodes"\nq0 = {{ r = 1.0, theta = 0.4 }}\n')
    good, bad = tmp_path / "good.toml", tmp_path / "bad.toml"
    good.write_text(text.format("casadi"))
    bad.write_text(text.format("c"))
    ok = subprocess.run([sys.executable, "-m", "mechgen", "run", str(good)], capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0, ok.stderr
    assert "energy_drift" in ok.stdout
    no = subprocess.run([sys.executable, "-m", "mechgen", "run", str(bad)], capture_output=True, text=True, timeout=120)
    assert no.returncode == 2 and "bad.toml" in no.stderr and "'method'" in no.stderr and "Traceback" not in no.stderr


def test_rate_state_slider_agrees_with_radau_and_names_a_run_away():
    """The quasi-static rate-and-state slider (two internal variables, no coordinate): mu after the velocity
    step agrees with scipy's Radau on the C kernels (aging law, k = 1.2 k_c); the slip law's run-away at
    k = 6e9 Pa/m (the velocity grows without bound, tests/test_rate_state.py) is a ConvergenceError located to
    the part of t where Radau also stops, never a hang or silent garbage."""
    import re

    from mechgen.errors import ConvergenceError

    values = {"law": "aging", "loading": "spring", "k": 6e9}
    ours = mechgen.simulate(mechgen.compile("rate_state_slider", values, backend="casadi"), t_end=40.0,
                            method="cvodes", rtol=1e-10, atol=1e-12, samples=2).outputs
    ref = mechgen.simulate(mechgen.compile("rate_state_slider", values, backend="c"), t_end=40.0, method="Radau",
                           rtol=1e-12, atol=1e-14, samples=2).outputs
    assert ours["mu"] == pytest.approx(ref["mu"], abs=1e-8)
    values["law"] = "slip"
    with pytest.raises(ConvergenceError) as radau:
        mechgen.simulate(mechgen.compile("rate_state_slider", values, backend="c"), t_end=40.0, method="Radau",
                         rtol=1e-10, atol=1e-12, samples=2)
    t_radau = float(re.search(r"stopped at t = ([0-9.e+-]+)", str(radau.value)).group(1))
    with pytest.raises(ConvergenceError) as info:
        mechgen.simulate(mechgen.compile("rate_state_slider", values, backend="casadi"), t_end=40.0,
                         method="cvodes", rtol=1e-10, atol=1e-12, samples=2)
    lo, hi = map(float, re.search(r"between t = ([0-9.e+-]+) and ([0-9.e+-]+)", str(info.value)).groups())
    assert hi - lo <= 40.0 / 400 * 1.001 and lo - 0.1 <= t_radau <= hi + 0.1
    assert "dphi/dt" in str(info.value)
