"""The text summary's lines for one analysis's outputs (``mechgen run`` prints them).

A kind's ``summary`` is :func:`lines` unless it leaves more out or adds a line of its own.
"""
from __future__ import annotations

#: outputs no summary prints (time series, grids, sampled shapes)
SERIES = ("t", "energy_series", "grid", "s", "shapes")


def fmt(value, width: int = 8, depth: int = 0) -> str:
    """One line: numbers to 6 digits, lists (and objects below the top) cut at ``width`` items with their size,
    nesting below two levels only sized; an output that is an object shows all its keys."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        if depth >= 2:
            return f"[...] ({len(value)})"
        shown = ", ".join(fmt(v, width, depth + 1) for v in value[:width])
        return f"[{shown}, ...] ({len(value)})" if len(value) > width else f"[{shown}]"
    if isinstance(value, dict):
        # an object's keys are names, not samples: at the top it is shown whole, below that cut like a list
        limit = len(value) if depth == 0 else width
        if depth >= 2:
            shown = ", ".join(str(k) for k in list(value)[:limit])
        else:
            shown = ", ".join(f"{k}: {fmt(v, width, depth + 1)}" for k, v in list(value.items())[:limit])
        return "{" + shown + (f", ...}} ({len(value)})" if len(value) > limit else "}")
    return str(value)


def output_lines(outputs: dict, *, skip: tuple = (), width: int = 8) -> list[str]:
    """``    name: value`` for every output but the series and ``skip``."""
    return [f"    {key}: {fmt(value, width=width)}" for key, value in outputs.items()
            if key not in SERIES and key not in skip]


def lines(outputs: dict) -> list[str]:
    """The default summary: every output but the series, lists cut at 8 items."""
    return output_lines(outputs)
