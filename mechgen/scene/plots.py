"""``--plot DIR``: PNG figures of scene results (matplotlib, the ``plot`` extra).

* sweep of modes/stability: frequencies (and growth rates) against the swept parameter
  (a Campbell diagram when the parameter is a spin speed);
* modes/stability: the frequencies, or the eigenvalues in the complex plane;
* simulate with ``series = true``: energy against time; chains: final mode energies;
* continua: mode shapes of a modes analysis, the deflection of a steady state.
"""
from __future__ import annotations

from pathlib import Path

from mechgen.errors import InputError


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise InputError("plotting needs matplotlib", key="--plot",
                         expected="matplotlib installed (pip install 'mechgen[plot]')") from exc
    return plt


def _sweep(plt, a: dict, path: Path) -> None:
    """Frequencies against the swept parameter; with stability results, growth rates in a second panel."""
    grid = a["outputs"]["grid"]
    name = next(iter(grid[0])) if grid else "parameter"
    x = [g[name] for g in grid]
    growth = a["outputs"].get("growth_rate")
    fig, axes = plt.subplots(2 if growth else 1, 1, figsize=(6, 6 if growth else 4), squeeze=False, sharex=True)
    ax = axes[0, 0]
    verdicts = a["outputs"].get("verdict") or ["stable"] * len(x)
    colours = {"stable": "k", "divergence": "tab:blue", "flutter": "tab:red", "unconverged": "tab:orange"}
    for xi, freqs, verdict in zip(x, a["outputs"].get("frequencies", []), verdicts):
        ax.plot([xi] * len(freqs), freqs, ".", color=colours.get(verdict, "k"), ms=3)
    if name == "Omega" and x and isinstance(x[0], (int, float)):
        ax.plot([min(x), max(x)], [min(x), max(x)], "r--", lw=1, label="1x (synchronous)")
        ax.legend(loc="upper left")
    ax.set_ylabel("frequency")
    ax.set_title(f"{a['name']}: frequencies vs {name}" + (" (red: flutter, blue: divergence, orange: unconverged)"
                                                          if growth else ""), fontsize=9)
    if growth:
        axes[1, 0].plot(x, growth, "o-", ms=3)
        axes[1, 0].axhline(0.0, color="0.6", lw=0.5)
        axes[1, 0].set_ylabel("growth rate max Re s")
    axes[-1, 0].set_xlabel(name)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _eigen(plt, a: dict, path: Path) -> None:
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


def _simulate(plt, a: dict, path: Path) -> bool:
    out = a["outputs"]
    if "energy_series" not in out and "mode_energies" not in out:
        return False
    fig, ax = plt.subplots(figsize=(6, 4))
    if "energy_series" in out:
        ax.plot(out["t"], out["energy_series"])
        ax.set_xlabel("t")
        ax.set_ylabel("energy")
    else:
        ax.bar(range(1, len(out["mode_energies"]) + 1), out["mode_energies"])
        ax.set_xlabel("mode k")
        ax.set_ylabel("E_k at t_end")
    ax.set_title(a["name"])
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _shapes(plt, a: dict, path: Path) -> bool:
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


def _campbell(plt, a: dict, path: Path) -> None:
    """Tracked whirl frequencies against spin speed (forward solid, backward dashed), multiples of the
    speed as excitation lines and the critical speeds where they cross."""
    out = a["outputs"]
    speeds, freqs = out["speeds"], list(zip(*out["frequencies"]))
    whirls = list(zip(*out["whirl"]))
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for k, (curve, labels) in enumerate(zip(freqs, whirls)):
        forward = labels[len(labels) // 2] == "forward"
        ax.plot(speeds, curve, "-" if forward else "--", color=f"C{k % 10}", lw=1.2,
                label=f"mode {k + 1} ({'F' if forward else 'B'})")
    top = max(max(c) for c in freqs)
    for r in sorted({c["multiple"] for c in out.get("critical_speeds", [])} or {1.0}):
        reach = min(speeds[-1], top / r)
        ax.plot([0, reach], [0, r * reach], "k:", lw=1)
        ax.annotate(f"{r:g}x", (reach, r * reach), fontsize=7)
    for c in out.get("critical_speeds", []):
        ax.plot(c["speed"], c["frequency"], "kx", ms=6)
    ax.set_xlabel(f"{out.get('parameter', 'speed')} (rad/s)")
    ax.set_ylabel("damped natural frequency (rad/s)")
    ax.set_title(f"{a['name']}: Campbell diagram (solid forward, dashed backward; x critical speeds)", fontsize=9)
    ax.legend(fontsize=7, ncol=2, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_results(results: dict, folder: Path) -> list[Path]:
    """Write one PNG per plottable analysis into ``folder``; returns the paths."""
    plt = _pyplot()
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for a in results["analyses"]:
        path = folder / f"{Path(results['scene']).stem}_{a['name']}.png"
        if a["kind"] == "sweep":
            _sweep(plt, a, path)
        elif a["kind"] == "campbell":
            _campbell(plt, a, path)
        elif a["kind"] in ("modes", "stability"):
            _eigen(plt, a, path)
            shapes = path.with_name(path.stem + "_shapes.png")
            if _shapes(plt, a, shapes):
                written.append(shapes)
        elif a["kind"] == "steady":
            if not _shapes(plt, a, path):
                continue
        elif a["kind"] == "simulate":
            if not _simulate(plt, a, path):
                continue
        else:
            continue
        written.append(path)
    return written
