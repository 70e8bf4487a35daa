"""mechgen.scene.expr_arrays: a parsed expression over arrays, with its gradient.

References: the scalar evaluator of mechgen.scene.expr (Expression.evaluate, row by row) for the
values, central differences of that scalar evaluator for the gradients, and the closed-form
derivative d/dk (K + k d0/d) = d0/d.
"""
from __future__ import annotations

import numpy as np
import pytest

from mechgen.errors import InputError
from mechgen.scene.expr import parse_expression
from mechgen.scene.expr_arrays import evaluate_rows

EXPRESSIONS = [
    "K + k * (d0 / d)", "a * exp(-t / tau) + c", "sin(a * t) * cos(b) - tan(0.3 * a)", "asin(0.5 * x / (1 + x)) + acos(0.1) + atan(a * x)",
    "atan2(a, x + 2) + sinh(0.1 * a) * cosh(b) / (1 + tanh(x))", "log(x + 3) + log(a + 2, b + 2) + sqrt(a * a + x)",
    "abs(a - x) + min(a, x, b) * max(a * x, 1) - a ** 2 / (b ** 1.5) + x ** a", "-(+a) / 2 + pi * e",
]


@pytest.mark.parametrize("text", EXPRESSIONS)
def test_values_and_gradients_match_the_scalar_evaluator(text):
    expr = parse_expression(text)
    rng = np.random.default_rng(3)
    n = 7
    columns = {"x": rng.uniform(0.2, 2.0, n), "t": rng.uniform(0.0, 3.0, n), "d": rng.uniform(5.0, 30.0, n)}
    params = {"a": 0.7, "b": 1.3, "c": -0.4, "K": 600.0, "k": 86.0, "tau": 1.7, "d0": 25.4}
    wrt = [p for p in ("a", "b", "c", "K", "k", "tau") if p in expr.names]
    values = {**columns, **params}
    v, g = evaluate_rows(expr, values, wrt, n)
    for i in range(n):
        row = {**{c: float(col[i]) for c, col in columns.items()}, **params}
        assert v[i] == pytest.approx(expr.evaluate(row), rel=1e-14, abs=1e-14)
        for j, name in enumerate(wrt):
            h = 1e-6 * max(1.0, abs(params[name]))
            up, down = dict(row), dict(row)
            up[name] += h
            down[name] -= h
            central = (expr.evaluate(up) - expr.evaluate(down)) / (2 * h)
            assert g[j, i] == pytest.approx(central, rel=1e-6, abs=1e-7)


def test_linear_gradient_is_the_closed_form():
    expr = parse_expression("K + k * (d0 / d)")
    d = np.array([7.1, 12.7, 25.4])
    v, g = evaluate_rows(expr, {"d": d, "d0": 25.4, "K": 607.0, "k": 86.0}, ["K", "k", "unused"], 3)
    np.testing.assert_array_equal(g[0], 1.0)
    np.testing.assert_allclose(g[1], 25.4 / d, rtol=1e-15)
    np.testing.assert_array_equal(g[2], 0.0)
    np.testing.assert_allclose(v, 607.0 + 86.0 * 25.4 / d, rtol=1e-15)


@pytest.mark.parametrize("text, message", [("sqrt(x - 1)", "row 2"), ("log(x - 1)", "row 1"), ("1 / (x - 2)", "row 3"),
                                           ("x ** 20000", "exponent"), ("exp(1000 * x)", "row 1")])
def test_domain_errors_name_the_first_bad_row(text, message):
    with pytest.raises(InputError, match=message):
        evaluate_rows(parse_expression(text, key="analysis[1].expression"), {"x": np.array([1.0, 0.5, 2.0])}, [], 3)


def test_an_unknown_name_is_refused():
    with pytest.raises(InputError, match="unknown name 'y'"):
        evaluate_rows(parse_expression("x + y"), {"x": 1.0}, [], 2)
