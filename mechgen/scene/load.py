"""Loading and validating scene files (TOML) into a frozen :class:`Scene`.

A scene names a model, sets its parameters (numbers, whitelisted expression
strings, or choice strings), picks active coordinates and lists analyses. The
loader checks everything against a :class:`ModelInfo` (names only, so it does
not depend on the symbolic model code) and raises
:class:`~mechgen.errors.SceneError` for the first problem, naming the file,
the dotted key (``params.Omega``, ``analysis[2].kind``; analysis indices and
list positions are 1-based) and what would have been accepted.

No user text is evaluated: expressions go through :mod:`mechgen.scene.expr`,
names are checked against the model or :func:`~mechgen.scene.expr.is_identifier`.
"""
from __future__ import annotations

import copy
import itertools
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Protocol, Sequence

import numpy as np

try:
    import tomllib
except ImportError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from mechgen.errors import InputError, SceneError
from mechgen.scene.expr import CONSTANTS, Expression, is_identifier, parse_expression

KINDS = ("modes", "stability", "steady", "simulate", "sweep", "campbell", "continuation")
STEADY_METHODS = ("newton", "shooting", "multiple_shooting", "collocation")
BACKENDS = ("c", "numpy", "casadi")
METHODS = ("BDF", "Radau", "LSODA", "RK45", "DOP853", "leapfrog")
TOP_KEYS = ("title", "model", "backend", "free", "params", "coordinates", "analysis", "segments", "parts")
MAX_SCENE_BYTES = 10 * 1024 * 1024
MAX_GRID = 1_000_000
MAX_TITLE = 500
IDENTIFIER_RULE = ("an identifier: ASCII letters, digits and underscores, not starting with a digit or '__', "
                   "at most 64 characters, not a Python keyword")
NUMBER = "a number or an expression string"


class ParamInfo(Protocol):
    """What the loader needs to know about one model parameter."""

    default: float | str
    choices: tuple[str, ...] | None
    integer: bool


class ModelInfo(Protocol):
    """Names of a model's parameters, coordinates and outputs."""

    name: str
    params: Mapping[str, ParamInfo]
    coordinates: tuple[str, ...]
    outputs: tuple[str, ...]


@dataclass(frozen=True)
class AnalysisSpec:
    """One validated analysis: defaults filled, expressions evaluated to floats.

    For ``sweep``, ``options["analysis"]`` is the inner :class:`AnalysisSpec`
    (named like its parent), ``options["over"]`` maps each swept parameter to
    its list of values and ``options["grid"]`` is the cartesian product of
    ``over`` (first parameter outermost) as a list of dicts.
    """

    name: str
    kind: str
    options: Mapping[str, Any]


@dataclass(frozen=True)
class Scene:
    """A validated scene; ``params`` holds a value for every model parameter."""

    path: str
    title: str
    model: str
    backend: str
    params: Mapping[str, float | int | str]
    free: tuple[str, ...]
    active: tuple[str, ...] | None
    analyses: tuple[AnalysisSpec, ...]
    segments: tuple = ()
    parts: tuple = ()
    #: the canonical reference of the model (a built-in name, an absolute file path, module:attribute)
    source: str = ""


@dataclass
class _Ctx:
    """Working state while validating analyses."""

    file: str
    model: ModelInfo
    params: dict[str, float | int | str]
    depends: dict[str, tuple[str, ...]]
    coordinates: tuple[str, ...]
    active: tuple[str, ...] | None
    all_names: tuple[str, ...] = ()
    earlier: dict[str, str] = field(default_factory=dict)
    current: str = ""
    swept: tuple[str, ...] = ()


# --------------------------------------------------------------------------- helpers

_PLAIN_KEY = re.compile(r"[A-Za-z0-9_\-]{1,64}")


def _part(name: object) -> str:
    """A key segment safe to print: plain names as is, anything else JSON-quoted and shortened."""
    text = str(name)
    if _PLAIN_KEY.fullmatch(text):
        return text
    quoted = json.dumps(text)
    return quoted if len(quoted) <= 40 else quoted[:36] + '..."'


def _show(value: object) -> str:
    """A short single-line rendering of a user value for messages."""
    text = repr(value)
    return text if len(text) <= 60 else text[:56] + "..."


def _join(key: str | None, name: object) -> str:
    return f"{key}.{_part(name)}" if key else _part(name)


def _fail(file: str | None, key: str | None, message: str, expected: str | None = None) -> SceneError:
    return SceneError(message, file=file, key=key, expected=expected)


def _listing(names: Sequence[str]) -> str:
    return ", ".join(names) if names else "(none)"


def _type_name(value: object) -> str:
    return {bool: "a boolean", int: "an integer", float: "a float", str: "a string", list: "an array",
            dict: "a table"}.get(type(value), type(value).__name__)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _finite(file: str | None, key: str, value: int | float) -> float | int:
    if isinstance(value, float) and not math.isfinite(value):
        raise _fail(file, key, f"value {value} is not finite", "a finite number")
    return value


def _expression(file: str | None, key: str, text: str) -> Expression:
    try:
        return parse_expression(text, file=file, key=key)
    except SceneError:
        raise
    except InputError as exc:
        raise _fail(file, key, exc.message, exc.expected) from None


def _evaluate(file: str | None, key: str, expr: Expression, values: Mapping[str, Any]) -> float:
    try:
        return expr.evaluate(values)
    except InputError as exc:
        raise _fail(file, key, exc.message, exc.expected) from None


# --------------------------------------------------------------------------- file and top level

