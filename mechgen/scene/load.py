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
Each analysis's keys are checked by its kind's schema (mechgen.analyses.registry); this module
names no kind.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

try:
    import tomllib
except ImportError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

from mechgen.errors import InputError, did_you_mean, file_kind
from mechgen.analyses.registry import get as get_kind
from mechgen.analyses.registry import names as analysis_kinds
from mechgen.analyses.schema import AnalysisSpec, OptionContext, analysis_kind, validate
from mechgen.scene.expr import CONSTANTS, Expression, is_identifier
from mechgen.scene.bounds import check_params, scene_limits
from mechgen.scene.layout import check_layout, load_layout
from mechgen.scene.info import ModelInfo, ParamInfo  # re-exported: the loader needs only what the protocols name
from mechgen.scene.values import (IDENTIFIER_RULE, NUMBER, ModelInfoLike, ParamInfoLike, choice_value, evaluate,
                                  expression, fail, finish, finite, is_choice, is_number, join, listing, param_info,
                                  part, show, type_name)

__all__ = ["AnalysisSpec", "ModelInfo", "ParamInfo", "Scene", "load_scene", "IDENTIFIER_RULE", "NUMBER"]

BACKENDS = ("c", "numpy", "casadi")
TOP_KEYS = ("title", "model", "backend", "free", "params", "coordinates", "analysis", "segments", "parts",
            "limits", "mesh")
#: the largest mesh file a scene may name (bytes)
MAX_MESH_BYTES = 2 << 30
MAX_SCENE_BYTES = 10 * 1024 * 1024
MAX_TITLE = 500


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
    #: parameter name -> the key the scene or a --set flag wrote its value at (defaults left out)
    written: Mapping[str, str] = field(default_factory=dict)
    #: a plane model's mesh file (``mesh = "part.msh"``, resolved against the scene's folder); "" when generated
    mesh: str = ""



# --------------------------------------------------------------------------- file and top level

