"""Scene loading: defaults, overrides, parameter resolution, sweeps and every error path."""
from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field

import pytest

from mechgen.errors import InputError, SceneError
from mechgen.scene.load import AnalysisSpec, Scene, load_scene


@dataclass(frozen=True)
class FakeParam:
    default: float | str
    choices: tuple[str, ...] | None = None
    integer: bool = False


@dataclass(frozen=True)
class FakeModel:
    name: str
    params: dict = field(default_factory=dict)
    coordinates: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()


ROTOR = FakeModel(
    "rotor",
    {"m": FakeParam(10.0), "k": FakeParam(4.0e5), "Omega": FakeParam(0.0), "N": FakeParam(4, integer=True),
     "law": FakeParam("linear", choices=("linear", "neo_hookean"))},
    ("x", "y", "theta"),
    ("orbit_radius", "energy"),
)
MODELS = {"rotor": ROTOR, "pendulum": FakeModel("pendulum", {"g": FakeParam(9.81)}, ("theta",), ("energy",))}


def lookup(name):
    return MODELS.get(name)


def names():
    return list(MODELS)


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return str(path)


def load(tmp_path, text, overrides=()):
    return load_scene(write(tmp_path, text), overrides=list(overrides), lookup_model=lookup, model_names=names)


def error(tmp_path, text, overrides=()) -> SceneError:
    with pytest.raises(SceneError) as info:
        load(tmp_path, text, overrides)
    err = info.value
    assert isinstance(err, InputError)
    assert "\n" not in str(err) and "Traceback" not in str(err)
    return err


MINIMAL = """
model = "rotor"
[[analysis]]
name = "m1"
kind = "modes"
"""


# --------------------------------------------------------------------------- valid scenes

FULL = """
title = "full"
model = "rotor"
backend = "numpy"
free = ["k"]
[params]
m = 2
Omega = "2*pi*f0"
f0 = 0.0
law = "neo_hookean"
[coordinates]
active = ["y", "x"]

[[analysis]]
name = "eq"
kind = "steady"
guess = { x = "m/4" }

[[analysis]]
name = "lin"
kind = "stability"
about = "eq"
count = 2

[[analysis]]
name = "sim"
kind = "simulate"
t_end = "10*m"
method = "leapfrog"
dt = 0.01
q0 = { x = 0.1 }
initial_mode = 1
outputs = ["energy"]
series = true

[[analysis]]
name = "campbell"
kind = "sweep"
over = { Omega = { start = 0.0, stop = 10.0, num = 3 }, N = [2, 3] }
analysis = { kind = "stability", tolerance = "1e-6" }
workers = 2
"""


def test_minimal_scene_fills_defaults(tmp_path):
    scene = load(tmp_path, MINIMAL)
    assert isinstance(scene, Scene)
    assert scene.title == "" and scene.model == "rotor" and scene.backend == "c"
    assert scene.params == {"m": 10.0, "k": 4.0e5, "Omega": 0.0, "N": 4, "law": "linear"}
    assert isinstance(scene.params["N"], int) and isinstance(scene.params["m"], float)
    assert scene.free == () and scene.active is None
    assert scene.analyses == (AnalysisSpec("m1", "modes", {}),)


def test_full_scene_round_trips(tmp_path):
    scene = load(tmp_path, FULL.replace("f0 = 0.0", "").replace("pi*f0", "pi*5"))
    assert scene.title == "full" and scene.backend == "numpy"
    assert scene.params["m"] == 2.0 and scene.params["Omega"] == pytest.approx(10 * math.pi)
    assert scene.params["law"] == "neo_hookean"
    assert scene.active == ("x", "y")
    assert scene.free == ("k", "Omega", "N")
    eq, lin, sim, sweep = scene.analyses
    assert eq.options == {"guess": {"x": 0.5}, "tol": 1e-10, "max_iter": 50}
    # no tolerance written: none filled in (the automatic per-eigenvalue threshold, not a fixed 1e-8)
    assert lin.options == {"about": "eq", "count": 2, "refine": True, "refine_rtol": 1e-2}
    assert sim.options == {"t_end": 20.0, "method": "leapfrog", "dt": 0.01, "rtol": 1e-8, "atol": 1e-10,
                           "q0": {"x": 0.1}, "v0": {}, "initial_mode": 1, "amplitude": 1.0,
                           "outputs": ["energy"], "series": True, "samples": 201}
    assert sweep.options["workers"] == 2 and sweep.options["progress"] is True
    assert sweep.options["analysis"] == AnalysisSpec("campbell", "stability", {"tolerance": 1e-6, "refine": True, "refine_rtol": 1e-2})


