"""`mechgen bench simulate --quick` runs the Duffing comparison and the sweep and writes its reports (a smoke
test: timings are reported, never asserted; the accuracy of every side is checked against the rtol 1e-13
reference, and the compiled and Python-stepped sides take the same steps, so their samples agree)."""
import json

from mechgen.cli import main


def test_quick_simulate_benchmark_writes_reports(tmp_path):
    assert main(["bench", "simulate", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "simulate.json").read_text())
    assert set(data["seconds"]) == {"mechgen compiled", "mechgen scipy stepper", "hand-written scipy"}
    # each side at rtol 1e-10 over 50 periods: within 1e-8 of the reference (its own error ~1e-10 here)
    assert all(e < 1e-8 for e in data["errors"].values())
    assert data["sweep_ok"] and data["sweep_points"] == 100
    # the hand-written C DOP853 loop takes scipy's steps, as the compiled loop does: the end states agree to
    # rounding accumulated over ~1800 steps (1e-9 of |x| ~ 1)
    assert data["hand_c"]["end_x_difference"] < 1e-9 and data["hand_c"]["hand_steps"] > 1000
    ratios = json.loads((tmp_path / "simulate_ratios.json").read_text())["ratios"]
    assert {r["peer"] for r in ratios} == {"mechgen scipy stepper", "hand-written scipy"}
    assert "compiled / scipy stepper" in (tmp_path / "simulate.md").read_text()
