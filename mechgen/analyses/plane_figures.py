"""Figures of plane continua: the deformed mesh coloured by the displacement, the von Mises stress per element,
mode shapes. They read the analysis entry's ``figure`` (mechgen.runtime.plane.system.PlaneSystem.figure_data,
kept beside the JSON outputs, never in them)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from mechgen.runtime.plane.plotting import von_mises

#: the displayed displacement's largest magnitude, as a fraction of the mesh's size
DEFORMATION_SCALE = 0.1
#: the most mode shapes one figure draws
MOST_MODES = 8


def _deformed(fig_data: dict, values: np.ndarray):
    """x, y of the nodes moved by the (scaled) in-plane displacement (two fields), else unmoved; the scale."""
    x, y = np.asarray(fig_data["x"]), np.asarray(fig_data["y"])
    if values.shape[0] != 2:
        return x, y, 0.0
    size = max(np.ptp(x), np.ptp(y))
    largest = float(np.max(np.hypot(values[0], values[1])))
    scale = DEFORMATION_SCALE * size / largest if largest > 0 else 0.0
    return x + scale * values[0], y + scale * values[1], scale


def panel(plt, ax, fig_data: dict, values: np.ndarray, title: str) -> None:
    """One state: a two-field displacement on the deformed mesh coloured by |u|; one field as filled contours."""
    import matplotlib.tri as mtri

    x, y, scale = _deformed(fig_data, values)
    tri = mtri.Triangulation(x, y, np.asarray(fig_data["triangles"]))
    colour = np.hypot(values[0], values[1]) if values.shape[0] == 2 else values[0]
    shown = ax.tripcolor(tri, colour, shading="gouraud", cmap="viridis")
    if values.shape[0] == 2:
        ax.triplot(tri, lw=0.15, color="k", alpha=0.4)
        title += f" (displacement x {scale:.3g})"
    plt.colorbar(shown, ax=ax, shrink=0.8, label="|u|" if values.shape[0] == 2 else fig_data["fields"][0])
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(title, fontsize=8)


def steady(plt, a: dict, path: Path) -> list[Path]:
    """The steady state on the deformed mesh and, with stresses, the von Mises stress per element."""
    data = a.get("figure")
    if not data:
        return []
    stress = data.get("stress")
    fig, axes = plt.subplots(1, 2 if stress is not None else 1, figsize=(11 if stress is not None else 6, 4.8),
                             squeeze=False)
    values = np.asarray(data["values"][0])
    panel(plt, axes[0, 0], data, values, f"{a['name']}: steady state")
    if stress is not None:
        import matplotlib.tri as mtri

        tri = mtri.Triangulation(np.asarray(data["x"]), np.asarray(data["y"]), np.asarray(data["triangles"]))
        ax = axes[0, 1]
        shown = ax.tripcolor(tri, facecolors=von_mises(np.asarray(stress))[np.asarray(data["cell"])], cmap="magma")
        plt.colorbar(shown, ax=ax, shrink=0.8, label="von Mises stress (element mean)")
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_title("von Mises stress", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


def modes(plt, a: dict, path: Path) -> bool:
    """The lowest mode shapes with their frequencies; False when the entry has no plane figure data."""
    data = a.get("figure")
    if not data:
        return False
    freqs = a["outputs"].get("frequencies", [])
    count = min(len(data["values"]), MOST_MODES)
    cols = min(count, 4)
    rows = (count + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.2 * rows), squeeze=False)
    for k, ax in enumerate(axes.ravel()):
        if k >= count:
            ax.axis("off")
            continue
        panel(plt, ax, data, np.asarray(data["values"][k]), f"mode {k + 1}: {freqs[k]:.5g} rad/s")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"{a['name']}: mode shapes", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
