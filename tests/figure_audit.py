"""Every default figure a reader trusts (issue 26, item 6): what a saved figure must have.

Each figure must have a title (an axes title or a suptitle); every panel that draws data has both axis labels;
a panel with two or more labelled curves has a legend; no linear axis spans less than 1e-9 of its own magnitude
(an axis scaled to round-off, such as E(t) of a conservative run drawn at its rounding noise, or the real parts
of an undamped spectrum at 1e-15). Used by tests/test_rerun.py, which draws every shipped scene's figures from
its second run (one run of each scene fewer than a separate figure test), and by tests/test_figures.py.
"""
from __future__ import annotations

import contextlib


def _has_data(ax) -> bool:
    return bool(ax.lines or ax.collections or ax.patches or ax.images)


def _labelled(ax) -> int:
    return sum(1 for artist in list(ax.lines) + list(ax.collections)
               if artist.get_label() and not artist.get_label().startswith("_"))


def _round_off(ax) -> list[str]:
    found = []
    for name, lim, scale in (("x", ax.get_xlim(), ax.get_xscale()), ("y", ax.get_ylim(), ax.get_yscale())):
        lo, hi = sorted(lim)
        size = max(abs(lo), abs(hi))
        if scale == "linear" and size > 0 and hi - lo < 1e-9 * size:
            found.append(f"{name} axis spans {hi - lo:.3g} at {size:.6g}")
    return found


def audit(fig) -> list[str]:
    """What a figure lacks (an empty list: nothing)."""
    problems = []
    titles = [ax.get_title() for ax in fig.axes] + [fig._suptitle.get_text() if fig._suptitle is not None else ""]
    axes = [ax for ax in fig.axes if ax.axison and ax.get_label() != "<colorbar>"]  # 3D axes: no axison
    if not any(t.strip() for t in titles):
        problems.append("no title")
    for i, ax in enumerate(axes):
        if not _has_data(ax):
            continue
        xlabel = ax.get_xlabel().strip() or any(other.get_xlabel().strip() for other in axes
                                                 if other is not ax and ax.get_shared_x_axes().joined(ax, other))
        ylabel = ax.get_ylabel().strip() or any(other.get_ylabel().strip() for other in axes
                                                 if other is not ax and ax.get_shared_y_axes().joined(ax, other))
        if not xlabel or not ylabel:  # a shared axis is labelled once (under the last panel, beside the first)
            problems.append(f"panel {i}: axis label missing (x {ax.get_xlabel()!r}, y {ax.get_ylabel()!r})")
        if _labelled(ax) >= 2 and ax.get_legend() is None and not fig.legends:
            problems.append(f"panel {i}: {_labelled(ax)} labelled curves and no legend")
        problems += [f"panel {i}: {p}" for p in _round_off(ax)]
    return problems


@contextlib.contextmanager
def audited_savefig(seen: dict[str, list[str]]):
    """While open, every Figure.savefig records ``seen[file name] = audit(figure)`` before it saves."""
    from pathlib import Path

    from matplotlib.figure import Figure

    save = Figure.savefig

    def checked(fig, path, *args, **kwargs):
        seen[Path(path).name] = audit(fig)
        return save(fig, path, *args, **kwargs)

    Figure.savefig = checked
    try:
        yield seen
    finally:
        Figure.savefig = save
