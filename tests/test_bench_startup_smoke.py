"""`mechgen bench startup --quick` runs the shipped scenes as whole processes and writes its reports
(a smoke test: the numbers are timings, reported, never asserted)."""
import json

from mechgen.cli import main


def test_quick_startup_benchmark_writes_reports(tmp_path):
    assert main(["bench", "startup", "--quick", "--out", str(tmp_path)]) == 0
    rows = json.loads((tmp_path / "startup.json").read_text())
    assert [r["scene"] for r in rows] == ["laval_rotor.toml", "beam_modes.toml"]
    assert all(r["wall_s"] > 0 and r["heavy_imports"] == [] for r in rows)
    assert all(r["ratio_unpinned_over_pinned"] == r["wall_s"] / r["pinned_wall_s"] for r in rows)
    assert "laval_rotor.toml" in (tmp_path / "startup.md").read_text()
