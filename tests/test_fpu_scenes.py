"""The symplectic kind's scenes: scenes/fpu_recurrence.toml and scenes/fpu_large.toml.

fpu_recurrence reproduces the converged FPU-alpha recurrence of tests/test_fpu_recurrence.py (146.394 T_1,
98.159 %, a dt-convergence study there); bad input exits 2 naming the file and the key.
"""
import json
from pathlib import Path

import pytest

import mechgen
from mechgen.cli import main

ROOT = Path(__file__).resolve().parent.parent


def _run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_fpu_recurrence_scene(tmp_path, capsys):
    target = tmp_path / "out.json"
    code, _, err = _run(["run", str(ROOT / "scenes" / "fpu_recurrence.toml"), "--json", str(target),
                         "--plot", str(tmp_path)], capsys)
    assert code == 0, err
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    for key in ("recurrence_periods", "recurrence_fraction", "energy_error", "steps_per_second",
                "bandwidth_fraction", "bandwidth_share", "bytes_per_step", "mode_energies_series", "t"):
        assert key in out
    # a step of symplectic_loop.c streams 8 N bytes per array read or written: per force call f zeroed, q in, f in
    # and out (4 arrays), per kick v, f in, v out (3), per drift q, v in, q out (3); the scene's ABA864 (Blanes,
    # Casas & Murua 2013) has 8 drifts and 7 kicks, each kick after its own force call (unit masses):
    # 8 N (7 x 4 + 7 x 3 + 8 x 3) = 584 N bytes at N = 31
    assert out["bytes_per_step"] == 584 * 31
    assert abs(out["recurrence_periods"] - 146.394) < 1e-3 and abs(out["recurrence_fraction"] - 0.98159) < 1e-4
    assert out["energy_error"] < 1e-8 and out["loop"] == "c"
    assert list(tmp_path.glob("*.png"))


def test_symplectic_python_function_matches_the_scene():
    system = mechgen.compile("fpu_chain", {"N": 31, "alpha": 0.25}, kernels=["force", "outputs", "linear"])
    res = mechgen.symplectic(system, integrator="leapfrog", dt=0.05, t_end=11000.0)
    assert abs(res.outputs["recurrence_periods"] - 146.394) < 0.05  # leapfrog's O(dt^2) error: 0.01 T_1


@pytest.mark.parametrize("key, value", [("integrator", '"euler"'), ("dt", "-1.0"), ("stride", "-3")])
def test_bad_input_names_the_key(tmp_path, capsys, key, value):
    text = (ROOT / "scenes" / "fpu_recurrence.toml").read_text()
    lines = [ln for ln in text.splitlines() if not ln.startswith(f"{key} =")]
    lines.append(f"{key} = {value}")
    path = tmp_path / "bad.toml"
    path.write_text("\n".join(lines) + "\n")
    code, _, err = _run(["run", str(path)], capsys)
    assert code == 2 and "bad.toml" in err and key in err and "Traceback" not in err


@pytest.mark.slow
def test_fpu_large_scene(tmp_path, capsys):
    """N = 10^6, 2000 leapfrog steps in C; prints the measured speed and bandwidth share."""
    target = tmp_path / "out.json"
    code, _, err = _run(["run", str(ROOT / "scenes" / "fpu_large.toml"), "--json", str(target)], capsys)
    assert code == 0, err
    out = json.loads(target.read_text())["analyses"][0]["outputs"]
    assert out["loop"] == "c" and out["energy_error"] < 1e-10 and out["steps"] == 2000
    assert out["steps_per_second"] > 0 and 0 < out["bandwidth_fraction"] and 0 < out["bandwidth_share"]
    assert out["bytes_per_step"] == 80 * 10**6
    print(f"N = 10^6: {out['steps_per_second']:.0f} steps/s, share of the all-core bandwidth "
          f"{out['bandwidth_share']:.2f} (deprecated fraction {out['bandwidth_fraction']:.2f})")
