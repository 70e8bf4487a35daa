"""The command line: scenes run end to end, JSON contract, and bad input -> exit 2 with a clear message."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mechgen.cli import main
from mechgen.errors import ModelError
from mechgen.symbolic.model import Model

ROOT = Path(__file__).resolve().parents[1]
HOSTILE = 'x); import os; os.system("echo pwned")  #'


def _run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_models_lists_every_builtin(capsys):
    code, out, _ = _run(["models"], capsys)
    assert code == 0
    assert {"laval_rotor", "fpu_chain", "spring_pendulum"} <= {line.split()[0] for line in out.splitlines()}


def test_show_prints_matrices(capsys):
    code, out, _ = _run(["show", "laval_rotor"], capsys)
    assert code == 0 and "Ip*Omega" in out and "K =" in out


@pytest.mark.parametrize("scene", ["laval_rotor", "spring_pendulum", "fpu_chain"])
def test_scene_runs_and_writes_json_contract(scene, tmp_path, capsys):
    target = tmp_path / "out.json"
    extra = ["--set", "N=16"] if scene == "fpu_chain" else []
    code, out, err = _run(["run", str(ROOT / "scenes" / f"{scene}.toml"), "--json", str(target)] + extra, capsys)
    assert code == 0, err
    data = json.loads(target.read_text())
    assert {"scene", "model", "backend", "analyses"} <= set(data)
    for a in data["analyses"]:
        assert {"name", "kind", "outputs", "seconds"} <= set(a)
    assert scene in out


def _write(tmp_path, text, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


GOOD = 'model = "laval_rotor"\n[[analysis]]\nname = "w"\nkind = "stability"\n'
BAD_SCENES = {
    "unknown_key": ('model = "laval_rotor"\ncolour = 3\n' + GOOD.split("\n", 1)[1], "colour"),
    "unknown_model": (GOOD.replace("laval_rotor", "warp_drive"), "model"),
    "unknown_param": (GOOD + "[params]\nwarp = 3\n", "warp"),
    "wrong_type": (GOOD.replace('kind = "stability"', "kind = 5"), "kind"),
    "bad_expression": (GOOD + '[params]\nOmega = "2*pi*("\n', "Omega"),
    "injected_expression": (GOOD + '[params]\nOmega = "__import__(\'os\').system(\'echo pwned\')"\n', "Omega"),
    "hostile_name": (GOOD.replace('name = "w"', f"name = '{HOSTILE}'"), "name"),
    "not_toml": ("model = laval_rotor [[[", "TOML"),
    "unknown_kind": (GOOD.replace("stability", "levitate"), "kind"),
}


@pytest.mark.parametrize("case", sorted(BAD_SCENES))
def test_bad_scene_exits_2_with_one_paragraph(case, tmp_path, capsys):
    text, key = BAD_SCENES[case]
    path = _write(tmp_path, text)
    target = tmp_path / "never.json"
    code, out, err = _run(["run", path, "--json", str(target)], capsys)
    assert code == 2
    assert "bad.toml" in err and key in err
    assert "Traceback" not in err and "pwned" not in out
    assert len(err.strip().splitlines()) == 1
    assert not target.exists()


def test_missing_file_and_bad_flags(tmp_path, capsys):
    code, _, err = _run(["run", str(tmp_path / "nope.toml")], capsys)
    assert code == 2 and "nope.toml" in err
    scene = str(ROOT / "scenes" / "laval_rotor.toml")
    code, _, err = _run(["run", scene, "--set", "warp=9"], capsys)
    assert code == 2 and "warp" in err
    code, _, err = _run(["run", scene, "--set", f"{HOSTILE}=1"], capsys)
    assert code == 2
    code, _, err = _run(["run", scene, "--backend", "fortran"], capsys)
    assert code == 2 and "backend" in err


def test_hostile_identifiers_are_rejected_at_declaration():
    model = Model("ok_model")
    with pytest.raises(ModelError, match="not a valid identifier"):
        model.coordinates(HOSTILE)
    with pytest.raises(ModelError):
        Model(HOSTILE)
    with pytest.raises(ModelError, match="already used"):
        model.coordinates("x", "x")


def test_a_model_function_returning_text_is_not_parsed():
    from mechgen.pipeline import derive
    from mechgen.symbolic.specialize import specialize

    model = Model("texty")
    model.coordinates("x")
    model.kinetic(lambda v: v.x**2 / 2)
    model.potential(lambda q: "__import__('os').system('echo pwned')")
    with pytest.raises(ModelError, match="returned str"):
        derive(model, specialize(model, {}))


def test_console_script_exit_code_for_bad_input(tmp_path):
    env = dict(os.environ)
    proc = subprocess.run([sys.executable, "-m", "mechgen", "run", str(tmp_path / "missing.toml")],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 2
    assert "missing.toml" in proc.stderr and "Traceback" not in proc.stderr


def test_plot_writes_pngs(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    code, out, err = _run(["run", str(ROOT / "scenes" / "laval_rotor.toml"), "--plot", str(tmp_path)], capsys)
    assert code == 0, err
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert pngs == ["laval_rotor_campbell.png", "laval_rotor_whirl.png"]
    assert all((tmp_path / p).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)


def test_run_says_once_that_plot_draws_the_figures(tmp_path, capsys):
    """Without --plot the run's output ends with one line naming ``--plot DIR``; with --plot it is left out
    (the figures are drawn, and the files written are listed instead)."""
    pytest.importorskip("matplotlib")
    scene = str(ROOT / "scenes" / "laval_rotor.toml")
    code, out, err = _run(["run", scene], capsys)
    assert code == 0, err
    hints = [line for line in out.splitlines() if "--plot DIR" in line]
    assert hints == ["(mechgen run SCENE --plot DIR draws the figures)"] and out.rstrip().endswith(hints[0])
    code, out, err = _run(["run", scene, "--plot", str(tmp_path)], capsys)
    assert code == 0, err
    assert "--plot DIR" not in out and "wrote " in out


def test_plot_continuum_shapes_and_sweep(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    code, out, err = _run(["run", str(ROOT / "scenes" / "beam_modes.toml"), "--plot", str(tmp_path)], capsys)
    assert code == 0, err
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert pngs == ["beam_modes_boundary_conditions.png", "beam_modes_modes.png", "beam_modes_modes_shapes.png"]
    assert all((tmp_path / p).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)


@pytest.mark.parametrize("given", [None, "8"])
def test_the_command_shortens_openblas_idle_spin_unless_the_user_set_it(given):
    """The ``mechgen`` command (cli.console, also ``python -m mechgen``) sets OPENBLAS_THREAD_TIMEOUT to BLAS_SPIN
    before numpy loads OpenBLAS (mechgen.cli imports no numpy), and keeps a value the user set; ``main`` called in
    a process of the user's own changes nothing."""
    from mechgen import cli

    probe = ("import contextlib, io, os, sys\nfrom mechgen import cli\nloaded = 'numpy' in sys.modules\n"
             "sys.argv = ['mechgen', '--version']\nwith contextlib.redirect_stdout(io.StringIO()):\n    cli.{entry}()\n"
             "print(loaded, os.environ.get('OPENBLAS_THREAD_TIMEOUT'))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_THREAD_TIMEOUT"}
    if given is not None:
        env["OPENBLAS_THREAD_TIMEOUT"] = given
    for entry, expected in (("console", given or cli.BLAS_SPIN), ("main", given)):
        out = subprocess.run([sys.executable, "-c", probe.format(entry=entry)], env=env, capture_output=True,
                             text=True, check=True).stdout.split()
        assert out == ["False", str(expected)]
