"""The event rules of the hybrid integrator (mechgen.runtime.integration.events, module doc), each against a closed form.

Small hybrid models are written to model files in a temporary folder (a model file is what a scene names and
what keys the compile cache) and compiled with ``mechgen.compile``; the engine is driven directly through
``integrate_hybrid`` and through the public ``mechgen.simulate`` and the command line.

The bouncing ball (a point mass m under gravity g, dropped from rest at height h; at y = 0 falling the reset
y' -> -e y'): the first impact at t_1 = sqrt(2 h / g) with speed v_1 = g t_1; after impact k the ball leaves at
e^k v_1 and returns after 2 e^k v_1 / g, so

    t_k = t_1 (1 + 2 e (1 - e^(k-1)) / (1 - e)),       T = lim t_k = t_1 (1 + e) / (1 - e)

(the Zeno accumulation time), and between impacts y(t) = e^k v_1 (t - t_k) - g (t - t_k)^2 / 2.
"""
from __future__ import annotations

import json
import math
import re
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate as si
from scipy.optimize import brentq

import mechgen
from mechgen.cli import main
from mechgen.runtime.core.budget import BudgetExceeded
from mechgen.runtime.integration.events import MAX_DEPTH, EventRules, integrate_hybrid, time_tolerance

G, COR, H = 9.81, 0.8, 1.0

BALL = '''\
"""A bouncing ball: flight under gravity; y falling through 0 resets y' -> -cor y'."""
from mechgen import Model, Param

model = Model("bouncing_ball", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("g", 9.81, "m/s^2", positive=True),
             Param("cor", 0.8, "", minimum=0.0))
model.coordinates("y")
flight = model.mode("flight")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@flight.guard(to="flight", direction="falling", reset=lambda v, p: {"y_dot": -p.cor * v.y})
def floor(q):
    return q.y


model.output("height", lambda q: q.y, unit="m")
'''

# a ball whose floor is watched by guards of identical functions, and by a clock at the closed-form impact time
TWINS = '''\
"""Simultaneous events: guards crossing at one instant."""
from mechgen import Model, Param

model = Model("twins", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("g", 9.81, "m/s^2"), Param("t_hit", 1.0, "s"))
model.coordinates("y")
flight = model.mode("flight")
left = model.mode("left")
right = model.mode("right")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@flight.guard(to="left", direction="falling", reset=lambda v: {"y_dot": -v.y})
def first(q):
    return q.y


@flight.guard(to="right", direction="falling", reset=lambda v: {"y_dot": -v.y})
def second(q):
    return q.y


@flight.terminal(direction="falling")
def stop(q):
    return q.y
'''

CLOCK = '''\
"""A ball whose floor is a transition and a clock at t_hit a terminal event."""
from mechgen import Model, Param

model = Model("clocked_ball", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("g", 9.81, "m/s^2"), Param("t_hit", 1.0, "s"))
model.coordinates("y")
flight = model.mode("flight")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@flight.guard(to="flight", direction="falling", reset=lambda v: {"y_dot": -v.y})
def floor(q):
    return q.y


@model.terminal(direction="rising")
def clock(t, p):
    return t - p.t_hit
'''

# grazing and tangent crossings of a particle drifting at constant speed (x = x0 + v0 t exactly)
DRIFT = '''\
"""A free particle: guards that graze and one that crosses at a tangency."""
from mechgen import Model, Param

model = Model("drift", doc=__doc__)
model.params(Param("m", 1.0, "kg"))
model.coordinates("x")
before = model.mode("before")
after = model.mode("after")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@before.guard(to="after", direction="both")
def graze(q):
    return (q.x - 1) ** 2


@before.guard(to="after", direction="both")
def graze_t(t):
    return -(t - 1) ** 2


@before.guard(to="after", direction="rising")
def cube(q):
    return (q.x - 1) ** 3
'''

