"""Issue 12, sections 4 and 5: every mistake in a scene or a flag is one paragraph, exit 2, naming the
scene file, the key the user wrote and what was expected; nothing is computed or written first.

Each case is run through ``mechgen.cli.main`` (the exit code and stderr a user sees); a few check,
with ``load_scene``, that the fix a message suggests is accepted.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from mechgen.cli import main
from mechgen.errors import ModelError, SceneError

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"


def _scene(tmp_path: Path, name: str, *edits: tuple[str, str], append: str = "", file: str = "scene.toml") -> Path:
    """A shipped scene with ``old -> new`` edits (each must apply once) and text appended."""
    text = (SCENES / f"{name}.toml").read_text()
    for old, new in edits:
        assert text.count(old) >= 1, old
        text = text.replace(old, new, 1)
    path = tmp_path / file
    path.write_text(text + append)
    return path


def _fails(argv: list, capsys, *words: str) -> str:
    """Run the CLI: exit 2, one paragraph on stderr with every word in it, nothing on stdout (no
    analysis ran: the summary is printed only after the run)."""
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    assert code == 2, out.err
    assert "Traceback" not in out.err
    assert len(out.err.strip().splitlines()) == 1, out.err
    assert out.out == ""
    for word in words:
        assert word in out.err, (word, out.err)
    return out.err


def _load(path: Path, overrides=()):
    from mechgen import models
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene

    return load_scene(str(path), overrides=list(overrides), lookup_model=lookup_model, model_names=models.known)


# ----------------------------------------------------------------------------- sizes (section 5)

@pytest.mark.parametrize("value", ["0", "-0", "-5", "1e308", "-0.0"])
def test_a_chain_size_out_of_range_is_refused_at_params_N(value, tmp_path, capsys):
    path = _scene(tmp_path, "fpu_chain", ("N = 32", f"N = {value}"))
    _fails(["run", path], capsys, str(path), "'params.N'", "an integer from 1 to 10000000")


def test_a_fractional_size_is_refused_as_not_an_integer(tmp_path, capsys):
    path = _scene(tmp_path, "fpu_chain", ("N = 32", "N = 1.5"))
    _fails(["run", path], capsys, str(path), "'params.N'", "not an integer", "an integer value")


@pytest.mark.parametrize("value", ["0", "-5", "1e308"])
def test_a_continuum_size_out_of_range_is_refused_at_params_N(value, tmp_path, capsys):
    """Before: 'at key discretisation' (0, -5, 1e308: SuperLU, numpy's 'Maximum allowed size')."""
    path = _scene(tmp_path, "beam_modes", ("N = 16", f"N = {value}"))
    err = _fails(["run", path], capsys, str(path), "'params.N'", "an integer from 1 to 10000000")
    assert "discretisation" not in err


def test_a_size_from_set_is_refused_at_the_flag(capsys):
    _fails(["run", SCENES / "fpu_chain.toml", "--set", "N=0"], capsys, "'--set N'", "an integer from 1 to")


def test_a_huge_size_names_the_safety_limit_and_how_to_raise_it(tmp_path, capsys):
    path = _scene(tmp_path, "fpu_chain", ("N = 32", "N = 20_000_000"))
    _fails(["run", path], capsys, str(path), "'params.N'", "10000000", "[limits] size = ")
    raised = _scene(tmp_path, "fpu_chain", ("N = 32", "N = 20_000_000"), ('backend = "c"', 'backend = "c"\n'
                    "[limits]\nsize = 30_000_000"), file="raised.toml")
    assert _load(raised).params["N"] == 20_000_000  # loads (and allocates nothing)


def test_quadrature_is_bounded_at_load_and_the_bound_can_be_raised(tmp_path, capsys):
    """Before: quadrature = 100000 allocated a 74.5 GiB Gauss companion matrix."""
    path = _scene(tmp_path, "beam_modes", ("N = 16", "N = 16\nquadrature = 100000"))
    _fails(["run", path], capsys, str(path), "'params.quadrature'", "from 0 to 100", "[limits] quadrature = ")
    raised = _scene(tmp_path, "beam_modes", ("N = 16", "N = 16\nquadrature = 150"),
                    ('backend = "c"', 'backend = "c"\n[limits]\nquadrature = 200'), file="raised.toml")
    assert _load(raised).params["quadrature"] == 150


def test_simulate_samples_are_bounded_and_the_bound_can_be_raised(tmp_path, capsys):
    path = _scene(tmp_path, "spring_pendulum", append="samples = 1e8\n")
    _fails(["run", path], capsys, str(path), "'analysis[3].samples'", "1000000", "[limits] samples = ")
    raised = _scene(tmp_path, "spring_pendulum", ('backend = "c"', 'backend = "c"\n[limits]\nsamples = 2e8'),
                    append="samples = 1e8\n", file="raised.toml")
    assert _load(raised).analyses[2].options["samples"] == 100_000_000


@pytest.mark.parametrize("table, key, words", [
    ("sise = 5", "limits.sise", ["unknown limit", "size", "samples", "quadrature", "N"]),
    ("size = -5", "limits.size", ["an integer from 1 to"]),
    ("size = 2.5", "limits.size", ["an integer from 1 to"]),
    ('size = "many"', "limits.size", ["a string", "an integer from 1 to"]),
])
def test_a_bad_limits_table_is_refused(table, key, words, tmp_path, capsys):
    path = _scene(tmp_path, "fpu_chain", ('backend = "c"', f'backend = "c"\n[limits]\n{table}'))
    _fails(["run", path], capsys, str(path), f"'{key}'", *words)


# ----------------------------------------------------------------------------- declared bounds (section 5)

@pytest.mark.parametrize("scene, old, new, key, words", [
    ("beam_modes", "L = 1.0", "L = -1.0", "params.L", ["L = -1.0 is not positive", "a value > 0"]),
    ("beam_modes", "rhoA = 1.0", "rhoA = -1.0", "params.rhoA", ["rhoA = -1.0 is not positive"]),
    ("timoshenko_modes", "rhoI = 0.001", "rhoI = 5e-324", "params.rhoI", ["subnormal", "2.225e-308"]),
    ("spring_pendulum", "m = 1.0", "m = 0", "params.m", ["m = 0.0 is not positive"]),
    ("laval_rotor", "m = ", "m = -0.0 # ", "params.m", ["is not positive"]),
    ("spring_pendulum", "m = 1.0", 'm = "1 - 1"', "params.m", ["is not positive"]),
])
def test_a_value_outside_its_declared_bounds_is_refused_at_the_key_written(scene, old, new, key, words, tmp_path,
                                                                            capsys):
    """Before: negative L at 'discretisation', negative rhoA at 'M', rhoI = 5e-324 and m = 0 accepted or
    a LinAlgError; now at the key the scene wrote, before compiling."""
    path = _scene(tmp_path, scene, (old, new))
    err = _fails(["run", path], capsys, str(path), f"'{key}'", *words)
    assert "'M'" not in err and "'discretisation'" not in err


def test_a_value_below_its_bound_from_set_is_refused_at_the_flag(capsys):
    _fails(["run", SCENES / "spring_pendulum.toml", "--set", "k=-40"], capsys, "'--set k'", "not positive")


def test_declared_minimum_and_maximum_of_a_user_model(tmp_path, capsys):
    model = tmp_path / "models" / "ratio.py"
    model.parent.mkdir()
    model.write_text(
        "from mechgen import Model, Param\nmodel = Model('ratio')\n"
        "model.params(Param('m', 1.0, positive=True), Param('nu', 0.3, minimum=-1.0, maximum=0.5))\n"
        "model.coordinates('x')\n\n\n@model.kinetic\ndef kinetic(v, p):\n    return p.m * v.x**2 / 2\n\n\n"
        "@model.potential\ndef potential(q, p):\n    return (1 + p.nu) * q.x**2 / 2\n")
    scene = tmp_path / "scene.toml"
    for value, words in (("0.7", ["nu = 0.7 is above the maximum 0.5", "a value <= 0.5"]),
                         ("-2", ["nu = -2.0 is below the minimum -1.0", "a value >= -1.0"])):
        scene.write_text(f'model = "models/ratio.py"\n[params]\nnu = {value}\n'
                         '[[analysis]]\nname = "m"\nkind = "modes"\n')
        _fails(["run", scene], capsys, str(scene), "'params.nu'", *words)
    scene.write_text('model = "models/ratio.py"\n[params]\nnu = 0.5\n[[analysis]]\nname = "m"\nkind = "modes"\n')
    assert _load(scene).params["nu"] == 0.5  # the bounds are inclusive


def test_bad_bounds_in_a_declaration_name_the_declaring_file():
    from mechgen import Param

    for default, kwargs, words in ((0.3, dict(minimum=1.0, maximum=0.0), "above maximum"),
                                   (0.3, dict(minimum=math.nan), "not a finite number"),
                                   (0.3, dict(maximum=0.1), "outside"),
                                   (None, {}, "not a finite number or a string"),
                                   ([1.0], {}, "not a finite number or a string"),
                                   (math.inf, {}, "not a finite number or a string"),
                                   (-1.0, dict(positive=True), "not positive"),
                                   (2.0, dict(below=1.0), "not below 1.0"),
                                   (0.3, dict(below="one"), "below = 'one' is not a finite number"),
                                   (2.5, dict(size=True), "not an integer")):
        with pytest.raises(ModelError, match=words) as info:
            Param("nu", default, **kwargs)
        assert info.value.file == __file__ and info.value.key.startswith("nu.")


# ----------------------------------------------------------------------------- parts and --set (section 4)

ROSS_EDIT = ("at = 0.5", "at = 0.6")


def test_a_part_off_a_vertex_is_reported_at_its_at_key_with_a_fix(tmp_path, capsys):
    """Before: 'at key discretisation' and no file. The message suggests two segments or an N whose
    uniform mesh has a vertex at every part (0.6, 1.0 on L = 1.5: N = 15)."""
    path = _scene(tmp_path, "ross_example_rotor", ROSS_EDIT)
    err = _fails(["run", path], capsys, str(path), "'parts[1].at'", "disk at s = 0.6", "not at a mesh vertex",
                 "segment boundary", "[[segments]] length = 0.6, elements = 2", "[[segments]] length = 0.9",
                 "N = 15")
    assert "'discretisation'" not in err
    fixed = _scene(tmp_path, "ross_example_rotor", ROSS_EDIT, ("N = 6", "N = 15"), file="fixed.toml")
    assert _load(fixed).parts[0].at == 0.6
    split = _scene(tmp_path, "ross_example_rotor", ROSS_EDIT,
                   append="\n[[segments]]\nlength = 0.6\nelements = 2\n[[segments]]\nlength = 0.9\nelements = 4\n",
                   file="split.toml")
    # the second disk (s = 1.0) is not on the 0.225 grid of the second segment: reported in its turn
    _fails(["run", split], capsys, str(split), "'parts[2].at'", "disk at s = 1")


def test_a_part_off_a_vertex_of_a_segment_names_the_segment_to_split(tmp_path, capsys):
    path = _scene(tmp_path, "stepped_rotor", append='\n[[parts]]\nkind = "disk"\nat = 0.31\nm = 2.0\n')
    _fails(["run", path], capsys, str(path), "'parts[1].at'", "replace segments[2] by",
           "[[segments]] length = 0.11, elements = 2, D = 0.045", "[[segments]] length = 0.04, elements = 1, D = 0.045")
    text = path.read_text().replace("length = 0.15\nelements = 3\nD = 0.045",
                                    "length = 0.11\nelements = 2\nD = 0.045\n\n[[segments]]\n"
                                    "length = 0.04\nelements = 1\nD = 0.045")
    fixed = tmp_path / "fixed.toml"
    fixed.write_text(text)
    scene = _load(fixed)
    assert len(scene.segments) == 4 and math.isclose(sum(s.length for s in scene.segments), 0.45)


def test_a_part_outside_the_domain_is_reported_at_its_at_key(tmp_path, capsys):
    path = _scene(tmp_path, "ross_example_rotor", ("at = 0.5", "at = 2.0"))
    _fails(["run", path], capsys, str(path), "'parts[1].at'", "outside the domain [0, 1.5]", "from 0 to 1.5")


def test_segments_with_a_global_basis_are_refused_at_load(tmp_path, capsys):
    path = _scene(tmp_path, "beam_modes", append="\n[[segments]]\nlength = 1.0\nelements = 4\n")
    text = path.read_text().replace('discretisation = "quintic"', 'discretisation = "sine"')
    path.write_text(text)
    _fails(["run", path], capsys, str(path), "'segments'", "global basis", "hermite")


@pytest.mark.parametrize("scene, flag, places", [
    ("ross_example_rotor", "disk_rho=1000", ["parts[1].rho", "parts[2].rho"]),
    ("stepped_rotor", "D=0.1", ["segments[1].D", "segments[2].D", "segments[3].D"]),
    ("stepped_rotor", "L=2", ["segments[1].length", "sum of the segment lengths"]),
])
def test_set_of_a_value_a_table_sets_is_refused(scene, flag, places, capsys):
    """docs/guide.md: [[segments]] and [[parts]] tables set their values themselves, so a --set of the same
    value would be ignored; it is refused, naming the tables and the scene file."""
    path = SCENES / f"{scene}.toml"
    name = flag.split("=")[0]
    _fails(["run", path, "--set", flag], capsys, f"'--set {name}'", "would be ignored", str(path), *places)


def test_set_of_a_part_value_no_table_sets_is_accepted():
    """disk_m is not set by the ROSS scene's disks: --set disk_m gives every disk that mass."""
    scene = _load(SCENES / "ross_example_rotor.toml", ["disk_m=1.5"])
    assert scene.params["disk_m"] == 1.5 and all("m" not in p.values for p in scene.parts)


# ----------------------------------------------------------------------------- misc (section 5)

def test_deeply_nested_arrays_are_refused_naming_the_file(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text('model = "spring_pendulum"\nx = ' + "[" * 500 + "]" * 500 + "\n")
    _fails(["run", path], capsys, str(path), "nested too deeply")


def test_a_deeply_nested_dict_scene_is_a_scene_error():
    import mechgen

    value: list = []
    for _ in range(5000):
        value = [value]
    with pytest.raises(SceneError, match="nested too deeply") as info:
        mechgen.run({"model": "spring_pendulum", "params": {"m": value}})
    assert info.value.file == "<dict>"


def test_a_part_kind_that_is_not_a_string_is_refused(tmp_path, capsys):
    path = _scene(tmp_path, "ross_example_rotor", ('kind = "disk"', 'kind = ["disk"]'))
    _fails(["run", path], capsys, str(path), "'parts[1].kind'", "an array, not a string", "a string",
           "bearing, disk")


@pytest.mark.parametrize("digits", [310, 5000])
def test_an_integer_beyond_the_double_range_in_set_is_refused(digits, capsys):
    _fails(["run", SCENES / "spring_pendulum.toml", "--set", "m=" + "9" * digits], capsys, "'--set m'",
           "beyond the range of a double", "1.8e308")


def test_an_integer_beyond_the_double_range_in_a_scene_is_refused(tmp_path, capsys):
    path = _scene(tmp_path, "spring_pendulum", ("m = 1.0", "m = " + "9" * 310))
    _fails(["run", path], capsys, str(path), "'params.m'", "310 digits")


def _no_temporaries(folder: Path) -> None:
    assert not [p for p in folder.rglob(".tmp-*")], list(folder.rglob("*"))


def test_json_naming_a_folder_is_refused_before_computing(tmp_path, capsys):
    folder = tmp_path / "out"
    folder.mkdir()
    _fails(["run", SCENES / "spring_pendulum.toml", "--json", folder], capsys, "'--json'", str(folder),
           "is a folder")
    _no_temporaries(tmp_path)


def test_json_and_plot_below_a_file_are_refused_before_computing(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("")
    _fails(["run", SCENES / "spring_pendulum.toml", "--json", afile / "x.json"], capsys, "'--json'", str(afile),
           "is not a folder")
    _fails(["run", SCENES / "spring_pendulum.toml", "--plot", afile], capsys, "'--plot'", str(afile),
           "not a folder")
    _fails(["run", SCENES / "spring_pendulum.toml", "--plot", afile / "sub"], capsys, "'--plot'", str(afile))
    assert afile.read_text() == ""
    _no_temporaries(tmp_path)


@pytest.mark.skipif(os.geteuid() == 0 if hasattr(os, "geteuid") else True, reason="root writes anywhere")
def test_json_in_a_read_only_folder_is_refused_before_computing(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        _fails(["run", SCENES / "spring_pendulum.toml", "--json", folder / "x.json"], capsys, "'--json'",
               "not writable")
    finally:
        folder.chmod(0o700)


def test_a_failed_json_write_leaves_no_temporary_file(tmp_path, capsys, monkeypatch):
    import mechgen.cli as cli

    def full(*_args, **_kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(cli.json, "dump", full)
    target = tmp_path / "res" / "x.json"
    code = main(["run", str(SCENES / "spring_pendulum.toml"), "--json", str(target)])
    err = capsys.readouterr().err
    assert code == 2 and "'--json'" in err and "No space left on device" in err and "Traceback" not in err
    assert not target.exists()
    _no_temporaries(tmp_path)


def test_json_to_a_new_folder_is_written(tmp_path, capsys):
    target = tmp_path / "new" / "sub" / "x.json"
    assert main(["run", str(SCENES / "spring_pendulum.toml"), "--json", str(target)]) == 0
    capsys.readouterr()
    assert json.loads(target.read_text())["model"] == "spring_pendulum"
    _no_temporaries(tmp_path)


# ----------------------------------------------------------------------------- late errors (second line)

def test_a_late_error_at_an_internal_key_names_the_scene_and_what_it_set(tmp_path, capsys):
    """One Gauss point per element would make the quintic mass matrix singular (found, or not, when M is
    factorised, depending on the BLAS kernel's round-off): refused before anything is assembled, the message naming
    the scene file, the key that set it and the least rule the basis needs."""
    path = _scene(tmp_path, "beam_modes", ("N = 16", "N = 16\nquadrature = 1"))
    code = main(["run", str(path)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert str(path) in err and "'params.quadrature'" in err and "under-integrate" in err and "at least 6" in err


def test_segment_and_part_values_keep_the_declared_bounds(tmp_path, capsys):
    """A segment's D is the model's D (declared positive); a part's rho is disk_rho."""
    path = _scene(tmp_path, "stepped_rotor", ("D = 0.045", "D = -0.045"))
    _fails(["run", path], capsys, str(path), "'segments[2].D'", "D = -0.045 is not positive")
    path = _scene(tmp_path, "ross_example_rotor", ("rho = 7810.0\nwidth", "rho = 5e-324\nwidth"), file="part.toml")
    _fails(["run", path], capsys, str(path), "'parts[1].rho'", "subnormal")


# ----------------------------------------------------------------------------- sweep grids (section 5)

@pytest.mark.parametrize("over, key, words", [
    ("{ N = [4, 0] }", "'analysis[3].over.N[2]'", ["N = 0", "an integer from 1 to"]),
    ("{ rhoA = [1.0, -2.0] }", "'analysis[3].over.rhoA[2]'", ["declared positive", "> 0"]),
    ("{ EI = { start = -1.0, stop = 1.0, num = 3 } }", "'analysis[3].over.EI'", ["declared positive"]),
])
def test_a_sweep_grid_value_meets_the_bounds_a_written_value_meets(over, key, words, tmp_path, capsys):
    """A grid's values are values the scene writes: refused at load, at the grid's key, like params.X."""
    path = _scene(tmp_path, "beam_modes", append=f"""
[[analysis]]
name = "grid"
kind = "sweep"
over = {over}
analysis = {{ kind = "modes", count = 2 }}
""")
    _fails(["run", path], capsys, str(path), key, *words)