def _read(path: str) -> dict:
    """Read and parse the TOML file."""
    p = Path(path)
    if not p.is_file():
        raise fail(path, None, "scene file not found", "an existing scene file")
    try:
        if p.stat().st_size > MAX_SCENE_BYTES:
            raise fail(path, None, f"scene file is larger than {MAX_SCENE_BYTES} bytes", "a small TOML file")
        raw = p.read_bytes()
    except OSError as exc:
        raise fail(path, None, f"cannot read the scene file ({exc.strerror})", "a readable scene file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise fail(path, None, f"scene file is not UTF-8 text (byte {exc.start})", "a UTF-8 TOML file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise fail(path, None, f"not valid TOML: {exc}", "a valid TOML document") from None
    except RecursionError:
        raise fail(path, None, "arrays or tables are nested too deeply for the TOML parser",
                   "a scene nested a few levels deep") from None


def _string(file: str, key: str, value: object, expected: str = "a string") -> str:
    if not isinstance(value, str):
        raise fail(file, key, f"{key} is {type_name(value)}, not a string", expected)
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
            raise fail(file, "model", exc.message, exc.expected) from None
    return lookup_model(name) if _REGISTERED.fullmatch(name) else None


def _top_level(file: str, data: dict, lookup_model: Callable[..., Any],
               model_names: Callable[[], list[str]], base: Path | None = None) -> tuple[str, Any, str]:
    """Check top-level keys, title, model and backend; returns (title, model info, backend).

    ``model`` is a name ``lookup_model(name)`` knows, or a path / ``module:attribute`` given to
    ``lookup_model(name, base=base)`` (``base``: the scene's folder).
    """
    for key in data:
        if key not in TOP_KEYS:
            raise fail(file, part(key), f"unknown top-level key {show(key)}", "one of: " + ", ".join(TOP_KEYS))
    title = _string(file, "title", data.get("title", ""))
    if len(title) > MAX_TITLE:
        raise fail(file, "title", f"title is {len(title)} characters long", f"at most {MAX_TITLE} characters")
    if "model" not in data:
        raise fail(file, "model", "the scene names no model",
                    "model = one of: " + listing(sorted(model_names())) + "; or " + MODEL_FORMS)
    name = _string(file, "model", data["model"])
    info = _model_info(file, name, lookup_model, base)
    if info is None:
        raise fail(file, "model", f"unknown model {show(name)}{did_you_mean(name, model_names())}",
                    "one of: " + listing(sorted(model_names())) + "; or " + MODEL_FORMS)
    backend = _string(file, "backend", data.get("backend", "c"))
    if backend not in BACKENDS:
        raise fail(file, "backend", f"unknown backend {show(backend)}", "one of: " + ", ".join(BACKENDS))
    return title, info, backend


def _mesh(file: str, data: dict, model, base: Path) -> str:
    """The absolute path of ``mesh`` (a gmsh file for a plane model), checked to be a regular file of at most
    :data:`MAX_MESH_BYTES` (opened non-blocking and checked with fstat: a FIFO never blocks); "" without one.
    Its contents are read (and refused, naming the file, when not a mesh) when the scene runs."""
    import os
    import stat

    if "mesh" not in data:
        return ""
    expected = "a gmsh .msh file for a plane model (path relative to the scene file's folder)"
    if not getattr(model, "plane_fields", ()):
        raise fail(file, "mesh", f"model {model.name} is not a plane continuum: it takes no mesh file", expected)
    written = _string(file, "mesh", data["mesh"])
    if written.lower().endswith(".geo"):
        raise fail(file, "mesh", f"mesh file {show(written)} is a gmsh geometry: a .geo file is a program (it may "
                   "run commands and write files), which a scene, being data, cannot run", expected + "; mesh the "
                   "geometry once (gmsh -2 part.geo, or mechgen.runtime.plane.gmsh_geo.mesh_from_geo in Python)")
    path = Path(written) if Path(written).is_absolute() else base / written
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise fail(file, "mesh", f"mesh file {show(written)} cannot be read ({exc.strerror}; looked for {path})",
                   expected) from None
    try:
        st = os.fstat(fd)
    finally:
        os.close(fd)
    if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_MESH_BYTES:
        what = f"is {file_kind(st.st_mode)}" if not stat.S_ISREG(st.st_mode) else f"is {st.st_size} bytes"
        raise fail(file, "mesh", f"mesh file {show(written)} {what} ({path})", expected)
    return str(path.resolve())


# --------------------------------------------------------------------------- parameters

def _raw_value(file: str | None, key: str, info: ParamInfoLike, value: object) -> Any:
    """A parameter value as given: a number, an :class:`Expression` or a choice string."""
    if is_choice(info):
        return choice_value(file, key, info, value)
    if is_number(value):
        return finite(file, key, value)
    if isinstance(value, str):
        return expression(file, key, value)
    raise fail(file, key, f"parameter value is {type_name(value)}", NUMBER)


def _override_value(key: str, info: ParamInfoLike, text: str) -> Any:
    """Parse a ``--set`` value: a number, else an expression, else a choice string."""
    text = text.strip()
    if is_choice(info):
        return choice_value(None, key, info, text)
    for convert in (int, float):
        try:
            value = convert(text)
        except ValueError:
            continue
        if isinstance(value, float) and math.isinf(value) and "inf" not in text.lower():
            raise fail(None, key, f"{show(text)} is beyond the range of a double (about 1.8e+308)",
                       "a finite number of magnitude at most 1.8e308")
        return finite(None, key, value)
    return expression(None, key, text)


def _apply_overrides(raw: dict, model: ModelInfoLike, overrides: Sequence[str]) -> None:
    """Parse ``name=value`` strings into ``raw`` (name -> (value, file, key))."""
    for item in overrides:
        if not isinstance(item, str) or "=" not in item:
            raise fail(None, "--set", f"override {show(item)} has no '='", "name=value")
        name, text = (part.strip() for part in item.split("=", 1))
        key = f"--set {part(name)}"
        info = param_info(None, key, model, name)
        raw[name] = (_override_value(key, info, text), None, key)


def _scene_params(file: str, data: dict, model: ModelInfoLike) -> dict:
    """Model defaults, then the scene's [params]; name -> (raw value, file, key)."""
    raw: dict[str, tuple[Any, str | None, str]] = {
        name: (info.default, None, f"default of parameter {name}") for name, info in model.params.items()}
    table = data.get("params", {})
    if not isinstance(table, dict):
        raise fail(file, "params", f"params is {type_name(table)}", "a table of name = value")
    for name, value in table.items():
        key = join("params", name)
        info = param_info(file, key, model, name)
        raw[name] = (_raw_value(file, key, info, value), file, key)
    return raw


class _Resolver:
    """Depth-first resolution of expression parameters with cycle detection."""

    def __init__(self, model: ModelInfoLike, raw: dict) -> None:
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
            raise fail(file, key, f"parameters depend on each other in a cycle: {cycle}",
                        "expressions that do not refer back to themselves")
        if isinstance(value, Expression):
            self.stack.append(name)
            for dep in value.names:
                self._check_dependency(dep, file, key)
                self.resolve(dep)
            self.stack.pop()
            self.depends[name] = value.names
            value = evaluate(file, key, value, self.values)
        info = self.model.params[name]
        self.values[name] = value if is_choice(info) else finish(file, key, info, value)

    def _check_dependency(self, dep: str, file: str | None, key: str) -> None:
        if dep not in self.model.params:
            numeric = [n for n, i in self.model.params.items() if not is_choice(i)]
            raise fail(file, key, f"unknown name '{dep}' in expression",
                        "a model parameter, " + " or ".join(CONSTANTS) + "; parameters: " + listing(numeric))
        if is_choice(self.model.params[dep]):
            raise fail(file, key, f"parameter '{dep}' is a choice and has no numeric value",
                        "numeric parameters only")


def _resolve_params(file: str, data: dict, model: ModelInfoLike, overrides: Sequence[str]):
    """All parameter values (name -> float | int | str), each expression parameter's names, and
    where the scene or a ``--set`` wrote each value it gives (name -> (file, key); defaults left out)."""
    raw = _scene_params(file, data, model)
    _apply_overrides(raw, model, overrides)
    resolver = _Resolver(model, raw)
    for name in model.params:
        resolver.resolve(name)
    written = {name: (f, key) for name, (_, f, key) in raw.items() if f is not None or key.startswith("--set")}
    return {name: resolver.values[name] for name in model.params}, resolver.depends, written


def _free(file: str, data: dict, model: ModelInfoLike) -> list[str]:
    value = data.get("free", [])
    if not isinstance(value, list):
        raise fail(file, "free", f"free is {type_name(value)}", "an array of parameter names")
    names: list[str] = []
    for i, name in enumerate(value, 1):
        info = param_info(file, f"free[{i}]", model, name)
        if is_choice(info):
            raise fail(file, f"free[{i}]", f"parameter '{name}' is a choice and cannot be kept symbolic",
                        "numeric parameters only")
        if name not in names:
            names.append(name)
    return names


def _active(file: str, data: dict, model: ModelInfoLike) -> tuple[str, ...] | None:
    table = data.get("coordinates")
    if table is None:
        return None
    if not isinstance(table, dict):
        raise fail(file, "coordinates", f"coordinates is {type_name(table)}", "a table with key 'active'")
    for key in table:
        if key != "active":
            raise fail(file, join("coordinates", key), f"unknown key {show(key)}", "active")
    names = table.get("active")
    if not isinstance(names, list) or not names:
        raise fail(file, "coordinates.active", "active must be a non-empty array of coordinate names",
                    "a non-empty array of the model's coordinates: " + listing(model.coordinates))
    for i, name in enumerate(names, 1):
        key = f"coordinates.active[{i}]"
        if not isinstance(name, str) or name not in model.coordinates:
            raise fail(file, key, f"unknown coordinate {show(name)}",
                        "one of the model's coordinates: " + listing(model.coordinates))
        if name in names[: i - 1]:
            raise fail(file, key, f"coordinate '{name}' is listed twice", "each coordinate once")
    return tuple(c for c in model.coordinates if c in names)


def _analysis_name(ctx: OptionContext, base: str, table: dict) -> str:
    key = f"{base}.name"
    if "name" not in table:
        raise fail(ctx.file, key, "missing key 'name'", IDENTIFIER_RULE)
    name = table["name"]
    if not is_identifier(name):
        raise fail(ctx.file, key, f"analysis name {show(name)} is not an identifier", IDENTIFIER_RULE)
    if name in ctx.earlier:
        raise fail(ctx.file, key, f"analysis name '{name}' is used twice", "a name unique in the scene")
    return name


def _analysis(ctx: OptionContext, index: int, table: object) -> AnalysisSpec:
    base = f"analysis[{index}]"
    if not isinstance(table, dict):
        raise fail(ctx.file, base, f"analysis entry is {type_name(table)}", "an [[analysis]] table")
    name = _analysis_name(ctx, base, table)
    kind = analysis_kind(ctx, base, table, analysis_kinds())
    ctx.current, ctx.swept = name, ()
    options = validate(ctx, base, get_kind(kind), {k: v for k, v in table.items() if k not in ("name", "kind")})
    ctx.swept = ()
    ctx.earlier[name] = kind
    return AnalysisSpec(name, kind, options)


def _analyses(ctx: OptionContext, data: dict) -> tuple[AnalysisSpec, ...]:
    entries = data.get("analysis")
    if not isinstance(entries, list) or not entries:
        what = "the scene has no analysis" if entries is None else f"analysis is {type_name(entries)}"
        raise fail(ctx.file, "analysis", what, "one or more [[analysis]] tables")
    ctx.all_names = tuple(e["name"] for e in entries if isinstance(e, dict) and isinstance(e.get("name"), str))
    return tuple(_analysis(ctx, i, entry) for i, entry in enumerate(entries, 1))


# --------------------------------------------------------------------------- entry point

def _plain(value: object) -> object:
    """A Python scene value as TOML would give it: tuples as lists, numpy scalars as numbers."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and type(value).__module__ == "numpy":
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return value


def load_scene(path, *, overrides: Sequence[str] = (), lookup_model: Callable[..., ModelInfoLike | None],
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
    file = "<dict>" if isinstance(path, Mapping) else str(path)
    try:
        return _load(path, file, overrides, lookup_model, model_names)
    except RecursionError:  # a value nested hundreds deep: tomllib, _plain or a check ran out of stack
        raise fail(file, None, "arrays or tables are nested too deeply", "a scene nested a few levels deep") from None


def _load(path, file: str, overrides: Sequence[str], lookup_model: Callable[..., ModelInfoLike | None],
          model_names: Callable[[], list[str]]) -> Scene:
    """The body of :func:`load_scene`."""
    if isinstance(path, Mapping):
        data, base = _plain(path), Path.cwd()
    else:
        data = _read(file)
        base = Path(file).resolve().parent
    title, model, backend = _top_level(file, data, lookup_model, model_names, base)
    params, depends, written = _resolve_params(file, data, model, overrides)
    limits = scene_limits(file, data, model)
    check_params(model, params, written, limits)
    free = _free(file, data, model)
    active = _active(file, data, model)
    ctx = OptionContext(file, model, params, depends, active or tuple(model.coordinates), active, limits=limits,
                        written=written)
    analyses = _analyses(ctx, data)
    for spec in analyses:
        free += [n for n in get_kind(spec.kind).frees(spec.options) if n not in free]
    segments, parts = load_layout(file, data, model, params)
    check_layout(file, data, model, params, segments, parts, written)
    free += sorted({n for seg in segments for n in seg.values if n not in free})
    return Scene(file, title, model.name, backend, params, tuple(free), active, analyses, segments, parts,
                 getattr(model, "key", "") or model.name, {name: key for name, (_, key) in written.items()},
                 _mesh(file, data, model, base))