def _read(path: str) -> dict:
    """Read and parse the TOML file."""
    p = Path(path)
    if not p.is_file():
        raise _fail(path, None, "scene file not found", "an existing scene file")
    try:
        if p.stat().st_size > MAX_SCENE_BYTES:
            raise _fail(path, None, f"scene file is larger than {MAX_SCENE_BYTES} bytes", "a small TOML file")
        raw = p.read_bytes()
    except OSError as exc:
        raise _fail(path, None, f"cannot read the scene file ({exc.strerror})", "a readable scene file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _fail(path, None, f"scene file is not UTF-8 text (byte {exc.start})", "a UTF-8 TOML file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _fail(path, None, f"not valid TOML: {exc}", "a valid TOML document") from None


def _string(file: str, key: str, value: object, expected: str = "a string") -> str:
    if not isinstance(value, str):
        raise _fail(file, key, f"{key} is {_type_name(value)}, not a string", expected)
    return value


_MODULE_REF = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*:([A-Za-z_][A-Za-z0-9_]*)?")
_REGISTERED = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]{0,99}")
MODEL_FORMS = "a path to a .py file relative to the scene's folder, or package.module:attribute"


def is_model_reference(name: str) -> bool:
    """Whether a scene's ``model`` names a file (``models/top.py``) or ``package.module:attribute``."""
    return len(name) <= 4096 and (name.endswith(".py") or "/" in name or "\\" in name
                                  or _MODULE_REF.fullmatch(name) is not None)


def _model_info(file: str, name: str, lookup_model: Callable[..., Any], base: Path | None):
    """The looked-up model of a scene's ``model`` value (None: no such name)."""
    if is_model_reference(name):
        try:
            return lookup_model(name, base=base)
        except InputError as exc:
            if exc.file:  # the model's own file is at fault: its message names it
                raise
            raise _fail(file, "model", exc.message, exc.expected) from None
    return lookup_model(name) if _REGISTERED.fullmatch(name) else None


def _top_level(file: str, data: dict, lookup_model: Callable[..., Any],
               model_names: Callable[[], list[str]], base: Path | None = None) -> tuple[str, Any, str]:
    """Check top-level keys, title, model and backend; returns (title, model info, backend).

    ``model`` is a name ``lookup_model(name)`` knows, or a path / ``module:attribute`` given to
    ``lookup_model(name, base=base)`` (``base``: the scene's folder).
    """
    for key in data:
        if key not in TOP_KEYS:
            raise _fail(file, _part(key), f"unknown top-level key {_show(key)}", "one of: " + ", ".join(TOP_KEYS))
    title = _string(file, "title", data.get("title", ""))
    if len(title) > MAX_TITLE:
        raise _fail(file, "title", f"title is {len(title)} characters long", f"at most {MAX_TITLE} characters")
    if "model" not in data:
        raise _fail(file, "model", "the scene names no model",
                    "model = one of: " + _listing(sorted(model_names())) + "; or " + MODEL_FORMS)
    name = _string(file, "model", data["model"])
    info = _model_info(file, name, lookup_model, base)
    if info is None:
        raise _fail(file, "model", f"unknown model {_show(name)}",
                    "one of: " + _listing(sorted(model_names())) + "; or " + MODEL_FORMS)
    backend = _string(file, "backend", data.get("backend", "c"))
    if backend not in BACKENDS:
        raise _fail(file, "backend", f"unknown backend {_show(backend)}", "one of: " + ", ".join(BACKENDS))
    return title, info, backend


# --------------------------------------------------------------------------- parameters

def _is_choice(info: ParamInfo) -> bool:
    return info.choices is not None or isinstance(info.default, str)


def _param_info(file: str | None, key: str, model: ModelInfo, name: object) -> ParamInfo:
    if not isinstance(name, str) or name not in model.params:
        raise _fail(file, key, f"model '{model.name}' has no parameter {_show(name)}",
                    "one of the model's parameters: " + _listing(list(model.params)))
    return model.params[name]


def _choice_value(file: str | None, key: str, info: ParamInfo, value: object) -> str:
    allowed = f"one of: {_listing(list(info.choices))}" if info.choices is not None else IDENTIFIER_RULE
    if not isinstance(value, str):
        raise _fail(file, key, f"this parameter is a choice, got {_type_name(value)}", f"a string, {allowed}")
    ok = value in info.choices if info.choices is not None else is_identifier(value)
    if not ok:
        raise _fail(file, key, f"{_show(value)} is not an allowed choice", allowed)
    return value


def _raw_value(file: str | None, key: str, info: ParamInfo, value: object) -> Any:
    """A parameter value as given: a number, an :class:`Expression` or a choice string."""
    if _is_choice(info):
        return _choice_value(file, key, info, value)
    if _is_number(value):
        return _finite(file, key, value)
    if isinstance(value, str):
        return _expression(file, key, value)
    raise _fail(file, key, f"parameter value is {_type_name(value)}", NUMBER)


def _override_value(key: str, info: ParamInfo, text: str) -> Any:
    """Parse a ``--set`` value: a number, else an expression, else a choice string."""
    text = text.strip()
    if _is_choice(info):
        return _choice_value(None, key, info, text)
    for convert in (int, float):
        try:
            return _finite(None, key, convert(text))
        except ValueError:
            continue
    return _expression(None, key, text)


def _apply_overrides(raw: dict, model: ModelInfo, overrides: Sequence[str]) -> None:
    """Parse ``name=value`` strings into ``raw`` (name -> (value, file, key))."""
    for item in overrides:
        if not isinstance(item, str) or "=" not in item:
            raise _fail(None, "--set", f"override {_show(item)} has no '='", "name=value")
        name, text = (part.strip() for part in item.split("=", 1))
        key = f"--set {_part(name)}"
        info = _param_info(None, key, model, name)
        raw[name] = (_override_value(key, info, text), None, key)


