"""Figures several kinds draw (``--plot DIR``, ``Result.plot``; matplotlib, the ``plot`` extra).

A kind's ``plot(plt, entry, path)`` gets pyplot, its scene-JSON entry ({"name", "kind",
"outputs", "seconds"}) and the path of its first figure, and returns the paths it wrote.
"""
from __future__ import annotations

from pathlib import Path

from mechgen.errors import InputError

VERDICT_COLOURS = {"stable": "k", "neutral": "tab:green", "divergence": "tab:blue", "flutter": "tab:red", "unconverged": "tab:orange"}


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


def eigen(plt, a: dict, path: Path) -> None:
    """The eigenvalues in the complex plane, or (without eigenvalues) the frequencies as bars."""
    fig, ax = plt.subplots(figsize=(5, 4))
    if "eigenvalues" in a["outputs"]:
        ev = a["outputs"]["eigenvalues"]
        ax.plot([e[0] for e in ev], [e[1] for e in ev], "o")
        ax.set_xlabel("Re s")
        ax.set_ylabel("Im s")
        ax.set_title(f"{a['name']}: {a['outputs'].get('verdict', '')}")
    else:
        freqs = a["outputs"]["frequencies"]
        ax.bar(range(1, len(freqs) + 1), freqs)
        ax.set_xlabel("mode")
        ax.set_ylabel("frequency")
        ax.set_title(a["name"])
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def shapes(plt, a: dict, path: Path) -> bool:
    """Mode shapes (modes of a continuum) or the deflection (steady state of a continuum) against s."""
    out = a["outputs"]
    key = "shapes" if "shapes" in out else "deflection" if "deflection" in out else None
    if key is None:
        return False
    fields = list(out[key])
    fig, axes = plt.subplots(len(fields), 1, figsize=(6, 2.2 + 1.6 * len(fields)), squeeze=False)
    for ax, f in zip(axes[:, 0], fields):
        curves = out[key][f] if key == "shapes" else [out[key][f]]
        for k, curve in enumerate(curves):
            label = f"mode {k + 1}: {out['frequencies'][k]:.4g}" if key == "shapes" else None
            ax.plot(out["s"], curve, label=label)
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.set_ylabel(f)
    axes[-1, 0].set_xlabel("s")
    if key == "shapes":
        axes[0, 0].legend(fontsize=7, loc="best")
    axes[0, 0].set_title(f"{a['name']}: {'mode shapes' if key == 'shapes' else 'deflection'}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def linear(plt, a: dict, path: Path) -> list[Path]:
    """A modes or stability analysis: its spectrum, and a continuum's mode shapes beside it."""
    eigen(plt, a, path)
    written = []
    shaped = path.with_name(path.stem + "_shapes.png")
    if shapes(plt, a, shaped):
        written.append(shaped)
    return written + [path]


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
