"""A readable text summary of scene results."""
from __future__ import annotations


def _fmt(value, width: int = 8) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        shown = ", ".join(_fmt(v) for v in value[:width])
        return f"[{shown}{', ...' if len(value) > width else ''}] ({len(value)})" if len(value) > width else f"[{shown}]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_fmt(v)}" for k, v in list(value.items())[:width]) + "}"
    return str(value)


def summary(results: dict) -> str:
    """Scene, model, backend, build report and each analysis's outputs, one per line."""
    build = results.get("build", {})
    lines = [f"scene {results['scene']}: {results.get('title', '')}",
             f"model {results['model']}, backend {results['backend']}"
             f"{' (cached)' if build.get('cached') else ''}",
             "kernels: " + ", ".join(f"{k} ({v['ops']} ops)" for k, v in build.get("kernels", {}).items())]
    for a in results["analyses"]:
        lines.append(f"[{a['kind']}] {a['name']} ({a['seconds']:.3f} s)")
        for key, value in a["outputs"].items():
            if key in ("t", "energy_series", "grid") or (a["kind"] == "sweep" and key == "eigenvalues"):
                continue
            lines.append(f"    {key}: {_fmt(value, width=4 if a['kind'] == 'sweep' else 8)}")
        if a["kind"] == "sweep":
            grid = a["outputs"].get("grid", [])
            if grid:
                lines.append(f"    grid: {len(grid)} points from {grid[0]} to {grid[-1]}")
    return "\n".join(lines)
