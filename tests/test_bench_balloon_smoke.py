"""The quick balloon benchmark runs, checks both tools' accuracy against converged references, and writes its
reports.

No timing assertions: the target (baseline / mechgen >= 3 at equal accuracy) lives in the benchmark's report.
"""
import json

import pytest

from mechgen.bench.balloon import POINTS, STOP, run_balloon_benchmarks
from bench_reports import check_standard_reports


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_quick_balloon_benchmark_writes_reports(tmp_path, capsys):
    result = run_balloon_benchmarks(tmp_path, quick=True)
    data = json.loads((tmp_path / "balloon_branch.json").read_text())
    md = (tmp_path / "balloon_branch.md").read_text()
    check_standard_reports(tmp_path, "balloon")
    assert md.startswith("# Ballooning string benchmark") and "baseline / mechgen" in md
    assert data["quick"] is True and result["quick"] is True
    refs = data["references"]
    # the two tools' converged references agree (independent implementations)
    assert refs["check"]["p_e_min_rel_diff"] < 1e-11 and refs["check"]["omega_1_rel_diff"] < 1e-8
    assert refs["p_e_min"] == pytest.approx(14.70509, abs=1e-5)                   # balloon_notes.md, section 4
    head = data["headline"]
    for side in ("baseline", "mechgen"):
        d = head[side]
        assert abs(d["points"] - POINTS) <= 2 and d["lambda0_range"][0] == pytest.approx(-0.5, abs=1e-12)
        assert d["lambda0_range"][1] == pytest.approx(STOP, abs=2e-3) and d["verdicts"] == ["stable"]
        assert d["p_e_min_error"] < 1e-9 and d["omega_1_error"] < 1e-4       # Galerkin N = 10 vs 40
    assert head["ratio_per_point"] > 0 and head["equal_accuracy"]["ratio_per_point"] > 0
    rows = {(r["tool"], r["setting"]): r for r in data["work_precision"]["branch"]}
    coarse, fine = rows[("mechgen", "Gauss s = 4, M = 10")], rows[("mechgen", "Gauss s = 4, M = 20")]
    assert fine["p_e_min_error"] < coarse["p_e_min_error"] / 50                     # order 8: 2^8 in theory
    galerkin = data["work_precision"]["galerkin"]
    assert galerkin[-1]["mechgen_omega_1_error"] < galerkin[0]["mechgen_omega_1_error"]
    user = data["user_path"][0]  # the scene as a user runs it, beside the pinned figures
    assert user["scene"] == "balloon_frequencies.toml" and user["unpinned"]["median_s"] > 0 and "as a user" in md
    assert "balloon_branch.md" in capsys.readouterr().out
