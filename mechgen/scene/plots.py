"""``--plot DIR``: PNG figures of scene results (matplotlib, the ``plot`` extra).

Each analysis is drawn by its kind's ``plot`` (mechgen.analyses.registry) into
``<scene>_<analysis>.png`` and its companions (``..._shapes.png``, ``..._curve.png`` ...).
"""
from __future__ import annotations

from pathlib import Path

from mechgen.analyses.figures import pyplot
from mechgen.analyses.registry import get


def plot_results(results: dict, folder: Path) -> list[Path]:
    """Write the figures of every plottable analysis into ``folder``; returns the paths."""
    plt = pyplot()
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for a in results["analyses"]:
        draw = get(a["kind"]).plot
        if draw is not None and "error" not in a:  # a failed analysis (its error in the summary) has nothing
            entry = {**a, "units": results.get("units", {})}  # the parameters' units, for the axes
            written += draw(plt, entry, folder / f"{Path(results['scene']).stem}_{a['name']}.png")
    return written
