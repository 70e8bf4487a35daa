"""Models from the user's own files: a path in a scene, package.module:attribute, an installed entry point;
through `mechgen run`, `mechgen.run` (a file or a dict), `mechgen show` and `mechgen.load_model`; the compile
cache; and every way a model file can be wrong (exit 2 naming the file and the line).

The reference numbers are closed forms of the user's own one-dof oscillator, T = m x'^2/2, V = k x^2/2:
omega = sqrt(k/m) and, released from x0 at rest, x(t) = x0 cos(omega t).
"""
from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError, ModelError

ROOT = Path(__file__).resolve().parents[1]

OSCILLATOR = '''\
"""A user's oscillator: T = m x'^2/2, V = k x^2/2, omega = sqrt(k/m)."""
from mechgen import Model, Param

{name} = Model("user_oscillator", doc=__doc__)
{name}.params(Param("m", 2.0, "kg", positive=True), Param("k", {k}, "N/m", positive=True))
{name}.coordinates("x")


@{name}.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@{name}.potential
def potential(q, p):
    return p.k * q.x**2 / 2


{name}.output("position", lambda q: q.x, unit="m")
'''

SCENE = '''\
model = "{model}"
[params]
k = 72.0
[[analysis]]
name = "free"
kind = "modes"
[[analysis]]
name = "released"
kind = "simulate"
t_end = 1.0
q0 = {{ x = 0.1 }}
rtol = 1e-10
atol = 1e-12
[[analysis]]
name = "stiffness"
kind = "sweep"
over = {{ k = [8.0, 18.0, 32.0] }}
workers = 2
[analysis.analysis]
kind = "modes"
'''
M = 2.0


def _oscillator(path: Path, *, name: str = "model", k: float = 50.0) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(OSCILLATOR.format(name=name, k=k))
    return path


def _project(tmp_path: Path) -> Path:
    """A user folder outside the package: models/osc.py and a scene naming it by a relative path."""
    folder = tmp_path / "project"
    _oscillator(folder / "models" / "osc.py")
    (folder / "osc.toml").write_text(SCENE.format(model="models/osc.py"))
    return folder


def _env(cache: Path, *paths: Path) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([*(str(p) for p in paths), str(ROOT)])
    env["MECHGEN_CACHE"] = str(cache)
    return env


def _mechgen(args: list[str], *, cwd: Path, env: dict) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mechgen", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


def _outputs(results: dict) -> dict:
    return {a["name"]: a["outputs"] for a in results["analyses"]}


def _check_oscillator(results: dict) -> None:
    """Every number of SCENE against the closed forms (k = 72, m = 2: omega = 6)."""
    out = _outputs(results)
    assert results["model"] == "user_oscillator"
    omega = math.sqrt(72.0 / M)
    assert out["free"]["frequencies"] == pytest.approx([omega], rel=1e-12)
    assert out["released"]["position"] == pytest.approx(0.1 * math.cos(omega * 1.0), rel=1e-6, abs=1e-9)
    assert [f[0] for f in out["stiffness"]["frequencies"]] == pytest.approx(
        [math.sqrt(k / M) for k in (8.0, 18.0, 32.0)], rel=1e-12)


# ----------------------------------------------------------------------------- a model file next to its scene

def test_a_scene_names_a_model_file_relative_to_its_folder_cli(tmp_path):
    folder = _project(tmp_path)
    target = tmp_path / "out.json"
    proc = _mechgen(["run", str(folder / "osc.toml"), "--json", str(target)], cwd=tmp_path,  # not the scene's folder
                    env=_env(tmp_path / "cache"))
    assert proc.returncode == 0, proc.stderr
    assert "user_oscillator" in proc.stdout
    _check_oscillator(json.loads(target.read_text()))


def test_mechgen_run_takes_a_scene_file_or_a_dict(tmp_path, monkeypatch):
    folder = _project(tmp_path)
    _check_oscillator(mechgen.run(folder / "osc.toml"))
    monkeypatch.chdir(folder)  # a dict's relative model path is taken from the current directory
    import tomllib

    scene = tomllib.loads((folder / "osc.toml").read_text())
    scene["analysis"][2]["workers"] = 0
    results = mechgen.run(scene)
    assert results["scene"] == "<dict>"
    _check_oscillator(results)


