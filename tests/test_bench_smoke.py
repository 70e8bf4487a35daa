"""`mechgen bench --quick` runs and writes its report (no timing assertions: targets live in the report).

The benchmark itself checks every method's numbers against the vectorised numpy
reference before timing it, so this also checks generated C against hand C.
"""
import json

import pytest

from mechgen.cli import main


@pytest.mark.slow  # the quick benchmark run
def test_quick_benchmark_writes_reports(tmp_path, capsys):
    assert main(["bench", "fpu", "beam", "--quick", "--out", str(tmp_path)]) == 0  # rotor: its own smoke test
    data = json.loads((tmp_path / "fpu_kernels.json").read_text())
    methods = {r["method"] for r in data["kernels"]}
    assert {"generated C", "hand C -O3", "numpy", "sympy.lambdify", "casadi SX"} <= methods
    assert (tmp_path / "fpu_kernels.csv").read_text().startswith("method,quantity,N,batch,seconds")
    # the hand-written numba loop is a peer when numba imports, else the reports say why it is missing
    assert ("numba" in methods) == (data["numba"] == "timed")
    ratios = {(r["quantity"], r["N"], r["batch"]): r for r in data["ratios"]}
    assert ratios[("force", 256, 1)]["gen_over_hand_c"] > 0 and ratios[("force", 256, 1)]["lambdify_over_gen"] > 0
    batched = data["batched_force_bandwidth"]
    assert (batched["N"], batched["states"]) == (64, 100) and batched["fraction"]["generated C"] > 0
    leapfrog = data["leapfrog_bandwidth"]
    assert leapfrog["N"] == 100_000 and leapfrog["fraction"] > 0 and leapfrog["energy_error"] < 1e-10
    (user,) = data["user_path"]  # the scene as a user runs it, beside the pinned figures
    assert user["scene"] == "fpu_chain.toml" and user["unpinned"]["median_s"] > 0 and user["pinned"]["median_s"] > 0
    assert json.loads((tmp_path / "beam_user_path.json").read_text())[0]["scene"] == "beam_modes.toml"
    assert "gen/hand" in capsys.readouterr().out
