"""Bad hybrid declarations and scene keys: a ModelError naming the model file and the item, exit 2 from a scene.

Every model file here is small and wrong in one way (mechgen.symbolic.hybrid, check_hybrid and reset_state):
a guard entering an undeclared mode, a mode without energies, a reset that changes the number of
coordinates or names an unknown entry, modes in a continuum or a chain (in either order of declaration), a
mode declared twice, a guard in a model without modes. Each is refused when the model is loaded or derived
(``mechgen.compile``) and, run from a scene, exits 2 with one paragraph naming the file and the item. A
scene's ``mode`` must name a mode of a hybrid model and is refused on a smooth one.
"""
from __future__ import annotations

from pathlib import Path

import pytest

import mechgen
from mechgen.cli import main
from mechgen.errors import ModelError

HEAD = '''\
from mechgen import Model, Param

model = Model("bad_hybrid")
model.params(Param("m", 1.0, "kg"), Param("g", 9.81, "m/s^2"))
model.coordinates("y")
'''

ENERGIES = '''

@model.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@model.potential
def potential(q, p):
    return p.m * p.g * q.y
'''

FLIGHT = HEAD + 'flight = model.mode("flight")\n' + ENERGIES

# name: (model file text, the words the message must hold: the item first)
BAD = {
    "guard_to_unknown_mode": (FLIGHT + '''

@flight.guard(to="landed", direction="falling")
def floor(q):
    return q.y
''', ["guard 'floor'", "'landed'", "not declared", "flight"]),
    "mode_without_energies": (HEAD + '''flight = model.mode("flight")
rest = model.mode("rest")


@flight.kinetic
def kinetic(v, p):
    return p.m / 2 * v.y**2


@flight.guard(to="rest", direction="falling")
def floor(q):
    return q.y
''', ["mode 'rest'", "no energies"]),
    "reset_changes_coordinates": (FLIGHT + '''

@flight.guard(to="flight", direction="falling", reset=lambda q, v: ([q.y, q.y], [-v.y, 0]))
def floor(q):
    return q.y
''', ["reset of guard floor", "2 coordinates for a state of 1", "cannot change the number of coordinates"]),
    "reset_unknown_name": (FLIGHT + '''

@flight.guard(to="flight", direction="falling", reset=lambda v: {"x_dot": -v.y})
def floor(q):
    return q.y
''', ["reset of guard floor", "'x_dot'", "not a coordinate", "y_dot"]),
    "mode_in_continuum": ('''\
from mechgen import Model, Param

model = Model("bad_hybrid")
model.params(Param("L", 1.0, "m"), Param("EI", 1.0, "N m^2"))
model.field("w", length="L")
model.mode("flight")
''', ["mode 'flight'", "lumped models"]),
    "continuum_after_mode": ('''\
from mechgen import Model, Param

model = Model("bad_hybrid")
model.params(Param("L", 1.0, "m"), Param("EI", 1.0, "N m^2"))
flight = model.mode("flight")
model.field("w", length="L")


@model.potential_density
def strain(u, p):
    return p.EI * u.w_ss**2 / 2
''', ["mode 'flight'", "lumped models", "continuum"]),
    "chain_after_mode": ('''\
from mechgen import Model, Param

model = Model("bad_hybrid")
model.params(Param("N", 4, "", size=True), Param("k", 1.0, "N/m"))
flight = model.mode("flight")
model.chain("u", sites="N")


@model.site_kinetic
def kinetic(v):
    return v.u**2 / 2


@model.bond_potential
def bond(q, q_next, p):
    return p.k * (q_next.u - q.u) ** 2 / 2
''', ["mode 'flight'", "lumped models", "chain"]),
    "duplicate_mode": (HEAD + 'model.mode("flight")\nmodel.mode("flight")\n' + ENERGIES,
                       ["mode 'flight'", "declared twice"]),
    "guard_without_modes": (HEAD + ENERGIES + '''

@model.terminal(direction="falling")
def floor(q):
    return q.y
''', ["guard 'floor'", "no modes"]),
}

#: those refused while the file is imported (the declaration itself raises)
AT_IMPORT = {"mode_in_continuum", "duplicate_mode"}


def _write(tmp_path: Path, case: str) -> Path:
    path = tmp_path / "models" / f"{case}.py"
    path.parent.mkdir(exist_ok=True)
    path.write_text(BAD[case][0])
    return path


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_hybrid_model_is_a_model_error_naming_file_and_item(case, tmp_path):
    path = _write(tmp_path, case)
    words = BAD[case][1]
    with pytest.raises(ModelError) as info:
        model = mechgen.load_model(path)
        assert case not in AT_IMPORT
        mechgen.compile(model, backend="numpy")
    assert info.value.file == str(path)
    for word in words:
        assert word in str(info.value), str(info.value)
    assert words[0].split()[0] in (info.value.key or "") + str(info.value)


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_hybrid_model_in_a_scene_exits_2(case, tmp_path, capsys):
    path = _write(tmp_path, case)
    scene = tmp_path / "scene.toml"
    scene.write_text(f'model = "models/{case}.py"\nbackend = "numpy"\n[[analysis]]\nname = "s"\nkind = "simulate"\n'
                     't_end = 1.0\n')
    target = tmp_path / "never.json"
    code = main(["run", str(scene), "--json", str(target)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert str(path) in err
    for word in BAD[case][1]:
        assert word in err, err
    assert not target.exists()


GOOD = FLIGHT + '''

@flight.guard(to="flight", direction="falling", reset=lambda v: {"y_dot": -v.y / 2})
def floor(q):
    return q.y
'''


@pytest.mark.parametrize("value, words", [('"nope"', ["mode", "unknown mode 'nope'", "flight"]),
                                          ("3", ["mode", "flight"])])
def test_scene_mode_must_name_a_mode(tmp_path, capsys, value, words):
    (tmp_path / "ball.py").write_text(GOOD)
    scene = tmp_path / "scene.toml"
    scene.write_text(f'model = "ball.py"\nbackend = "numpy"\n[[analysis]]\nname = "s"\nkind = "simulate"\n'
                     f't_end = 1.0\nq0 = {{ y = 1.0 }}\nmode = {value}\n')
    code = main(["run", str(scene)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "'analysis[1].mode'" in err and str(scene) in err
    for word in words:
        assert word in err, err


def test_scene_mode_on_a_smooth_model_exits_2(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text('model = "spring_pendulum"\n[[analysis]]\nname = "s"\nkind = "simulate"\nt_end = 1.0\n'
                     'mode = "flight"\n')
    code = main(["run", str(scene)])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "'analysis[1].mode'" in err and "has no modes" in err


def test_a_good_mode_runs_from_the_scene(tmp_path, capsys):
    """The same scene with ``mode = "flight"`` runs: dropped from 1 m, the first impact at sqrt(2/g)."""
    (tmp_path / "ball.py").write_text(GOOD)
    scene = tmp_path / "scene.toml"
    scene.write_text('model = "ball.py"\nbackend = "numpy"\n[[analysis]]\nname = "s"\nkind = "simulate"\n'
                     't_end = 0.5\nq0 = { y = 1.0 }\nmode = "flight"\nmethod = "DOP853"\nrtol = 1e-12\n'
                     'atol = 1e-14\n')
    target = tmp_path / "out.json"
    assert main(["run", str(scene), "--json", str(target)]) == 0, capsys.readouterr().err
    import json

    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    assert [e["t"] for e in out["events"]] == pytest.approx([(2 / 9.81) ** 0.5], abs=1e-12)