def test_a_dict_scene_names_its_errors_as_dict(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match="<dict>.*model.*does not exist"):
        mechgen.run({"model": "models/none.py", "analysis": [{"name": "m", "kind": "modes"}]})
    with pytest.raises(InputError, match="<dict>.*unknown top-level key"):
        mechgen.run({"model": "laval_rotor", "colour": 3})


def test_an_edited_model_file_is_loaded_again_in_the_same_process(tmp_path):
    path = _oscillator(tmp_path / "osc.py", k=50.0)
    scene = {"model": str(path), "analysis": [{"name": "free", "kind": "modes"}]}
    first = _outputs(mechgen.run(scene))["free"]["frequencies"]
    _oscillator(path, k=98.0)
    second = _outputs(mechgen.run(scene))["free"]["frequencies"]
    assert first == pytest.approx([math.sqrt(50.0 / M)], rel=1e-12)
    assert second == pytest.approx([math.sqrt(98.0 / M)], rel=1e-12)


def test_sweep_workers_started_fresh_find_the_model_by_its_canonical_key(tmp_path):
    """A spawned worker imports nothing of the parent: the task's key (an absolute path) must resolve alone."""
    folder = _project(tmp_path)
    code = textwrap.dedent(f"""
        import json, multiprocessing
        multiprocessing.set_start_method("spawn")
        import mechgen
        print(json.dumps(mechgen.run({str(folder / "osc.toml")!r})))
    """)
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=_env(tmp_path / "cache"),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    _check_oscillator(json.loads(proc.stdout.strip().splitlines()[-1]))


def test_show_and_load_model_take_a_path(tmp_path, monkeypatch):
    folder = _project(tmp_path)
    proc = _mechgen(["show", "models/osc.py"], cwd=folder, env=_env(tmp_path / "cache"))
    assert proc.returncode == 0, proc.stderr
    assert "model user_oscillator" in proc.stdout and str(folder / "models" / "osc.py") in proc.stdout
    assert "r[x] = k*x + m*x_ddot" in proc.stdout and "K =\n  [k]" in proc.stdout
    model = mechgen.load_model(folder / "models" / "osc.py")
    assert model.name == "user_oscillator" and model.file == str((folder / "models" / "osc.py").resolve())
    assert mechgen.load_model("models/osc.py", base=folder) is model  # one module per file and content
    monkeypatch.chdir(folder)
    assert mechgen.load_model("models/osc.py") is model


# ----------------------------------------------------------------------------- module:attribute and entry points

