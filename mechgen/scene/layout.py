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
from mechgen.scene.bounds import LIMITS, check_value
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
            check_value(file, join(base, name), name, model.params[name], values[name], LIMITS)
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
        if not isinstance(kind, str):
            what = "missing key 'kind'" if kind is None else f"kind is {type_name(kind)}, not a string"
            raise fail(file, f"{base}.kind", what, "a string, one of: " + listing(sorted(kinds)))
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
            full = f"{kind}_{name}"
            if full in model.params:
                check_value(file, join(base, name), name, model.params[full], values[name], LIMITS)
        check_part(file, base, model, kind, values, params)
        out.append(Part(kind, at, values))
    return tuple(out)


def check_part(file: str | None, base: str, model: Any, kind: str, values: dict, params: dict) -> None:
    """The part kind's declared checks (Model.part's ``checks``, in the model's facts) on one part's values, what the
    part leaves out being the scene's ``<kind>_<name>`` in ``params`` or the declared default: the first check that
    fails is refused (exit 2) at ``<base>.<key>``, naming the values it compared."""
    checks = (getattr(model, "part_checks", None) or {}).get(kind, ())
    if not checks:
        return
    from mechgen.scene.expr import parse_condition

    full = {}
    for n in model.parts[kind]:
        full[n] = float(values[n] if n in values else params.get(f"{kind}_{n}", model.params[f"{kind}_{n}"].default))
    for key, text, expected in checks:
        condition = parse_condition(text, file=file, key=join(base, key))
        if not condition.holds(full):
            shown = ", ".join(f"{n} = {full[n]:g}" for n in condition.names)
            raise fail(file, join(base, key), f"a {kind} with {shown} fails the model's check {text!r}", expected)


def load_layout(file: str, data: dict, model: Any, params: dict) -> tuple[tuple[Segment, ...], tuple[Part, ...]]:
    """Validated segments and parts of a scene (both empty when it has none)."""
    if ("segments" in data or "parts" in data) and not getattr(model, "continuum", False):
        key = "segments" if "segments" in data else "parts"
        raise fail(file, key, f"model '{model.name}' is not a continuum", "segments and parts only for continua")
    return _segments(file, data, model, params), _parts(file, data, model, params)


# --------------------------------------------------------------------------- load-time checks of a layout

def check_layout(file: str, data: dict, model: Any, params: dict, segments: tuple, parts: tuple,
                 written: dict) -> None:
    """What the mesh and the ``--set`` flags must agree with, checked before anything is compiled:
    segments need finite elements, every part sits on a mesh vertex inside the domain, and no
    ``--set`` names a value a segment or part table sets (the table's value would win)."""
    if not getattr(model, "continuum", False):
        return
    _check_overrides(file, model, segments, parts, written)
    if not segments and not parts:
        return
    from mechgen.runtime.fields.discretise import ELEMENTS, GLOBAL

    kind = params.get("discretisation")
    if kind in GLOBAL:
        if segments:
            raise fail(file, "segments", f"segments need finite elements; discretisation = {show(kind)} is a "
                       "global basis", "discretisation = one of: " + listing(list(ELEMENTS)))
        return
    _check_vertices(file, model, params, segments, parts)


def _check_overrides(file: str, model: Any, segments: tuple, parts: tuple, written: dict) -> None:
    """Refuse ``--set NAME=value`` where a [[segments]] or [[parts]] table sets NAME (docs/guide.md: tables win
    over [params] and --set, so the flag would be silently ignored)."""
    length = getattr(model, "length", None)
    for name, (_, key) in written.items():
        if not key.startswith("--set"):
            continue
        places = [f"segments[{i}].{name}" for i, seg in enumerate(segments, 1) if name in seg.values]
        for i, piece in enumerate(parts, 1):
            short = name[len(piece.kind) + 1:] if name.startswith(f"{piece.kind}_") else None
            if short is not None and short in piece.values:
                places.append(f"parts[{i}].{short}")
        if name == length and segments:
            places = [f"segments[{i}].length" for i in range(1, len(segments) + 1)]
            why = f"the length {name} is the sum of the segment lengths"
        else:
            why = f"the scene's tables set {name} themselves"
        if places:
            raise fail(None, key, f"this value would be ignored: {why} ({', '.join(places)} in {file})",
                       f"a parameter no table of the scene sets; change {places[0]} in {file} instead")


def _check_vertices(file: str, model: Any, params: dict, segments: tuple, parts: tuple) -> None:
    """Each part at a mesh vertex (finite elements): reported at ``parts[i].at`` with a layout that
    would put a vertex there (the mesh rule of mechgen.runtime.fields.mesh.build_mesh)."""
    import numpy as np

    from mechgen.runtime.fields.mesh import Layout, build_mesh

    size = int(params.get("N", 1))
    length = sum(seg.length for seg in segments) if segments else float(params[model.length])
    if not segments and size > 10_000_000:
        return  # bounds.check_params refused it already unless the limit was raised: the runtime checks
    nodes = build_mesh(Layout(segments), size, length).nodes
    for i, piece in enumerate(parts, 1):
        key = f"parts[{i}].at"
        if not -1e-12 * length <= piece.at <= length * (1 + 1e-12):
            raise fail(file, key, f"the {piece.kind} at s = {piece.at:g} lies outside the domain [0, {length:g}]",
                       f"a position from 0 to {length:g} (m)")
        k = int(np.argmin(np.abs(nodes - piece.at)))
        if abs(nodes[k] - piece.at) <= 1e-9 * length:
            continue
        near = ", ".join(f"{x:g}" for x in nodes[max(k - 1, 0):k + 2])
        raise fail(file, key, f"the {piece.kind} at s = {piece.at:g} is not at a mesh vertex (nearest "
                   f"vertices: {near}); parts sit on element boundaries",
                   _vertex_fix(segments, size, length, piece.at, [p.at for p in parts]))


def _vertex_fix(segments: tuple, size: int, length: float, at: float, every: list) -> str:
    """What puts a vertex at s = ``at``: two segments split there, or (no segments) an N whose uniform
    mesh has a vertex at every part position in ``every``."""
    def split(seg_length: float, elements: int, offset: float, extra: str) -> str:
        first = min(max(1, round(elements * offset / seg_length)), max(1, elements - 1))
        return (f"[[segments]] length = {offset:g}, elements = {first}{extra} and [[segments]] length = "
                f"{seg_length - offset:g}, elements = {max(1, elements - first)}{extra}")

    if not segments:
        text = "a segment boundary there: " + split(length, size, at, "")
        def fits(n: int) -> bool:
            return all(abs(x * n / length - round(x * n / length)) <= 1e-9 * n for x in every)

        better = next((n for n in range(size, min(4 * size, size + 10_000) + 1) if fits(n)), None)
        return text + (f", or N = {better}" if better is not None else "")
    start = 0.0
    for j, seg in enumerate(segments, 1):
        if start <= at <= start + seg.length:
            extra = "".join(f", {k} = {v:g}" for k, v in seg.values.items())
            return f"a segment boundary there: replace segments[{j}] by " + split(seg.length, seg.elements,
                                                                                   at - start, extra)
        start += seg.length
    return "a segment boundary there"
