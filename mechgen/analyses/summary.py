"""The text summary's lines for one analysis's outputs (``mechgen run`` prints them).

A kind's ``summary`` is :func:`lines` unless it leaves more out or adds a line of its own.
"""
from __future__ import annotations

#: outputs no summary prints (time series, grids, sampled shapes)
SERIES = ("t", "energy_series", "grid", "s", "shapes")


def fmt(value, width: int = 8, depth: int = 0) -> str:
    """One line: numbers to 6 digits, lists cut at ``width`` items, nesting below two levels only sized."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        if depth >= 2:
            return f"[...] ({len(value)})"
        shown = ", ".join(fmt(v, width, depth + 1) for v in value[:width])
        return f"[{shown}, ...] ({len(value)})" if len(value) > width else f"[{shown}]"
    if isinstance(value, dict):
        if depth >= 2:
            return "{" + ", ".join(str(k) for k in list(value)[:width]) + "}"
        return "{" + ", ".join(f"{k}: {fmt(v, width, depth + 1)}" for k, v in list(value.items())[:width]) + "}"
    return str(value)


def output_lines(outputs: dict, *, skip: tuple = (), width: int = 8) -> list[str]:
    """``    name: value`` for every output but the series and ``skip``."""
    return [f"    {key}: {fmt(value, width=width)}" for key, value in outputs.items()
            if key not in SERIES and key not in skip]


def lines(outputs: dict) -> list[str]:
    """The default summary: every output but the series, lists cut at 8 items."""
    return output_lines(outputs)
