"""Validating an analysis's options against its kind's schema (scene tables and Python keywords alike).

A kind's schema maps each option name to an :class:`Option`: a check ``(ctx, key, value) -> value``
and a default (:data:`REQUIRED`, :data:`ABSENT`, :data:`ALL_OUTPUTS` or a value that is copied).
:func:`validate` rejects unknown names, runs the checks, fills the defaults and then the kind's
cross-key check. The checks shared by several kinds live here; a kind's own ones live in its module.
"""
from __future__ import annotations

import copy
import itertools
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from mechgen.errors import did_you_mean
from mechgen.scene.expr import is_identifier
from mechgen.scene.values import (IDENTIFIER_RULE, NUMBER, ModelInfoLike, choice_value, evaluate, expression,
                                  fail, finish, finite, is_choice, is_number, join, listing, param_info, show,
                                  type_name)

MAX_GRID = 1_000_000

REQUIRED = object()
ABSENT = object()
ALL_OUTPUTS = object()


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
class Option:
    """One option of a kind: its check, its default, (for a required one) what is expected, and ``doc``: what
    the key means, one sentence with its units (the reference pages and the Python functions' docstrings show
    it: mechgen.analyses.reference, mechgen.analyses.public)."""

    check: Callable[["OptionContext", str, object], Any]
    default: Any = ABSENT
    expected: str = "a value"
    doc: str = ""


@dataclass
class OptionContext:
    """What the checks of one scene's (or one Python call's) analyses see.

    ``params`` are the resolved parameter values (for expressions), ``depends`` each expression
    parameter's names, ``coordinates`` the active ones, ``earlier`` the analyses before this one
    (name -> kind), ``swept`` the parameters the enclosing sweep or continuation sets.
    """

    file: str | None
    model: ModelInfoLike
    params: dict
    depends: dict
    coordinates: tuple[str, ...]
    active: tuple[str, ...] | None
    all_names: tuple[str, ...] = ()
    earlier: dict[str, str] = field(default_factory=dict)
    current: str = ""
    swept: tuple[str, ...] = ()
    #: the scene's safety limits (mechgen.scene.bounds.scene_limits; empty: the defaults)
    limits: Mapping[str, int] = field(default_factory=dict)
    #: parameter name -> (file, key) where the scene or a --set flag wrote its value (defaults left out)
    written: Mapping[str, tuple] = field(default_factory=dict)
    #: the options come from the user's own Python call (mechgen.analyses.public), not from a scene: a scene is
    #: data and may not choose what mechgen trusts (a Dask scheduler), a Python argument may
    trusted: bool = False


# --------------------------------------------------------------------------- the schema walk

def analysis_kind(ctx: OptionContext, base: str, table: dict, kinds: Sequence[str]) -> str:
    """The table's ``kind``, one of ``kinds``."""
    key = f"{base}.kind"
    expected = "one of: " + ", ".join(kinds)
    if "kind" not in table:
        raise fail(ctx.file, key, "missing key 'kind'", expected)
    kind = table["kind"]
    if not isinstance(kind, str) or kind not in kinds:
        raise fail(ctx.file, key, f"unknown analysis kind {show(kind)}{did_you_mean(kind, kinds)}", expected)
    return kind


def validate(ctx: OptionContext, base: str, kind, table: Mapping[str, Any]) -> dict[str, Any]:
    """A kind's options (an AnalysisKind's ``schema`` and ``check``): keys checked, defaults filled."""
    schema = kind.schema
    for name in table:
        if name not in schema:
            raise fail(ctx.file, join(base, name), f"unknown key {show(name)} for a {kind.name} analysis"
                       f"{did_you_mean(name, schema)}",
                       "one of: " + ", ".join(schema))
    options: dict[str, Any] = {}
    for name, option in schema.items():
        if name in table:
            options[name] = option.check(ctx, f"{base}.{name}", table[name])
        elif option.default is REQUIRED:
            raise fail(ctx.file, f"{base}.{name}", f"missing required key '{name}' for a {kind.name} analysis",
                       option.expected)
        elif option.default is ALL_OUTPUTS:
            options[name] = list(ctx.model.outputs)
        elif option.default is not ABSENT:
            options[name] = copy.deepcopy(option.default)
    if kind.check is not None:
        kind.check(ctx, base, options)
    return options


# --------------------------------------------------------------------------- shared checks

def number(ctx: OptionContext, key: str, value: object) -> float:
    """A number or an expression of the resolved parameters."""
    if is_number(value):
        return float(finite(ctx.file, key, value))
    if not isinstance(value, str):
        raise fail(ctx.file, key, f"value is {type_name(value)}", NUMBER)
    expr = expression(ctx.file, key, value)
    for name in expr.names:
        if name in ctx.swept:
            raise fail(ctx.file, key, f"expression uses swept parameter '{name}', whose value changes "
                       "across the grid", "an expression of parameters that are not swept")
    return evaluate(ctx.file, key, expr, ctx.params)


