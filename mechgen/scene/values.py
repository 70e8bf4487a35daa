"""Checking values a user wrote (a scene file, a ``--set`` flag, an analysis option from Python).

Every failure is a :class:`~mechgen.errors.SceneError` naming the file (if any), the dotted key
and what would have been accepted. Numbers may be expression strings, parsed by the whitelist
parser of :mod:`mechgen.scene.expr` (no user text is evaluated as Python).
"""
from __future__ import annotations

import json
import math
import re
import sys
from typing import Any, Mapping, Protocol, Sequence

from mechgen.errors import InputError, SceneError, did_you_mean
from mechgen.scene.expr import Expression, is_identifier, parse_expression

IDENTIFIER_RULE = ("an identifier: ASCII letters, digits and underscores, not starting with a digit or '__', "
                   "at most 64 characters, not a Python keyword")
NUMBER = "a number or an expression string"

_PLAIN_KEY = re.compile(r"[A-Za-z0-9_\-]{1,64}")


class ParamInfoLike(Protocol):
    """What the loader needs to know about one model parameter (a :class:`mechgen.scene.info.ParamInfo`
    has it; checks of values take anything that does)."""

    default: float | str
    choices: tuple[str, ...] | None
    integer: bool


class ModelInfoLike(Protocol):
    """Names of a model's parameters, coordinates and outputs (a :class:`mechgen.scene.info.ModelInfo`
    has them)."""

    name: str
    params: Mapping[str, ParamInfoLike]
    coordinates: tuple[str, ...]
    outputs: tuple[str, ...]


def part(name: object) -> str:
    """A key segment safe to print: plain names as is, anything else JSON-quoted and shortened."""
    text = str(name)
    if _PLAIN_KEY.fullmatch(text):
        return text
    quoted = json.dumps(text)
    return quoted if len(quoted) <= 40 else quoted[:36] + '..."'


def show(value: object) -> str:
    """A short single-line rendering of a user value for messages."""
    try:
        text = repr(value)
    except ValueError:  # an int beyond sys.get_int_max_str_digits()
        return "an integer of more than 4300 digits"
    return text if len(text) <= 60 else text[:56] + "..."


def join(key: str | None, name: object) -> str:
    """The dotted key ``key.name`` (``name`` alone at the top level)."""
    return f"{key}.{part(name)}" if key else part(name)


def fail(file: str | None, key: str | None, message: str, expected: str | None = None) -> SceneError:
    """The error to raise for a bad value at ``key`` of ``file``."""
    return SceneError(message, file=file, key=key, expected=expected)


def listing(names: Sequence[str]) -> str:
    """Names separated by commas, or ``(none)``."""
    return ", ".join(names) if names else "(none)"


def type_name(value: object) -> str:
    """'an integer', 'a table' ...: the TOML type of a value, for messages."""
    return {bool: "a boolean", int: "an integer", float: "a float", str: "a string", list: "an array",
            dict: "a table"}.get(type(value), type(value).__name__)


def is_number(value: object) -> bool:
    """True for an int or float that is not a bool."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def finite(file: str | None, key: str, value: int | float) -> float | int:
    """``value`` when it is finite, else a SceneError.

    An integer is finite here when it converts to a float, |value| <= sys.float_info.max
    (about 1.8e308): every numeric parameter reaches the kernels as a double.
    """
    if isinstance(value, float) and not math.isfinite(value):
        raise fail(file, key, f"value {value} is not finite", "a finite number")
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > sys.float_info.max:
        try:
            digits = len(str(abs(value)))
        except ValueError:  # str() refuses ints of more than sys.get_int_max_str_digits() digits
            digits = int(math.log10(abs(value))) + 1
        raise fail(file, key, f"integer value of about {digits} digits is beyond the range of a double "
                   f"(about {sys.float_info.max:.3g})", "a finite number of magnitude at most 1.8e308")
    return value


def expression(file: str | None, key: str, text: str) -> Expression:
    """An expression string parsed by the whitelist parser (errors name the file and key)."""
    try:
        return parse_expression(text, file=file, key=key)
    except SceneError:
        raise
    except InputError as exc:
        raise fail(file, key, exc.message, exc.expected) from None


def evaluate(file: str | None, key: str, expr: Expression, values: Mapping[str, Any]) -> float:
    """The value of a parsed expression with the parameters ``values``."""
    try:
        return expr.evaluate(values)
    except InputError as exc:
        raise fail(file, key, exc.message, exc.expected) from None


# --------------------------------------------------------------------------- model parameters

def is_choice(info: ParamInfoLike) -> bool:
    """True for a parameter whose value is a string (a discretisation, a law ...)."""
    return info.choices is not None or isinstance(info.default, str)


def param_info(file: str | None, key: str, model: ModelInfoLike, name: object) -> ParamInfoLike:
    """The model's parameter ``name``, or a SceneError listing the parameters."""
    if not isinstance(name, str) or name not in model.params:
        raise fail(file, key, f"model '{model.name}' has no parameter {show(name)}"
                   f"{did_you_mean(name, model.params)}",
                   "one of the model's parameters: " + listing(list(model.params)))
    return model.params[name]


def choice_value(file: str | None, key: str, info: ParamInfoLike, value: object) -> str:
    """A valid value of a choice parameter."""
    allowed = f"one of: {listing(list(info.choices))}" if info.choices is not None else IDENTIFIER_RULE
    if not isinstance(value, str):
        raise fail(file, key, f"this parameter is a choice, got {type_name(value)}", f"a string, {allowed}")
    ok = value in info.choices if info.choices is not None else is_identifier(value)
    if not ok:
        raise fail(file, key, f"{show(value)} is not an allowed choice", allowed)
    return value


def finish(file: str | None, key: str, info: ParamInfoLike, value: float) -> float | int:
    """A numeric parameter value as the model takes it: an int for an integer parameter, else a float."""
    if not info.integer:
        return float(value)
    if not float(value).is_integer():
        raise fail(file, key, f"value {value!r} is not an integer", "an integer value")
    return int(value)
