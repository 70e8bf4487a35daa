"""What every benchmark suite shares: timing, BLAS pinning, the machine's description, reports and plots.

Timing (each function states what it measures):

* :func:`timed` - one call: (seconds, result);
* :func:`best_time` - the best mean of enough calls to last a minimum time (micro-benchmarks);
* :func:`repeat_times` - the per-call seconds of several timed runs after a warm-up (their best and median);
* :func:`in_fresh_process` and :func:`empty_cache` - a whole new interpreter, optionally with an empty
  compile cache (first-run and start-up timings);
* :func:`scene_process` and :func:`user_path` - ``mechgen run SCENE`` as a user runs it (a new process, the
  default environment: no BLAS thread variables) beside the same run pinned to one BLAS thread.

Fairness: :func:`blas_threads` limits BLAS/OpenMP threads for every tool alike, :func:`blas_info` records
them, :func:`environment` records the machine and the load average. Reports: :func:`write_csv`,
:func:`write_json` and :func:`write_text` write atomically (a reader never sees half a file);
:func:`loglog_plot` draws a work-precision diagram (time against error, log-log); :func:`suite_report`
writes the three reports every work-precision suite has, in one format: ``<suite>_work_precision.csv``,
``<suite>_work_precision.png`` (the reference named on the plot and in every CSV row) and
``<suite>_ratios.json`` (wall-time ratios against the suite's peers, each with the condition it was
measured at).
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

#: the repository root (scenes/, benchmarks/)
ROOT = Path(__file__).resolve().parents[2]


# -- timing ---------------------------------------------------------------------------------------------------
def timed(fn: Callable):
    """(seconds, result) of one call of ``fn``."""
    start = time.perf_counter()
    out = fn()
    return time.perf_counter() - start, out


def best_time(fn: Callable, *, min_time: float = 0.1, repeats: int = 5) -> float:
    """Best over ``repeats`` of the mean time of enough calls to last ``min_time`` seconds."""
    fn()
    number, elapsed = 1, 0.0
    while True:
        start = time.perf_counter()
        for _ in range(number):
            fn()
        elapsed = time.perf_counter() - start
        if elapsed >= min_time:
            break
        number *= 2 if elapsed <= 0 else max(2, int(min_time / max(elapsed, 1e-9)))
    best = elapsed / number
    for _ in range(repeats - 1):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def repeat_times(fn: Callable, repeats: int, min_time: float = 0.0) -> list[float]:
    """Per-call seconds of ``repeats`` timed runs (after one untimed warm-up); a run loops to last ``min_time``."""
    fn()
    number = 1
    if min_time > 0:
        start = time.perf_counter()
        fn()
        once = max(time.perf_counter() - start, 1e-7)
        number = max(1, int(min_time / once))
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        out.append((time.perf_counter() - start) / number)
    return out


def interleaved_rounds(sides: dict, repeats: int) -> dict:
    """{side: (its seconds per round, its last value)} of the callables ``sides``: one untimed warm-up call of each
    (builds, imports and first loads excluded on every side), then ``repeats`` rounds that call every side once,
    the order reversed every other round, so that the machine's load falls on all sides alike."""
    values = {side: fn() for side, fn in sides.items()}
    times: dict = {side: [] for side in sides}
    order = list(sides)
    for k in range(repeats):
        for side in order if k % 2 == 0 else order[::-1]:
            start = time.perf_counter()
            values[side] = sides[side]()
            times[side].append(time.perf_counter() - start)
    return {side: (times[side], values[side]) for side in sides}


@contextlib.contextmanager
def empty_cache():
    """Point $MECHGEN_CACHE at a fresh temporary directory for the duration (first-run timings)."""
    old = os.environ.get("MECHGEN_CACHE")
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["MECHGEN_CACHE"] = tmp
        try:
            yield
        finally:
            if old is None:
                os.environ.pop("MECHGEN_CACHE", None)
            else:
                os.environ["MECHGEN_CACHE"] = old


def in_fresh_process(code: str, *args: str, env: dict | None = None) -> dict:
    """Run ``code`` in a new interpreter (cold imports and sympy caches, the current $MECHGEN_CACHE) from the
    repository root with ``args`` as sys.argv[1:] and ``env`` (default: this process's environment); its last
    stdout line is JSON, returned parsed. A failed run raises RuntimeError with the end of its stderr."""
    done = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          env=os.environ.copy() if env is None else env, cwd=ROOT)
    if done.returncode != 0:
        raise RuntimeError(f"benchmark child process exited {done.returncode}: {done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


# -- the user path: a scene as a whole process, default environment against pinned -----------------------------
#: the variables through which BLAS/OpenMP thread counts are chosen (stripped from a user-path child)
THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
#: a scene may be at most this much slower unpinned than pinned (issue #12)
UNPINNED_TARGET = 1.2


def user_env(pinned: bool = False) -> dict:
    """This process's environment without :data:`THREAD_VARS` (the default a user has), or with all of them
    set to 1 (``pinned``: the benchmarks' one BLAS thread)."""
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARS}
    if pinned:
        env.update(dict.fromkeys(THREAD_VARS, "1"))
    return env


