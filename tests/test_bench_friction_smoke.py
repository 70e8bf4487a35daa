"""`mechgen bench friction --quick` runs and writes its reports (a smoke test: timings are reported, never
asserted; the errors it reports are checked: the imposed step against its closed form, the slider's
reference against CVODES at the same tight tolerance)."""
import json

import pytest

from mechgen.cli import main
from bench_reports import check_standard_reports


@pytest.mark.slow  # the quick benchmark run
def test_quick_friction_benchmark_writes_reports(tmp_path):
    assert main(["bench", "friction", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "friction.json").read_text())
    sides = {r["side"] for r in data["slider"]}
    assert sides == {"mechgen cvodes", "mechgen Radau", "hand-written Radau"}
    assert all(d < 1e-9 for d in data["reference_check"].values())  # two integrators agree at rtol 1e-13
    # against the closed form (module doc) at rtol 1e-6: a global error within ten local tolerances
    assert all(r["error"] < 10 * r["rtol"] for r in data["work_precision"])
    assert all(r["error"] < 1e-4 for r in data["slider"])
    assert all(r["error"] < 10 * r["rtol"] for r in data["hysteresis"])  # the Jenkins W (Griffin 1980)
    text = (tmp_path / "friction.md").read_text()
    assert "At equal accuracy" in text and (tmp_path / "friction.csv").exists()
    check_standard_reports(tmp_path, "friction")