def test_sweep_grid_is_cartesian_product_in_order(tmp_path):
    scene = load(tmp_path, FULL.replace("f0 = 0.0", "").replace("pi*f0", "pi*5"))
    grid = scene.analyses[3].options["grid"]
    assert grid == [{"Omega": 0.0, "N": 2}, {"Omega": 0.0, "N": 3}, {"Omega": 5.0, "N": 2},
                    {"Omega": 5.0, "N": 3}, {"Omega": 10.0, "N": 2}, {"Omega": 10.0, "N": 3}]
    assert all(isinstance(p["N"], int) for p in grid)


def test_sweep_with_single_point_and_list(tmp_path):
    scene = load(tmp_path, MINIMAL + """
[[analysis]]
name = "s"
kind = "sweep"
over = { m = { start = 1.0, stop = 5.0, num = 1 }, k = ["2*m", 3] }
analysis = { kind = "simulate", t_end = 1.0 }
""")
    spec = scene.analyses[1]
    assert spec.options["grid"] == [{"m": 1.0, "k": 20.0}, {"m": 1.0, "k": 3.0}]
    assert spec.options["analysis"].options["outputs"] == ["orbit_radius", "energy"]
    assert scene.free == ("m", "k")


def test_defaults_of_simulate(tmp_path):
    scene = load(tmp_path, """
model = "pendulum"
[[analysis]]
name = "sim"
kind = "simulate"
t_end = 5
""")
    assert scene.analyses[0].options == {"t_end": 5.0, "method": "auto", "rtol": 1e-8, "atol": 1e-10, "q0": {},
                                         "v0": {}, "amplitude": 1.0, "outputs": ["energy"], "samples": 201}
    # series left out: the time history is kept while it is small (mechgen.analyses.time_series.keep_series)


# --------------------------------------------------------------------------- parameters and overrides

def test_expressions_reference_model_defaults_and_chain(tmp_path):
    scene = load(tmp_path, MINIMAL + '[params]\nOmega = "sqrt(k/m)"\nm = "2*N"\n')
    assert scene.params["m"] == 8.0
    assert scene.params["Omega"] == pytest.approx(math.sqrt(4.0e5 / 8.0))


def test_overrides_replace_scene_values(tmp_path):
    text = MINIMAL + '[params]\nm = 3.0\nOmega = "2*pi"\n'
    scene = load(tmp_path, text, overrides=["m=5", "Omega = 2*pi*m", "law=neo_hookean", "N=8"])
    assert scene.params["m"] == 5.0 and isinstance(scene.params["m"], float)
    assert scene.params["Omega"] == pytest.approx(10 * math.pi)
    assert scene.params["law"] == "neo_hookean"
    assert scene.params["N"] == 8 and isinstance(scene.params["N"], int)


@pytest.mark.parametrize("override, key, word", [
    ("nope=1", "--set nope", "Omega"),
    ("m", "--set", "name=value"),
    ("m=sin(", "--set m", "syntax"),
    ("m=__import__('os')", "--set m", "not allowed"),
    ("m=nan", "--set m", "finite"),
    ("law=plastic", "--set law", "neo_hookean"),
    ("N=2.5", "--set N", "integer"),
])
def test_bad_overrides(tmp_path, override, key, word):
    err = error(tmp_path, MINIMAL, overrides=[override])
    assert err.key == key and word in str(err)


