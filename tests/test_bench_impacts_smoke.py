"""`mechgen bench impacts --quick` runs and writes its reports (a smoke test: the timings are reported, never
asserted; the errors it reports are checked against the closed forms' accuracy)."""
import json

import pytest

from mechgen.cli import main
from bench_reports import check_standard_reports


@pytest.mark.slow  # the quick benchmark run
def test_quick_impact_benchmark_writes_reports(tmp_path):
    assert main(["bench", "impacts", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "impacts.json").read_text())
    assert [r["law"] for r in data["sweep"]] == ["kelvin_voigt", "modified_kelvin_voigt", "maxwell",
                                                 "standard_linear", "hunt_crossley"]
    assert all(r["mechgen_error"] < 1e-8 for r in data["sweep"])  # the closed forms (tests/impact_reference.py)
    assert all(r["ratio"] == r["handwritten_s"] / r["mechgen_s"] for r in data["sweep"])
    assert "ratio" in (tmp_path / "impacts.md").read_text()
    check_standard_reports(tmp_path, "impacts")
