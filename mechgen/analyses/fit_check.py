"""The scene keys of a ``fit`` (mechgen.analyses.fit) and their checks, each a SceneError at its key.

Beyond each key's own check, :func:`check` requires exactly one of ``expression`` / ``analysis``,
the columns named (``observed``, ``sigma`` > 0, ``group``, ``inputs``) in the data, every name of
the expression a column, a constant or a parameter, the parameters of an analysis fit numeric
model parameters (not computed by another's expression), at least as many rows per group as
parameters, and a starting value for each parameter within its bounds. It fills ``_start``,
``_bounds`` (lower, upper arrays), ``_x_column`` and ``_key`` for the run.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import fit_data, schema
from mechgen.analyses.fit_model import OUTPUT
from mechgen.analyses.registry import get, sweepable_kinds
from mechgen.analyses.schema import ABSENT, REQUIRED, AnalysisSpec, Option
from mechgen.errors import SceneError
from mechgen.scene.bounds import check_value
from mechgen.scene.expr import CONSTANTS, is_identifier
from mechgen.scene.values import (IDENTIFIER_RULE, expression, fail, is_choice, join, listing, param_info, show,
                                  type_name)

JACOBIANS = ("3-point", "2-point")
#: the outputs of a fit besides the parameters' (a parameter may not take one of these names)
OUTPUTS = ("residuals", "fitted", "observed", "rms", "dof", "covariance", "groups", "group_rows", "converged",
           "message", "evaluations", "x_column", "x_values")
EXPRESSION_ONLY = ("constants",)
ANALYSIS_ONLY = ("output", "inputs", "jacobian", "diff_step")
EITHER = ('either expression = "formula of columns, constants and parameters" or analysis = {kind = ...} '
          'with output = "name"')


def _names(ctx, key: str, value: object) -> list[str]:
    """A non-empty array of distinct identifiers."""
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, "empty array" if value == [] else f"value is {type_name(value)}",
                   "a non-empty array of names")
    for i, name in enumerate(value, 1):
        if not is_identifier(name):
            raise fail(ctx.file, f"{key}[{i}]", f"value is {show(name)}", IDENTIFIER_RULE)
        if name in value[: i - 1]:
            raise fail(ctx.file, f"{key}[{i}]", f"'{name}' is listed twice", "each name once")
    return list(value)


def _numbers(ctx, key: str, value: object) -> dict[str, float]:
    """A table name = number (or an expression of the scene's parameters)."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table: name = number")
    out = {}
    for name, item in value.items():
        if not is_identifier(name):
            raise fail(ctx.file, join(key, name), f"name {show(name)} is not an identifier", IDENTIFIER_RULE)
        out[name] = schema.number(ctx, join(key, name), item)
    return out


def _expression(ctx, key: str, value: object):
    if not isinstance(value, str):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a formula string, e.g. \"K + k * (d0 / d)\"")
    return expression(ctx.file, key, value)


def _table(ctx, key: str, value: object) -> dict:
    """The inner analysis's table, validated by :func:`check` (once the parameters and inputs are known)."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a table with kind and its options")
    return dict(value)


def _output(ctx, key: str, value: object) -> tuple[str, int | None]:
    match = OUTPUT.fullmatch(value) if isinstance(value, str) else None
    if match is None:
        raise fail(ctx.file, key, f"value is {show(value)}", 'an output name, or "name[i]" for entry i (1-based) '
                   "of a list output")
    return match.group(1), int(match.group(2)) if match.group(2) else None


def _tol(ctx, key: str, value: object) -> float:
    value = schema.positive(ctx, key, value)
    if value < np.finfo(float).eps:
        raise fail(ctx.file, key, f"tol = {value!r} is below the machine epsilon", "a number >= 2.2e-16")
    return value


SCHEMA = {
    "parameters": Option(_names, REQUIRED, "an array of the names of the parameters to estimate",
                         doc="the names of the parameters to estimate"),
    "start": Option(_numbers, doc="starting values, name = value (default the scene's values)"),
    "data": Option(fit_data.load, REQUIRED, fit_data.TABLE, doc="the data: a table {column = [values]} or a CSV "
                   "file's path, relative to the working directory"),
    "observed": Option(schema.name, REQUIRED, "the name of the data column the model reproduces",
                       doc="the data column the model reproduces (y)"),
    "sigma": Option(schema.name, doc="a data column of standard deviations that weights the rows (in the "
                    "observed column's unit; default 1)"),
    "group": Option(schema.name, doc="a data column: the parameters are estimated separately for each of its "
                    "distinct values"),
    "expression": Option(_expression, doc="the model as a formula of data columns, constants and the "
                         "parameters (instead of analysis)"),
    "constants": Option(_numbers, doc="named numbers the expression uses, name = value"),
    "analysis": Option(_table, doc="the model as an inner analysis table (modes, stability, steady or "
                       "simulate), run once per row"),
    "output": Option(_output, doc="the inner analysis's number output compared with observed, or name[i] "
                     "(entry i, 1-based, of a list output)"),
    "inputs": Option(_names, doc="data columns that set model parameters per row"),
    "jacobian": Option(schema.one_of("jacobian", JACOBIANS), doc="finite differences of an analysis fit: "
                       "3-point (the default) or 2-point"),
    "diff_step": Option(schema.positive, doc="the finite differences' relative step (default 1e-6)"),
    "tol": Option(_tol, 1e-10, doc="least_squares' ftol = xtol = gtol"),
    "max_seconds": Option(schema.positive, ABSENT, doc="the wall-time budget (s, default 600)"),
    "max_evaluations": Option(schema.count, doc="the most evaluations of the model on all rows of a group, the "
                              "Jacobian's included (default none)"),
}


def frees(options: dict) -> list[str]:
    """An analysis fit's parameters, its inputs and what its inner analysis keeps free; an expression fit: none."""
    if "analysis" not in options:
        return []
    names = list(dict.fromkeys([*options["parameters"], *options.get("inputs", [])]))
    inner = options["analysis"]
    return names + [n for n in get(inner.kind).frees(inner.options) if n not in names]


