"""Declared checks of a part kind (Model.part's ``checks``, issue 33): a part whose values fail one is refused when
the scene is loaded (or mechgen.compile called), exit 2 at ``parts[i].<key>``, not deep in the run (a disk whose bore
exceeds its outer diameter has a negative mass m_g = rho pi/4 (outer^2 - inner^2) width, found once as a singular M)."""
from __future__ import annotations

import re
import time
from pathlib import Path

import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import InputError, ModelError
from mechgen.scene.expr import parse_condition

SCENES = Path(__file__).resolve().parent.parent / "scenes"
DISK = "inner < outer or inner == 0 and outer == 0"


def _run(argv, capsys) -> tuple[int, str]:
    code = main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    return code, err


@pytest.mark.parametrize("inner", ["0.3", "0.28"])
def test_a_disk_bore_at_or_above_its_outer_diameter_is_refused_at_load(tmp_path, capsys, inner):
    """scenes/ross_example_rotor.toml (outer = 0.28 m) with inner = 0.3 m or 0.28 m: exit 2 at parts[1].inner naming
    both values and the check, before anything is compiled or solved."""
    text = re.sub(r"inner = 0\.05", f"inner = {inner}", (SCENES / "ross_example_rotor.toml").read_text(), count=1)
    scene = tmp_path / "ross.toml"
    scene.write_text(text)
    started = time.monotonic()
    code, err = _run(["run", str(scene)], capsys)
    assert code == 2 and "at key 'parts[1].inner'" in err and "ross.toml" in err, err
    assert f"inner = {float(inner):g}, outer = 0.28" in err and "below the outer diameter" in err, err
    assert time.monotonic() - started < 10  # at load: nothing compiled, no eigen-solve


def test_the_shipped_rotor_scene_and_a_disk_without_geometry_pass(tmp_path):
    """The shipped disks (bore 0.05 m in 0.28 m) load, and so does a disk given by m, Id, Ip alone (both diameters
    left at their default 0: no geometric disk)."""
    from mechgen import models
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene

    text = (SCENES / "ross_example_rotor.toml").read_text()
    bare = tmp_path / "bare.toml"
    bare.write_text(re.sub(r"rho = 7810.0\nwidth = 0.07\nouter = 0.28\ninner = 0.05\n",
                           "m = 32.6\nId = 0.16\nIp = 0.32\n", text, count=1))
    for path in (SCENES / "ross_example_rotor.toml", bare):
        scene = load_scene(str(path), lookup_model=lookup_model, model_names=models.known)
        assert [p.kind for p in scene.parts].count("disk") == 2, path
    assert "inner" not in load_scene(str(bare), lookup_model=lookup_model, model_names=models.known).parts[0].values


def test_compile_applies_the_same_checks():
    """mechgen.compile(..., parts=[...]): the same refusal at parts[i].<key>; a bore left out takes the value the
    compile gives for disk_inner (then 0.2 > outer = 0.1), and a good disk compiles."""
    with pytest.raises(InputError) as info:
        mechgen.compile("spinning_shaft", {"N": 4}, backend="numpy", kernels=["linear"],
                        parts=[{"kind": "disk", "at": 0.5, "outer": 0.1, "inner": 0.1}])
    assert info.value.key == "parts[1].inner", info.value
    with pytest.raises(InputError) as info:
        mechgen.compile("spinning_shaft", {"N": 4, "disk_inner": 0.2}, backend="numpy", kernels=["linear"],
                        parts=[{"kind": "disk", "at": 0.5, "outer": 0.1}])
    assert info.value.key == "parts[1].inner" and "inner = 0.2, outer = 0.1" in str(info.value), info.value


def test_condition_grammar():
    """Comparisons (chained) of whitelisted arithmetic joined by and/or; anything else refused, nothing eval'd."""
    c = parse_condition(DISK)
    assert c.names == ("inner", "outer")
    assert c.holds({"inner": 0.05, "outer": 0.28}) and c.holds({"inner": 0.0, "outer": 0.0})
    assert not c.holds({"inner": 0.28, "outer": 0.28}) and not c.holds({"inner": 0.1, "outer": 0.0})
    assert parse_condition("0 <= a < 2 * b").holds({"a": 1.0, "b": 1.0})
    assert not parse_condition("0 <= a < 2 * b").holds({"a": 2.0, "b": 1.0})
    for bad in ["a", "not a < b", "a in b", "a < b if c else d", "a < __import__('os')", "(a < b) + 1", ""]:
        with pytest.raises(InputError):
            parse_condition(bad)


def _part_model(tmp_path, checks: str) -> Path:
    path = tmp_path / "ringed.py"
    path.write_text(
        "from mechgen import Model, Param, fix\n"
        "model = Model('ringed_string')\n"
        "model.params(Param('P', 1.0, 'N', positive=True), Param('rhoA', 1.0, 'kg/m', positive=True),\n"
        "             Param('L', 1.0, 'm', positive=True))\n"
        "model.field('w', length='L', discretisation='hermite', N=8)\n"
        f"model.part('ring', Param('a', 0.0, 'm'), Param('b', 1.0, 'm'), Param('m', 0.0, 'kg'), checks={checks})\n"
        "@model.kinetic_density\n"
        "def kinetic(u, p):\n    return p.rhoA / 2 * u.w_t**2\n"
        "@model.potential_density\n"
        "def potential(u, p):\n    return p.P / 2 * u.w_s**2\n"
        "@model.point_kinetic('ring')\n"
        "def ring(u, p, part):\n    return part.m / 2 * u.w_t**2\n"
        "@model.boundary\n"
        "def boundary():\n    return [fix('w', 'start'), fix('w', 'end')]\n")
    return path


def test_a_users_part_kind_declares_its_own_check(tmp_path, capsys):
    """A model file of the user's: its check refuses a part at load (a default filling the value left out) and lets
    a good one run; a check at a name that is not the part's, or a condition outside the grammar, is a ModelError."""
    _part_model(tmp_path, '{"a": ("a < b", "a below b")}')
    scene = tmp_path / "s.toml"
    body = ('model = "ringed.py"\nbackend = "numpy"\n[[parts]]\nkind = "ring"\nat = 0.5\nm = 0.1\n{extra}\n'
            '[[analysis]]\nname = "m"\nkind = "modes"\n')
    scene.write_text(body.format(extra="a = 2.0"))
    code, err = _run(["run", str(scene)], capsys)
    assert code == 2 and "at key 'parts[1].a'" in err and "a = 2, b = 1" in err, err
    scene.write_text(body.format(extra="a = 0.5"))
    assert _run(["run", str(scene)], capsys)[0] == 0
    with pytest.raises(ModelError):
        mechgen.load_model(str(_part_model(tmp_path, '{"c": ("a < b", "a below b")}')))
    from mechgen.scene.info import info_of_model

    for checks in ['{"a": ("a < z", "a below z")}', '{"a": ("a + b", "a plus b")}']:
        with pytest.raises(ModelError):
            info_of_model(mechgen.load_model(str(_part_model(tmp_path, checks))))
