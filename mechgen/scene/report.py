"""A readable text summary of scene results (each analysis's lines come from its kind)."""
from __future__ import annotations

from mechgen.analyses.registry import get


def summary(results: dict) -> str:
    """Scene, model, backend, build report and each analysis's outputs, one per line."""
    build = results.get("build", {})
    lines = [f"scene {results['scene']}: {results.get('title', '')}",
             f"model {results['model']}, backend {results['backend']}"
             f"{' (cached)' if build.get('cached') else ''}",
             "kernels: " + ", ".join(f"{k} ({v['ops']} ops)" for k, v in build.get("kernels", {}).items())]
    for a in results["analyses"]:
        if "error" in a:
            lines.append(f"[{a['kind']}] {a['name']} FAILED: {a['error']}")
            continue
        lines.append(f"[{a['kind']}] {a['name']} ({a['seconds']:.3f} s)")
        lines += get(a["kind"]).summary(a["outputs"])
    return "\n".join(lines)