def needs(options: dict, *, internal: bool) -> set[str]:
    """The inner analysis's kernels; none for an expression."""
    inner = options.get("analysis")
    return get(inner.kind).needs(inner.options, internal=internal) if inner is not None else set()


def check(ctx, base: str, options: dict) -> None:
    """The cross-key checks (module docstring)."""
    has_expression, has_analysis = "expression" in options, "analysis" in options
    if has_expression == has_analysis:
        raise fail(ctx.file, f"{base}.{'analysis' if has_analysis else 'expression'}",
                   "both expression and analysis are given" if has_analysis else "neither expression nor analysis "
                   "is given", EITHER)
    for key in EXPRESSION_ONLY if has_analysis else ANALYSIS_ONLY:
        if key in options:
            raise fail(ctx.file, f"{base}.{key}", f"'{key}' applies to an {'expression' if has_analysis else 'analysis'}"
                       " fit", "the keys of an " + ("analysis fit: output, inputs, jacobian, diff_step" if has_analysis
                                                   else "expression fit: constants"))
    data = options["data"]
    for key in ("observed", "sigma", "group"):
        if key in options:
            fit_data.column(ctx, f"{base}.{key}", data, options[key])
    if "sigma" in options:
        values = data.columns[options["sigma"]]
        if not (values > 0).all():
            row = int(np.flatnonzero(~(values > 0))[0])
            raise fail(ctx.file, f"{base}.sigma", f"{data.where(row, options['sigma'])}: sigma = {float(values[row])!r}",
                       "standard deviations > 0")
    names = options["parameters"]
    if has_expression:
        _check_expression(ctx, base, options)
    else:
        _check_analysis(ctx, base, options)
    for i, name in enumerate(names, 1):
        taken = [n for n in OUTPUTS if n in (name, f"{name}_stderr")] + [n for n in names if n == f"{name}_stderr"]
        if taken:
            raise fail(ctx.file, f"{base}.parameters[{i}]", f"parameter '{name}' would report under the name "
                       f"'{taken[0]}', which the fit reports already", "a name that is not one of: " + ", ".join(OUTPUTS))
    _check_rows(ctx, base, options)
    _start(ctx, base, options)
    options["_key"] = base


def _check_expression(ctx, base: str, options: dict) -> None:
    expr, data, names = options["expression"], options["data"], options["parameters"]
    constants = options.get("constants", {})
    key = f"{base}.expression"
    for name in constants:
        if name in data.columns or name in names:
            raise fail(ctx.file, join(f"{base}.constants", name), f"constant '{name}' is also a "
                       + ("data column" if name in data.columns else "parameter"), "a name of its own")
    for i, name in enumerate(names, 1):
        if name in data.columns:
            raise fail(ctx.file, f"{base}.parameters[{i}]", f"parameter '{name}' is also a data column", "a name of its own")
        if name not in expr.names:
            raise fail(ctx.file, f"{base}.parameters[{i}]", f"parameter '{name}' does not appear in the expression "
                       f"{show(expr.text)}", "names of the expression: " + listing(list(expr.names)))
    known = [*data.columns, *constants, *names]
    for name in expr.names:
        if name not in known:
            raise fail(ctx.file, key, f"unknown name '{name}' in expression {show(expr.text)}",
                       "a data column, a constant, a parameter or " + " or ".join(CONSTANTS) + ": " + listing(known))
        if name == options["observed"]:
            raise fail(ctx.file, key, f"the expression uses the observed column '{name}'",
                       "a model of the observed column in terms of the others")
    options["_x_column"] = next((n for n in expr.names if n in data.columns), None)