@pytest.mark.parametrize("params, cycle", [
    ('m = "m + 1"', "m -> m"),
    ('m = "k"\nk = "Omega"\nOmega = "2*m"', "m -> k -> Omega -> m"),
])
def test_cycles_are_named(tmp_path, params, cycle):
    err = error(tmp_path, MINIMAL + "[params]\n" + params + "\n")
    assert "cycle" in str(err) and cycle in str(err)
    assert err.key.startswith("params.")


# --------------------------------------------------------------------------- error cases

def test_missing_file(tmp_path):
    path = str(tmp_path / "absent.toml")
    with pytest.raises(SceneError) as info:
        load_scene(path, lookup_model=lookup, model_names=names)
    assert info.value.file == path and info.value.key is None
    assert info.value.expected == "an existing scene file" and "absent.toml" in str(info.value)


def test_invalid_toml_names_line(tmp_path):
    err = error(tmp_path, 'model = "rotor"\n\nm = = 3\n')
    assert "not valid TOML" in str(err) and "line 3" in str(err) and err.file.endswith("scene.toml")


def test_non_utf8_file(tmp_path):
    path = tmp_path / "bin.toml"
    path.write_bytes(b"model = \"\xff\"\n")
    with pytest.raises(SceneError, match="UTF-8"):
        load_scene(str(path), lookup_model=lookup, model_names=names)


HOSTILE = 'x); import os; os.system("echo pwned")  #'

