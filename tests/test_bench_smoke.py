"""`mechgen bench --quick` runs and writes its report (no timing assertions: targets live in the report).

The benchmark itself checks every method's numbers against the vectorised numpy
reference before timing it, so this also checks generated C against hand C.
"""
import json

from mechgen.cli import main


def test_quick_benchmark_writes_reports(tmp_path, capsys):
    assert main(["bench", "fpu", "beam", "--quick", "--out", str(tmp_path)]) == 0  # rotor: its own smoke test
    data = json.loads((tmp_path / "fpu_kernels.json").read_text())
    methods = {r["method"] for r in data["kernels"]}
    assert {"generated C", "hand C -O3", "numpy", "sympy.lambdify", "casadi SX"} <= methods
    assert (tmp_path / "fpu_kernels.csv").read_text().startswith("method,quantity,N,batch,seconds")
    (user,) = data["user_path"]  # the scene as a user runs it, beside the pinned figures
    assert user["scene"] == "fpu_chain.toml" and user["unpinned"]["median_s"] > 0 and user["pinned"]["median_s"] > 0
    assert json.loads((tmp_path / "beam_user_path.json").read_text())[0]["scene"] == "beam_modes.toml"
    assert "gen/hand" in capsys.readouterr().out
