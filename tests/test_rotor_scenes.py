"""Rotor scenes end to end (JSON names, values against ROSS) and bad layouts -> exit 2 naming file and key."""
import json
from pathlib import Path

import numpy as np
import pytest

from mechgen.cli import main

ROOT = Path(__file__).resolve().parents[1]
ROSS = json.loads((ROOT / "benchmarks" / "ross_data" / "ross_reference.json").read_text())["rotors"]["example"]


def _run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_ross_example_scene_reports_whirl_campbell_and_critical_speeds(tmp_path, capsys):
    target = tmp_path / "out.json"
    code, _, err = _run(["run", str(ROOT / "scenes" / "ross_example_rotor.toml"), "--json", str(target),
                         "--backend", "numpy"], capsys)
    assert code == 0, err
    results = {a["name"]: a["outputs"] for a in json.loads(target.read_text())["analyses"]}
    modes = results["at_rest"]
    np.testing.assert_allclose(modes["frequencies"], ROSS["modal"]["0.0"]["lateral_only"]["wd"][:8], rtol=1e-6)
    # at rest on anisotropic bearings (kxx != kyy, undamped) every orbit is a straight line: 'linear' (issue 25),
    # as ROSS's orbit analysis finds it (its robust label 'Planar': |kappa| < 1e-6 at every node)
    assert [w.lower() for w in ROSS["modal"]["0.0"]["lateral_only"]["whirl_robust"][:8]] == ["planar"] * 8
    assert modes["whirl"] == ["linear"] * 8
    assert np.max(np.abs(modes["whirl_ratio"])) < 1e-6
    speeds = results["speeds"]
    for k, speed in enumerate(("0.0", "500.0", "1000.0", "2000.0")):
        np.testing.assert_allclose(speeds["frequencies"][k], ROSS["modal"][speed]["lateral_only"]["wd"][:8],
                                   rtol=1e-6)
    camp = results["campbell"]
    assert len(camp["speeds"]) == 50 and len(camp["frequencies"]) == 50 and len(camp["whirl"][0]) == 8
    # tracked curves: at 1000 rad/s the same set as the sorted modes, in the order of the first speed
    np.testing.assert_allclose(sorted(camp["frequencies"][-1]), speeds["frequencies"][2], rtol=1e-9)
    # mode 5 falls (backward) all the way from its straight-line orbit at rest (as in at_rest above)
    assert [row[4] for row in camp["whirl"]] == ["linear"] + ["backward"] * 49
    assert camp["whirl"][0] == ["linear"] * 8
    # critical speeds: each is a fixed point f_j(Omega) = Omega of its curve
    for crit in camp["critical_speeds"]:
        curve = np.array(camp["frequencies"])[:, crit["mode"] - 1]
        assert np.interp(crit["speed"], camp["speeds"], curve) == pytest.approx(crit["speed"], rel=1e-3)
    assert len(camp["critical_speeds"]) == 6
    # 28 unknowns: too few for a reduced basis of 4 x (8 + 4) vectors, so every speed is solved at full size
    assert camp["method"] == "exact" and camp["exact_solves"] == 50


def test_stepped_scene_pairs_split_with_spin(capsys, tmp_path):
    target = tmp_path / "out.json"
    code, _, err = _run(["run", str(ROOT / "scenes" / "stepped_rotor.toml"), "--json", str(target),
                         "--backend", "numpy"], capsys)
    assert code == 0, err
    results = {a["name"]: a["outputs"] for a in json.loads(target.read_text())["analyses"]}
    rest = np.array(results["at_rest"]["frequencies"])
    np.testing.assert_allclose(rest[0::2], rest[1::2], rtol=1e-8)
    for freqs, labels in zip(results["spin_rates"]["frequencies"][1:], results["spin_rates"]["whirl"][1:]):
        assert labels[:4] == ["backward", "forward", "backward", "forward"]
        assert np.all(np.diff(freqs) > 0)
    joined = results["joined_both_ways"]["frequencies"]
    np.testing.assert_allclose(joined[1], joined[0], rtol=1e-8)
    # the Campbell's reduced basis against the full-size modes at the five spin rates (0, 1000 ... 4000 rad/s)
    camp = results["campbell"]
    assert camp["method"] == "reduced" and camp["exact_solves"] < len(camp["speeds"])
    for k, speed in enumerate((0.0, 1000.0, 2000.0, 3000.0, 4000.0)):
        row = camp["frequencies"][camp["speeds"].index(speed)]
        np.testing.assert_allclose(sorted(row), results["spin_rates"]["frequencies"][k][:6], rtol=1e-9)


BASE = '''model = "spinning_shaft"
backend = "numpy"
[params]
discretisation = "quintic"
N = 4
L = 1.0
[[analysis]]
name = "m"
kind = "modes"
count = 2
'''


@pytest.mark.parametrize("extra,key,words", [
    ('[[parts]]\nkind = "flywheel"\nat = 0.5\n', "parts[1].kind", ["unknown part kind", "disk"]),
    ('[[parts]]\nkind = "disk"\nat = 0.5\nmass = 3.0\n', "parts[1].mass", ["unknown key", "Ip"]),
    ('[[parts]]\nkind = "disk"\nm = 3.0\n', "parts[1].at", ["missing key 'at'"]),
    ('[[parts]]\nkind = "disk"\nat = "x + 1"\n', "parts[1].at", ["unknown name"]),
    ('[[segments]]\nlength = 0.5\nelements = 2\nwidth = 3\n', "segments[1].width", ["unknown segment key"]),
    ('[[segments]]\nlength = -0.5\nelements = 2\n', "segments[1].length", ["not positive"]),
    ('[[segments]]\nlength = 0.5\nelements = 2.5\n', "segments[1].elements", ["integer"]),
    ('[[segments]]\nlength = 0.5\nelements = 2\nbc = "free-free"\n', "segments[1].bc", ["unknown segment key"]),
    ('segments = 3\n', "segments", ["tables"]),
    ('[[analysis]]\nname = "c"\nkind = "campbell"\nover = { Omega = [0.0, 1.0] }\nmethod = "fast"\n',
     "analysis[1].method", ["unknown campbell method"]),
])
def test_bad_layouts_exit_2_naming_the_key(tmp_path, capsys, extra, key, words):
    scene = tmp_path / "bad.toml"
    scene.write_text(BASE.replace("[[analysis]]", extra + "[[analysis]]") if extra.startswith("[[") else
                     extra + BASE)
    code, _, err = _run(["run", str(scene)], capsys)
    assert code == 2
    assert str(scene) in err and key in err and all(w in err for w in words), err


def test_part_off_the_mesh_exits_2(tmp_path, capsys):
    scene = tmp_path / "off.toml"
    scene.write_text(BASE.replace("[[analysis]]", '[[parts]]\nkind = "disk"\nat = 0.3\nm = 1.0\n[[analysis]]'))
    code, _, err = _run(["run", str(scene)], capsys)
    assert code == 2 and "not at a mesh vertex" in err and "0.25, 0.5" in err, err


def test_layout_on_a_lumped_model_exits_2(tmp_path, capsys):
    scene = tmp_path / "lumped.toml"
    scene.write_text('model = "laval_rotor"\n[[parts]]\nkind = "disk"\nat = 0.0\n'
                     '[[analysis]]\nname = "m"\nkind = "modes"\n')
    code, _, err = _run(["run", str(scene)], capsys)
    assert code == 2 and "not a continuum" in err, err