def test_module_attribute_reference(tmp_path):
    package = tmp_path / "site" / "userpkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    _oscillator(package / "oscillators.py", name="spring")
    (tmp_path / "osc.toml").write_text(SCENE.format(model="userpkg.oscillators:spring"))
    env = _env(tmp_path / "cache", tmp_path / "site")
    target = tmp_path / "out.json"
    proc = _mechgen(["run", "osc.toml", "--json", str(target)], cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr
    _check_oscillator(json.loads(target.read_text()))
    proc = _mechgen(["show", "userpkg.oscillators:spring"], cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "model user_oscillator" in proc.stdout and "K =\n  [k]" in proc.stdout
    proc = _mechgen(["show", "userpkg.oscillators:nothing"], cwd=tmp_path, env=env)
    assert proc.returncode == 2 and "oscillators.py" in proc.stderr and "no Model called 'nothing'" in proc.stderr


def _installed_distribution(site: Path) -> None:
    """A real distribution on the path: a package and its <name>.dist-info with METADATA and entry_points.txt."""
    (site / "epdemo").mkdir(parents=True)
    (site / "epdemo" / "__init__.py").write_text("")
    _oscillator(site / "epdemo" / "models.py", k=32.0)
    info = site / "epdemo-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: epdemo\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[mechgen.models]\nepdemo_osc = epdemo.models:model\n"
                                           "laval_rotor = epdemo.models:model\n")  # a built-in's name: ignored


def test_entry_point_models_are_listed_shown_and_run(tmp_path):
    _installed_distribution(tmp_path / "site")
    env = _env(tmp_path / "cache", tmp_path / "site")
    proc = _mechgen(["models"], cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr
    rows = {line.split()[0]: line for line in proc.stdout.splitlines()}
    assert "entry point of epdemo 1.0 (epdemo.models:model)" in rows["epdemo_osc"]
    assert "A user's oscillator" in rows["epdemo_osc"]
    assert rows["laval_rotor"].split()[1] == "built-in" and "Laval" in rows["laval_rotor"]
    scene = 'model = "epdemo_osc"\n[[analysis]]\nname = "free"\nkind = "modes"\n'
    (tmp_path / "ep.toml").write_text(scene)
    target = tmp_path / "out.json"
    proc = _mechgen(["run", "ep.toml", "--json", str(target)], cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr
    assert _outputs(json.loads(target.read_text()))["free"]["frequencies"] == pytest.approx([math.sqrt(32.0 / M)],
                                                                                            rel=1e-12)
    proc = _mechgen(["show", "epdemo_osc"], cwd=tmp_path, env=env)
    assert proc.returncode == 0 and "entry point of epdemo" in proc.stdout
    proc = _mechgen(["run", "ep.toml"], cwd=tmp_path, env=_env(tmp_path / "cache"))  # not installed here
    assert proc.returncode == 2 and "unknown model 'epdemo_osc'" in proc.stderr


# ----------------------------------------------------------------------------- the compile cache

def _derive_seconds(folder: Path, cache: Path) -> float:
    target = folder / "out.json"
    proc = _mechgen(["run", "osc.toml", "--json", str(target)], cwd=folder, env=_env(cache))
    assert proc.returncode == 0, proc.stderr
    build = json.loads(target.read_text())["build"]
    return build["seconds"]["derive"] + build["seconds"]["lower"] + build["seconds"]["emit"]


def test_a_user_model_is_derived_once_and_cached_by_its_bytes(tmp_path):
    folder = tmp_path / "project"
    _oscillator(folder / "osc.py")
    (folder / "osc.toml").write_text('model = "osc.py"\n[[analysis]]\nname = "free"\nkind = "modes"\n')
    cache = tmp_path / "cache"
    assert _derive_seconds(folder, cache) > 0.0
    assert _derive_seconds(folder, cache) == 0.0  # a new process: nothing derived, lowered or emitted
    with (folder / "osc.py").open("a") as fh:
        fh.write("# an edit: new bytes, a new cache entry\n")
    assert _derive_seconds(folder, cache) > 0.0


def test_two_models_in_one_file_are_two_cache_entries(tmp_path):
    """The cache is keyed by the file's bytes and the model's name: two Models in one file (same parameter
    values, different energies) must not share kernels. soft: omega^2 = k/m, hard: omega^2 = 4 k/m."""
    text = _oscillator(tmp_path / "unused.py").read_text()
    two = text.replace("model", "soft") + "\n\n" + text.replace("model", "hard").replace(
        '"user_oscillator"', '"hard_oscillator"').replace("p.k * q.x**2 / 2", "2 * p.k * q.x**2")
    (tmp_path / "two.py").write_text(two)
    got = {}
    for name in ("soft", "hard"):
        scene = {"model": f"{tmp_path / 'two.py'}:{name}", "analysis": [{"name": "free", "kind": "modes"}]}
        got[name] = _outputs(mechgen.run(scene))["free"]["frequencies"]
    assert got["soft"] == pytest.approx([math.sqrt(50.0 / M)], rel=1e-12)
    assert got["hard"] == pytest.approx([math.sqrt(4 * 50.0 / M)], rel=1e-12)
    with pytest.raises(ModelError, match="no Model called 'model' \\(it has hard, soft\\)"):
        mechgen.load_model(tmp_path / "two.py")


# ----------------------------------------------------------------------------- bad model files

HEAD = "from mechgen import Model, Param\nmodel = Model(\"bad\")\n"
BAD_MODELS = {
    # name: (model file text, what the message must say, the line it must name or None)
    "syntax_error": ('from mechgen import Model, Param\nmodel = Model("bad"\nmodel.coordinates("x")\n',
                     ["syntax error"], 2),
    "raises_on_import": (HEAD + "model.params(Param('k', 1.0))\nratio = 1 / 0\n",
                         ["ZeroDivisionError", "division by zero"], 4),
    "no_model": ("from mechgen import Model\nthing = 3\n", ["defines no Model", "model = Model("], None),
    "undeclared_parameter": (HEAD + "model.params(Param('m', 1.0), Param('k', 1.0))\nmodel.coordinates('x')\n\n\n"
                             "@model.potential\ndef potential(q, p):\n    return p.kk * q.x**2 / 2\n",
                             ["potential", "p.kk", "not a declared parameter", "m, k"], 9),
    "keyword_coordinate": (HEAD + "model.coordinates('x', 'lambda')\n", ["keyword", "'lambda'"], 3),
    "keyword_parameter": (HEAD + "model.params(Param('m', 1.0), Param('class', 1.0))\n", ["keyword", "'class'"], 3),
    "vector_energy": (HEAD + "model.params(Param('k', 1.0))\nmodel.coordinates('x', 'y')\n\n\n@model.potential\n"
                      "def potential(q, p):\n    return [p.k * q.x**2 / 2, q.y**2]\n",
                      ["potential", "not a scalar", "a list of 2 entries"], 7),
    "vector_density": (HEAD + "model.params(Param('L', 1.0), Param('EI', 1.0))\nmodel.field('w', length='L')\n\n\n"
                       "@model.potential_density\ndef strain(u, p):\n    return (p.EI * u.w_ss**2 / 2,)\n",
                       ["strain", "potential_density", "not a scalar", "tuple"], 7),
    "stray_symbol": ("import sympy as sp\n" + HEAD + "model.params(Param('k', 1.0))\nmodel.coordinates('x')\n"
                     "c = sp.Symbol('c')\n\n\n@model.potential\ndef potential(q, p):\n    return c * q.x**2\n",
                     ["potential", "symbol c", "Param"], 9),
    "unknown_jet": (HEAD + "model.params(Param('L', 1.0))\nmodel.field('w', length='L')\n\n\n"
                    "@model.potential_density\ndef strain(u, p):\n    return u.w_x**2\n", ["strain", "no jet 'w_x'"], 9),
}


IMPORT_TIME = {"syntax_error", "raises_on_import", "no_model", "keyword_coordinate", "keyword_parameter"}


def _one_paragraph(err: str) -> str:
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    return err


@pytest.mark.parametrize("case", sorted(BAD_MODELS))
def test_a_bad_model_file_exits_2_naming_the_file_and_line(case, tmp_path, capsys):
    text, words, line = BAD_MODELS[case]
    model = tmp_path / "models" / f"{case}.py"
    model.parent.mkdir()
    model.write_text(text)
    scene = tmp_path / "scene.toml"
    scene.write_text(f'model = "models/{case}.py"\n[[analysis]]\nname = "m"\nkind = "modes"\n')
    target = tmp_path / "never.json"
    code = main(["run", str(scene), "--json", str(target)])
    err = _one_paragraph(capsys.readouterr().err)
    assert code == 2
    assert str(model) in err
    for word in words:
        assert word in err, err
    if line is not None:
        assert re.search(rf"\bline {line}\b", err), err
    assert not target.exists()
    assert main(["show", str(model)]) == 2  # the same message from `mechgen show PATH`
    assert str(model) in _one_paragraph(capsys.readouterr().err)
    from mechgen.scene.show import show_model

    if case in IMPORT_TIME:  # the file itself does not import
        with pytest.raises(ModelError) as info:
            mechgen.load_model(model)
        assert info.value.file == str(model)
    with pytest.raises(ModelError) as info:  # load, then derive
        show_model(str(model))
    assert info.value.file == str(model)


def test_a_missing_model_file_or_module_names_the_scene(tmp_path, capsys):
    for ref, words in (("models/none.py", ["does not exist", str(tmp_path / "models" / "none.py")]),
                       ("nosuchpkg_xyz.models:spring", ["no module 'nosuchpkg_xyz.models'"]),
                       ("warp_drive", ["unknown model", "laval_rotor", "package.module:attribute"])):
        scene = tmp_path / "scene.toml"
        scene.write_text(f'model = "{ref}"\n[[analysis]]\nname = "m"\nkind = "modes"\n')
        assert main(["run", str(scene)]) == 2
        err = _one_paragraph(capsys.readouterr().err)
        assert str(scene) in err and "'model'" in err
        for word in words:
            assert word in err, err


def test_declaration_errors_name_the_declaring_file():
    from mechgen import Model, Param

    with pytest.raises(ModelError, match="keyword") as info:
        Param("lambda", 1.0)
    assert info.value.file == __file__
    model = Model("scripted")
    assert model.file is None  # built in a function: its file's bytes do not determine it, so no cache key
    with pytest.raises(ModelError, match="keyword") as info:
        model.coordinates("if")
    assert info.value.file == __file__


def test_a_scripted_model_with_a_stray_symbol_names_the_function():
    import sympy as sp

    from mechgen import Model, Param
    from mechgen.pipeline import derive
    from mechgen.symbolic.specialize import specialize

    model = Model("scripted")
    model.params(Param("k", 1.0))
    model.coordinates("x")
    c = sp.Symbol("c")
    model.potential(lambda q, p: c * q.x**2)
    with pytest.raises(ModelError, match="the symbol c") as info:
        derive(model, specialize(model, {}))
    assert info.value.file == __file__ and "<lambda>" in info.value.message


# ----------------------------------------------------------------------------- a continuum from a user file

@pytest.mark.slow
def test_a_user_continuum_reaches_the_steady_branch_code(tmp_path):
    """A copy of the balloon under another name, outside the package: steady states and shape outputs
    (mechgen/scene/branches.py) find it by its canonical key and agree with the built-in to round-off."""
    text = (ROOT / "mechgen" / "models" / "balloon_string.py").read_text()
    text = text.replace('Model("balloon_string", doc=__doc__, file=__file__)', 'Model("my_balloon", doc=__doc__)')
    assert 'Model("my_balloon"' in text
    (tmp_path / "my_balloon.py").write_text(text)
    scene = {"params": {"h": 10.0, "beta": 100.0, "lambda0": -0.5, "N": 10},
             "analysis": [{"name": "start", "kind": "steady", "method": "collocation", "form": "hamiltonian",
                           "bulge": {"x": [2.0]}, "aliases": {"p_e": "tension_start"}}]}
    mine = _outputs(mechgen.run({**scene, "model": str(tmp_path / "my_balloon.py")}))["start"]
    builtin = _outputs(mechgen.run({**scene, "model": "balloon_string"}))["start"]
    assert mine["loops"] == builtin["loops"] == 1
    assert mine["p_e"] == pytest.approx(builtin["p_e"], rel=1e-10)


# ----------------------------------------------------------------------------- the user guide's section, verbatim

def _readme_section() -> str:
    text = (ROOT / "docs" / "guide.md").read_text()  # moved there from the README (issue 26)
    start = text.index("## Your own models")
    end = text.index("\n## ", start + 1)
    return text[start:end]


def test_readme_your_own_models_runs_verbatim(tmp_path, monkeypatch):
    section = _readme_section()
    python = re.findall(r"```python\n(.*?)```", section, re.S)
    toml = re.findall(r"```toml\n(.*?)```", section, re.S)
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "oscillator.py").write_text(python[0])
    (tmp_path / "oscillator.toml").write_text(toml[0])
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(python[1], "guide.md", "exec"), namespace)  # the guide's own Python use, as written
    omega = math.sqrt(50.0 / 2.0)  # the scene's k and m
    for results in (namespace["results"], namespace["same"]):
        assert _outputs(results)["free"]["frequencies"] == pytest.approx([omega], rel=1e-12)
    assert namespace["model"].name == "oscillator"
