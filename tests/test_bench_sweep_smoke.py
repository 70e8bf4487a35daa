"""`mechgen bench sweep --quick` runs the Laval sweep on every executor and writes its reports (a smoke test:
the timings are reported, never asserted; the benchmark itself checks that every executor gives the serial
numbers bit for bit, and the serial ones against the closed-form whirl)."""
import csv
import json

import pytest

from mechgen.cli import main

pytest.importorskip("distributed")


def test_quick_sweep_benchmark_writes_reports(tmp_path):
    assert main(["bench", "sweep", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "sweep.json").read_text())
    assert data["points"] == 500 and set(data["executors"]) == {"serial", "processes", "dask", "dask (running cluster)"}
    assert data["closed_form_error"] < 1e-9
    serial = data["executors"]["serial"]
    assert serial["overhead_per_point_ms"] == 0.0 and serial["tasks"] == 500
    assert data["ratio_dask_over_processes"] == data["executors"]["dask"]["wall_s"] / data["executors"]["processes"]["wall_s"]
    rows = list(csv.DictReader((tmp_path / "sweep_work_precision.csv").open()))
    assert {r["series"] for r in rows} == set(data["executors"]) and all("closed-form" in r["reference"] for r in rows)
    ratios = json.loads((tmp_path / "sweep_ratios.json").read_text())["ratios"]
    assert [r["peer"] for r in ratios] == ["local processes (2 workers)"] * 3
    assert "dask / processes" in (tmp_path / "sweep.md").read_text().replace("(LocalCluster started for the run) ", "")
