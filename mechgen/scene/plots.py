"""``--plot DIR``: PNG figures of scene results (matplotlib, the ``plot`` extra).

* sweep of modes/stability: frequencies (and growth rates) against the swept parameter
  (a Campbell diagram when the parameter is a spin speed);
* modes/stability: the frequencies, or the eigenvalues in the complex plane;
* simulate with ``series = true``: energy against time; chains: final mode energies;
* continua: mode shapes of a modes analysis, the deflection of a steady state, and for a steady state
  of a continuum with several fields its curve (the first field against the last: a balloon's x
  against z);
* continuation: the branch diagram (an output against the parameter, points coloured by the
  stability verdict, shape outputs such as the loop count written where they change, folds,
  stability changes and the ``at`` crossings marked), the shapes of the ``at`` points (first field
  against the last), with ``eigenvalues`` their real and imaginary parts along the branch, and the
  lowest frequencies against the parameter (a log axis when it spans decades: a beta sweep).
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


VERDICT_COLOURS = {"stable": "k", "divergence": "tab:blue", "flutter": "tab:red", "unconverged": "tab:orange"}
_POINT_KEYS = ("start", "verdict", "frequencies", "eigenvalues")


def _branch_axes(out: dict) -> tuple[str, str, list[str]]:
    """(parameter, the output drawn against it, the shape outputs written on the diagram) of a continuation:
    the output of ``at``, else the minimized one, else the first number reported per point."""
    points = out["branch"]
    name = out.get("parameter") or next(iter(points[0]))
    at = [k[3:] for k in out if k.startswith("at_") and not k.endswith("_shapes")]
    minimized = [k[:-4] for k in out if k.endswith("_min") and f"{name}_at_{k[:-4]}_min" in out]
    numeric = [k for k, v in points[0].items() if k not in _POINT_KEYS and k != name and isinstance(v, float)]
    return name, (at or minimized or numeric)[0], list(out.get("shape_outputs", []))


def _families(points: list) -> list[list[dict]]:
    """The branch's points split by start (one list per branch, in order)."""
    groups: dict = {}
    for p in points:
        groups.setdefault(p.get("start"), []).append(p)
    return list(groups.values())


