"""Model facts the scene loader validates against (names only, nothing symbolic).

A :class:`ModelInfo` is what a scene run needs to know of a model before (and, when its
kernels are cached, instead of) importing it: parameter names, defaults, choices and
kinds, coordinates, outputs, fields, parts. It is JSON-able and cached by the model
file's content (:func:`model_info`):

* ``mechgen/generated/<model>/info.json`` for the built-in models (written by
  ``mechgen regen``, read-only at run time),
* else the user compile cache (kind ``info``),
* else the model is imported once and its facts are stored in the user cache.

An entry is valid when its key, ``content_key(INFO_SCHEMA, sources_digest(), sha256 of the
model file, attribute)``, equals the one of the model file now on disk; a model whose file
cannot be known before import (a module without a ``.py`` source) is imported every time.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, replace
from functools import lru_cache
from pathlib import Path

from mechgen import models
from mechgen.errors import InputError, did_you_mean

#: version of the JSON layout of a ModelInfo (part of its cache key)
INFO_SCHEMA = "model-info-6"
GENERATED = Path(__file__).resolve().parent.parent / "generated"


@dataclass(frozen=True)
class ParamInfo:
    """What a scene may set for one parameter.

    ``numeric``: may appear in expressions (not a choice, not a size); ``runtime``: a choice of
    the numerics only (Param.runtime), left out of the kernels' cache key. The bounds a scene's
    value is checked against at load time (mechgen.scene.bounds): ``positive`` (> 0),
    ``minimum`` / ``maximum`` (inclusive), ``below`` (exclusive upper bound).
    """

    default: float | str
    choices: tuple[str, ...] | None
    integer: bool
    below: float | None = None
    numeric: bool = True
    runtime: bool = False
    positive: bool = False
    minimum: float | None = None
    maximum: float | None = None
    #: the declared unit ("kg", "N/m"; "" for a nondimensional one): figures label their axes with it
    unit: str = ""


@dataclass(frozen=True)
class ModelInfo:
    """Names of a model's parameters, coordinates and outputs, and the kind of model it is.

    ``params`` is in declaration order. ``coordinates`` are the scene-visible coordinates (a
    chain's sites expanded), ``coordinates_all`` the model's own names (Model.coordinates_all).
    ``part_params`` are always free (Model.part_params); ``chain`` is ``(coordinate, sites
    parameter)`` of a lattice model.
    """

    name: str
    params: dict
    coordinates: tuple[str, ...]
    outputs: tuple[str, ...]
    continuum: bool = False
    length: str | None = None
    parts: dict | None = None
    stress_form: bool = False
    fields: tuple[str, ...] = ()
    shape_outputs: tuple[str, ...] = ()
    internals: bool = False
    chain: tuple[str, str] | None = None
    coordinates_all: tuple[str, ...] = ()
    part_params: tuple[str, ...] = ()
    #: a hybrid model's modes (mechgen.symbolic.hybrid), the initial one first; empty for a smooth model
    modes: tuple[str, ...] = ()
    file: str | None = field(default=None, compare=False)
    #: a plane continuum's fields (mechgen.symbolic.plane); empty for every other model
    plane_fields: tuple[str, ...] = ()
    #: each part kind's declared checks (Model.part): {kind: ((key, condition, expected), ...)}
    part_checks: dict = field(default_factory=dict)
    #: the canonical reference of the model (mechgen.models.resolve): what a scene's run compiles
    key: str = field(default="", compare=False)

    def units(self) -> dict[str, str]:
        """{parameter: its declared unit} for the parameters that declare one."""
        return {k: p.unit for k, p in self.params.items() if p.unit}

    def param(self, name: str) -> ParamInfo:
        """The ParamInfo of ``name`` (InputError naming the model when there is none)."""
        try:
            return self.params[name]
        except KeyError:
            raise InputError(f"model {self.name} has no parameter {name!r}{did_you_mean(name, self.params)}", key=name,
                             expected=f"one of {', '.join(self.params)}") from None

    def to_json(self) -> dict:
        """JSON form (see :func:`info_from_json`)."""
        data = asdict(self)
        data.pop("file")
        data.pop("key")
        # orders matter (free names and parts follow the declaration): pairs, not objects that sort_keys reorders
        data["params"] = [[k, v] for k, v in data["params"].items()]
        data["parts"] = None if self.parts is None else [[k, list(v)] for k, v in self.parts.items()]
        data["part_checks"] = [[k, [list(c) for c in v]] for k, v in self.part_checks.items() if v]
        return data


def declared_range(param, counts: set) -> tuple[float | None, float | None]:
    """(minimum, maximum) of a parameter: the declaration's own (``Param.minimum`` / ``maximum`` when
    it has them), and for a size at least 0, at least 1 for one that counts sites or elements
    (``counts``: a chain's sites parameter, a continuum's N)."""
    low, high = getattr(param, "minimum", None), getattr(param, "maximum", None)
    if param.size:
        floor = 1 if param.name in counts else 0
        low = floor if low is None else max(low, floor)
    return low, high


def info_of_model(model) -> ModelInfo:
    """The ModelInfo of an imported :class:`~mechgen.symbolic.model.Model`."""
    cont = model.continuum
    counts = {model.chain_spec.sites} if model.is_lattice else set()
    if cont is not None:
        counts.add("N")
    params = {p.name: ParamInfo(p.default, p.choices, p.integer, p.below, p.is_numeric, p.runtime,
                                p.positive, *declared_range(p, counts), unit=p.unit or "")
              for p in model.param_list}
    coords = model.coordinates_all
    chain = None
    if model.is_lattice:
        n = int(model.param(model.chain_spec.sites).default)
        coords = tuple(f"{model.chain_spec.coordinate}_{i + 1}" for i in range(n))
        chain = (model.chain_spec.coordinate, model.chain_spec.sites)
    return ModelInfo(model.name, params, tuple(coords), tuple(model.output_names), cont is not None,
                     cont.length if cont else None, {k: tuple(v) for k, v in model.parts.items()},
                     model.complementary_fn is not None, tuple(model.field_names),
                     tuple(o.name for o in getattr(model, "shape_outputs", ())), bool(model.internals), chain,
                     tuple(model.coordinates_all), tuple(model.part_params()), _modes(model), model.file,
                     plane_fields=tuple(model.plane_spec.fields) if model.is_plane else (),
                     part_checks=_part_checks(model))


def _part_checks(model) -> dict:
    """The model's part checks (Model.part), each condition parsed once here: ModelError naming the model file at a
    condition outside the grammar or one that names something other than the part's parameters."""
    from mechgen.errors import ModelError
    from mechgen.scene.expr import parse_condition

    out = {}
    for kind, checks in getattr(model, "part_checks", {}).items():
        for key, text, _ in checks:
            where = f"part {kind!r} check at {key!r}"
            try:
                names = parse_condition(text).names
            except InputError as exc:
                raise ModelError(f"{where}: {exc.message}", file=model.file, key="part", expected=exc.expected) from None
            unknown = [n for n in names if n not in model.parts[kind]]
            if unknown:
                raise ModelError(f"{where}: condition {text!r} names {unknown[0]!r}, not a parameter of the part",
                                 file=model.file, key="part", expected="one of: " + ", ".join(model.parts[kind]))
        if checks:
            out[kind] = tuple(tuple(c) for c in checks)
    return out


