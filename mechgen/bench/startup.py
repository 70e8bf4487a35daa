"""``mechgen bench startup``: a cached scene run timed as a whole process, with its import share.

For each scene (the Laval rotor and a continuum, the Euler-Bernoulli beam's modes) the scene is
run once to fill the caches, then ``python -X importtime -m mechgen run SCENE`` is started
``repeats`` times in a fresh subprocess. Reported per scene: the median wall time of the whole
process (interpreter start, imports, kernel load, analyses, output), the median time spent in
imports (the sum of the top-level cumulative times that ``-X importtime`` prints) and its share,
and whether sympy, jinja2, scipy.optimize or mechgen.symbolic were imported (they must not be: a
cached run derives nothing). Every run is made as a user makes it, in the default environment (no
``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``, ``MKL_NUM_THREADS``), interleaved with the same run pinned
to one BLAS thread (``pinned_wall_s`` and ``ratio_unpinned_over_pinned``; issue #12). ``quick``: one
repeat (a smoke test of the suite: still one unpinned and one pinned run per scene, each checked for heavy
imports). Writes ``out/startup.{json,md}``.
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

from mechgen.bench.common import ROOT, UNPINNED_TARGET, user_env, write_json, write_text

SCENES = ("laval_rotor.toml", "beam_modes.toml")
HEAVY = ("sympy", "jinja2", "scipy.optimize", "mechgen.symbolic")
TARGET_S = 0.5


def import_seconds(stderr: str) -> tuple[float, set[str]]:
    """Total import time (s) of an ``-X importtime`` log (top-level entries) and the modules it names."""
    total, names = 0.0, set()
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        _, cumulative, name = line[len("import time:"):].split("|")
        names.add(name.strip())
        if not name.startswith("  "):  # one space after the bar: a top-level import
            total += int(cumulative) * 1e-6
    return total, names


def time_scene(scene: Path, repeats: int = 7) -> dict:
    """Median whole-process time of a cached ``mechgen run scene`` and its import share, as a user runs it (the
    default environment: no BLAS thread variables; ``wall_s``) and pinned to one BLAS thread (``pinned_wall_s``),
    interleaved (the order alternating between repeats)."""
    cmd = [sys.executable, "-X", "importtime", "-m", "mechgen", "run", str(scene)]
    subprocess.run(cmd[:1] + cmd[3:], check=True, capture_output=True, env=user_env(), cwd=ROOT)  # fill the caches
    walls, imports, heavy = {False: [], True: []}, {False: [], True: []}, set()
    for k in range(repeats):
        for pinned in ((False, True) if k % 2 == 0 else (True, False)):
            start = time.perf_counter()
            proc = subprocess.run(cmd, check=True, capture_output=True, text=True, env=user_env(pinned), cwd=ROOT)
            walls[pinned].append(time.perf_counter() - start)
            seconds, names = import_seconds(proc.stderr)
            imports[pinned].append(seconds)
            heavy |= {h for h in HEAVY if h in names}
    wall, imp = statistics.median(walls[False]), statistics.median(imports[False])
    pinned = statistics.median(walls[True])
    return {"scene": scene.name, "repeats": repeats, "wall_s": wall, "imports_s": imp, "import_share": imp / wall,
            "wall_min_s": min(walls[False]), "heavy_imports": sorted(heavy), "target_s": TARGET_S,
            "pinned_wall_s": pinned, "pinned_imports_s": statistics.median(imports[True]),
            "ratio_unpinned_over_pinned": wall / pinned, "unpinned_target": UNPINNED_TARGET}


def run_startup_benchmarks(out: Path, *, quick: bool = False) -> dict:
    """Time every scene of :data:`SCENES`; writes ``out/startup.{json,md}``."""
    folder = ROOT / "scenes"
    rows = [time_scene(folder / name, repeats=1 if quick else 7) for name in SCENES]
    write_json(out / "startup.json", rows)
    lines = ["| scene | whole process (median, s) | imports (s) | import share | heavy imports | pinned (median, s) | "
             f"unpinned / pinned (target <= {UNPINNED_TARGET:g}) |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['scene']} | {r['wall_s']:.3f} | {r['imports_s']:.3f} | {r['import_share']:.0%} | "
              f"{', '.join(r['heavy_imports']) or 'none'} | {r['pinned_wall_s']:.3f} | "
              f"{r['ratio_unpinned_over_pinned']:.2f} |" for r in rows]
    write_text(out / "startup.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    return {"rows": rows}
