"""``mechgen bench threads`` (issue #12): every shipped scene as a user runs it against pinned to one BLAS thread.

Each scene of ``scenes/`` is run as a whole process (``python -m mechgen run SCENE --json ...``, the compile
cache filled by one untimed run first) in two environments: **unpinned**, the default a user has (no
``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``, ``MKL_NUM_THREADS``: mechgen's own thread control,
:mod:`mechgen.runtime.core.threads`, decides), and **pinned**, all three set to 1. The runs are interleaved
(each round runs every scene in both environments, the order alternating between rounds) so that a busy
machine's load falls on both alike; reported per scene: the median wall time of each, their ratio, the
analyses' own seconds and the slowest analysis's ratio. Target: no scene slower unpinned than pinned by more
than :data:`mechgen.bench.common.UNPINNED_TARGET` (1.2). Writes ``out/threads.json`` and ``out/threads.md``.

``quick=True``: two small scenes, one round (a smoke run; its ratios mean little).
"""
from __future__ import annotations

import os
from pathlib import Path

from mechgen.bench.common import ROOT, environment, user_path, user_path_markdown, write_json, write_text

#: the quick run's scenes
QUICK_SCENES = ("laval_rotor.toml", "spring_pendulum.toml")


def shipped_scenes() -> list[Path]:
    """The scenes shipped in ``scenes/``, by name."""
    return sorted((ROOT / "scenes").glob("*.toml"))


def run_threads_benchmarks(out: Path, quick: bool = False) -> dict:
    """Time every shipped scene unpinned and pinned (:func:`mechgen.bench.common.user_path`, median of 3,
    interleaved); write ``out/threads.{json,md}``; return the results."""
    out = Path(out)
    scenes = [ROOT / "scenes" / n for n in QUICK_SCENES] if quick else shipped_scenes()
    env = environment()
    rows = user_path(scenes, repeats=1 if quick else 3)
    env["loadavg_after"] = list(os.getloadavg())
    over = [r["scene"] for r in rows if not r["within_target"]]
    res = {"quick": quick, "environment": env, "scenes": rows, "over_target": over}
    write_json(out / "threads.json", res, indent=1)
    text = "\n".join([
        "# Scenes unpinned against pinned BLAS threads (issue #12)", "",
        f"{'QUICK run (one round). ' if quick else ''}Machine: {env['cpu_count']} cores; load average "
        f"{env['loadavg_before'][0]:.2f} before, {env['loadavg_after'][0]:.2f} after.", "",
        user_path_markdown(rows, "Every scene, whole process"), "",
        f"Over target: {', '.join(over) if over else 'none'}."])
    write_text(out / "threads.md", text + "\n")
    print(text)
    print(f"\nwrote {out / 'threads.json'}, {out / 'threads.md'}")
    return res