def _modes(model) -> tuple[str, ...]:
    """The modes of a hybrid model, the initial one first (empty for a smooth one)."""
    names = tuple(getattr(model, "mode_names", ()))
    initial = getattr(model, "initial_mode", None)
    return tuple([initial] + [n for n in names if n != initial]) if names else ()


def info_from_json(data: dict, *, file: str | None = None) -> ModelInfo:
    """A ModelInfo from its JSON form (tuples restored)."""
    def tup(v):
        return tuple(v) if v is not None else None

    params = {k: ParamInfo(v["default"], tup(v["choices"]), v["integer"], v["below"], v["numeric"], v["runtime"],
                           v["positive"], v["minimum"], v["maximum"], v.get("unit", ""))
              for k, v in data["params"]}
    parts = {k: tuple(v) for k, v in data["parts"]} if data.get("parts") is not None else None
    return ModelInfo(data["name"], params, tuple(data["coordinates"]), tuple(data["outputs"]), data["continuum"],
                     data["length"], parts, data["stress_form"], tuple(data["fields"]), tuple(data["shape_outputs"]),
                     data["internals"], tup(data["chain"]), tuple(data["coordinates_all"]),
                     tuple(data["part_params"]), tuple(data.get("modes", ())), file,
                     plane_fields=tuple(data.get("plane_fields", ())),
                     part_checks={k: tuple(tuple(c) for c in v) for k, v in data.get("part_checks", ())})