def _scene_params(file: str, data: dict, model: ModelInfo) -> dict:
    """Model defaults, then the scene's [params]; name -> (raw value, file, key)."""
    raw: dict[str, tuple[Any, str | None, str]] = {
        name: (info.default, None, f"default of parameter {name}") for name, info in model.params.items()}
    table = data.get("params", {})
    if not isinstance(table, dict):
        raise _fail(file, "params", f"params is {_type_name(table)}", "a table of name = value")
    for name, value in table.items():
        key = _join("params", name)
        info = _param_info(file, key, model, name)
        raw[name] = (_raw_value(file, key, info, value), file, key)
    return raw


def _finish(file: str | None, key: str, info: ParamInfo, value: float) -> float | int:
    if not info.integer:
        return float(value)
    if not float(value).is_integer():
        raise _fail(file, key, f"value {value!r} is not an integer", "an integer value")
    return int(value)


class _Resolver:
    """Depth-first resolution of expression parameters with cycle detection."""

    def __init__(self, model: ModelInfo, raw: dict) -> None:
        self.model, self.raw = model, raw
        self.values: dict[str, float | int | str] = {}
        self.depends: dict[str, tuple[str, ...]] = {}
        self.stack: list[str] = []

    def resolve(self, name: str) -> None:
        """Resolve ``name`` and everything its expression uses."""
        if name in self.values:
            return
        value, file, key = self.raw[name]
        if name in self.stack:
            cycle = " -> ".join(self.stack[self.stack.index(name):] + [name])
            raise _fail(file, key, f"parameters depend on each other in a cycle: {cycle}",
                        "expressions that do not refer back to themselves")
        if isinstance(value, Expression):
            self.stack.append(name)
            for dep in value.names:
                self._check_dependency(dep, file, key)
                self.resolve(dep)
            self.stack.pop()
            self.depends[name] = value.names
            value = _evaluate(file, key, value, self.values)
        info = self.model.params[name]
        self.values[name] = value if _is_choice(info) else _finish(file, key, info, value)

    def _check_dependency(self, dep: str, file: str | None, key: str) -> None:
        if dep not in self.model.params:
            numeric = [n for n, i in self.model.params.items() if not _is_choice(i)]
            raise _fail(file, key, f"unknown name '{dep}' in expression",
                        "a model parameter, " + " or ".join(CONSTANTS) + "; parameters: " + _listing(numeric))
        if _is_choice(self.model.params[dep]):
            raise _fail(file, key, f"parameter '{dep}' is a choice and has no numeric value",
                        "numeric parameters only")


def _resolve_params(file: str, data: dict, model: ModelInfo, overrides: Sequence[str]):
    """All parameter values (name -> float | int | str) and each expression parameter's names."""
    raw = _scene_params(file, data, model)
    _apply_overrides(raw, model, overrides)
    resolver = _Resolver(model, raw)
    for name in model.params:
        resolver.resolve(name)
    return {name: resolver.values[name] for name in model.params}, resolver.depends


def _free(file: str, data: dict, model: ModelInfo) -> list[str]:
    value = data.get("free", [])
    if not isinstance(value, list):
        raise _fail(file, "free", f"free is {_type_name(value)}", "an array of parameter names")
    names: list[str] = []
    for i, name in enumerate(value, 1):
        info = _param_info(file, f"free[{i}]", model, name)
        if _is_choice(info):
            raise _fail(file, f"free[{i}]", f"parameter '{name}' is a choice and cannot be kept symbolic",
                        "numeric parameters only")
        if name not in names:
            names.append(name)
    return names


def _active(file: str, data: dict, model: ModelInfo) -> tuple[str, ...] | None:
    table = data.get("coordinates")
    if table is None:
        return None
    if not isinstance(table, dict):
        raise _fail(file, "coordinates", f"coordinates is {_type_name(table)}", "a table with key 'active'")
    for key in table:
        if key != "active":
            raise _fail(file, _join("coordinates", key), f"unknown key {_show(key)}", "active")
    names = table.get("active")
    if not isinstance(names, list) or not names:
        raise _fail(file, "coordinates.active", "active must be a non-empty array of coordinate names",
                    "a non-empty array of the model's coordinates: " + _listing(model.coordinates))
    for i, name in enumerate(names, 1):
        key = f"coordinates.active[{i}]"
        if not isinstance(name, str) or name not in model.coordinates:
            raise _fail(file, key, f"unknown coordinate {_show(name)}",
                        "one of the model's coordinates: " + _listing(model.coordinates))
        if name in names[: i - 1]:
            raise _fail(file, key, f"coordinate '{name}' is listed twice", "each coordinate once")
    return tuple(c for c in model.coordinates if c in names)


# --------------------------------------------------------------------------- option validators

def _number(ctx: _Ctx, key: str, value: object) -> float:
    """A number or an expression of the resolved parameters."""
    if _is_number(value):
        return float(_finite(ctx.file, key, value))
    if not isinstance(value, str):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", NUMBER)
    expr = _expression(ctx.file, key, value)
    for name in expr.names:
        if name in ctx.swept:
            raise _fail(ctx.file, key, f"expression uses swept parameter '{name}', whose value changes "
                        "across the grid", "an expression of parameters that are not swept")
    return _evaluate(ctx.file, key, expr, ctx.params)


def _positive(ctx: _Ctx, key: str, value: object) -> float:
    number = _number(ctx, key, value)
    if number <= 0:
        raise _fail(ctx.file, key, f"value {number!r} is not positive", "a number > 0")
    return number


def _int_at_least(ctx: _Ctx, key: str, value: object, low: int) -> int:
    if not isinstance(value, int) or isinstance(value, bool):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", f"an integer >= {low}")
    if value < low:
        raise _fail(ctx.file, key, f"value {value} is below {low}", f"an integer >= {low}")
    return value


