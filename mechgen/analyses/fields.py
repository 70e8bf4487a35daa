"""A continuum's reduced states sampled as fields along s (mode shapes, a deflection), as the outputs report them."""
from __future__ import annotations

import numpy as np


def field_shapes(system, columns: np.ndarray, name: str, samples: int = 101) -> dict:
    """Fields of each column of reduced states on an even grid: {"s": [...], name: {field: curves}}.

    Mode shapes ("shapes") are scaled to a largest |value| of 1 over all fields, that
    value positive; a deflection keeps its units (one curve per field).
    """
    s = np.linspace(0.0, system.disc.length, samples)
    curves: dict = {f: [] for f in system.disc.fields}
    columns = np.asarray(columns)
    every = system.field_values(columns, s) if columns.shape[1] else {}  # the rows tabulated once for all columns
    for j in range(columns.shape[1]):
        values = {f: v[:, j] for f, v in every.items()}
        if name == "shapes":
            stacked = np.concatenate(list(values.values()))
            peak = stacked[np.argmax(np.abs(stacked))]
            values = {f: v / peak if peak else v for f, v in values.items()}
        for f, v in values.items():
            curves[f].append([float(x) for x in v])
    if name == "deflection":
        curves = {f: c[0] for f, c in curves.items()}
    return {"s": [float(v) for v in s], name: curves}