def positive(ctx: OptionContext, key: str, value: object) -> float:
    """A number > 0."""
    value = number(ctx, key, value)
    if value <= 0:
        raise fail(ctx.file, key, f"value {value!r} is not positive", "a number > 0")
    return value


class ParamExpression(float):
    """A number given in a scene as an expression of parameters (``frequency = "2*w"``): its value, and the
    expression's ``text``, so that an analysis that moves a parameter (a continuation) evaluates it again there."""

    def __new__(cls, value: float, text: str) -> "ParamExpression":
        obj = float.__new__(cls, value)
        obj.text = text
        return obj

    def __reduce__(self):
        return ParamExpression, (float(self), self.text)

    @property
    def names(self) -> tuple[str, ...]:
        """The parameter names the expression uses."""
        from mechgen.scene.expr import parse_expression

        return tuple(parse_expression(self.text).names)

    def at(self, values: Mapping[str, float]) -> float:
        """The expression's value with the parameters ``values``."""
        from mechgen.scene.expr import parse_expression

        return float(parse_expression(self.text).evaluate(values))

    def moved(self, name: str, value: float, values: Mapping[str, float]) -> float:
        """Its value with the parameter ``name`` at ``value`` (the others as when it was given, or ``values``
        where a continuation keeps them free): itself when it does not use ``name``."""
        if name not in self.names:
            return float(self)
        return self.at({**values, name: float(value)})


def positive_expression(ctx: OptionContext, key: str, value: object) -> float:
    """A number > 0; given as an expression of parameters, a :class:`ParamExpression` that keeps it."""
    number_value = positive(ctx, key, value)
    return ParamExpression(number_value, value) if isinstance(value, str) else number_value


def int_at_least(ctx: OptionContext, key: str, value: object, low: int) -> int:
    """An integer >= ``low``."""
    if not isinstance(value, int) or isinstance(value, bool):
        raise fail(ctx.file, key, f"value is {type_name(value)}", f"an integer >= {low}")
    if value < low:
        raise fail(ctx.file, key, f"value {value} is below {low}", f"an integer >= {low}")
    return value


def count(ctx: OptionContext, key: str, value: object) -> int:
    """An integer >= 1."""
    return int_at_least(ctx, key, value, 1)


def count_within(limit: str) -> Callable:
    """A check of an integer from 1 to the safety limit ``limit`` (mechgen.scene.bounds.LIMITS, which a
    scene raises in its ``[limits]`` table); an integral float such as 1e6 counts as an integer."""
    def check(ctx: OptionContext, key: str, value: object) -> int:
        from mechgen.scene.bounds import LIMITS, number_text

        if isinstance(value, float) and math.isfinite(value) and value.is_integer():
            value = int(value)
        n = count(ctx, key, value)
        top = ctx.limits.get(limit, LIMITS[limit])
        if n > top:
            raise fail(ctx.file, key, f"{limit} = {number_text(n)} is above the safety limit {top}",
                       f"an integer from 1 to {top} (the limit guards against typos: raise it with "
                       f"[limits] {limit} = ... in the scene)")
        return n

    return check


def boolean(ctx: OptionContext, key: str, value: object) -> bool:
    """true or false."""
    if not isinstance(value, bool):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "true or false")
    return value


def one_of(what: str, names: Sequence[str]) -> Callable:
    """A check of a string option whose value is one of ``names`` (``what`` names it in the message)."""
    def check(ctx: OptionContext, key: str, value: object) -> str:
        if not isinstance(value, str) or value not in names:
            raise fail(ctx.file, key, f"unknown {what} {show(value)}{closest_value(value, names)}",
                       "one of: " + ", ".join(names))
        return value

    return check


def closest_value(value: object, names: Sequence[str]) -> str:
    """`` (did you mean 'DOP853'?)`` for a mistyped choice: a case-insensitive match first, else difflib's."""
    if isinstance(value, str):
        same = [n for n in names if n.lower() == value.lower()]
        if same:
            return f" (did you mean {same[0]!r}?)"
    return did_you_mean(value, names)


def name(ctx: OptionContext, key: str, value: object) -> str:
    """An identifier (an output name)."""
    if not isinstance(value, str) or not is_identifier(value):
        raise fail(ctx.file, key, f"value is {show(value)}", IDENTIFIER_RULE)
    return value