def _count(ctx: _Ctx, key: str, value: object) -> int:
    return _int_at_least(ctx, key, value, 1)


def _workers(ctx: _Ctx, key: str, value: object) -> int:
    return _int_at_least(ctx, key, value, 0)


def _bool(ctx: _Ctx, key: str, value: object) -> bool:
    if not isinstance(value, bool):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "true or false")
    return value


def _method(ctx: _Ctx, key: str, value: object) -> str:
    if not isinstance(value, str) or value not in METHODS:
        raise _fail(ctx.file, key, f"unknown method {_show(value)}", "one of: " + ", ".join(METHODS))
    return value


def _one_of(what: str, names: Sequence[str]) -> Callable:
    """A validator of a string key whose value is one of ``names`` (``what`` names it in the message)."""
    def check(ctx: _Ctx, key: str, value: object) -> str:
        if not isinstance(value, str) or value not in names:
            raise _fail(ctx.file, key, f"unknown {what} {_show(value)}", "one of: " + ", ".join(names))
        return value

    return check


_steady_method = _one_of("steady method", STEADY_METHODS)
_branch_method = _one_of("continuation method", ("collocation", "gauss", "multiple_shooting"))
BRANCH_DIRECTIONS = ("increasing", "decreasing", "both")
_direction = _one_of("direction", BRANCH_DIRECTIONS)
_campbell_method = _one_of("campbell method", ("auto", "exact", "reduced"))


def _steady_form(ctx: _Ctx, key: str, value: object) -> str:
    forms = ("lagrangian", "hamiltonian")
    if not isinstance(value, str) or value not in forms:
        raise _fail(ctx.file, key, f"unknown steady form {_show(value)}", "one of: " + ", ".join(forms))
    if value == "hamiltonian" and not ctx.model.stress_form:
        raise _fail(ctx.file, key, f"model {ctx.model.name} declares no complementary energy density",
                    "form = 'lagrangian' (the Hamiltonian form needs @model.complementary_density)")
    return value


def _modes_table(ctx: _Ctx, key: str, value: object) -> dict[str, list[float]]:
    """{field: [a_1, a_2, ...]}: sine amplitudes added to a boundary-value problem's initial guess."""
    if not isinstance(value, dict):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "a table: field = [amplitudes of sin(j pi s/L)]")
    out = {}
    for name, amps in value.items():
        sub = _join(key, name)
        if not is_identifier(name):
            raise _fail(ctx.file, sub, f"{_show(name)} is not a field name", IDENTIFIER_RULE)
        if not isinstance(amps, list) or not amps:
            raise _fail(ctx.file, sub, f"value is {_type_name(amps)}", "an array of numbers")
        out[name] = [_number(ctx, f"{sub}[{i}]", a) for i, a in enumerate(amps, 1)]
    return out


def _aliases(ctx: _Ctx, key: str, value: object) -> dict[str, str]:
    """{new_name: output_name}: report an output (e.g. tension_start) under a name of the scene's choosing."""
    if not isinstance(value, dict):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "a table: name = \"output_name\"")
    for name, target in value.items():
        if not is_identifier(name) or not isinstance(target, str) or not is_identifier(target):
            raise _fail(ctx.file, _join(key, name), f"alias {_show(name)} = {_show(target)}",
                        "identifiers on both sides: name = \"output_name\"")
    return dict(value)


def _hold(ctx: _Ctx, key: str, value: object) -> dict[str, float]:
    """{output_end: value}: one output at an end of a steady BVP held fixed (e.g. p_e = 17.5)."""
    if not isinstance(value, dict) or len(value) != 1:
        raise _fail(ctx.file, key, f"value is {_show(value)}", "a table with one entry: output = number, e.g. "
                    "{ tension_start = 17.5 } (or an alias)")
    (name, number), = value.items()
    if not is_identifier(name):
        raise _fail(ctx.file, _join(key, name), f"{_show(name)} is not an output name", IDENTIFIER_RULE)
    return {name: _number(ctx, _join(key, name), number)}


def _free_parameter(ctx: _Ctx, key: str, value: object) -> str:
    """A numeric parameter a steady BVP solves for (with ``hold``)."""
    info = _param_info(ctx.file, key, ctx.model, value)
    if _is_choice(info) or info.integer:
        raise _fail(ctx.file, key, f"parameter {_show(value)} is not a real number", "a numeric model parameter")
    if value in ctx.swept:
        raise _fail(ctx.file, key, f"parameter {_show(value)} is swept", "a parameter the sweep does not set")
    return value


# --------------------------------------------------------------------------- branches of steady states



def _param_values(ctx: _Ctx, key: str, value: object) -> dict[str, float]:
    """{parameter: number}: a steady analysis's own values of numeric parameters (made free)."""
    if not isinstance(value, dict) or not value:
        raise _fail(ctx.file, key, f"value is {_show(value)}", "a table of numeric parameters, e.g. { lambda0 = 0.3 }")
    out = {}
    for name, number in value.items():
        sub = _join(key, name)
        info = _param_info(ctx.file, sub, ctx.model, name)
        if _is_choice(info) or info.integer:
            raise _fail(ctx.file, sub, f"parameter {_show(name)} is not a real number", "a numeric model parameter")
        if name in ctx.swept:
            raise _fail(ctx.file, sub, f"parameter {_show(name)} is swept", "a parameter the sweep does not set")
        out[name] = _number(ctx, sub, number)
        if info.below is not None and not out[name] < info.below:
            raise _fail(ctx.file, sub, f"{name} = {out[name]!r} is not below {info.below!r}",
                        f"a value below {info.below!r}")
    return out


