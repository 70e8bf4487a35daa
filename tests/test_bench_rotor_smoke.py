"""The quick rotor benchmark runs, checks mechgen against ROSS before timing, and writes its reports.

No timing assertions: targets (ROSS / mechgen >= 20) live in the benchmark's report.
"""
import importlib.util
import json

import pytest

from mechgen.bench.rotor import COUNT, TOL, run_rotor_benchmarks
from bench_reports import check_standard_reports

HAVE_ROSS = importlib.util.find_spec("ross") is not None


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_quick_rotor_benchmark_writes_reports(tmp_path, capsys):
    result = run_rotor_benchmarks(tmp_path, quick=True)
    data = json.loads((tmp_path / "rotor_campbell.json").read_text())
    md = (tmp_path / "rotor_campbell.md").read_text()
    check_standard_reports(tmp_path, "rotor", ratios=importlib.util.find_spec("ross") is not None)
    assert md.startswith("# Rotor Campbell benchmark")
    assert data["quick"] is True and result["quick"] is True
    camp = data["campbell"]
    assert len(camp["mechgen_frequencies"]) == camp["speeds"]
    assert all(len(row) == COUNT for row in camp["mechgen_frequencies"])
    assert camp["mechgen_tracking"]["median_s"] > 0
    assert data["large"]["unknowns"] > 500 and len(data["large"]["frequencies_500"]) == COUNT
    rows = data["work_precision"]["rows"]
    errors = {(r["method"], r["N"]): r["max_rel_error"] for r in rows}
    assert errors[("mechgen timoshenko2", 192)] < errors[("mechgen timoshenko2", 48)]  # refinement helps
    assert errors[("mechgen quintic", 24)] < 1e-8
    for fix in data["candidate_fixes"]:  # the measured candidate fixes compute the same Campbell diagram
        assert fix["max_rel_diff_vs_run_campbell"] < TOL
    conf = data["configurations"]  # as a user runs it: unpinned (default environment) and pinned children
    assert all(v is None for v in conf["unpinned"]["environment"].values())
    assert set(conf["pinned"]["environment"].values()) == {"1"}
    for side in ("unpinned", "pinned"):
        assert conf[side]["mechgen"]["median_s"] > 0 and conf[side]["speeds"] == camp["speeds"]
    assert data["user_path"][0]["scene"] == "ross_example_rotor.toml" and "As a user runs both" in md
    out = capsys.readouterr().out
    assert "rotor_campbell.md" in out
    if HAVE_ROSS:
        acc = data["accuracy"]
        assert acc["passed"] and acc["max_rel_diff"] <= TOL
        assert [r["speed"] for r in acc["rows"]] == [0.0, 1000.0]
        assert all(len(r["mechgen"]) == len(r["ross"]) == COUNT for r in acc["rows"])
        assert camp["campbell_max_rel_diff"] <= TOL
        assert camp["ratio_ross_over_mechgen"] > 0
        assert "ROSS / mechgen" in md
    else:
        assert data["ross_skipped"] and "ROSS skipped" in md
