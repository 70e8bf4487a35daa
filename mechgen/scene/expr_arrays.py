"""A parsed expression evaluated over arrays (one entry per data row), with its exact gradient.

:mod:`mechgen.scene.expr` parses and checks expression text (the only parser of user text);
this module walks the checked tree of an :class:`~mechgen.scene.expr.Expression` with numpy
arrays instead of floats, in forward mode: every node carries its value v (n,) and, for the
names in ``wrt``, dv/dw (len(wrt), n). The derivative rules are those of calculus:

    (a b)' = a' b + a b',  (a / b)' = (a' - (a/b) b') / b,  (a^b)' = b a^(b-1) a' + a^b ln(a) b',
    sin' = cos, cos' = -sin, tan' = 1 + tan^2, asin' = 1/sqrt(1-x^2), acos' = -1/sqrt(1-x^2),
    atan' = 1/(1+x^2), atan2(y, x)' = (x y' - y x') / (x^2 + y^2), sinh' = cosh, cosh' = sinh,
    tanh' = 1 - tanh^2, exp' = exp, log(x)' = x'/x, log(x, b) = ln x / ln b, sqrt' = 1/(2 sqrt),
    abs' = sign, min/max: the derivative of the argument chosen (the first, on a tie).

The semantics are :meth:`Expression.evaluate`'s: every intermediate value finite (a domain error,
a division by zero, an overflow is a non-finite value here) and |exponent| <= MAX_EXPONENT, else
an InputError naming the expression and the first data row (1-based) at fault; the gradient must
be finite too. A gradient is only carried where a subtree uses a name of ``wrt``.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from mechgen.errors import InputError
from mechgen.scene.expr import MAX_EXPONENT, Expression

_UNARY = {
    "sin": (np.sin, lambda x, v: np.cos(x)), "cos": (np.cos, lambda x, v: -np.sin(x)),
    "tan": (np.tan, lambda x, v: 1.0 + v * v), "asin": (np.arcsin, lambda x, v: 1.0 / np.sqrt(1.0 - x * x)),
    "acos": (np.arccos, lambda x, v: -1.0 / np.sqrt(1.0 - x * x)), "atan": (np.arctan, lambda x, v: 1.0 / (1.0 + x * x)),
    "sinh": (np.sinh, lambda x, v: np.cosh(x)), "cosh": (np.cosh, lambda x, v: np.sinh(x)),
    "tanh": (np.tanh, lambda x, v: 1.0 - v * v), "exp": (np.exp, lambda x, v: v),
    "log": (np.log, lambda x, v: 1.0 / x), "sqrt": (np.sqrt, lambda x, v: 0.5 / v),
    "abs": (np.abs, lambda x, v: np.sign(x)),
}


class _Walk:
    """One evaluation: the bound values, the names differentiated and the expression (for messages)."""

    def __init__(self, expr: Expression, values: Mapping[str, object], wrt: Sequence[str], rows: int) -> None:
        self.expr, self.values, self.wrt, self.rows = expr, values, list(wrt), rows

    def error(self, what: str, bad: np.ndarray) -> InputError:
        row = int(np.flatnonzero(bad)[0]) + 1
        return InputError(f"expression {self.expr.text!r} {what} at data row {row}", file=self.expr.file,
                          key=self.expr.key, expected="arguments inside each function's domain and finite values")

    def finite(self, v: np.ndarray) -> np.ndarray:
        bad = ~np.isfinite(v)
        if bad.any():
            raise self.error("is not finite (a domain error, a division by zero or an overflow)", bad)
        return v

    def leaf(self, name: str):
        v = np.broadcast_to(np.asarray(self.values[name], dtype=float), (self.rows,))
        if name not in self.wrt:
            return self.finite(v), None
        g = np.zeros((len(self.wrt), self.rows))
        g[self.wrt.index(name)] = 1.0
        return self.finite(v), g

    def node(self, node: tuple):
        tag = node[0]
        if tag == "num":
            return np.full(self.rows, node[1]), None
        if tag == "name":
            return self.leaf(node[1])
        if tag == "unary":
            v, g = self.node(node[2])
            return (-v, None if g is None else -g) if node[1] == "-" else (v, g)
        if tag == "bin":
            return self.binary(node[1], self.node(node[2]), self.node(node[3]))
        return self.call(node[1], [self.node(a) for a in node[2]])

    def binary(self, op: str, left, right):
        (a, ga), (b, gb) = left, right
        if op in "+-":
            sign = 1.0 if op == "+" else -1.0
            v = self.finite(a + sign * b)
            return v, _add(ga, None if gb is None else sign * gb)
        if op == "*":
            return self.finite(a * b), _add(_scale(ga, b), _scale(gb, a))
        if op == "/":
            v = self.finite(a / b)
            g = _add(ga, _scale(gb, -v))
            return v, None if g is None else g / b
        big = np.abs(b) > MAX_EXPONENT
        if big.any():
            raise self.error(f"has an exponent of magnitude above {MAX_EXPONENT:g}", big)
        v = self.finite(np.power(a, b))
        g = None
        if ga is not None:
            g = _scale(ga, b * np.power(a, b - 1.0))
        if gb is not None:
            g = _add(g, _scale(gb, np.where(v == 0.0, 0.0, v * np.log(np.where(a > 0, a, 1.0)))))
            negative = (a < 0) & np.any(gb != 0, axis=0)
            if negative.any():
                raise self.error("has a negative base under an exponent that is differentiated", negative)
        return v, g

    def call(self, name: str, args: list):
        if name in ("min", "max"):
            stack = np.stack([v for v, _ in args])
            pick = (np.argmin if name == "min" else np.argmax)(stack, axis=0)
            v = np.take_along_axis(stack, pick[None], axis=0)[0]
            if all(g is None for _, g in args):
                return v, None
            grads = np.stack([np.zeros((len(self.wrt), self.rows)) if g is None else g for _, g in args])
            return v, np.take_along_axis(grads, pick[None, None, :].repeat(len(self.wrt), 1), axis=0)[0]
        if name == "atan2":
            (y, gy), (x, gx) = args
            r2 = x * x + y * y
            return self.finite(np.arctan2(y, x)), _add(_scale(gy, x / r2), _scale(gx, -y / r2))
        if name == "log" and len(args) == 2:
            (x, gx), (base, gb) = args
            lx, lb = np.log(x), np.log(base)
            self.finite(lx)
            v = self.finite(lx / lb)
            return v, _add(_scale(gx, 1.0 / (x * lb)), _scale(gb, -v / (base * lb)))
        function, derivative = _UNARY[name]
        (x, gx), = args
        v = self.finite(function(x))
        return v, None if gx is None else _scale(gx, derivative(x, v))


def _add(a, b):
    if a is None:
        return b
    return a if b is None else a + b


def _scale(g, factor):
    return None if g is None else g * factor


def evaluate_rows(expr: Expression, values: Mapping[str, object], wrt: Sequence[str],
                  rows: int) -> tuple[np.ndarray, np.ndarray]:
    """The expression's value at each of ``rows`` rows and its gradient with respect to ``wrt``.

    Args:
        expr: a parsed expression (mechgen.scene.expr.parse_expression).
        values: name -> a number or an array of ``rows`` numbers, for every name the expression uses.
        wrt: the names to differentiate with respect to.
        rows: the number of rows.

    Returns:
        (value (rows,), gradient (len(wrt), rows)); a row of the gradient is zero for a name the
        expression does not use.

    Raises:
        InputError: an unknown name, or a non-finite value or derivative (naming the first row).
    """
    missing = [n for n in expr.names if n not in values]
    if missing:
        raise InputError(f"unknown name '{missing[0]}' in expression {expr.text!r}", file=expr.file, key=expr.key,
                         expected="one of the known names: " + ", ".join(sorted(values)))
    walk = _Walk(expr, values, wrt, rows)
    with np.errstate(all="ignore"):
        v, g = walk.node(expr.tree)
        g = np.zeros((len(walk.wrt), rows)) if g is None else np.array(g, dtype=float)
        bad = ~np.isfinite(g)
        if bad.any():
            name = walk.wrt[int(np.flatnonzero(bad.any(axis=1))[0])]
            raise walk.error(f"has a derivative with respect to {name} that is not finite", bad.any(axis=0))
    return np.array(v, dtype=float), g