ERRORS = [
    # (scene text, expected key, words in the message)
    ('model = "rotor"\nbogus = 1\n' + MINIMAL.split('"rotor"')[1], "bogus", ["unknown top-level key", "analysis"]),
    ('title = 3\n' + MINIMAL, "title", ["string"]),
    ('[[analysis]]\nname = "a"\nkind = "modes"\n', "model", ["rotor", "pendulum"]),
    ('model = "nope"\n[[analysis]]\nname = "a"\nkind = "modes"\n', "model", ["unknown model", "pendulum, rotor"]),
    (f"model = '{HOSTILE}'\n[[analysis]]\nname = 'a'\nkind = 'modes'\n", "model", ["unknown model"]),
    ('model = 3\n', "model", ["string"]),
    ('backend = "fortran"\n' + MINIMAL, "backend", ["c, numpy, casadi"]),
    (MINIMAL + "[params]\nnope = 1\n", "params.nope", ["no parameter", "m, k, Omega, N, law"]),
    (MINIMAL + f"[params]\n'{HOSTILE}' = 1\n", None, ["no parameter"]),
    (MINIMAL + "[params]\nm = true\n", "params.m", ["a number or an expression string"]),
    (MINIMAL + "[params]\nm = [1]\n", "params.m", ["a number or an expression string"]),
    (MINIMAL + "[params]\nm = inf\n", "params.m", ["finite"]),
    (MINIMAL + "[params]\nm = \"__import__('os')\"\n", "params.m", ["not allowed"]),
    (MINIMAL + '[params]\nm = "2 *"\n', "params.m", ["syntax"]),
    (MINIMAL + '[params]\nm = "2*q"\n', "params.m", ["unknown name 'q'", "Omega"]),
    (MINIMAL + '[params]\nm = "2*law"\n', "params.m", ["choice"]),
    (MINIMAL + "[params]\nN = 2.5\n", "params.N", ["integer"]),
    (MINIMAL + '[params]\nlaw = "plastic"\n', "params.law", ["linear, neo_hookean"]),
    (MINIMAL + "[params]\nlaw = 1\n", "params.law", ["choice"]),
    ('params = 3\n' + MINIMAL, "params", ["table"]),
    ('free = ["nope"]\n' + MINIMAL, "free[1]", ["no parameter"]),
    ('free = ["law"]\n' + MINIMAL, "free[1]", ["choice"]),
    ('free = "m"\n' + MINIMAL, "free", ["array"]),
    (MINIMAL + '[coordinates]\nactive = ["x", "z"]\n', "coordinates.active[2]", ["x, y, theta"]),
    (MINIMAL + '[coordinates]\nactive = ["x", "x"]\n', "coordinates.active[2]", ["twice"]),
    (MINIMAL + '[coordinates]\nactive = []\n', "coordinates.active", ["non-empty"]),
    (MINIMAL + '[coordinates]\nfrozen = ["x"]\n', "coordinates.frozen", ["active"]),
    ('model = "rotor"\n', "analysis", ["one or more"]),
    ('model = "rotor"\n[analysis]\nname = "a"\nkind = "modes"\n', "analysis", ["one or more"]),
    ('model = "rotor"\n[[analysis]]\nkind = "modes"\n', "analysis[1].name", ["missing", "identifier"]),
    ('model = "rotor"\n[[analysis]]\nname = "a"\n', "analysis[1].kind", ["missing", "modes, stability"]),
    (MINIMAL + '[[analysis]]\nname = "b"\nkind = "fly"\n', "analysis[2].kind",
     ["one of: modes, stability, steady, simulate, sweep"]),
    (MINIMAL + '[[analysis]]\nname = "m1"\nkind = "modes"\n', "analysis[2].name", ["twice"]),
    (f"model = 'rotor'\n[[analysis]]\nname = '{HOSTILE}'\nkind = 'modes'\n", "analysis[1].name", ["not an identifier"]),
    ('model = "rotor"\n[[analysis]]\nname = "class"\nkind = "modes"\n', "analysis[1].name", ["identifier"]),
    ('model = "rotor"\n[[analysis]]\nname = "__a"\nkind = "modes"\n', "analysis[1].name", ["identifier"]),
    (MINIMAL + "bogus = 1\n", "analysis[1].bogus", ["unknown key", "about, at, count"]),
    (MINIMAL + "count = 0\n", "analysis[1].count", [">= 1"]),
    (MINIMAL + "count = 1.5\n", "analysis[1].count", ["integer"]),
    (MINIMAL + "at = { z = 1 }\n", "analysis[1].at.z", ["unknown coordinate", "x, y, theta"]),
    (MINIMAL + 'at = { x = "1/0" }\n', "analysis[1].at.x", ["division by zero"]),
    (MINIMAL + 'about = "later"\n[[analysis]]\nname = "later"\nkind = "steady"\n', "analysis[1].about",
     ["comes later"]),
    (MINIMAL + '[[analysis]]\nname = "b"\nkind = "stability"\nabout = "m1"\n', "analysis[2].about",
     ["not steady"]),
    (MINIMAL + 'about = "ghost"\n', "analysis[1].about", ["no analysis named"]),
    (MINIMAL.replace("modes", "stability") + "tolerance = -1\n", "analysis[1].tolerance", ["> 0"]),
    (MINIMAL.replace("modes", "steady") + 'tol = "x"\n', "analysis[1].tol", ["unknown name 'x'"]),
    (MINIMAL.replace("modes", "steady") + "max_iter = true\n", "analysis[1].max_iter", ["integer"]),
    (MINIMAL.replace("modes", "simulate"), "analysis[1].t_end", ["missing required key"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\nmethod = 'euler'\n", "analysis[1].method", ["leapfrog"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\nmethod = 'leapfrog'\n", "analysis[1].dt", ["time step"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\ndt = 2\n", "analysis[1].dt", ["exceeds t_end"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 0\n", "analysis[1].t_end", ["> 0"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\noutputs = ['pwned']\n", "analysis[1].outputs[1]",
     ["orbit_radius, energy"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\ninitial_mode = 4\n", "analysis[1].initial_mode",
     ["from 1 to 3"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\nseries = 1\n", "analysis[1].series", ["true or false"]),
    (MINIMAL.replace("modes", "simulate") + "t_end = 1\nsample_rate = 5\n", "analysis[1].sample_rate", ["unknown key"]),
    (MINIMAL.replace("modes", "sweep") + "analysis = { kind = 'modes' }\n", "analysis[1].over", ["missing"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = [1] }\n", "analysis[1].analysis", ["missing"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = [1] }\nanalysis = { kind = 'sweep' }\n",
     "analysis[1].analysis.kind", ["modes, stability, steady, simulate"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = [1] }\nanalysis = { count = 1 }\n",
     "analysis[1].analysis.kind", ["missing"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = [1] }\nanalysis = { kind = 'modes', name = 'x' }\n",
     "analysis[1].analysis.name", ["unknown key"]),
    (MINIMAL.replace("modes", "sweep") + "over = { Omega = { start = 0, stop = 1, num = 0 } }\n"
     "analysis = { kind = 'modes' }\n", "analysis[1].over.Omega.num", [">= 1"]),
    (MINIMAL.replace("modes", "sweep") + "over = { Omega = { start = 0, num = 2 } }\nanalysis = { kind = 'modes' }\n",
     "analysis[1].over.Omega.stop", ["missing"]),
    (MINIMAL.replace("modes", "sweep") + "over = { Omega = { start = 0, stop = 1, num = 2, step = 1 } }\n"
     "analysis = { kind = 'modes' }\n", "analysis[1].over.Omega.step", ["unknown key"]),
    (MINIMAL.replace("modes", "sweep") + "over = { Omega = [] }\nanalysis = { kind = 'modes' }\n",
     "analysis[1].over.Omega", ["non-empty"]),
    (MINIMAL.replace("modes", "sweep") + "over = { law = ['linear', 'rubber'] }\nanalysis = { kind = 'modes' }\n",
     "analysis[1].over.law[2]", ["rubber", "neo_hookean"]),
    (MINIMAL.replace("modes", "sweep") + "over = { law = 'linear' }\nanalysis = { kind = 'modes' }\n",
     "analysis[1].over.law", ["array of choices"]),
    (MINIMAL.replace("modes", "sweep") + "over = { N = [1.5] }\nanalysis = { kind = 'modes' }\n",
     "analysis[1].over.N", ["integer"]),
    (MINIMAL.replace("modes", "sweep") + "over = { nope = [1] }\nanalysis = { kind = 'modes' }\n",
     "analysis[1].over.nope", ["no parameter"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = [1] }\nanalysis = { kind = 'simulate', t_end = '1/m' }\n",
     "analysis[1].analysis.t_end", ["swept parameter 'm'"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = [1, 2] }\nanalysis = { kind = 'modes' }\n"
     "[params]\nOmega = 'm'\n", "analysis[1].over.m", ["computed from 'm'"]),
    ('model = "rotor"\n[[analysis]]\nname = "e"\nkind = "steady"\n[[analysis]]\nname = "s"\nkind = "sweep"\n'
     "over = { m = [1] }\nanalysis = { kind = 'modes', about = 'e' }\n", "analysis[2].analysis.about",
     ["inside a sweep"]),
    (MINIMAL.replace("modes", "sweep") + "over = { m = { start = 0, stop = 1, num = 2000 }, "
     "k = { start = 0, stop = 1, num = 2000 } }\nanalysis = { kind = 'modes' }\n", "analysis[1].over", ["points"]),
]


@pytest.mark.parametrize("text, key, words", ERRORS)
def test_error_names_file_key_and_expectation(tmp_path, text, key, words):
    err = error(tmp_path, text)
    message = str(err)
    assert err.file.endswith("scene.toml") and "scene.toml" in message
    if key is not None:
        assert err.key == key and f"'{key}'" in message
    assert err.expected
    for word in words:
        assert word in message, message


def test_hostile_key_is_quoted_not_echoed_raw(tmp_path):
    err = error(tmp_path, MINIMAL + "[params]\n\"a\\nb); os.system('x')\" = 1\n")
    assert err.key.startswith('params."') and "\n" not in str(err)


def test_frozen_coordinate_is_not_settable(tmp_path):
    text = MINIMAL.replace("modes", "steady") + 'guess = { theta = 1 }\n[coordinates]\nactive = ["x"]\n'
    err = error(tmp_path, text)
    assert err.key == "analysis[1].guess.theta" and "not active" in str(err) and "active coordinates: x" in str(err)


def test_first_error_is_reported(tmp_path):
    err = error(tmp_path, 'model = "nope"\nbackend = "fortran"\n')
    assert err.key == "model"