def info_key(source: models.ModelSource) -> str | None:
    """Cache key of a model's facts: schema, mechgen sources, the model file's bytes, the attribute (None: no file)."""
    from mechgen.codegen.cache import content_key, file_sha256, sources_digest

    if source.file is None or not Path(source.file).is_file():
        return None
    return content_key(INFO_SCHEMA, sources_digest(), file_sha256(Path(source.file)), source.attribute)


def info_document(info: ModelInfo, key: str) -> str:
    """The text of an ``info.json``: the key it is valid for and the facts (deterministic)."""
    return json.dumps({"schema": INFO_SCHEMA, "key": key, "info": info.to_json()}, indent=1, sort_keys=True) + "\n"


def _read_info(path: Path, key: str, file: str | None) -> ModelInfo | None:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        if doc.get("schema") != INFO_SCHEMA or doc.get("key") != key:
            return None
        return info_from_json(doc["info"], file=file)
    except (OSError, ValueError, KeyError, TypeError):
        return None


def cached_info(source: models.ModelSource) -> ModelInfo | None:
    """The stored facts of a model when they match its file now on disk (committed layer, then user cache)."""
    from mechgen.codegen.cache import lookup

    key = info_key(source)
    if key is None:
        return None
    file = str(source.file)
    if source.origin == "built-in":
        found = _read_info(GENERATED / source.key / "info.json", key, file)
        if found is not None:
            return found
    entry = lookup("info", key)
    return _read_info(entry / "info.json", key, file) if entry is not None else None


def source_info(source: models.ModelSource) -> ModelInfo:
    """The facts of a model: from the caches when valid, else imported once and stored in the user cache."""
    found = cached_info(source)
    if found is not None:
        return found
    info = info_of_model(source.load())
    key = info_key(source)
    if key is not None:
        from mechgen.codegen.cache import get_or_create

        text = info_document(info, key)
        get_or_create("info", key, lambda folder: (folder / "info.json").write_text(text, encoding="utf-8"))
    return info


@lru_cache(maxsize=64)
def _model_info(key: str, stamp: tuple) -> ModelInfo:
    return source_info(models.resolve(key))


def model_info(ref: str, *, base: str | Path | None = None) -> ModelInfo:
    """The :class:`ModelInfo` a model reference names (built-in name, path, module:attribute), cached.

    Memoised per process by the reference and the model file's modification stamp.
    """
    source = models.resolve(ref, base=base)
    stamp = ()
    if source.file is not None:
        try:
            st = Path(source.file).stat()
            stamp = (st.st_mtime_ns, st.st_size)
        except OSError:
            pass
    return _model_info(source.key, stamp)


def lookup_model(ref: str, base=None) -> ModelInfo | None:
    """ModelInfo of the model a scene names, or None when no model has that name.

    ``ref`` is a built-in or entry-point name, a path (relative to ``base``, the scene's folder)
    or ``package.module:attribute`` (:func:`mechgen.models.resolve`). A path or module that
    does not exist, and a model file that fails to import, raise their InputError.
    """
    try:
        source = models.resolve(ref, base=base)
    except InputError:
        if models.is_path(ref) or ":" in ref:
            raise
        return None
    return replace(model_info(source.key), key=source.key)
