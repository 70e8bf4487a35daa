"""Shared check of the bench harness's standard reports (mechgen.bench.common.suite_report) for the smoke tests."""
import csv
import importlib.util
import json
from pathlib import Path


def check_standard_reports(out: Path, suite: str, *, ratios: bool = True) -> list[dict]:
    """The three files exist; every CSV row names the reference; ratios are peer_s / ours_s. The CSV rows."""
    rows = list(csv.DictReader((out / f"{suite}_work_precision.csv").open()))
    assert rows and all(r["reference"] for r in rows)
    assert {"series", "setting", "seconds", "error", "reference"} <= set(rows[0])
    assert all(float(r["seconds"]) > 0 for r in rows)
    data = json.loads((out / f"{suite}_ratios.json").read_text())
    assert data["suite"] == suite and data["reference"] == rows[0]["reference"]
    for r in data["ratios"]:
        assert r["peer"] and r["condition"]
        assert abs(r["ratio"] - r["peer_s"] / r["ours_s"]) <= 1e-12 * r["ratio"]
    if ratios:
        assert data["ratios"]
    if importlib.util.find_spec("matplotlib") is not None:
        assert (out / f"{suite}_work_precision.png").stat().st_size > 0
    return rows
