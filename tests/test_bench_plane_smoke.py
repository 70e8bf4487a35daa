"""The plane assembly benchmark at a small size: it checks mechgen's plane-stress stiffness (the numeric path, and
the compiled membrane_gravity model's tangent with its rim held) equal to scikit-fem's before timing (so this also
checks both assemble the same operator) and writes its reports (no timing assertions: the target lives in the
report)."""
import json

import pytest

pytest.importorskip("skfem")

from mechgen.bench.plane import run_plane_benchmarks  # noqa: E402
from bench_reports import check_standard_reports  # noqa: E402


def test_plane_benchmark_small_size_writes_reports(tmp_path, capsys):
    result = run_plane_benchmarks(tmp_path, quick=True, sizes=(3000,))
    rows = result["rows"]
    assert [r["element"] for r in rows] == ["P1", "P2"]
    for r in rows:
        assert r["max_rel_difference"] < 1e-12 and 2000 < r["unknowns"] < 4500
        assert r["assemble_ratio"] == r["assemble_mechgen_s"] / r["assemble_skfem_s"] > 0
    users = result["user_path"]
    assert [r["element"] for r in users] == ["P1", "P2"] and all(r["max_rel_difference"] < 1e-12 for r in users)
    assert all(0 < r["free"] < r["unknowns"] for r in users)  # the rim's dofs removed on both sides
    check_standard_reports(tmp_path, "plane")
    data = json.loads((tmp_path / "plane_assembly.json").read_text())
    assert data["environment"]["skfem"] == "12.0.2" and len(data["rows"]) == 2 and len(data["user_path"]) == 2
    assert "| P2 |" in (tmp_path / "plane_assembly.md").read_text()
    assert "mechgen against scikit-fem" in capsys.readouterr().out
