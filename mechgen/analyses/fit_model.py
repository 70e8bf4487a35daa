"""The observation models of a ``fit``: what the model predicts for the observed column, row by row.

:class:`ExpressionModel`: y_i = f(columns_i, constants, theta), an expression parsed by
mechgen.scene.expr and evaluated over the rows with its exact gradient df/dtheta
(mechgen.scene.expr_arrays). :class:`AnalysisModel`: y_i = the output of an inner analysis (modes,
stability, steady or simulate) of the model with the parameters theta and the row's inputs;
its Jacobian is left to finite differences, so the inner analysis's accuracy (an integrator's
rtol, a Newton tolerance) bounds that of the Jacobian and of the estimate.
"""
from __future__ import annotations

import math
import re

import numpy as np

from mechgen.analyses.context import POINTS, PointRunner, run_at_point
from mechgen.analyses.parameters import with_free_params
from mechgen.errors import InputError, SceneError
from mechgen.scene.expr_arrays import evaluate_rows
from mechgen.scene.values import listing, show

#: ``name`` or ``name[i]`` (i 1-based): the inner analysis's output a fit compares
OUTPUT = re.compile(r"([A-Za-z_][A-Za-z0-9_]{0,63})(?:\[([1-9][0-9]{0,8})\])?")


class ExpressionModel:
    """y = expression(columns, constants, parameters) over the rows, with dy/dparameters."""

    def __init__(self, expr, data, constants: dict, parameters: list[str]) -> None:
        self.expr, self.parameters = expr, list(parameters)
        self.values = {**{n: data.columns[n] for n in expr.names if n in data.columns}, **constants}
        self.exact = True

    def predict(self, theta: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(y at the rows, dy/dtheta as (rows, parameters))."""
        values = {n: (v[rows] if isinstance(v, np.ndarray) else v) for n, v in self.values.items()}
        values.update(zip(self.parameters, (float(t) for t in theta)))
        try:
            y, grad = evaluate_rows(self.expr, values, self.parameters, len(rows))
        except SceneError:
            raise
        except InputError as exc:
            raise SceneError(exc.message + f" (parameters {_shown(self.parameters, theta)})", file=exc.file,
                             key=exc.key, expected=exc.expected) from None
        return y, grad.T


def _shown(names, theta) -> str:
    return ", ".join(f"{n} = {float(t):.6g}" for n, t in zip(names, theta))


def _at_point(task: tuple) -> dict:
    """The inner analysis on a copy of the system with the point's parameter values (the Python API's path)."""
    system, kind, options, point = task
    return run_at_point(kind, with_free_params(system, point, key="parameters"), options)


class AnalysisModel:
    """y_i = the inner analysis's output ``output`` at theta and row i's ``inputs``."""

    def __init__(self, system, context: dict, inner, output: tuple, inputs: list[str], data,
                 parameters: list[str], key: str, budget) -> None:
        self.points = context.get(POINTS) or PointRunner(_at_point, lambda kind, opts, point: (system, kind, opts, point))
        self.inner, self.output, self.key, self.budget = inner, output, key, budget
        self.inputs = {n: data.columns[n] for n in inputs}
        self.parameters = list(parameters)
        self.exact = False

    def predict(self, theta: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, None]:
        """(y at the rows, None: no Jacobian)."""
        y = np.empty(len(rows))
        for j, row in enumerate(rows):
            point = {n: float(t) for n, t in zip(self.parameters, theta)}
            point.update({n: float(v[row]) for n, v in self.inputs.items()})
            outputs = self.points.evaluate(self.points.task(self.inner.kind, dict(self.inner.options), point))
            y[j] = self.pick(outputs)
            self.budget.check_time(lambda: f"{j} of {len(rows)} rows at {_shown(self.parameters, theta)}")
        return y, None

    def pick(self, outputs: dict) -> float:
        """The compared output's value (``name`` or ``name[i]``), or a SceneError at ``output``."""
        name, index = self.output
        text = f"{name}[{index}]" if index else name
        scalars = [k for k, v in outputs.items() if _is_number(v)]
        lists = [f"{k}[i]" for k, v in outputs.items() if isinstance(v, list) and v and all(map(_is_number, v))]
        expected = f"a number output of the {self.inner.kind} analysis: " + listing(scalars + lists)
        if name not in outputs:
            raise SceneError(f"the {self.inner.kind} analysis has no output {show(name)}", key=self.key,
                             expected=expected)
        value = outputs[name]
        if index is not None:
            if not isinstance(value, list) or not 1 <= index <= len(value):
                what = f"has {len(value)} entries" if isinstance(value, list) else "is not a list"
                raise SceneError(f"output {show(text)}: '{name}' {what}", key=self.key, expected=expected)
            value = value[index - 1]
        if not _is_number(value) or not math.isfinite(float(value)):
            raise SceneError(f"output {show(text)} is {show(value)}, not a finite number", key=self.key,
                             expected=expected)
        return float(value)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
