"""The figures of a time history (``simulate``'s default plot; ``--plot DIR``, ``Result.plot``).

``plot = "time"`` (the default): each coordinate against t, up to :data:`MAX_CURVES` of them (the first ones,
the title says so), and the energy against t as a companion ``<stem>_energy.png``; a model with more unknowns
than that (a continuum, a chain) and declared outputs also gets them against t, ``<stem>_outputs.png``; ``plot = "phase"``: each
coordinate against its velocity (a phase portrait, one panel per coordinate, up to :data:`MAX_PANELS`).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: the most coordinates drawn against t in one figure (a chain has thousands)
MAX_CURVES = 8
#: the most phase portraits in one figure
MAX_PANELS = 6
TIME_LABEL = "t (s, or the model's time unit)"
#: the energy series a trajectory carries besides the states (drawn in the energy figure, not as states)
ENERGIES = ("kinetic_energy", "potential_energy", "energy", "work", "dissipated")


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
    written = [against_time(plt, a, names, path) if names else stacked(plt, a, path)]
    if any(out.get("energy_series") or ()):  # a model with no energy (first-order laws only) has nothing to draw
        written.append(energy(plt, a, path.with_name(path.stem + "_energy.png")))
    declared = [n for n in out["trajectory"] if n not in ENERGIES and n not in names
                and not (n.endswith("_dot") and n[:-4] in names)]
    if len(names) > MAX_CURVES and declared:  # a continuum or a chain: its outputs say more than its first dofs
        written.append(stacked(plt, a, path.with_name(path.stem + "_outputs.png"), declared))
    return written


def stacked(plt, a: dict, path: Path, names: list[str] | None = None) -> Path:
    """Each of ``names`` in its own panel against t (up to MAX_PANELS; their scales differ): by default every
    series but the energies (a model without coordinates: its internal variables); a continuum's or a chain's
    declared outputs (flow rate, tip deflection) beside the figure of its first unknowns."""
    out = a["outputs"]
    title = "outputs" if names is not None else "time history"
    names = (names if names is not None else [n for n in out["trajectory"] if n not in ENERGIES])[:MAX_PANELS]
    fig, axes = plt.subplots(len(names) or 1, 1, figsize=(7, 1.8 * max(len(names), 1) + 0.6), sharex=True,
                             squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(out["t"], out["trajectory"][name])
        _events(ax, out)
        ax.set_ylabel(name)
    axes[-1, 0].set_xlabel(TIME_LABEL)
    fig.suptitle(f"{a['name']}: {title}")
    return _save(plt, fig, path)


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
    """A run's energy: with a balance (forces, dissipation, resets that take energy), E(t) - E(0) beside the work
    W(t) and the dissipated energy D(t) and their difference W - D, which it must follow; otherwise the drift
    (E(t) - E(0)) / max(|T| + |V|), the run's error on the scale of its energy (E itself would be drawn at its
    rounding noise)."""
    out = a["outputs"]
    traj = out.get("trajectory") or {}
    t, E = np.asarray(out["t"], float), np.asarray(out["energy_series"], float)
    fig, ax = plt.subplots(figsize=(6, 3.5))
    if "work" in traj and "dissipated" in traj:
        W, D = np.asarray(traj["work"], float), np.asarray(traj["dissipated"], float)
        ax.plot(t, E - E[0], label="E - E(0)")
        ax.plot(t, W, label="W: work of the forces")
        ax.plot(t, D, label="D: dissipated")
        ax.plot(t, W - D, "k:", label="W - D")
        ax.legend(fontsize=7)
        ax.set_ylabel("energy (J, or the model's unit)")
        ax.set_title(f"{a['name']}: energy balance (error {out.get('energy_balance_error', 0.0):.2g})")
    else:
        T, V = (np.asarray(traj.get(k, np.zeros_like(E)), float) for k in ("kinetic_energy", "potential_energy"))
        scale = float(np.max(np.abs(T) + np.abs(V), initial=0.0)) or float(np.max(np.abs(E), initial=0.0)) or 1.0
        ax.plot(t, (E - E[0]) / scale)
        ax.set_ylabel("(E - E(0)) / max(|T| + |V|)")
        ax.set_title(f"{a['name']}: energy drift" + (f" {out['energy_drift']:.2g}" if "energy_drift" in out else ""))
    _events(ax, out)
    ax.set_xlabel(TIME_LABEL)
    ax.ticklabel_format(axis="y", useOffset=False, style="sci", scilimits=(-3, 4))
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