def _shape_value(ctx: _Ctx, key: str, value: object) -> dict[str, float]:
    """{shape_output: value}: a steady start with this value of a model-declared shape output (loops = 2)."""
    known = tuple(getattr(ctx.model, "shape_outputs", ()))
    expected = "a table with one entry, a shape output of the model = number: " + _listing(known)
    if not isinstance(value, dict) or len(value) != 1:
        raise _fail(ctx.file, key, f"value is {_show(value)}", expected)
    (name, number), = value.items()
    if name not in known:
        raise _fail(ctx.file, _join(key, name), f"model '{ctx.model.name}' has no shape output {_show(name)}", expected)
    return {name: _number(ctx, _join(key, name), number)}


def _starts(ctx: _Ctx, key: str, value: object) -> str | list[str]:
    """One earlier steady analysis, or an array of them (one branch each)."""
    if not isinstance(value, list):
        return _about(ctx, key, value)
    if not value:
        raise _fail(ctx.file, key, "empty array", "an array of earlier steady analyses")
    names = [_about(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    for i, name in enumerate(names, 1):
        if name in names[:i - 1]:
            raise _fail(ctx.file, f"{key}[{i}]", f"start '{name}' is listed twice", "distinct steady analyses")
    return names


def _output_values(ctx: _Ctx, key: str, value: object) -> dict[str, float]:
    """{output: number}: values whose crossings a branch locates (at = { p_e = 5.0 })."""
    if not isinstance(value, dict) or not value:
        raise _fail(ctx.file, key, f"value is {_show(value)}", "a table: output = number, e.g. { p_e = 5.0 }")
    out = {}
    for name, number in value.items():
        if not is_identifier(name):
            raise _fail(ctx.file, _join(key, name), f"{_show(name)} is not an output name", IDENTIFIER_RULE)
        out[name] = _number(ctx, _join(key, name), number)
    return out


def _bounds(ctx: _Ctx, key: str, value: object) -> dict[str, tuple[float, float]]:
    """{output: [low, high]}: a branch ends where an output leaves its range."""
    expected = "a table: output = [low, high] with low < high, e.g. { p_e = [0, 12] }"
    if not isinstance(value, dict) or not value:
        raise _fail(ctx.file, key, f"value is {_show(value)}", expected)
    out = {}
    for name, pair in value.items():
        sub = _join(key, name)
        if not is_identifier(name):
            raise _fail(ctx.file, sub, f"{_show(name)} is not an output name", IDENTIFIER_RULE)
        if not isinstance(pair, list) or len(pair) != 2:
            raise _fail(ctx.file, sub, f"value is {_show(pair)}", expected)
        lo, hi = (_number(ctx, f"{sub}[{i}]", v) for i, v in enumerate(pair, 1))
        if not lo < hi:
            raise _fail(ctx.file, sub, f"the range [{lo!r}, {hi!r}] is empty", expected)
        out[name] = (lo, hi)
    return out


def _check_branch_outputs(ctx: _Ctx, base: str, options: dict[str, Any]) -> None:
    """Names in ``at`` and ``bounds``: aliases, <output>_<start|end|max|min>, <field>_s_<start|end>, shape outputs."""
    if not getattr(ctx.model, "fields", ()):
        return
    known = set(options.get("aliases", {})) | set(getattr(ctx.model, "shape_outputs", ()))
    known |= {f"{o}_{end}" for o in ctx.model.outputs for end in ("start", "end", "max", "min")}
    known |= {f"{f}_s_{end}" for f in ctx.model.fields for end in ("start", "end")}
    for key in ("at", "bounds"):
        for name in options.get(key, {}):
            if name not in known:
                raise _fail(ctx.file, f"{base}.{key}.{name}", f"no output {_show(name)} on a branch",
                            "an alias of this analysis or <output>_start/_end/_max/_min: " + _listing(sorted(known)))


def _parameter(ctx: _Ctx, key: str, value: object) -> str:
    info = _param_info(ctx.file, key, ctx.model, value)
    if _is_choice(info) or info.integer:
        raise _fail(ctx.file, key, f"parameter {_show(value)} is not a real number", "a numeric model parameter")
    _check_not_derived(ctx, key, value)
    ctx.swept = (value,)
    return value


def _name(ctx: _Ctx, key: str, value: object) -> str:
    if not isinstance(value, str) or not is_identifier(value):
        raise _fail(ctx.file, key, f"value is {_show(value)}", IDENTIFIER_RULE)
    return value


def _coord_table(ctx: _Ctx, key: str, value: object) -> dict[str, float]:
    """A table coordinate name -> number or expression."""
    if not isinstance(value, dict):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "a table of coordinate = value")
    out: dict[str, float] = {}
    for name, item in value.items():
        sub = _join(key, name)
        if not isinstance(name, str) or name not in ctx.coordinates:
            frozen = ctx.active is not None and name in ctx.model.coordinates
            which = "active coordinates" if ctx.active is not None else "model's coordinates"
            what = f"coordinate '{name}' is not active" if frozen else f"unknown coordinate {_show(name)}"
            raise _fail(ctx.file, sub, what, f"one of the {which}: " + _listing(ctx.coordinates))
        out[name] = _number(ctx, sub, item)
    return out


def _about(ctx: _Ctx, key: str, value: object) -> str:
    """Name of an earlier ``steady`` analysis."""
    steady = [n for n, k in ctx.earlier.items() if k == "steady"]
    expected = "the name of an earlier steady analysis: " + _listing(steady)
    if ctx.swept:
        raise _fail(ctx.file, key, "'about' is not available inside a sweep", "no 'about' key")
    if not isinstance(value, str):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", expected)
    if value in ctx.earlier and ctx.earlier[value] != "steady":
        raise _fail(ctx.file, key, f"analysis '{value}' is a {ctx.earlier[value]} analysis, not steady", expected)
    if value not in ctx.earlier:
        later = value in ctx.all_names
        what = f"analysis '{value}' comes later in the scene" if later else f"no analysis named {_show(value)}"
        raise _fail(ctx.file, key, what, expected)
    return value


def _outputs(ctx: _Ctx, key: str, value: object) -> list[str]:
    known = ctx.model.outputs
    if not isinstance(value, list):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "an array of output names: " + _listing(known))
    names: list[str] = []
    for i, name in enumerate(value, 1):
        if not isinstance(name, str) or name not in known:
            raise _fail(ctx.file, f"{key}[{i}]", f"unknown output {_show(name)}",
                        "one of the model's outputs: " + _listing(known))
        if name not in names:
            names.append(name)
    return names


