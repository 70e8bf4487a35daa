"""Figures several kinds draw (``--plot DIR``, ``Result.plot``; matplotlib, the ``plot`` extra).

A kind's ``plot(plt, entry, path)`` gets pyplot, its scene-JSON entry ({"name", "kind",
"outputs", "seconds"}) and the path of its first figure, and returns the paths it wrote.
"""
from __future__ import annotations

import math
from pathlib import Path

from mechgen.errors import InputError

VERDICT_COLOURS = {"stable": "k", "neutral": "tab:green", "divergence": "tab:blue", "flutter": "tab:red", "unconverged": "tab:orange"}


def labelled(a: dict, name: str) -> str:
    """An axis label for the model's parameter ``name``: with its declared unit (the entry's ``units``) when it
    has one, e.g. "P (N)"."""
    unit = (a.get("units") or {}).get(name)
    return f"{name} ({unit})" if unit else name


def pyplot():
    """matplotlib.pyplot on the Agg backend, or an InputError saying how to install it."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise InputError("plotting needs matplotlib", key="--plot",
                         expected="matplotlib installed (pip install 'mechgen[plot]')") from exc
    return plt


#: a spread of real parts below this fraction of the largest |Im s| is round-off (an undamped spectrum)
ROUND_OFF = 1e-9


def eigen(plt, a: dict, path: Path) -> None:
    """The eigenvalues in the complex plane, or (without eigenvalues) the frequencies as bars. Real parts that
    differ by round-off only (an undamped or conservative spectrum) are drawn on the axis at a readable scale
    (+-5 % of the largest |Im s|), not at 1e-15."""
    fig, ax = plt.subplots(figsize=(5, 4))
    if "eigenvalues" in a["outputs"]:
        ev = a["outputs"]["eigenvalues"]
        re, im = [e[0] for e in ev], [e[1] for e in ev]
        ax.plot(re, im, "o")
        reach = max([abs(v) for v in re + im] + [0.0])
        if reach == 0.0 or max(abs(v) for v in re) <= ROUND_OFF * reach:
            ax.set_xlim(-0.05 * (reach or 1.0), 0.05 * (reach or 1.0))
        ax.axvline(0.0, color="0.7", lw=0.5)
        ax.set_xlabel("Re s (1/s)")
        ax.set_ylabel("Im s (rad/s)")
        ax.set_title(f"{a['name']}: {a['outputs'].get('verdict', '')}")
    else:
        freqs = a["outputs"]["frequencies"]
        ax.bar(range(1, len(freqs) + 1), freqs)
        ax.set_xlabel("mode")
        ax.set_ylabel("natural frequency (rad/s)")
        ax.set_title(f"{a['name']}: natural frequencies")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def shapes(plt, a: dict, path: Path) -> bool:
    """Mode shapes (modes of a continuum) or the deflection (steady state of a continuum) against s."""
    out = a["outputs"]
    key = "shapes" if "shapes" in out and "s" in out else "deflection" if "deflection" in out else None
    if key is None:
        return False
    fields = list(out[key])
    fig, axes = plt.subplots(len(fields), 1, figsize=(6, 2.2 + 1.6 * len(fields)), squeeze=False, sharex=True)
    for row, (ax, f) in enumerate(zip(axes[:, 0], fields)):
        curves = out[key][f] if key == "shapes" else [out[key][f]]
        for k, curve in enumerate(curves):  # one legend (the first panel's): the modes are the same in each
            label = f"mode {k + 1}: {out['frequencies'][k]:.4g} rad/s" if key == "shapes" and row == 0 else None
            ax.plot(out["s"], curve, label=label)
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.set_ylabel(f)
    axes[-1, 0].set_xlabel("s (position along the continuum)")
    if key == "shapes":
        axes[0, 0].legend(fontsize=7, loc="best")
    axes[0, 0].set_title(f"{a['name']}: {'mode shapes' if key == 'shapes' else 'deflection'}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def linear(plt, a: dict, path: Path) -> list[Path]:
    """A modes or stability analysis: its spectrum, and beside it a continuum's mode shapes, a lumped
    model's mode shapes as bars (``_shapes.png``) and a rotor's orbits (``_orbits.png``)."""
    eigen(plt, a, path)
    written = []
    shaped = path.with_name(path.stem + "_shapes.png")
    if a.get("figure"):
        from mechgen.analyses import plane_figures

        if plane_figures.modes(plt, a, shaped):
            written.append(shaped)
    elif shapes(plt, a, shaped) or bars(plt, a, shaped):
        written.append(shaped)
    orbits = path.with_name(path.stem + "_orbits.png")
    if ellipses(plt, a, orbits):
        written.append(orbits)
    return written + [path]


#: the most modes a shapes or orbits figure draws (the lowest ones)
MOST_PANELS = 12


def _grid(plt, count: int, width: float, height: float):
    """A figure of ``count`` panels, at most four a row; unused panels switched off."""
    cols = min(count, 4)
    rows = (count + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False)
    for ax in axes.ravel()[count:]:
        ax.axis("off")
    return fig, axes.ravel()[:count]


def _finish(fig, title: str, path: Path) -> None:
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def bars(plt, a: dict, path: Path) -> bool:
    """A lumped model's mode shapes: one panel per mode (the lowest MOST_PANELS), a bar per coordinate
    (real shapes: phi_i; complex shapes: Re X_i and Im X_i side by side), titled with the frequency."""
    out = a["outputs"]
    modes = out.get("shapes")
    if not isinstance(modes, list) or not modes or not isinstance(modes[0], dict):
        return False
    modes = modes[:MOST_PANELS]
    names = list(modes[0])
    fig, axes = _grid(plt, len(modes), 0.45 * len(names) + 1.8, 2.6)
    x = list(range(len(names)))
    for k, (ax, shape) in enumerate(zip(axes, modes)):
        values = [shape[n] for n in names]
        if isinstance(values[0], dict):
            re = [v["amplitude"] * math.cos(v["phase"]) for v in values]
            im = [v["amplitude"] * math.sin(v["phase"]) for v in values]
            ax.bar([i - 0.2 for i in x], re, width=0.4, label="Re")
            ax.bar([i + 0.2 for i in x], im, width=0.4, label="Im")
            if k == 0:
                ax.legend(fontsize=6)
        else:
            ax.bar(x, values)
        ax.axhline(0.0, color="0.5", lw=0.5)
        ax.set_xticks(x, names, rotation=45 if len(names) > 4 else 0, fontsize=7)
        ax.set_xlabel("coordinate", fontsize=7)
        ax.set_ylabel("Re X, Im X" if isinstance(values[0], dict) else "phi (mass-normalised)", fontsize=7)
        ax.set_title(f"mode {k + 1}: {out['frequencies'][k]:.4g} rad/s", fontsize=8)
    kind = "complex (Re, Im)" if isinstance(modes[0][names[0]], dict) else "mass-normalised"
    _finish(fig, f"{a['name']}: {kind} mode shapes", path)
    plt.close(fig)
    return True


def ellipses(plt, a: dict, path: Path) -> bool:
    """A rotor's orbits: one panel per mode (the lowest MOST_PANELS), the ellipse at its station (semi-axes
    ``orbits``, turning as ``whirl_ratio``'s sign says, an arrow at its start), equal axes; a mode without
    an orbit there (whirl ``none``) is said in words, not drawn at round-off scale."""
    out = a["outputs"]
    orbits = out.get("orbits")
    if not isinstance(orbits, list) or not orbits:
        return False
    fig, axes = _grid(plt, min(len(orbits), MOST_PANELS), 2.6, 2.6)
    for k, ax in enumerate(axes):
        o, label = orbits[k], out["whirl"][k]
        ax.set_title(f"mode {k + 1}: {out['frequencies'][k]:.4g} rad/s, {label}", fontsize=8)
        if label == "none" or o["major"] <= 0.0:
            ax.text(0.5, 0.5, "no orbit at the\nwhirl stations", ha="center", va="center", fontsize=8)
            ax.set_xticks([])
            ax.set_yticks([])
            continue
        sense = 1.0 if out["whirl_ratio"][k] >= 0 else -1.0
        ts = [2 * math.pi * i / 120 for i in range(121)]
        c, s = math.cos(o["angle"]), math.sin(o["angle"])
        xs = [o["major"] * math.cos(t) * c - sense * o["minor"] * math.sin(t) * s for t in ts]
        ys = [o["major"] * math.cos(t) * s + sense * o["minor"] * math.sin(t) * c for t in ts]
        ax.plot(xs, ys, "-")
        ax.annotate("", xy=(xs[6], ys[6]), xytext=(xs[0], ys[0]), arrowprops={"arrowstyle": "->"})
        reach = 1.15 * o["major"]
        ax.set_xlim(-reach, reach)
        ax.set_ylim(-reach, reach)
        ax.set_aspect("equal")
        ax.axhline(0.0, color="0.7", lw=0.5)
        ax.axvline(0.0, color="0.7", lw=0.5)
        ax.set_xlabel("x", fontsize=7)
        ax.set_ylabel("y", fontsize=7)
    _finish(fig, f"{a['name']}: orbits at the whirl station (arrow: direction of whirl)", path)
    plt.close(fig)
    return True


def curves(plt, title: str, items: list[tuple[str, dict]], path: Path) -> bool:
    """Curves of continua (first field against the last: a balloon's x against z), one panel each."""
    items = [(label, c) for label, c in items if len(c) >= 2]
    if not items:
        return False
    cols = min(len(items), 4)
    rows = (len(items) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(2.6 * cols, 3.6 * rows), squeeze=False)
    for ax, (label, fields) in zip(axes.ravel(), items):
        first, last = list(fields)[0], list(fields)[-1]
        ax.plot(fields[first], fields[last], "-")
        ax.axvline(0.0, color="0.7", lw=0.5)
        ax.set_xlabel(first)
        ax.set_ylabel(last)
        ax.set_title(label, fontsize=8)
    for ax in axes.ravel()[len(items):]:
        ax.axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def loop(plt, x, force, path: Path, *, xlabel: str, title: str, style: str = "-") -> list[Path]:
    """A force against displacement loop (an impact's hysteresis, a contact's cycle), one panel."""
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(x, force, style, ms=2)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("force")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]