# a throw: the guard -y'^2 touches zero at the apex and never crosses; landing (y falling) ends the run
THROW = '''\
"""A throw from the floor: grazing at the apex, landing terminal."""
from mechgen import Model, Param

model = Model("throw", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("g", 9.81, "m/s^2"))
model.coordinates("y")
air = model.mode("air")
ground = model.mode("ground")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y


@air.guard(to="ground", direction="both")
def apex(v):
    return -v.y**2


@air.terminal(direction="falling")
def landed(q):
    return q.y
'''

# pushed from rest by a constant force F: x = F t^2 / (2 m); g = x - c t^3 has g = g_t = 0 at t = 0
PUSHED = '''\
"""A particle pushed from rest: a guard with g = 0 and dg/dt = 0 at the start."""
from mechgen import Model, Param

model = Model("pushed", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("F", 1.0, "N"), Param("c", 0.25, "m/s^3"))
model.coordinates("x")
go = model.mode("go")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.forces
def push(p):
    return {"x": p.F}


@go.terminal(direction="both")
def overtaken(q, p, t):
    return q.x - p.c * t**3
'''

# a timer g = t^2 (tau - t): g = g_t = 0 at t = 0, one zero at tau; the particle drifts slowly
TIMER = '''\
"""A timer with g = dg/dt = 0 at the start."""
from mechgen import Model, Param

model = Model("timer", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("tau", 0.01, "s"))
model.coordinates("x")
run = model.mode("run")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@run.terminal(direction="both")
def timer(t, p):
    return t**2 * (p.tau - t)
'''

# a slowly drifting particle watched by a fast guard g = x - A sin(w t)
FAST = '''\
"""A fast oscillating guard on a slow particle."""
import sympy as sp
from mechgen import Model, Param

model = Model("fast_guard", doc=__doc__)
model.params(Param("m", 1.0, "kg"), Param("A", 1.0, "m"), Param("w", 1.0, "rad/s"))
model.coordinates("x")
slow = model.mode("slow")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@slow.terminal(direction="falling")
def cross(q, p, t):
    return q.x - p.A * sp.sin(p.w * t)
'''

# a mass on a spring k that meets a second spring k2 at x = d
STOP = '''\
"""A spring-mass oscillator meeting a stop spring at x = d."""
from mechgen import Model, Param

model = Model("spring_stop", doc=__doc__)
model.params(Param("m", 2.0, "kg"), Param("k", 8.0, "N/m"), Param("k2", 50.0, "N/m"), Param("d", 0.1, "m"))
model.coordinates("x")
free = model.mode("free")
pressed = model.mode("pressed")


@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.x**2


@model.potential
def spring(q, p):
    return p.k / 2 * q.x**2


@pressed.potential
def stop(q, p):
    return p.k2 / 2 * (q.x - p.d) ** 2


@free.guard(to="pressed", direction="rising")
def touch(q, p):
    return q.x - p.d


@pressed.guard(to="free", direction="falling")
def leave(q, p):
    return q.x - p.d


model.output("position", lambda q: q.x, unit="m")
'''

TWINS_FREE = TWINS.split("@flight.terminal")[0].replace('"twins"', '"twins_free"')

SOURCES = {"ball": BALL, "twins": TWINS, "twins_free": TWINS_FREE, "clock": CLOCK, "drift": DRIFT, "throw": THROW, "pushed": PUSHED, "timer": TIMER,
           "fast": FAST, "stop": STOP}


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("hybrid_models")
    for name, text in SOURCES.items():
        (path / f"{name}.py").write_text(text)
    return path


@pytest.fixture(scope="module")
def systems(folder):
    """Compiled lazily, once per module."""
    cache: dict = {}

    def get(name: str, backend: str = "c"):
        if (name, backend) not in cache:
            cache[name, backend] = mechgen.compile(str(folder / f"{name}.py"), backend=backend)
        return cache[name, backend]
    return get


def ball_times(t_end: float, h: float = H, g: float = G, e: float = COR) -> np.ndarray:
    """t_k of the module doc, k = 1, 2, ... while t_k <= t_end."""
    t1 = math.sqrt(2 * h / g)
    out, k = [], 1
    while True:
        t = t1 * (1 + 2 * e * (1 - e ** (k - 1)) / (1 - e))
        if t > t_end:
            return np.array(out)
        out.append(t)
        k += 1


