"""``--plot DIR``: PNG figures of scene results (matplotlib, the ``plot`` extra).

Each analysis is drawn by its kind's ``plot`` (mechgen.analyses.registry) into
``<scene>_<analysis>.png`` and its companions (``..._shapes.png``, ``..._curve.png`` ...).

The figures are drawn into a fresh private folder inside DIR (``tempfile.mkdtemp``: nothing planted there)
and each is then renamed over its name in DIR: a link planted in DIR is replaced, never followed, and a
name held by a folder, device, FIFO or socket is refused (exit 2 at ``--plot``), never written into.
"""
from __future__ import annotations

import os
import shutil
import stat
import tempfile
from pathlib import Path

from mechgen.analyses.figures import pyplot
from mechgen.analyses.registry import get
from mechgen.errors import InputError, file_kind

#: what --plot expects, for messages
EXPECTED = "a folder to write the plots into, whose figure names are free or regular files"


def plot_results(results: dict, folder: Path) -> list[Path]:
    """Write the figures of every plottable analysis into ``folder``; returns the paths."""
    plt = pyplot()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(dir=folder, prefix=".tmp-plots-"))
    except OSError as exc:
        raise InputError(f"cannot write into {folder} ({exc.strerror})", key="--plot", expected=EXPECTED) from None
    written = []
    try:
        for a in results["analyses"]:
            draw = get(a["kind"]).plot
            if draw is not None and "error" not in a:  # a failed analysis (its error in the summary) has nothing
                entry = {**a, "units": results.get("units", {}),  # the parameters' units, for the axes
                         "figure": results.get("_figures", {}).get(a["name"])}  # a plane model's mesh and values
                drawn = _drawn(draw, plt, entry, staging / f"{Path(results['scene']).stem}_{a['name']}.png")
                written += [place(path, folder / path.name) for path in drawn]
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return written


def _drawn(draw, plt, entry: dict, path: Path) -> list[Path]:
    """The kind's figures of one analysis, drawn into the staging folder; a name the file system refuses (too
    long) is exit 2 at --plot."""
    try:
        return draw(plt, entry, path)
    except OSError as exc:
        plt.close("all")
        raise InputError(f"cannot write the figure {path.name[:60]} ({exc.strerror})", key="--plot",
                         expected=EXPECTED + " (shorter scene and analysis names)") from None


def place(drawn: Path, target: Path) -> Path:
    """Rename a drawn figure over ``target`` (atomic; a link at ``target`` is replaced, not followed); an
    existing ``target`` that is not a regular file or a link is refused."""
    try:
        mode = os.lstat(target).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise InputError(f"cannot inspect {target} ({exc.strerror})", key="--plot", expected=EXPECTED) from None
    if mode is not None and not (stat.S_ISREG(mode) or stat.S_ISLNK(mode)):
        raise InputError(f"{target} exists and is {file_kind(mode)}, not a regular file", key="--plot",
                         expected=EXPECTED)
    try:
        os.replace(drawn, target)
    except OSError as exc:
        raise InputError(f"cannot write {target} ({exc.strerror})", key="--plot", expected=EXPECTED) from None
    return target