def aliases(ctx: OptionContext, key: str, value: object) -> dict[str, str]:
    """{new_name: output_name}: report an output (e.g. tension_start) under a name of the scene's choosing."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table: name = \"output_name\"")
    for alias, target in value.items():
        if not is_identifier(alias) or not isinstance(target, str) or not is_identifier(target):
            raise fail(ctx.file, join(key, alias), f"alias {show(alias)} = {show(target)}",
                       "identifiers on both sides: name = \"output_name\"")
    return dict(value)


def coordinate_table(ctx: OptionContext, key: str, value: object) -> dict[str, float]:
    """A table coordinate name -> number or expression."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table of coordinate = value")
    out: dict[str, float] = {}
    for coord, item in value.items():
        sub = join(key, coord)
        if not isinstance(coord, str) or coord not in ctx.coordinates:
            frozen = ctx.active is not None and coord in ctx.model.coordinates
            which = "active coordinates" if ctx.active is not None else "model's coordinates"
            what = f"coordinate '{coord}' is not active" if frozen else f"unknown coordinate {show(coord)}"
            raise fail(ctx.file, sub, what, f"one of the {which}: " + listing(ctx.coordinates))
        out[coord] = number(ctx, sub, item)
    return out


def about(ctx: OptionContext, key: str, value: object) -> str:
    """Name of an earlier ``steady`` analysis."""
    steady = [n for n, k in ctx.earlier.items() if k == "steady"]
    expected = "the name of an earlier steady analysis: " + listing(steady)
    if ctx.swept:
        raise fail(ctx.file, key, "'about' is not available inside a sweep", "no 'about' key")
    if not isinstance(value, str):
        raise fail(ctx.file, key, f"value is {type_name(value)}", expected)
    if value in ctx.earlier and ctx.earlier[value] != "steady":
        raise fail(ctx.file, key, f"analysis '{value}' is a {ctx.earlier[value]} analysis, not steady", expected)
    if value not in ctx.earlier:
        later = value in ctx.all_names
        what = f"analysis '{value}' comes later in the scene" if later else f"no analysis named {show(value)}"
        raise fail(ctx.file, key, what, expected)
    return value


# --------------------------------------------------------------------------- parameter grids

def value_range(ctx: OptionContext, key: str, table: dict) -> list[float]:
    """{start, stop, num} -> evenly spaced values."""
    for item in table:
        if item not in ("start", "stop", "num"):
            raise fail(ctx.file, join(key, item), f"unknown key {show(item)}", "start, stop, num")
    for item in ("start", "stop", "num"):
        if item not in table:
            raise fail(ctx.file, join(key, item), f"missing key '{item}'", "a table {start, stop, num}")
    start, stop = number(ctx, f"{key}.start", table["start"]), number(ctx, f"{key}.stop", table["stop"])
    num = int_at_least(ctx, f"{key}.num", table["num"], 1)
    if num > MAX_GRID:
        raise fail(ctx.file, f"{key}.num", f"num {num} is too large", f"at most {MAX_GRID}")
    return [float(v) for v in np.linspace(start, stop, num)]


def parameter_values(ctx: OptionContext, key: str, param: str, value: object) -> list[float | int]:
    """The values a grid gives one parameter: an array (of numbers or choices) or {start, stop, num}, each within
    the parameter's declared bounds and size limits (mechgen.scene.bounds.check_value), as a written value is."""
    info = param_info(ctx.file, key, ctx.model, param)
    if is_choice(info):
        if not isinstance(value, list) or not value:
            raise fail(ctx.file, key, f"value is {type_name(value)}", "a non-empty array of choices")
        return [choice_value(ctx.file, f"{key}[{i}]", info, v) for i, v in enumerate(value, 1)]
    if isinstance(value, dict):
        values = value_range(ctx, key, value)
    elif isinstance(value, list) and value:
        values = [number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    else:
        what = "empty array" if value == [] else f"value is {type_name(value)}"
        raise fail(ctx.file, key, what, "a non-empty array of numbers or a table {start, stop, num}")
    values = [finish(ctx.file, key, info, v) for v in values]
    from mechgen.scene.bounds import check_value  # the bounds every value the scene writes meets

    ranged = isinstance(value, dict)
    for i, v in enumerate(values, 1):
        check_value(ctx.file, key if ranged else f"{key}[{i}]", param, info, v, ctx.limits)
    return values


def check_not_derived(ctx: OptionContext, key: str, param: str) -> None:
    """A swept parameter may not feed another parameter's expression (it would go stale)."""
    for other, uses in ctx.depends.items():
        if param in uses:
            raise fail(ctx.file, key, f"parameter '{other}' is computed from '{param}', so sweeping '{param}' "
                       f"would leave '{other}' at its scene value", "a parameter no expression depends on")


def over(ctx: OptionContext, key: str, value: object) -> dict[str, list]:
    """{parameter: values}: the parameters a grid runs over (sets ``ctx.swept``)."""
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}" if not isinstance(value, dict) else "empty table",
                   "a table: parameter = [values] or {start, stop, num}")
    out = {}
    for param, item in value.items():
        sub = join(key, param)
        out[param] = parameter_values(ctx, sub, param, item)
        check_not_derived(ctx, sub, param)
    size = math.prod(len(v) for v in out.values())
    if size > MAX_GRID:
        raise fail(ctx.file, key, f"the grid has {size} points", f"at most {MAX_GRID} points")
    ctx.swept = tuple(out)
    return out