def _branch(plt, a: dict, path: Path) -> bool:
    """p_e (or another output) against the parameter: verdict colours, loop counts, folds, changes, crossings."""
    out = a["outputs"]
    if not out.get("branch"):
        return False
    name, output, shapes = _branch_axes(out)
    fig, ax = plt.subplots(figsize=(7, 5))
    for family in _families(out["branch"]):
        lam = [p[name] for p in family]
        val = [p.get(output, float("nan")) for p in family]
        ax.plot(lam, val, "-", color="0.75", lw=0.8, zorder=1)
        for verdict in VERDICT_COLOURS:
            sel = [i for i, p in enumerate(family) if p.get("verdict", "stable") == verdict]
            if sel:
                ax.plot([lam[i] for i in sel], [val[i] for i in sel], ".", ms=3, color=VERDICT_COLOURS[verdict],
                        zorder=2)
        for key in shapes:
            last = None
            for i, p in enumerate(family):
                if p.get(key) != last:
                    last = p.get(key)
                    ax.annotate(f"{key} {last:g}", (lam[i], val[i]), fontsize=7, xytext=(4, 4),
                                textcoords="offset points", color="tab:green")
    for fold in out.get("folds", []):
        ax.plot(fold[name], fold.get(output, float("nan")), "x", color="tab:purple", ms=7)
    for change in out.get("stability_changes", []):
        ax.plot(change[name], change.get(output, float("nan")), "d", color="tab:orange", ms=6, mfc="none")
    for key in [k[3:] for k in out if k.startswith("at_") and not k.endswith("_shapes")]:
        for p in out[f"at_{key}"]:
            ax.plot(p[name], p[key], "o", ms=8, mfc="none", color="tab:green")
    handles = [plt.Line2D([], [], ls="", marker=".", color=c, label=v) for v, c in VERDICT_COLOURS.items()]
    handles += [plt.Line2D([], [], ls="", marker="x", color="tab:purple", label="fold"),
                plt.Line2D([], [], ls="", marker="d", mfc="none", color="tab:orange", label="stability change"),
                plt.Line2D([], [], ls="", marker="o", mfc="none", color="tab:green", label="at")]
    ax.legend(handles=handles, fontsize=7, loc="best")
    ax.set_xlabel(name)
    ax.set_ylabel(output)
    ax.set_title(f"{a['name']}: {output} against {name}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _curves(plt, title: str, curves: list[tuple[str, dict]], path: Path) -> bool:
    """Curves of continua (first field against the last: a balloon's x against z), one panel each."""
    curves = [(label, c) for label, c in curves if len(c) >= 2]
    if not curves:
        return False
    cols = min(len(curves), 4)
    rows = (len(curves) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(2.6 * cols, 3.6 * rows), squeeze=False)
    for ax, (label, fields) in zip(axes.ravel(), curves):
        first, last = list(fields)[0], list(fields)[-1]
        ax.plot(fields[first], fields[last], "-")
        ax.axvline(0.0, color="0.7", lw=0.5)
        ax.set_xlabel(first)
        ax.set_ylabel(last)
        ax.set_title(label, fontsize=8)
    for ax in axes.ravel()[len(curves):]:
        ax.axis("off")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _eigenvalues_along(plt, a: dict, path: Path, count: int = 4) -> bool:
    """Real and imaginary parts of the eigenvalues with the smallest |Im| (Im >= 0) at every branch point."""
    points = a["outputs"]["branch"]
    if not points or "eigenvalues" not in points[0]:
        return False
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for i, p in enumerate(points):
        ev = sorted((e for e in p["eigenvalues"] if e[1] >= 0), key=lambda e: (abs(e[1]), -e[0]))[:count]
        colour = VERDICT_COLOURS.get(p.get("verdict"), "k")
        top.plot([i] * len(ev), [e[0] for e in ev], ".", ms=3, color=colour)
        bottom.plot([i] * len(ev), [e[1] for e in ev], ".", ms=3, color=colour)
    for i in range(len(points) - 1):
        if points[i].get("verdict") != points[i + 1].get("verdict"):
            for ax in (top, bottom):
                ax.axvline(i + 0.5, color="0.6", lw=0.6, ls="--")
    name = a["outputs"].get("parameter", "parameter")
    ticks = list(range(0, len(points), max(1, len(points) // 8)))
    bottom.set_xticks(ticks, [f"{points[i][name]:.3g}" for i in ticks])
    top.axhline(0.0, color="0.6", lw=0.5)
    top.set_ylabel("Re mu")
    bottom.set_ylabel("Im mu")
    bottom.set_xlabel(f"branch points in order ({name} marked)")
    top.set_title(f"{a['name']}: the {count} eigenvalues with the smallest Im >= 0 (colour: verdict)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _frequencies_along(plt, a: dict, path: Path) -> bool:
    """The lowest frequencies of every branch point against the parameter (log axis over decades)."""
    out = a["outputs"]
    points = [p for p in out.get("branch", []) if p.get("frequencies")]
    if not points:
        return False
    name = out.get("parameter") or next(iter(points[0]))
    lam = [p[name] for p in points]
    fig, ax = plt.subplots(figsize=(7, 5))
    for k in range(max(len(p["frequencies"]) for p in points)):
        ax.plot(lam, [p["frequencies"][k] if k < len(p["frequencies"]) else float("nan") for p in points], "-",
                lw=1.0)
    if min(lam) > 0 and max(lam) / min(lam) > 100:
        ax.set_xscale("log")
    ax.set_xlabel(name)
    ax.set_ylabel("frequency")
    ax.set_title(f"{a['name']}: the lowest frequencies along the branch", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _continuation(plt, a: dict, path: Path) -> list[Path]:
    written = [path] if _branch(plt, a, path) else []
    out = a["outputs"]
    name = out.get("parameter", "parameter")
    for key in [k[3:] for k in out if k.startswith("at_") and not k.endswith("_shapes")]:
        labels = [f"{name} = {p[name]:.4g}" + (f", loops {p['loops']:g}" if "loops" in p else "")
                  + (f", {p['verdict']}" if "verdict" in p else "") for p in out[f"at_{key}"]]
        shapes = path.with_name(f"{path.stem}_at_{key}.png")
        if _curves(plt, f"{a['name']}: steady states at {key} = {out[f'at_{key}'][0][key]:.4g}" if labels else "",
                   list(zip(labels, out.get(f"at_{key}_shapes", []))), shapes):
            written.append(shapes)
    eig = path.with_name(path.stem + "_eigenvalues.png")
    if _eigenvalues_along(plt, a, eig):
        written.append(eig)
    freq = path.with_name(path.stem + "_frequencies.png")
    if _frequencies_along(plt, a, freq):
        written.append(freq)
    return written


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
        elif a["kind"] == "continuation":
            written += _continuation(plt, a, path)
            continue
        elif a["kind"] == "steady":
            if not _shapes(plt, a, path):
                continue
            deflection = a["outputs"].get("deflection")
            curve = path.with_name(path.stem + "_curve.png")
            if isinstance(deflection, dict) and len(deflection) >= 2 and isinstance(
                    next(iter(deflection.values()))[0], float) and _curves(plt, a["name"], [("", deflection)], curve):
                written.append(curve)
        elif a["kind"] == "simulate":
            if not _simulate(plt, a, path):
                continue
        else:
            continue
        written.append(path)
    return written