def zeno_time(h: float = H, g: float = G, e: float = COR) -> float:
    return math.sqrt(2 * h / g) * (1 + e) / (1 - e)


# ----------------------------------------------------------------------------- 1. the bouncing ball

@pytest.mark.parametrize("method, rtol, tol", [("DOP853", 1e-12, 1e-13), ("RK45", 1e-12, 1e-13),
                                               ("Radau", 1e-12, 1e-13), ("BDF", 1e-13, 3e-12)])
def test_ball_event_times_match_the_closed_form(systems, method, rtol, tol):
    """t_k of the module doc for six impacts. Flight is a quadratic in t, which the Runge-Kutta and collocation
    methods integrate exactly: their event times are exact to rounding. BDF restarts at order 1 after every
    reset, so its times carry its own integration error (~10 rtol over the run). Radau and BDF take the
    generated Jacobian (njev > 0)."""
    system = systems("ball")
    tr = integrate_hybrid(system, np.array([H, 0.0]), 3.0, method=method, rtol=rtol, atol=rtol * 1e-2)
    ref = ball_times(3.0)
    got = np.array([e.t for e in tr.events])
    assert len(got) == len(ref) == 6
    assert np.max(np.abs(got - ref)) < tol
    assert all(e.guard == "floor" and e.source == e.target == 0 for e in tr.events)
    # the reset: leaving impact k at e^k v_1
    v1 = G * math.sqrt(2 * H / G)
    assert [e.x_after[1] for e in tr.events] == pytest.approx([COR**k * v1 for k in range(1, 7)], rel=1e-10)
    if method in ("Radau", "BDF"):
        assert tr.njev > 0


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_ball_through_simulate_in_every_backend(systems, backend):
    """``mechgen.simulate`` of the ball: ``events`` ({t, from, to, guard}) at t_k, ``final_mode``, ``t_final`` and
    the height at t_end = 3 s, y = e^6 v_1 (3 - t_6) - g (3 - t_6)^2 / 2 (module doc)."""
    system = systems("ball", backend)
    result = mechgen.simulate(system, t_end=3.0, q0={"y": H}, method="DOP853", rtol=1e-12, atol=1e-14)
    out = result.outputs
    ref = ball_times(3.0)
    assert [e["t"] for e in out["events"]] == pytest.approx(list(ref), abs=1e-12)
    assert {(e["from"], e["to"], e["guard"]) for e in out["events"]} == {("flight", "flight", "floor")}
    assert out["final_mode"] == "flight" and out["t_final"] == 3.0
    v6, s = COR**6 * G * math.sqrt(2 * H / G), 3.0 - ref[-1]
    assert out["height"] == pytest.approx(v6 * s - G * s**2 / 2, abs=1e-11)
    json.dumps(result.to_json())  # the event log is JSON


def _scene(folder: Path, analysis: str, name: str = "scene.toml", model: str = "ball.py") -> str:
    path = folder / name
    path.write_text(f'model = "{model}"\nbackend = "c"\n[[analysis]]\n{analysis}')
    return str(path)