def grid(values: Mapping[str, list]) -> list[dict[str, float | int]]:
    """The cartesian product of ``values`` (first parameter outermost) as a list of points."""
    names = list(values)
    return [dict(zip(names, combo)) for combo in itertools.product(*(values[n] for n in names))]


def no_check(ctx: OptionContext, base: str, options: dict) -> None:
    """The cross-key check of a kind that has none."""


#: the options of the linear analyses (modes, stability): where to linearise and how many modes
LINEAR_OPTIONS = {
    "about": Option(about, doc="the name of an earlier steady analysis whose state is the operating point "
                    "to linearise about"),
    "at": Option(coordinate_table, doc="the operating point's coordinates (a table coordinate = value; left "
                 "out: zero), re-solved by Newton when it is not an equilibrium"),
    "count": Option(count, doc="how many of the lowest (elastic) modes to compute; left out: all of them"),
    "roundoff_rtol": Option(positive, doc="a continuum's largest accepted bound on the lowest frequency's "
                            "relative error from round-off (output roundoff_bound; default 1e-2); above it the run is "
                            "refused at params.N"),
}


# ------------------------------------------------------------------------ where a grid's points run


def workers(ctx: OptionContext, key: str, value: object) -> int:
    """A count of worker processes (local processes, or the Dask LocalCluster's workers); 0: the default, two."""
    return int_at_least(ctx, key, value, 0)


#: what a scene that names a scheduler is told to do instead
SCHEDULER_INSTEAD = ("no scheduler key in the scene: executor = \"dask\" alone runs the points on a LocalCluster "
                     "mechgen starts on the loopback; a running scheduler is the user's choice, given on the command "
                     "line (mechgen run SCENE --scheduler tcp://host:port), in Dask's scheduler-address setting "
                     "(DASK_SCHEDULER_ADDRESS) or as the scheduler= argument in Python")


def scheduler(ctx: OptionContext, key: str, value: object) -> str:
    """A Dask scheduler's address, tcp://host:port or tls://host:port, from a Python call only: a scene is data,
    and connecting to a scheduler trusts it to run code in this process (its results are unpickled), so a scene
    file (or a scene dict) that names one is refused (``mechgen run --scheduler`` instead)."""
    from mechgen.runtime.core.sweep import SCHEDULER_FORM, scheduler_address

    if not ctx.trusted:
        raise fail(ctx.file, key, "a scene cannot name a Dask scheduler (connecting to one trusts it to run code "
                   "in this process)", SCHEDULER_INSTEAD)
    try:
        return scheduler_address(value)
    except ValueError as exc:
        raise fail(ctx.file, key, f"value is {show(value)}: {exc}", SCHEDULER_FORM) from None


def executor_options() -> dict[str, Option]:
    """The keys of a kind whose independent points run on an executor (mechgen.runtime.core.sweep.SweepExecutor):
    ``executor`` (serial | processes | dask; left out: processes when ``workers`` > 1, else serial),
    ``workers`` (0: two) and ``scheduler`` (with dask: a running scheduler instead of a LocalCluster)."""
    from mechgen.runtime.core.sweep import EXECUTORS

    return {"executor": Option(one_of("executor", EXECUTORS), ABSENT,
                               doc="where the independent points run: serial, processes or dask (left out: "
                               "processes when workers > 1, else serial)"),
            "workers": Option(workers, 0, doc="how many local processes, or Dask LocalCluster workers, run the "
                              "points (0: two)"),
            "scheduler": Option(scheduler, ABSENT, doc="Python calls only (the scheduler= argument): with executor "
                                "= \"dask\", the address of a running Dask scheduler (tcp://host:port or "
                                "tls://host:port) to use instead of a LocalCluster. A scene file cannot name one "
                                "(refused, exit 2): connecting trusts the scheduler to run code in this process, so "
                                "it is the user's choice, mechgen run SCENE --scheduler tcp://host:port or Dask's "
                                "scheduler-address setting (DASK_SCHEDULER_ADDRESS)")}


def check_executor(ctx: OptionContext, base: str, options: dict) -> None:
    """A ``scheduler`` needs ``executor = "dask"``."""
    if "scheduler" in options and options.get("executor") != "dask":
        raise fail(ctx.file, join(base, "scheduler"), "a scheduler without executor = \"dask\"",
                   "executor = \"dask\" beside scheduler, or no scheduler")
