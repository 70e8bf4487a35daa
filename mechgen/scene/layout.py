"""Scene layout of a continuum: ``[[segments]]`` (a stepped shaft) and ``[[parts]]`` (disks, bearings).

::

    [[segments]]            # uniform pieces, in order from s = 0
    length = 0.25           # m (number or expression of the scene's parameters)
    elements = 2            # finite elements in this segment
    D = 0.05                # any numeric model parameter: its value on this segment

    [[parts]]
    kind = "disk"           # a part kind the model declares (model.part)
    at = 0.25               # position s (m); a mesh vertex for finite elements
    m = 32.6                # the part's own parameters (see the model's doc)

Parameters set per segment are kept symbolic in the kernels (one kernel, many
segments); the model's length parameter becomes the sum of the segment lengths.
"""
from __future__ import annotations

from typing import Any

from mechgen.runtime.fields.mesh import Part, Segment
from mechgen.scene.values import NUMBER, evaluate, expression, fail, finite, is_number, join, listing, show, type_name

DISCRETISATION_PARAMS = ("discretisation", "N", "quadrature", "constraints")


def _number(file: str, key: str, value: object, params: dict) -> float:
    if is_number(value):
        return float(finite(file, key, value))
    if isinstance(value, str):
        return float(evaluate(file, key, expression(file, key, value), params))
    raise fail(file, key, f"value is {type_name(value)}", NUMBER)


def _tables(file: str, data: dict, name: str) -> list:
    entries = data.get(name, [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise fail(file, name, f"{name} is {type_name(entries)}", f"[[{name}]] tables")
    return entries


def _segments(file: str, data: dict, model: Any, params: dict) -> tuple[Segment, ...]:
    out = []
    length_param = getattr(model, "length", None)
    numeric = [n for n, i in model.params.items() if i.choices is None and not isinstance(i.default, str)
               and n not in DISCRETISATION_PARAMS and n != length_param and not n.startswith(_part_prefixes(model))]
    for i, table in enumerate(_tables(file, data, "segments"), 1):
        base = f"segments[{i}]"
        for required in ("length", "elements"):
            if required not in table:
                raise fail(file, join(base, required), f"missing key '{required}'",
                            "a length > 0 (m)" if required == "length" else "an integer >= 1")
        length = _number(file, f"{base}.length", table["length"], params)
        if not length > 0:
            raise fail(file, f"{base}.length", f"length {length!r} is not positive", "a length > 0")
        elements = table["elements"]
        if not (isinstance(elements, int) and not isinstance(elements, bool)) or not 1 <= elements <= 100_000:
            raise fail(file, f"{base}.elements", f"elements is {show(elements)}", "an integer from 1 to 100000")
        values = {}
        for name, value in table.items():
            if name in ("length", "elements"):
                continue
            if name not in numeric:
                raise fail(file, join(base, name), f"unknown segment key {show(name)}",
                            "length, elements or a numeric model parameter: " + listing(numeric))
            values[name] = _number(file, join(base, name), value, params)
        out.append(Segment(length, elements, values))
    return tuple(out)


def _part_prefixes(model: Any) -> tuple[str, ...]:
    return tuple(f"{kind}_" for kind in getattr(model, "parts", {})) or ("\0",)


def _parts(file: str, data: dict, model: Any, params: dict) -> tuple[Part, ...]:
    kinds = getattr(model, "parts", {})
    out = []
    for i, table in enumerate(_tables(file, data, "parts"), 1):
        base = f"parts[{i}]"
        kind = table.get("kind")
        if kind not in kinds:
            raise fail(file, f"{base}.kind", f"unknown part kind {show(kind)} for model '{model.name}'",
                        "one of: " + listing(sorted(kinds)))
        if "at" not in table:
            raise fail(file, f"{base}.at", "missing key 'at'", "the part's position s (m)")
        at = _number(file, f"{base}.at", table["at"], params)
        values = {}
        for name, value in table.items():
            if name in ("kind", "at"):
                continue
            if name not in kinds[kind]:
                raise fail(file, join(base, name), f"unknown key {show(name)} for a {kind}",
                            "kind, at or a parameter of the part: " + listing(list(kinds[kind])))
            values[name] = _number(file, join(base, name), value, params)
        out.append(Part(kind, at, values))
    return tuple(out)


def load_layout(file: str, data: dict, model: Any, params: dict) -> tuple[tuple[Segment, ...], tuple[Part, ...]]:
    """Validated segments and parts of a scene (both empty when it has none)."""
    if ("segments" in data or "parts" in data) and not getattr(model, "continuum", False):
        key = "segments" if "segments" in data else "parts"
        raise fail(file, key, f"model '{model.name}' is not a continuum", "segments and parts only for continua")
    return _segments(file, data, model, params), _parts(file, data, model, params)
