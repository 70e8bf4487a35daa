"""The figures of ``phase_boundary`` and ``phase_kinetics`` (mechgen run SCENE --plot DIR).

* ``phase_boundary``: the stress-strain law sigma(gamma) with the Maxwell line sigma = sigma_M between the phase
  strains and the two equal areas between them shaded (above and below the line); beside it the stored energy
  W(gamma) with its common tangent W(gamma_1) + sigma_M (gamma - gamma_1), the same rule seen on W (the tangent
  touches W at both phase strains). A convex law: the law alone, titled so.
* ``phase_kinetics``: the stress-elongation hysteresis loop (loading and unloading drawn apart, the Maxwell stress
  dashed), and the boundary position s(t) with the events marked.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np


def _save(plt, fig, title: str, path: Path) -> list[Path]:
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


def law_figure(plt, a: dict, path: Path) -> list[Path]:
    """sigma(gamma) with the Maxwell line and the equal areas shaded; W(gamma) with the common tangent."""
    out = a["outputs"]
    g, s, w = (np.asarray(out["law"][k], float) for k in ("strain", "stress", "energy_density"))
    if not out["phase_boundary"]:
        fig, ax = plt.subplots(figsize=(5, 4))
        ax.plot(g, s)
        ax.set_xlabel("strain gamma")
        ax.set_ylabel("stress sigma")
        return _save(plt, fig, f"{a['name']}: stress-strain law (convex stored energy: no phase boundary)", path)
    sigma_m = out["maxwell_stress"]
    g1, g2 = out["phase_strains"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.plot(g, s, label="sigma(gamma)")
    left.plot([g1, g2], [sigma_m, sigma_m], "k--", lw=1, label=f"Maxwell stress {sigma_m:.4g}")
    inside = (g >= g1) & (g <= g2)
    left.fill_between(g[inside], s[inside], sigma_m, where=s[inside] >= sigma_m, alpha=0.3, color="C1",
                      label="equal areas")
    left.fill_between(g[inside], s[inside], sigma_m, where=s[inside] <= sigma_m, alpha=0.3, color="C1")
    left.plot([g1, g2], [sigma_m, sigma_m], "ko", ms=4)
    left.set_xlabel("strain gamma")
    left.set_ylabel("stress sigma")
    left.legend(fontsize=8)
    right.plot(g, w, label="W(gamma)")
    w1 = float(np.interp(g1, g, w))
    right.plot(g, w1 + sigma_m * (g - g1), "k--", lw=1, label="common tangent (slope sigma_M)")
    right.set_xlabel("strain gamma")
    right.set_ylabel("stored energy W")
    right.set_ylim(min(w.min(), (w1 + sigma_m * (g - g1)).min()), w.max())
    right.legend(fontsize=8)
    return _save(plt, fig, f"{a['name']}: Maxwell stress by equal areas, phase strains {g1:.4g} and {g2:.4g}", path)


def kinetics_figure(plt, a: dict, path: Path) -> list[Path]:
    """The stress-elongation loop (loading, unloading) and s(t) with the events."""
    out = a["outputs"]
    t, s = np.asarray(out["t"], float), np.asarray(out["s"], float)
    delta, sigma = np.asarray(out["elongation"], float), np.asarray(out["stress"], float)
    turn = int(np.argmax(delta))
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.plot(delta[:turn + 1], sigma[:turn + 1], label="loading")
    left.plot(delta[turn:], sigma[turn:], label="unloading")
    left.axhline(out["maxwell_stress"], color="k", lw=1, ls="--", label="Maxwell stress")
    left.set_xlabel("elongation delta")
    left.set_ylabel("stress sigma")
    left.legend(fontsize=8)
    right.plot(t, s)
    for event in out["events"]:
        if event["guard"] != "turn":
            right.axvline(event["t"], color="0.7", lw=0.8)
            right.annotate(event["guard"], (event["t"], 0.5 * max(float(s.max()), 1e-300)), rotation=90, fontsize=7)
    right.set_xlabel("time t")
    right.set_ylabel("boundary position s")
    title = (f"{a['name']}: hysteresis loop (dissipated {out['dissipated']:.4g}, residual "
             f"{out['dissipation_residual']:.1e}) and the boundary's position")
    return _save(plt, fig, title, path)