def _check_analysis(ctx, base: str, options: dict) -> None:
    data, names = options["data"], options["parameters"]
    if "output" not in options:
        raise fail(ctx.file, f"{base}.output", "missing key 'output' for an analysis fit",
                   'the inner analysis\'s number output to compare: "name" or "name[i]"')
    for i, name in enumerate(names, 1):
        key = f"{base}.parameters[{i}]"
        _numeric(ctx, key, name)
        if name in data.columns:
            raise fail(ctx.file, key, f"parameter '{name}' is also a data column", "a name of its own")
    inputs = options.get("inputs", [])
    for i, name in enumerate(inputs, 1):
        key = f"{base}.inputs[{i}]"
        values = fit_data.column(ctx, key, data, name)
        info = _numeric(ctx, key, name)
        if name in names or name == options["observed"]:
            raise fail(ctx.file, key, f"input '{name}' is also " + ("a parameter to estimate" if name in names else
                       "the observed column"), "a column that sets a model parameter per row")
        for row, value in enumerate(values):
            try:
                check_value(ctx.file, key, name, info, float(value), ctx.limits)
            except SceneError as exc:
                raise fail(ctx.file, key, f"{data.where(row, name)}: {exc.message}", exc.expected) from None
    table = options["analysis"]
    key = f"{base}.analysis"
    kind = schema.analysis_kind(ctx, key, table, sweepable_kinds(table.get("kind") if isinstance(table, dict) else None))
    saved, ctx.swept = ctx.swept, tuple(dict.fromkeys([*ctx.swept, *names, *inputs]))
    try:
        inner = schema.validate(ctx, key, get(kind), {k: v for k, v in table.items() if k != "kind"})
    finally:
        ctx.swept = saved
    options["analysis"] = AnalysisSpec(ctx.current, kind, inner)
    options.setdefault("jacobian", "3-point")
    options.setdefault("diff_step", 1e-6)
    options["_x_column"] = inputs[0] if inputs else None


def _numeric(ctx, key: str, name: str):
    """A numeric, non-integer model parameter that no expression parameter is computed from."""
    info = param_info(ctx.file, key, ctx.model, name)
    if is_choice(info) or not info.numeric or info.integer:
        what = "a choice" if is_choice(info) else "a size" if not info.numeric else "an integer"
        raise fail(ctx.file, key, f"parameter '{name}' is {what}", "a real-valued model parameter")
    schema.check_not_derived(ctx, key, name)
    return info


def _check_rows(ctx, base: str, options: dict) -> None:
    data, count = options["data"], len(options["parameters"])
    grouped = "group" in options
    for value, rows in fit_data.groups(data.columns[options["group"]] if grouped else None, data.rows):
        if len(rows) < count:
            where = f"group {options['group']} = {value:g} has" if grouped else "the data have"
            rows_text = f"{len(rows)} row" + ("s" if len(rows) != 1 else "")
            raise fail(ctx.file, f"{base}.{'group' if grouped else 'data'}", f"{where} {rows_text}, fewer than "
                       f"the {count} parameters", "at least as many rows as parameters" + (" in every group" if grouped
                                                                                         else ""))


def _start(ctx, base: str, options: dict) -> None:
    """``_start`` (a value per parameter) and ``_bounds`` (lower, upper: the declared bounds of an analysis fit)."""
    names, given = options["parameters"], options.get("start", {})
    for name in given:
        if name not in names:
            raise fail(ctx.file, join(f"{base}.start", name), f"'{name}' is not a parameter being estimated",
                       "one of: " + listing(names))
    analysis = "analysis" in options
    start, lower, upper = [], [], []
    for name in names:
        key = join(f"{base}.start", name)
        info = ctx.model.params.get(name) if analysis else None
        if name in given:
            value = given[name]
        elif name in ctx.params and isinstance(ctx.params[name], (int, float)):
            value = float(ctx.params[name])
        elif info is not None:
            value = float(info.default)
        else:
            raise fail(ctx.file, key, f"no starting value for parameter '{name}' (not a model parameter)",
                       "start = { name = value } for each parameter of an expression fit")
        low, high = -np.inf, np.inf
        if info is not None:
            check_value(ctx.file, key, name, info, value, ctx.limits)
            low = 0.0 if info.positive else low
            low = max(low, info.minimum) if info.minimum is not None else low
            high = min(x for x in (info.maximum, info.below, np.inf) if x is not None)
        start.append(value)
        lower.append(low)
        upper.append(high)
    options["_start"] = np.array(start)
    options["_bounds"] = (np.array(lower), np.array(upper))
