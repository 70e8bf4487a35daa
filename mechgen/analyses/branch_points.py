"""The record of one point of an orbit branch: the continued parameter beside the orbit's outputs."""
from __future__ import annotations


def branch_point(parameter: str, value: float, outputs: dict) -> dict:
    """``{parameter: value, **outputs}``, except that an output whose name the continued parameter takes (a model
    parameter called ``amplitude``, ``period`` or ``frequency``: the stick-slip contact's forcing ``amplitude``) is
    kept as ``orbit_<name>`` rather than overwritten by the parameter's value, or overwriting it."""
    record = {parameter: float(value)}
    for key, item in outputs.items():
        record[f"orbit_{key}" if key == parameter else key] = item
    return record
