"""The figures of a ``response`` (``--plot DIR``, ``Result.plot``): a Bode plot and the orbits.

The Bode plot ``<name>.png``: the amplitude |X_k| (log scale) and the phase arg X_k (degrees, unwrapped
along the frequencies) of each output coordinate against the driving frequency or speed, in the analysis's
``speed_unit``; coordinates that do not move at any frequency are left out (the title says how many), and a
zero amplitude (at speed 0, an unbalance's force is zero) is a gap in the log-scale curve. The orbit
figure ``<name>_orbits.png`` (when the response reports orbits): one panel per frequency of ``orbit_at``, each
pair's ellipse x = Re(X_x e^{i theta}), y = Re(X_y e^{i theta}) over theta in [0, 2 pi], a dot at theta = 0
(t = 0) and the whirl label.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: a coordinate whose largest amplitude is at most this times the largest of all is drawn as at rest
AT_REST = 1e-12


def plot(plt, entry: dict, path: Path) -> list[Path]:
    """The Bode plot, and the orbit figure when there are orbits; the paths written."""
    written = [bode(plt, entry, Path(path))]
    if entry["outputs"].get("orbit"):
        written.append(orbit_figure(plt, entry, Path(path).with_name(Path(path).stem + "_orbits.png")))
    return written


def _axis_label(out: dict) -> str:
    unit = out.get("speed_unit", "rad/s")
    what = "spin speed" if out.get("forcing") == "unbalance" else "driving frequency"
    return f"{what} ({unit})"


def _axis(out: dict) -> list[float]:
    return out.get("omega_in_unit", out["omega"])


def bode(plt, entry: dict, path: Path) -> Path:
    """Amplitude (log) and phase (degrees) against frequency or speed, one curve per moving coordinate."""
    out = entry["outputs"]
    x = _axis(out)
    top = max((max(a) for a in out["amplitude"].values()), default=0.0)
    moving = [n for n, a in out["amplitude"].items() if max(a) > AT_REST * top]
    fig, (amp, phase) = plt.subplots(2, 1, figsize=(6.5, 5.5), sharex=True)
    for k, name in enumerate(moving):
        a = np.asarray(out["amplitude"][name], dtype=float)
        seen = a > AT_REST * top  # a zero amplitude has no phase: a gap in both curves
        ph = np.full(len(a), np.nan)
        ph[seen] = np.rad2deg(np.unwrap(np.asarray(out["phase"][name])[seen]))
        amp.semilogy(x, np.where(seen, a, np.nan), color=f"C{k % 10}", label=name)
        phase.plot(x, ph, color=f"C{k % 10}", label=name)
    amp.set_ylabel(f"|H| (per unit force at {out['input']})" if out.get("input") else "|X| (coordinate units)")
    phase.set_ylabel("phase (deg)")
    phase.set_xlabel(_axis_label(out))
    rest = len(out["amplitude"]) - len(moving)
    note = f"; {rest} coordinate(s) at rest left out" if rest else ""
    amp.set_title(f"{entry['name']}: Bode plot ({out.get('forcing', 'input')}{note})", fontsize=9)
    if len(moving) > 1:
        amp.legend(fontsize=8)
        phase.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _complex(out: dict, name: str, i: int) -> complex:
    return out["amplitude"][name][i] * np.exp(1j * out["phase"][name][i])


def orbit_figure(plt, entry: dict, path: Path) -> Path:
    """One panel per frequency of ``orbit_at``: each pair's orbit ellipse (equal axes), the point at t = 0."""
    out = entry["outputs"]
    omega, shown = np.asarray(out["omega"]), _axis(out)
    picks = [int(np.argmin(np.abs(omega - w))) for w in out["orbit_at"]]
    pairs = [p for p in out["orbit"] if all(c in out["amplitude"] for c in p.split(","))]
    theta = np.linspace(0.0, 2.0 * np.pi, 181)
    cols = 2 if len(picks) == 4 else min(len(picks), 3)
    rows = (len(picks) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.1 * rows + 0.5), squeeze=False)
    for ax, i in zip(axes.flat, picks):
        for k, pair in enumerate(pairs):
            cx, cy = pair.split(",")
            X, Y = _complex(out, cx, i), _complex(out, cy, i)
            whirl = out["orbit"][pair]["whirl"][i]
            ax.plot((X * np.exp(1j * theta)).real, (Y * np.exp(1j * theta)).real, color=f"C{k % 10}",
                    label=f"{cy} vs {cx}: {whirl}")
            ax.plot([X.real], [Y.real], "o", color=f"C{k % 10}", ms=3)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{shown[i]:.4g} {out.get('speed_unit', 'rad/s')}", fontsize=8)
        ax.set_xlabel(", ".join(p.split(",")[0] for p in pairs), fontsize=8)
        ax.set_ylabel(", ".join(p.split(",")[1] for p in pairs), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6, loc="upper right")
    for ax in list(axes.flat)[len(picks):]:
        ax.set_visible(False)
    fig.suptitle(f"{entry['name']}: orbits (dot: t = 0)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
