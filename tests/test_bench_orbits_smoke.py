"""`mechgen bench orbits --quick` runs and writes its reports (a smoke test: timings are reported, never asserted;
the fold errors it reports are checked: harmonic balance with 9 harmonics and shooting at rtol 1e-8 find both folds
to 1e-8 of the reference, and the reference's folds are those of tests/test_orbit_branch.py)."""
import json

import pytest

from bench_reports import check_standard_reports
from mechgen.cli import main


@pytest.mark.slow  # the quick benchmark run
def test_quick_orbit_benchmark_writes_reports(tmp_path):
    assert main(["bench", "orbits", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "orbits.json").read_text())
    assert data["reference_folds"] == pytest.approx([1.3242362, 1.7797195], abs=1e-6)
    assert data["errors"]["harmonic balance H=9"] < 1e-8 and data["errors"]["shooting rtol=1e-08"] < 1e-8
    assert "target" in (tmp_path / "orbits.md").read_text()
    check_standard_reports(tmp_path, "orbits")