def scene_process(scene: Path, *, pinned: bool = False, overrides: tuple[str, ...] = ()) -> dict:
    """One ``python -m mechgen run SCENE --json ...`` in a new process from the repository root, environment
    :func:`user_env` (``pinned``), ``--set`` for each of ``overrides``: {"wall_s": the whole process's wall time,
    "analyses_s": {analysis name: the seconds the scene JSON records for it}}. A failed run raises
    RuntimeError with the end of its stderr."""
    with tempfile.TemporaryDirectory() as tmp:
        target = Path(tmp) / "out.json"
        cmd = [sys.executable, "-m", "mechgen", "run", str(scene), "--json", str(target),
               *(f"--set={o}" for o in overrides)]
        start = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, env=user_env(pinned), cwd=ROOT)
        wall = time.perf_counter() - start
        if done.returncode != 0:
            raise RuntimeError(f"mechgen run {Path(scene).name} exited {done.returncode}: {done.stderr[-2000:]}")
        data = json.loads(target.read_text())
    return {"wall_s": wall, "analyses_s": {a["name"]: float(a["seconds"]) for a in data["analyses"]}}


def _medians(runs: list[dict]) -> dict:
    names = runs[0]["analyses_s"]
    return {"median_s": statistics.median(r["wall_s"] for r in runs), "all_s": [r["wall_s"] for r in runs],
            "analyses_median_s": {n: statistics.median(r["analyses_s"][n] for r in runs) for n in names}}


def user_path(scenes: Iterable[Path], repeats: int = 3, *, overrides: tuple[str, ...] = (),
              warm: bool = True) -> list[dict]:
    """Every scene as a user runs it (:func:`scene_process`, default environment) and pinned to one BLAS
    thread, interleaved so that the machine's load falls on both alike: after one untimed run of each scene
    (``warm``: fills the compile cache), ``repeats`` rounds in which each scene runs unpinned then pinned
    (pinned first in every other round). Per scene: both configurations' median whole-process wall time
    (and of each analysis, as the scene JSON records it), ``ratio_unpinned_over_pinned`` of the medians and
    whether it is within :data:`UNPINNED_TARGET` (also per analysis: ``analyses_ratio``)."""
    scenes = [Path(s) for s in scenes]
    if warm:
        for scene in scenes:
            scene_process(scene, overrides=overrides)
    runs = {s: {"unpinned": [], "pinned": []} for s in scenes}
    for k in range(repeats):
        for scene in scenes:
            for pinned in ((False, True) if k % 2 == 0 else (True, False)):
                got = scene_process(scene, pinned=pinned, overrides=overrides)
                runs[scene]["pinned" if pinned else "unpinned"].append(got)
                print(f"[user path] round {k + 1}/{repeats} {scene.name} {'pinned' if pinned else 'unpinned'}: "
                      f"{got['wall_s']:.2f} s", file=sys.stderr, flush=True)
    rows = []
    for scene in scenes:
        un, pin = _medians(runs[scene]["unpinned"]), _medians(runs[scene]["pinned"])
        ratio = un["median_s"] / pin["median_s"]
        rows.append({"scene": scene.name, "overrides": list(overrides), "repeats": repeats, "warm": warm, "unpinned": un,
                     "pinned": pin, "ratio_unpinned_over_pinned": ratio, "target": UNPINNED_TARGET,
                     "within_target": ratio <= UNPINNED_TARGET,
                     "analyses_ratio": {n: un["analyses_median_s"][n] / max(pin["analyses_median_s"][n], 1e-9)
                                        for n in un["analyses_median_s"]}})
    return rows


def user_path_markdown(rows: list[dict], title: str = "As a user runs it") -> str:
    """A table of :func:`user_path` rows: both configurations' medians, their ratio and the slowest
    analysis's ratio."""
    lines = [f"## {title}", "",
             f"`mechgen run SCENE` as a whole process ({'cached' if all(r['warm'] for r in rows) else 'no warm-up run: the first may compile, a quick run'}), median of "
             f"{rows[0]['repeats'] if rows else 0}, interleaved: unpinned = the default environment "
             f"(no {', '.join(THREAD_VARS)}), pinned = all of them 1. Target: unpinned / pinned <= "
             f"{UNPINNED_TARGET:g}.", "",
             "| scene | unpinned | pinned | unpinned / pinned | slowest analysis (unpinned / pinned) |",
             "|---|---|---|---|---|"]
    for r in rows:
        ratios = r["analyses_ratio"]
        worst = max(ratios, key=lambda n: ratios[n]) if ratios else None
        an = "-" if worst is None else (f"{worst}: {r['unpinned']['analyses_median_s'][worst]:.3f} s / "
                                        f"{r['pinned']['analyses_median_s'][worst]:.3f} s = {ratios[worst]:.2f}")
        flag = "" if r["within_target"] else " (over target)"
        lines.append(f"| {r['scene']} | {r['unpinned']['median_s']:.3f} s | {r['pinned']['median_s']:.3f} s | "
                     f"{r['ratio_unpinned_over_pinned']:.2f}{flag} | {an} |")
    return "\n".join(lines)