def _cli(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_ball_scene_through_the_cli(folder, capsys):
    """The same run from a scene file with ``mechgen run``: the JSON's events at t_k."""
    scene = _scene(folder, 'name = "drop"\nkind = "simulate"\nt_end = 3.0\nq0 = { y = 1.0 }\nmethod = "DOP853"\n'
                           'rtol = 1e-12\natol = 1e-14\n')
    target = folder / "out.json"
    code, _, err = _cli(["run", scene, "--json", str(target)], capsys)
    assert code == 0, err
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    assert [e["t"] for e in out["events"]] == pytest.approx(list(ball_times(3.0)), abs=1e-12)
    assert out["final_mode"] == "flight"


# ----------------------------------------------------------------------------- 2. Zeno and max_events

def _reached(text: str) -> float:
    return float(re.search(r"reached t = ([0-9.eE+-]+) of t_end", text).group(1))


def test_zeno_ball_ends_with_budget_exceeded_near_the_accumulation_time(systems):
    """Run past T = t_1 (1 + e) / (1 - e): more than zeno_events = 100 impacts within zeno_span = 1e-9 t_end
    must end the run (BudgetExceeded, key zeno_events) at T, in mode flight, in bounded time."""
    system, T = systems("ball"), zeno_time()
    start = time.perf_counter()
    with pytest.raises(BudgetExceeded) as info:
        integrate_hybrid(system, np.array([H, 0.0]), 1.5 * T, method="DOP853", rtol=1e-10, atol=1e-12)
    assert time.perf_counter() - start < 10.0
    exc = info.value
    assert exc.key == "zeno_events" and "mode flight" in str(exc)
    assert _reached(str(exc)) == pytest.approx(T, rel=1e-7)


def test_max_events_ends_the_run_at_the_next_event(systems):
    """max_events = 3: the fourth impact (t_4) raises BudgetExceeded naming max_events and t_4."""
    with pytest.raises(BudgetExceeded) as info:
        integrate_hybrid(systems("ball"), np.array([H, 0.0]), 3.0, method="DOP853", rtol=1e-12, atol=1e-14,
                         rules=EventRules(max_events=3))
    assert info.value.key == "max_events" and "mode flight" in str(info.value)
    assert _reached(str(info.value)) == pytest.approx(ball_times(3.0)[3], rel=1e-8)


def test_zeno_scene_exits_1_naming_time_mode_and_key(folder, capsys):
    """From a scene: exit 1, one message naming the time T, the mode and the key; ``max_events`` likewise."""
    T = zeno_time()
    scene = _scene(folder, f'name = "zeno"\nkind = "simulate"\nt_end = {1.5 * T}\nq0 = {{ y = 1.0 }}\n'
                           'method = "DOP853"\nrtol = 1e-10\natol = 1e-12\n', "zeno.toml")
    code, _, err = _cli(["run", scene], capsys)
    assert code == 1
    assert "zeno_events" in err and "mode flight" in err and "Traceback" not in err
    assert _reached(err) == pytest.approx(T, rel=1e-7)
    scene = _scene(folder, 'name = "few"\nkind = "simulate"\nt_end = 3.0\nq0 = { y = 1.0 }\nmax_events = 2\n'
                           'method = "DOP853"\nrtol = 1e-12\natol = 1e-14\n', "few.toml")
    code, _, err = _cli(["run", scene], capsys)
    assert code == 1 and "max_events" in err and "mode flight" in err
    assert _reached(err) == pytest.approx(ball_times(3.0)[2], rel=1e-8)


@pytest.mark.parametrize("zeno_events, raises", [(5, True), (6, False)])
def test_zeno_counts_more_than_zeno_events_within_zeno_span(systems, zeno_events, raises):
    """The rule is "more than zeno_events events within zeno_span": the ball's six impacts t_1..t_6 lie
    within t_6 - t_1 = 2.43 s < zeno_span = 2.5 s, so zeno_events = 5 ends the run at the sixth, at t_6,
    and zeno_events = 6 does not."""
    ref = ball_times(3.0)
    assert ref[-1] - ref[0] < 2.5 < ref[-1]
    rules = EventRules(zeno_events=zeno_events, zeno_span=2.5)

    def run():
        return integrate_hybrid(systems("ball"), np.array([H, 0.0]), 3.0, method="DOP853", rtol=1e-12, atol=1e-14,
                                rules=rules)
    if raises:
        with pytest.raises(BudgetExceeded) as info:
            run()
        assert info.value.key == "zeno_events" and _reached(str(info.value)) == pytest.approx(ref[5], rel=1e-8)
    else:
        assert len(run().events) == 6


# ----------------------------------------------------------------------------- 3. grazing and tangency

def test_grazing_guards_never_fire_and_a_tangent_crossing_fires_once(systems):
    """x = t (x0 = 0, v0 = 1, no force): (x - 1)^2 and -(t - 1)^2 touch zero at t = 1 without changing sign
    (in floating point too: a square is never negative), so neither fires; (x - 1)^3 crosses at the same
    tangency (g = g_t = 0 there) with a sign change and fires once, at t = 1."""
    for method in ("DOP853", "Radau"):
        tr = integrate_hybrid(systems("drift"), np.array([0.0, 1.0]), 2.0, method=method, rtol=1e-10, atol=1e-12)
        assert [e.guard for e in tr.events] == ["cube"]
        assert tr.events[0].t == pytest.approx(1.0, abs=1e-9)
        assert tr.final_mode == 1 and tr.t_final == 2.0


def test_apex_graze_never_fires_and_landing_ends_the_throw(systems):
    """A throw from y = 0 at v0 = 4 m/s: g = -y'^2 touches zero at the apex t = v0/g and never crosses; the
    terminal ``landed`` (y falling) starts on its surface moving away (no event at t = 0) and ends the run
    at t = 2 v0 / g."""
    v0 = 4.0
    tr = integrate_hybrid(systems("throw"), np.array([0.0, v0]), 5.0, method="DOP853", rtol=1e-12, atol=1e-14)
    assert [(e.guard, e.target) for e in tr.events] == [("landed", None)]
    assert tr.terminated and tr.t_final == pytest.approx(2 * v0 / G, abs=1e-12)


# ----------------------------------------------------------------------------- 4. events at t = 0

def test_impact_starting_at_contact_fires_at_t0(systems):
    """viscoelastic_impact (Kelvin-Voigt) from x = 0 moving in at v_in: ``touch`` is logged at t = 0; release
    after the half period of the damped oscillation, t = pi / omega_d, omega_d = omega_n sqrt(1 - zeta^2)."""
    system = mechgen.compile("viscoelastic_impact", {"law": "kelvin_voigt", "zeta": 0.1})
    tr = integrate_hybrid(system, np.array([0.0, 1.0, 0.0]), 5.0, method="DOP853", rtol=1e-12, atol=1e-14)
    assert [(e.guard, round(e.t, 10)) for e in tr.events][:1] == [("touch", 0.0)]
    assert tr.events[1].guard == "release"
    assert tr.events[1].t == pytest.approx(math.pi / math.sqrt(1 - 0.1**2), rel=1e-10)
    away = integrate_hybrid(system, np.array([0.0, -1.0, 0.0]), 5.0, method="DOP853", rtol=1e-12, atol=1e-14)
    assert away.events == () and away.final_mode == 0


def test_unknown_sign_at_the_start_waits_for_a_nonzero_value(systems):
    """x = F t^2 / (2 m) from rest; g = x - c t^3 has g = 0 and g_t = 0 at t = 0 (no event there, though its
    direction is "both"); it is positive after, and crosses (falling) at t* = F / (2 m c) = 2 s."""
    for method in ("DOP853", "Radau", "BDF"):
        tr = integrate_hybrid(systems("pushed"), np.array([0.0, 0.0]), 5.0, method=method, rtol=1e-12, atol=1e-14)
        assert [e.guard for e in tr.events] == ["overtaken"]
        assert tr.events[0].t == pytest.approx(2.0, rel=1e-9)


def test_unknown_sign_inside_a_long_first_step(systems):
    """g = t^2 (tau - t), tau = 10 ms: g = g_t = 0 at t = 0, positive after, one zero at t = tau. The particle
    drifts at 1e-6 m/s from x = 1 km, so the integrator's first step (~60 ms for RK45) spans the zero: the sign
    must come from the step's first 2^-12, not from its end (where g is already negative)."""
    y0 = np.array([1e3, 1e-6])
    assert _first_step("RK45", y0, 1e-10, 1e-12) > 0.05
    tr = integrate_hybrid(systems("timer"), y0, 1.0, method="RK45", rtol=1e-10, atol=1e-12)
    assert [e.guard for e in tr.events] == ["timer"]
    assert tr.events[0].t == pytest.approx(0.01, rel=1e-12)


# ----------------------------------------------------------------------------- 5. simultaneous events

def test_simultaneous_identical_guards_terminal_first_then_declaration_order(systems):
    """Three guards of one function y: ``first`` (-> left), ``second`` (-> right), the terminal ``stop``
    declared last. All cross at t_1 = sqrt(2 h / g): the terminal wins (the run ends there); without it
    (the same model less its terminal) ``first``, declared before ``second``, wins."""
    tr = integrate_hybrid(systems("twins"), np.array([H, 0.0]), 3.0, method="DOP853", rtol=1e-12, atol=1e-14)
    assert [(e.guard, e.target) for e in tr.events] == [("stop", None)]
    assert tr.events[0].t == pytest.approx(math.sqrt(2 * H / G), abs=1e-12)
    tr = integrate_hybrid(systems("twins_free"), np.array([H, 0.0]), 0.6, method="DOP853", rtol=1e-12, atol=1e-14)
    assert [(e.guard, e.target) for e in tr.events] == [("first", 1)]


@pytest.mark.parametrize("offset, expected", [(0.0, ["clock"]), (0.4, ["clock"]), (-0.4, ["clock"]),
                                              (1e3, ["floor", "clock"])])
def test_a_terminal_within_the_location_tolerance_of_a_transition_wins(systems, offset, expected):
    """The floor (transition) crosses at t_1; the terminal clock t - t_hit at t_hit = t_1 + offset * tol, tol
    the location tolerance (time_tolerance: 1e-12 t_end here). Within tol (|offset| <= 1) the two are a tie
    and the terminal wins whichever is sampled first; 1000 tol later the floor fires first and the clock
    ends the run after."""
    t1, t_end = math.sqrt(2 * H / G), 1.0
    tol = time_tolerance(t1, t_end)
    system = systems("clock").with_params(t_hit=t1 + offset * tol)
    tr = integrate_hybrid(system, np.array([H, 0.0]), t_end, method="DOP853", rtol=1e-12, atol=1e-14)
    assert [e.guard for e in tr.events] == expected
    assert tr.events[0].t == pytest.approx(t1, abs=2 * tol)
    assert tr.terminated


# ----------------------------------------------------------------------------- 6. missed events

def _first_step(method: str, y0: np.ndarray, rtol: float, atol: float) -> float:
    """The first step scipy's integrator takes on x'' = 0 from y0 (independent of the guard)."""
    cls = {"RK45": si.RK45, "DOP853": si.DOP853, "Radau": si.Radau}[method]
    extra = {"jac": lambda t, y: np.array([[0.0, 1.0], [0.0, 0.0]])} if method == "Radau" else {}
    solver = cls(lambda t, y: np.array([y[1], 0.0]), 0.0, y0, 1e3, rtol=rtol, atol=atol, **extra)
    solver.step()
    return solver.t


@pytest.mark.parametrize("method", ["RK45", "DOP853", "Radau"])
@pytest.mark.parametrize("x0", [0.5, -0.5])
def test_fast_guard_first_crossing_inside_steps_of_many_periods(systems, method, x0):
    """g = x - A sin(w t), x = x0 + v0 t with v0 = 1e-6 m/s: the motion is so slow that the first step spans
    N = h w / (2 pi) periods of g. With |x0| = A/2, g stays past zero for a third of each period, so the
    rule (module doc: zeros of g found down to 2^-12 of the step) resolves N < 2^12 / 3 = 1365 periods per
    step. The first falling zero is the root of x0 + v0 t = A sin(w t) on its first falling bracket (one
    period scanned finely, then Brent), and the guard is evaluated a few tens of times."""
    A, v0, rtol, atol = 1.0, 1e-6, 1e-10, 1e-12
    y0 = np.array([x0, v0])
    h = _first_step(method, y0, rtol, atol)
    for periods in (3.3, 33.3, 333.3, 1300.0):
        assert periods < 2**MAX_DEPTH / 3
        w = 2 * math.pi * periods / h
        tr = integrate_hybrid(systems("fast").with_params(A=A, w=w), y0, 1e3, method=method, rtol=rtol, atol=atol)

        def g(t):
            return x0 + v0 * t - A * np.sin(w * t)
        grid = np.linspace(0.0, 1.01 * 2 * math.pi / w, 4001)
        i = np.flatnonzero((g(grid[:-1]) > 0) & (g(grid[1:]) <= 0))[0]
        root = brentq(g, grid[i], grid[i + 1], xtol=1e-300, rtol=1e-15)
        assert tr.events[0].t == pytest.approx(root, rel=1e-12), periods
        assert tr.guard_evaluations < 100


def test_guard_overhead_on_an_ordinary_impact():
    """The cost of the rules on ordinary steps: one guard evaluation per accepted step, its rates from the
    integrator's own dx/dt (RK45, DOP853, Radau keep it), plus a bounded few per event (the start of a mode,
    Brent's iterations, the location). Measured on the Kelvin-Voigt impact entered at t = -0.5 s."""
    system = mechgen.compile("viscoelastic_impact", {"law": "kelvin_voigt", "zeta": 0.1})
    for method in ("DOP853", "Radau"):
        tr = integrate_hybrid(system, np.array([-0.5, 1.0, 0.0]), 20.0, method=method, rtol=1e-10, atol=1e-12)
        assert [e.guard for e in tr.events] == ["touch", "release"]
        assert tr.guard_evaluations <= tr.steps + 20 * (len(tr.events) + 1)
        assert tr.extra["rate_evaluations"] <= 10 * (len(tr.events) + 1)


# ----------------------------------------------------------------------------- 7. event location accuracy

def test_kelvin_voigt_restitution_converges_with_rtol():
    """Kelvin-Voigt impact (Butcher & Segalman 2000, eq. 4): released when x returns to 0 after the half
    period, e = exp(-zeta pi / sqrt(1 - zeta^2)). Within 1e-8 at rtol 1e-10, and the error falls as rtol
    falls: the slope of log error against log rtol over a ladder 1e-5 ... 1e-11 is positive (DOP853
    measured ~1, the integrator's own tolerance proportionality)."""
    zeta = 0.1
    exact = math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    system = mechgen.compile("viscoelastic_impact", {"law": "kelvin_voigt", "zeta": zeta})

    def restitution(rtol: float, method: str = "DOP853") -> float:
        tr = integrate_hybrid(system, np.array([0.0, 1.0, 0.0]), 10.0, method=method, rtol=rtol, atol=rtol * 1e-2,
                              stop_after=lambda e: e.guard == "release")
        return -tr.events[-1].x_after[1]

    assert restitution(1e-10) == pytest.approx(exact, rel=1e-8)
    assert restitution(1e-10, "Radau") == pytest.approx(exact, rel=1e-8)
    ladder = np.logspace(-5, -11, 7)
    errors = np.array([abs(restitution(r) - exact) / exact for r in ladder])
    slope = np.polyfit(np.log(ladder), np.log(errors), 1)[0]
    print(f"Kelvin-Voigt restitution: error ~ rtol^{slope:.2f}")
    assert slope > 0.5
    assert errors[-1] < errors[0] * 1e-4


# ----------------------------------------------------------------------------- other analyses

def test_other_analyses_see_the_initial_mode(systems):
    """``modes``/``stability`` of a hybrid system are those of its initial mode: the spring-stop oscillator
    starts free, omega = sqrt(k/m) = 2 rad/s. Its simulate from x = 0 at v0 meets the stop at
    t_c = asin(d omega / v0) / omega (x = (v0/omega) sin(omega t)) and, with no dissipation and a stop spring
    unloaded at contact, conserves energy. The viscoelastic impact starts in flight: one rigid mode."""
    system = systems("stop")
    assert mechgen.modes(system).outputs["frequencies"] == pytest.approx([2.0], rel=1e-12)
    assert mechgen.stability(system).outputs["verdict"] in ("stable", "neutral")
    v0 = 1.0
    out = mechgen.simulate(system, t_end=3.0, v0={"x": v0}, method="DOP853", rtol=1e-12, atol=1e-14).outputs
    assert out["events"][0]["guard"] == "touch" and out["events"][1]["guard"] == "leave"
    assert out["events"][0]["t"] == pytest.approx(math.asin(0.1 * 2.0 / v0) / 2.0, abs=1e-12)
    assert out["energy_drift"] < 1e-9
    impact = mechgen.compile("viscoelastic_impact", {"law": "kelvin_voigt"})
    assert mechgen.modes(impact).outputs["rigid_modes"] == 1  # in flight: a free mass
