"""What every benchmark suite shares: timing, BLAS pinning, the machine's description, reports and plots.

Timing (each function states what it measures):

* :func:`timed` - one call: (seconds, result);
* :func:`best_time` - the best mean of enough calls to last a minimum time (micro-benchmarks);
* :func:`repeat_times` - the per-call seconds of several timed runs after a warm-up (their best and median);
* :func:`in_fresh_process` and :func:`empty_cache` - a whole new interpreter, optionally with an empty
  compile cache (first-run and start-up timings).

Fairness: :func:`blas_threads` limits BLAS/OpenMP threads for every tool alike, :func:`blas_info` records
them, :func:`environment` records the machine and the load average. Reports: :func:`write_csv`,
:func:`write_json` and :func:`write_text` write atomically (a reader never sees half a file);
:func:`loglog_plot` draws a work-precision diagram (time against error, log-log).
"""
from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import platform
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


def in_fresh_process(code: str, *args: str) -> dict:
    """Run ``code`` in a new interpreter (cold imports and sympy caches, the current $MECHGEN_CACHE) from the
    repository root with ``args`` as sys.argv[1:]; its last stdout line is JSON, returned parsed."""
    done = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True,
                          env=os.environ.copy(), cwd=ROOT)
    return json.loads(done.stdout.strip().splitlines()[-1])


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
