"""`mechgen bench threads --quick` runs scenes as whole processes unpinned and pinned and writes its reports (a
smoke test: the numbers are timings, reported, never asserted), and the user path's environment is the
default one: no BLAS thread variable in the unpinned child, all of them 1 in the pinned one."""
import json

from mechgen.bench.common import THREAD_VARS, user_env
from mechgen.bench.threads import QUICK_SCENES
from mechgen.cli import main


def test_user_env_strips_or_pins_the_thread_variables(monkeypatch):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "7")
    monkeypatch.setenv("MECHGEN_CACHE", "/somewhere")
    unpinned, pinned = user_env(), user_env(pinned=True)
    assert not set(THREAD_VARS) & set(unpinned) and unpinned["MECHGEN_CACHE"] == "/somewhere"
    assert {pinned[k] for k in THREAD_VARS} == {"1"} and pinned["MECHGEN_CACHE"] == "/somewhere"


def test_quick_threads_benchmark_writes_reports(tmp_path):
    assert main(["bench", "threads", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "threads.json").read_text())
    rows = data["scenes"]
    assert [r["scene"] for r in rows] == list(QUICK_SCENES) and data["quick"] is True
    for r in rows:
        for side in ("unpinned", "pinned"):
            assert r[side]["median_s"] > 0 and len(r[side]["all_s"]) == r["repeats"] == 1
            assert r[side]["analyses_median_s"] and all(v >= 0 for v in r[side]["analyses_median_s"].values())
        assert r["ratio_unpinned_over_pinned"] == r["unpinned"]["median_s"] / r["pinned"]["median_s"]
        assert set(r["analyses_ratio"]) == set(r["unpinned"]["analyses_median_s"])
    assert data["over_target"] == [r["scene"] for r in rows if not r["within_target"]]
    md = (tmp_path / "threads.md").read_text()
    assert all(name in md for name in QUICK_SCENES) and "unpinned / pinned" in md
