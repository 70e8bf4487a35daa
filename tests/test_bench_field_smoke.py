"""The quick continua benchmark runs and writes its reports (no timing assertions: targets live in the report).

The benchmark checks its numbers before timing them (mechgen's Hermite matrices
against the closed form, scikit-fem's against mechgen's), so this also checks
that both libraries assemble the same beam.
"""
import csv
import importlib.util
import json

from mechgen.bench.beam import run_field_benchmarks
from bench_reports import check_standard_reports


def test_quick_field_benchmark_writes_reports(tmp_path, capsys):
    result = run_field_benchmarks(tmp_path, quick=True)
    rows = list(csv.DictReader((tmp_path / "beam_work_precision.csv").open()))
    assert {r["discretisation"] for r in rows} == {"hermite", "quintic", "legendre", "beam"}
    assert len(rows) == len(result["work_precision"])
    hermite = [float(r["max_rel_error"]) for r in rows if r["discretisation"] == "hermite"]
    assert hermite == sorted(hermite, reverse=True)  # refinement helps on the quick ladder
    assert min(float(r["max_rel_error"]) for r in rows if r["discretisation"] == "beam") < 1e-10
    check_standard_reports(tmp_path, "beam", ratios=importlib.util.find_spec("skfem") is not None)
    assembly = json.loads((tmp_path / "beam_assembly.json").read_text())
    assert assembly["elements"] == 2000 and assembly["checks"]["mechgen_vs_closed_form"] < 1e-12
    assert "mechgen linear()" in assembly["seconds"]
    if importlib.util.find_spec("skfem") is not None:
        assert "linear() / asm" in assembly["ratios"]
    if importlib.util.find_spec("matplotlib") is not None:
        assert (tmp_path / "beam_work_precision.png").stat().st_size > 0
    assert (tmp_path / "beam_work_precision.md").read_text().startswith("# Clamped-free")
    out = capsys.readouterr().out
    assert "max rel. error" in out
    assert "mechgen / scikit-fem" in out or "skipped" in out