# -- fairness and the machine ---------------------------------------------------------------------------------
@contextlib.contextmanager
def blas_threads(n: int = 1):
    """Limit BLAS/OpenMP threads of every tool alike (threadpoolctl, when installed); yields n, or None."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        yield None
        return
    with threadpool_limits(limits=n):
        yield n


def blas_info() -> list:
    """The BLAS/OpenMP libraries loaded and their thread counts (empty without threadpoolctl)."""
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return []
    return [{"api": i.get("internal_api"), "num_threads": i.get("num_threads")} for i in threadpool_info()]


def environment(**versions) -> dict:
    """Python, numpy and scipy versions, the CPU count, the machine and the load average now
    (``loadavg_before``; a suite adds ``loadavg_after``), with ``versions`` (e.g. ross=...) after scipy."""
    import scipy

    return {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__, **versions,
            "cpu_count": os.cpu_count(), "machine": platform.machine(), "loadavg_before": list(os.getloadavg())}


# -- reports --------------------------------------------------------------------------------------------------
def write_text(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (a temporary file in the same folder, then a rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=path.suffix)
    try:
        with os.fdopen(fd, "w", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def write_json(path: Path, data, *, indent: int = 2) -> Path:
    """``data`` as JSON (numpy scalars as floats), one trailing newline, atomically."""
    return write_text(path, json.dumps(data, indent=indent, default=float) + "\n")


def write_csv(path: Path, rows: Iterable, header: list[str] | None = None) -> Path:
    """Rows as CSV, atomically: dicts (columns from ``header`` or the first row's keys) or sequences under
    ``header``."""
    rows = list(rows)
    buf = io.StringIO(newline="")
    if rows and isinstance(rows[0], dict):
        writer = csv.DictWriter(buf, fieldnames=header or list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    else:
        writer = csv.writer(buf)
        if header:
            writer.writerow(header)
        writer.writerows(rows)
    return write_text(path, buf.getvalue())


def loglog_plot(path: Path, series: dict, *, xlabel: str, ylabel: str, title: str, floor: float = 0.0) -> bool:
    """A work-precision diagram: one line per entry of ``series`` (label -> list of (x, y, annotation)), log-log,
    y clipped below at ``floor`` (values exact to round-off drawn at the floor). False when matplotlib is
    missing (nothing written)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, ax = plt.subplots(figsize=(7, 5))
    for label, points in series.items():
        x = [pt[0] for pt in points]
        y = [max(pt[1], floor) for pt in points]
        ax.loglog(x, y, "o-", label=label)
        for (_, _, note), xi, yi in zip(points, x, y):
            ax.annotate(str(note), (xi, yi), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def suite_report(out: Path, suite: str, points: Iterable[dict], *, reference: str, error: str, time: str,
                 title: str, ratios: Iterable[dict] = (), floor: float = 1e-16) -> list[Path]:
    """The harness's standard reports of suite ``suite`` in ``out`` (the files it wrote):

    * ``<suite>_work_precision.csv``: one row per point, columns series, setting, seconds, error, reference
      (``points``: dicts with keys series, setting, seconds, error; ``error`` measured against ``reference``),
      then any further keys of the points as more columns;
    * ``<suite>_work_precision.png``: error against seconds, log-log, one line per series, the reference
      named in the title (skipped without matplotlib);
    * ``<suite>_ratios.json``: {suite, reference, error, time, ratios}, each ratio a dict with peer (the other
      tool), ours_s and peer_s (seconds, one run, same machine), ratio = peer_s / ours_s (> 1: we are faster)
      and condition (what was held equal: the accuracy, the problem size).
    """
    out = Path(out)
    base = ["series", "setting", "seconds", "error", "reference"]
    rows, extra = [], {}
    for p in points:
        rows.append({**p, "series": str(p["series"]), "setting": str(p["setting"]), "seconds": float(p["seconds"]),
                     "error": float(p["error"]), "reference": reference})
        extra.update(dict.fromkeys(k for k in p if k not in base))
    files = [write_csv(out / f"{suite}_work_precision.csv", [{k: r.get(k, "") for k in base + list(extra)}
                                                               for r in rows], header=base + list(extra))]
    series: dict = {}
    for r in rows:
        series.setdefault(r["series"], []).append((r["seconds"], r["error"], r["setting"]))
    png = out / f"{suite}_work_precision.png"
    if rows and loglog_plot(png, series, xlabel=time, ylabel=error, title=f"{title}\nreference: {reference}",
                            floor=floor):
        files.append(png)
    table = []
    for r in ratios:
        ours, theirs = float(r["ours_s"]), float(r["peer_s"])
        table.append({"peer": str(r["peer"]), "ours_s": ours, "peer_s": theirs,
                      "ratio": theirs / ours if ours > 0 else float("inf"), "condition": str(r["condition"])})
    files.append(write_json(out / f"{suite}_ratios.json", {"suite": suite, "reference": reference, "error": error,
                                                          "time": time, "ratios": table}))
    return files
