"""The figures of a time history (``simulate``'s default plot; ``--plot DIR``, ``Result.plot``).

``plot = "time"`` (the default): each coordinate against t, up to :data:`MAX_CURVES` of them (the first ones,
the title says so), and the energy against t as a companion ``<stem>_energy.png``; ``plot = "phase"``: each
coordinate against its velocity (a phase portrait, one panel per coordinate, up to :data:`MAX_PANELS`).
"""
from __future__ import annotations

from pathlib import Path

#: the most coordinates drawn against t in one figure (a chain has thousands)
MAX_CURVES = 8
#: the most phase portraits in one figure
MAX_PANELS = 6
TIME_LABEL = "t (s, or the model's time unit)"


def coordinates_of(trajectory: dict) -> list[str]:
    """The coordinates among a trajectory's names: those whose velocity ``<name>_dot`` is there too."""
    return [name for name in trajectory if f"{name}_dot" in trajectory]


def time_history(plt, a: dict, path: Path) -> list[Path]:
    """The figures of a simulate entry with a trajectory (its output ``plot``, ``phase`` when the analysis asked
    for a phase portrait); the paths written."""
    out = a["outputs"]
    names = coordinates_of(out["trajectory"])
    if out.get("plot") == "phase":
        return [phase_portrait(plt, a, names, path)]
    written = [against_time(plt, a, names, path)]
    if out.get("energy_series"):
        written.append(energy(plt, a, path.with_name(path.stem + "_energy.png")))
    return written


def against_time(plt, a: dict, names: list[str], path: Path) -> Path:
    """Each coordinate q_i(t), one curve each, a legend when there are several."""
    out = a["outputs"]
    shown = names[:MAX_CURVES]
    fig, ax = plt.subplots(figsize=(7, 4))
    for name in shown:
        ax.plot(out["t"], out["trajectory"][name], label=name)
    _events(ax, out)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("coordinates (the model's units)")
    more = f" (first {len(shown)} of {len(names)})" if len(names) > len(shown) else ""
    ax.set_title(f"{a['name']}: coordinates{more}")
    if len(shown) > 1:
        ax.legend(loc="best", fontsize="small")
    return _save(plt, fig, path)


def phase_portrait(plt, a: dict, names: list[str], path: Path) -> Path:
    """q_i against q_i_dot, one panel per coordinate, the start marked."""
    out = a["outputs"]["trajectory"]
    shown = names[:MAX_PANELS]
    cols = min(3, len(shown)) or 1
    rows = -(-len(shown) // cols) or 1
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.2 * rows), squeeze=False)
    for ax, name in zip(axes.flat, shown):
        ax.plot(out[name], out[f"{name}_dot"], lw=0.8)
        ax.plot(out[name][:1], out[f"{name}_dot"][:1], "o", label="start")
        ax.set_xlabel(name)
        ax.set_ylabel(f"{name}_dot (per unit time)")
    for ax in list(axes.flat)[len(shown):]:
        ax.set_visible(False)
    fig.suptitle(f"{a['name']}: phase portrait")
    return _save(plt, fig, path)


def energy(plt, a: dict, path: Path) -> Path:
    """E(t) = T + V at the samples (its change, when it varies by less than its size's round-off)."""
    out = a["outputs"]
    E = out["energy_series"]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(out["t"], E)
    _events(ax, out)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("energy T + V (J, or the model's unit)")
    ax.ticklabel_format(axis="y", useOffset=False, style="sci", scilimits=(-3, 4))
    ax.set_title(f"{a['name']}: energy")
    return _save(plt, fig, path)


def _events(ax, out: dict) -> None:
    """Thin vertical lines at a hybrid run's event times (at most 200 of them)."""
    for e in out.get("events", [])[:200]:
        ax.axvline(e["t"], color="0.8", lw=0.5, zorder=0)


def _save(plt, fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
