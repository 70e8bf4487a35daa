"""A readable text summary of scene results."""
from __future__ import annotations


def _fmt(value, width: int = 8, depth: int = 0) -> str:
    """One line: numbers to 6 digits, lists cut at ``width`` items, nesting below two levels only sized."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        if depth >= 2:
            return f"[...] ({len(value)})"
        shown = ", ".join(_fmt(v, width, depth + 1) for v in value[:width])
        return f"[{shown}{', ...' if len(value) > width else ''}] ({len(value)})" if len(value) > width else f"[{shown}]"
    if isinstance(value, dict):
        if depth >= 2:
            return "{" + ", ".join(str(k) for k in list(value)[:width]) + "}"
        return "{" + ", ".join(f"{k}: {_fmt(v, width, depth + 1)}" for k, v in list(value.items())[:width]) + "}"
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
            if key in ("t", "energy_series", "grid", "s", "shapes") or (a["kind"] in ("sweep", "campbell")
                                                                      and key in ("eigenvalues", "log_dec")):
                continue
            lines.append(f"    {key}: {_fmt(value, width=4 if a['kind'] == 'sweep' else 8)}")
        if a["kind"] == "sweep":
            grid = a["outputs"].get("grid", [])
            if grid:
                lines.append(f"    grid: {len(grid)} points from {grid[0]} to {grid[-1]}")
    return "\n".join(lines)