# --------------------------------------------------------------------------- sweeps

def _range(ctx: _Ctx, key: str, table: dict) -> list[float]:
    """{start, stop, num} -> evenly spaced values."""
    for name in table:
        if name not in ("start", "stop", "num"):
            raise _fail(ctx.file, _join(key, name), f"unknown key {_show(name)}", "start, stop, num")
    for name in ("start", "stop", "num"):
        if name not in table:
            raise _fail(ctx.file, _join(key, name), f"missing key '{name}'", "a table {start, stop, num}")
    start, stop = _number(ctx, f"{key}.start", table["start"]), _number(ctx, f"{key}.stop", table["stop"])
    num = _int_at_least(ctx, f"{key}.num", table["num"], 1)
    if num > MAX_GRID:
        raise _fail(ctx.file, f"{key}.num", f"num {num} is too large", f"at most {MAX_GRID}")
    return [float(v) for v in np.linspace(start, stop, num)]


def _sweep_values(ctx: _Ctx, key: str, name: str, value: object) -> list[float | int]:
    info = _param_info(ctx.file, key, ctx.model, name)
    if _is_choice(info):
        if not isinstance(value, list) or not value:
            raise _fail(ctx.file, key, f"value is {_type_name(value)}", "a non-empty array of choices")
        return [_choice_value(ctx.file, f"{key}[{i}]", info, v) for i, v in enumerate(value, 1)]
    if isinstance(value, dict):
        values = _range(ctx, key, value)
    elif isinstance(value, list) and value:
        values = [_number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    else:
        what = "empty array" if value == [] else f"value is {_type_name(value)}"
        raise _fail(ctx.file, key, what, "a non-empty array of numbers or a table {start, stop, num}")
    return [_finish(ctx.file, key, info, v) for v in values]


def _check_not_derived(ctx: _Ctx, key: str, name: str) -> None:
    """A swept parameter may not feed another parameter's expression (it would go stale)."""
    for other, uses in ctx.depends.items():
        if name in uses:
            raise _fail(ctx.file, key, f"parameter '{other}' is computed from '{name}', so sweeping '{name}' "
                        f"would leave '{other}' at its scene value", "a parameter no expression depends on")


def _over(ctx: _Ctx, key: str, value: object) -> dict[str, list]:
    if not isinstance(value, dict) or not value:
        raise _fail(ctx.file, key, f"value is {_type_name(value)}" if not isinstance(value, dict) else "empty table",
                    "a table: parameter = [values] or {start, stop, num}")
    over = {}
    for name, item in value.items():
        sub = _join(key, name)
        over[name] = _sweep_values(ctx, sub, name, item)
        _check_not_derived(ctx, sub, name)
    size = math.prod(len(v) for v in over.values())
    if size > MAX_GRID:
        raise _fail(ctx.file, key, f"the grid has {size} points", f"at most {MAX_GRID} points")
    ctx.swept = tuple(over)
    return over


def _speeds(ctx: _Ctx, key: str, value: object) -> dict[str, list]:
    """A campbell range: one numeric parameter (the spin speed) with increasing values."""
    over = _over(ctx, key, value)
    if len(over) != 1:
        raise _fail(ctx.file, key, f"a campbell diagram runs over one parameter, got {len(over)}",
                    "one entry: Omega = {start, stop, num} or an array")
    (name, values), = over.items()
    if _is_choice(_param_info(ctx.file, key, ctx.model, name)) or len(values) < 2 or np.any(np.diff(values) <= 0):
        raise _fail(ctx.file, _join(key, name), "campbell speeds must be two or more increasing numbers",
                    "increasing numbers, e.g. {start = 0, stop = 1000, num = 50}")
    return over


def _multiples(ctx: _Ctx, key: str, value: object) -> list[float]:
    if not isinstance(value, list) or not value:
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "a non-empty array of positive numbers")
    return [_positive(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]


def _inner(ctx: _Ctx, key: str, value: object) -> AnalysisSpec:
    """The analysis a sweep repeats: a table with ``kind`` (not sweep) and that kind's keys."""
    inner_kinds = [k for k in KINDS if k not in ("sweep", "campbell", "continuation")]
    if not isinstance(value, dict):
        raise _fail(ctx.file, key, f"value is {_type_name(value)}", "a table with kind and its options")
    kind = _kind(ctx, key, value, inner_kinds)
    options = _options(ctx, key, kind, {k: v for k, v in value.items() if k != "kind"})
    return AnalysisSpec(ctx.current, kind, options)


def _grid(over: Mapping[str, list]) -> list[dict[str, float | int]]:
    names = list(over)
    return [dict(zip(names, combo)) for combo in itertools.product(*(over[n] for n in names))]


# --------------------------------------------------------------------------- analyses

_REQUIRED = object()
_ABSENT = object()
_ALL_OUTPUTS = object()

_LINEAR = {"about": (_about, _ABSENT), "at": (_coord_table, _ABSENT), "count": (_count, _ABSENT)}
SCHEMAS: dict[str, dict[str, tuple[Callable, Any]]] = {
    "modes": dict(_LINEAR),
    "stability": {**_LINEAR, "tolerance": (_positive, 1e-8), "refine": (_bool, True),
                  "refine_rtol": (_positive, 1e-2)},
    "steady": {"guess": (_coord_table, {}), "tol": (_positive, 1e-10), "max_iter": (_count, 50),
               "method": (_steady_method, _ABSENT), "bulge": (_modes_table, _ABSENT), "mesh": (_count, _ABSENT),
               "nodes": (_count, _ABSENT), "aliases": (_aliases, _ABSENT), "form": (_steady_form, _ABSENT),
               "params": (_param_values, _ABSENT), "shape": (_shape_value, _ABSENT),
               "hold": (_hold, _ABSENT), "free": (_free_parameter, _ABSENT), "stability": (_bool, _ABSENT)},
    "simulate": {"t_end": (_positive, _REQUIRED), "method": (_method, "BDF"), "dt": (_positive, _ABSENT),
                 "rtol": (_positive, 1e-8), "atol": (_positive, 1e-10), "q0": (_coord_table, {}),
                 "v0": (_coord_table, {}), "initial_mode": (_count, _ABSENT), "amplitude": (_number, 1.0),
                 "outputs": (_outputs, _ALL_OUTPUTS), "series": (_bool, False), "samples": (_count, 201)},
    "sweep": {"over": (_over, _REQUIRED), "analysis": (_inner, _REQUIRED), "workers": (_workers, 0),
              "progress": (_bool, True)},
    "continuation": {"about": (_starts, _REQUIRED), "parameter": (_parameter, _REQUIRED), "stop": (_number, _REQUIRED),
                     "step": (_positive, 0.05), "max_step": (_positive, _ABSENT), "max_points": (_count, 200),
                     "method": (_branch_method, _ABSENT), "stages": (_count, _ABSENT),
                     "mesh": (_count, 100),
                     "stability": (_bool, True), "minimize": (_name, _ABSENT), "aliases": (_aliases, {}),
                     "direction": (_direction, _ABSENT), "bounds": (_bounds, _ABSENT),
                     "at": (_output_values, _ABSENT), "eigenvalues": (_bool, False)},
    "campbell": {"over": (_speeds, _REQUIRED), "count": (_count, 8), "multiples": (_multiples, [1.0]),
                 "method": (_campbell_method, _ABSENT),
                 "about": (_about, _ABSENT), "at": (_coord_table, _ABSENT)},
}


def _kind(ctx: _Ctx, base: str, table: dict, kinds: Sequence[str]) -> str:
    key = f"{base}.kind"
    expected = "one of: " + ", ".join(kinds)
    if "kind" not in table:
        raise _fail(ctx.file, key, "missing key 'kind'", expected)
    kind = table["kind"]
    if not isinstance(kind, str) or kind not in kinds:
        raise _fail(ctx.file, key, f"unknown analysis kind {_show(kind)}", expected)
    return kind


def _options(ctx: _Ctx, base: str, kind: str, table: dict) -> dict[str, Any]:
    """Validate a kind's keys, fill defaults and run the cross-key checks."""
    schema = SCHEMAS[kind]
    for name in table:
        if name not in schema:
            raise _fail(ctx.file, _join(base, name), f"unknown key {_show(name)} for a {kind} analysis",
                        "one of: " + ", ".join(schema))
    options: dict[str, Any] = {}
    for name, (check, default) in schema.items():
        if name in table:
            options[name] = check(ctx, f"{base}.{name}", table[name])
        elif default is _REQUIRED:
            raise _fail(ctx.file, f"{base}.{name}", f"missing required key '{name}' for a {kind} analysis",
                        _describe(name))
        elif default is _ALL_OUTPUTS:
            options[name] = list(ctx.model.outputs)
        elif default is not _ABSENT:
            options[name] = copy.deepcopy(default)
    _cross_checks(ctx, base, kind, options)
    return options


def _describe(name: str) -> str:
    return {"t_end": "a number > 0 (or an expression)", "over": "a table: parameter = [values] or {start, stop, num}",
            "analysis": "a table with kind and its options", "dt": "a number > 0 (or an expression)"}.get(name, "a value")


def _cross_checks(ctx: _Ctx, base: str, kind: str, options: dict[str, Any]) -> None:
    if kind == "simulate":
        if options["method"] == "leapfrog" and "dt" not in options:
            raise _fail(ctx.file, f"{base}.dt", "method 'leapfrog' needs a time step dt", _describe("dt"))
        if "dt" in options and options["dt"] > options["t_end"]:
            raise _fail(ctx.file, f"{base}.dt", f"dt {options['dt']!r} exceeds t_end {options['t_end']!r}",
                        "a time step no larger than t_end")
        if options.get("initial_mode", 0) > len(ctx.coordinates):
            raise _fail(ctx.file, f"{base}.initial_mode", f"initial_mode {options['initial_mode']} exceeds the "
                        f"{len(ctx.coordinates)} coordinates", f"an integer from 1 to {len(ctx.coordinates)}")
    if kind == "sweep":
        options["grid"] = _grid(options["over"])
    if kind == "steady" and ("hold" in options) != ("free" in options):
        missing = "free" if "hold" in options else "hold"
        raise _fail(ctx.file, f"{base}.{missing}", f"'hold' and 'free' go together; '{missing}' is missing",
                    "hold = { output = value } with free = \"parameter\"")
    if kind == "steady" and "shape" in options and "bulge" in options:
        raise _fail(ctx.file, f"{base}.bulge", "'shape' takes its starting guesses from the model; 'bulge' would be "
                    "ignored", "either shape or bulge")
    if kind == "steady" and ("params" in options or "shape" in options) and options.get("method", "newton") == "newton":
        raise _fail(ctx.file, f"{base}.method", "params and shape are for a boundary-value steady state",
                    "method = shooting, multiple_shooting or collocation")
    if kind == "continuation":
        if isinstance(options["about"], list) and "minimize" in options:
            raise _fail(ctx.file, f"{base}.minimize", "minimize follows one branch; 'about' lists several starts",
                        "one start (about = \"name\") with minimize")
        _check_branch_outputs(ctx, base, options)
    if kind == "steady" and ("hold" in options or options.get("stability") or "form" in options) \
            and options.get("method", "newton") == "newton":
        raise _fail(ctx.file, f"{base}.method", "hold, stability and form need a boundary-value steady state",
                    "method = shooting, multiple_shooting or collocation")


def _analysis_name(ctx: _Ctx, base: str, table: dict) -> str:
    key = f"{base}.name"
    if "name" not in table:
        raise _fail(ctx.file, key, "missing key 'name'", IDENTIFIER_RULE)
    name = table["name"]
    if not is_identifier(name):
        raise _fail(ctx.file, key, f"analysis name {_show(name)} is not an identifier", IDENTIFIER_RULE)
    if name in ctx.earlier:
        raise _fail(ctx.file, key, f"analysis name '{name}' is used twice", "a name unique in the scene")
    return name


def _analysis(ctx: _Ctx, index: int, table: object) -> AnalysisSpec:
    base = f"analysis[{index}]"
    if not isinstance(table, dict):
        raise _fail(ctx.file, base, f"analysis entry is {_type_name(table)}", "an [[analysis]] table")
    name = _analysis_name(ctx, base, table)
    kind = _kind(ctx, base, table, KINDS)
    ctx.current, ctx.swept = name, ()
    options = _options(ctx, base, kind, {k: v for k, v in table.items() if k not in ("name", "kind")})
    ctx.swept = ()
    ctx.earlier[name] = kind
    return AnalysisSpec(name, kind, options)


def _analyses(ctx: _Ctx, data: dict) -> tuple[AnalysisSpec, ...]:
    entries = data.get("analysis")
    if not isinstance(entries, list) or not entries:
        what = "the scene has no analysis" if entries is None else f"analysis is {_type_name(entries)}"
        raise _fail(ctx.file, "analysis", what, "one or more [[analysis]] tables")
    ctx.all_names = tuple(e["name"] for e in entries if isinstance(e, dict) and isinstance(e.get("name"), str))
    return tuple(_analysis(ctx, i, entry) for i, entry in enumerate(entries, 1))


# --------------------------------------------------------------------------- entry point

def _plain(value: object) -> object:
    """A Python scene value as TOML would give it: tuples as lists, numpy scalars as numbers."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return value


def load_scene(path, *, overrides: Sequence[str] = (), lookup_model: Callable[..., ModelInfo | None],
               model_names: Callable[[], list[str]]) -> Scene:
    """Load, validate and resolve a scene file, or a dict of a scene's contents.

    Args:
        path: the scene TOML file, or a mapping with the contents a TOML file would have
            (messages name it ``<dict>``; a relative model path is taken from the current directory).
        overrides: ``name=value`` strings (``--set``); they replace [params] values.
        lookup_model: model name -> :class:`ModelInfo`, or None when unknown; a path or
            ``package.module:attribute`` comes with ``base=`` the scene's folder.
        model_names: the known model names (for messages).

    Returns:
        The validated :class:`Scene`.

    Raises:
        SceneError: the first problem found, naming the file, the key and what
            was expected.
    """
    if isinstance(path, Mapping):
        file, data, base = "<dict>", _plain(path), Path.cwd()
    else:
        file = str(path)
        data = _read(file)
        base = Path(file).resolve().parent
    title, model, backend = _top_level(file, data, lookup_model, model_names, base)
    params, depends = _resolve_params(file, data, model, overrides)
    for name, info in model.params.items():
        below = getattr(info, "below", None)
        if below is not None and not params[name] < below:
            raise _fail(file, f"params.{name}", f"{name} = {params[name]!r} is not below {below!r}",
                        f"a value below {below!r}")
    free = _free(file, data, model)
    active = _active(file, data, model)
    ctx = _Ctx(file, model, params, depends, active or tuple(model.coordinates), active)
    analyses = _analyses(ctx, data)
    for index, spec in enumerate(analyses, 1):
        if spec.kind in ("sweep", "campbell"):
            free += [n for n in spec.options["over"] if n not in free]
        inner = spec.options["analysis"] if spec.kind == "sweep" else spec
        if inner.kind == "steady" and inner.options.get("free") and inner.options["free"] not in free:
            free.append(inner.options["free"])
        if inner.kind == "steady":
            free += [n for n in inner.options.get("params", {}) if n not in free]
        if spec.kind == "continuation":
            name = spec.options["parameter"]
            below = getattr(model.params[name], "below", None)
            if below is not None and not spec.options["stop"] < below:
                raise _fail(file, f"analysis[{index}].stop", f"stop {spec.options['stop']!r} is not below "
                            f"{below!r}, the bound of parameter '{name}'", f"a value below {below!r}")
            if name not in free:
                free.append(name)
    from mechgen.scene.layout import load_layout

    segments, parts = load_layout(file, data, model, params)
    free += sorted({n for seg in segments for n in seg.values if n not in free})
    return Scene(file, title, model.name, backend, params, tuple(free), active, analyses, segments, parts,
                 getattr(model, "key", "") or model.name)
