"""Text of a program block's operations (mechgen.codegen.lower_ad), written without sympy.

A program block is CasADi's straight-line program: each :class:`~mechgen.codegen.ir.Operation` is one
arithmetic operation or one function of temporaries, gathered locals and numbers. Building a sympy object for
each (hundreds of thousands for a 64-link pendulum's kernels) and printing it through sympy's printers took
two thirds of such a build, so the backends print them from these tables instead, in three dialects: ``c``
(C99, math.h), ``numpy`` (vectorised, module ``np``) and ``math`` (one point on Python floats, module
``math``: a domain error raises, as :class:`mechgen.codegen.printing.MathPrinter`'s text does).

The forms are those of :mod:`mechgen.codegen.printing`: a small integral power is a bracketed product
(x**3 -> (x*x*x), exact without -ffast-math), x**(1/2) is sqrt, x**-1 is (1.0/x), numbers print with 17
significant digits (repr of the double) and non-finite ones as the dialect's infinity or NaN.
:func:`operation_expr` gives the same operation as a sympy expression, for a backend without a table (CasADi)
and for the tests that compare the two.
"""
from __future__ import annotations

import math

import sympy as sp

from mechgen.codegen.ir import Operation
from mechgen.codegen.printing import MAX_UNROLLED_POWER

#: binary operators and two-argument functions: the format of each dialect ({0}, {1}: the arguments' texts)
_BINARY = {
    "add": ("{0} + {1}",) * 3,
    "sub": ("{0} - {1}",) * 3,
    "mul": ("{0}*{1}",) * 3,
    "div": ("{0}/{1}",) * 3,
    "pow": ("pow({0}, {1})", "{0}**{1}", "math.pow({0}, {1})"),
    "atan2": ("atan2({0}, {1})", "np.arctan2({0}, {1})", "math.atan2({0}, {1})"),
    "fmin": ("fmin({0}, {1})", "np.minimum({0}, {1})", "min({0}, {1})"),
    "fmax": ("fmax({0}, {1})", "np.maximum({0}, {1})", "max({0}, {1})"),
}
#: operators of one argument
_UNARY = {
    "neg": ("-{0}",) * 3,
    "sq": ("{0}*{0}",) * 3,
    "twice": ("2.0*{0}",) * 3,
    "inv": ("1.0/{0}",) * 3,
    "sign": ("(({0} > 0) - ({0} < 0))", "np.sign({0})", "(({0} > 0) - ({0} < 0))"),
    "fabs": ("fabs({0})", "np.abs({0})", "math.fabs({0})"),
}
#: functions of one argument: C99 and math name -> numpy name
_FUNCTIONS = {"sqrt": "sqrt", "exp": "exp", "log": "log", "sin": "sin", "cos": "cos", "tan": "tan",
              "asin": "arcsin", "acos": "arccos", "atan": "arctan", "sinh": "sinh", "cosh": "cosh",
              "tanh": "tanh", "asinh": "arcsinh", "acosh": "arccosh", "atanh": "arctanh"}
DIALECTS = ("c", "numpy", "math")
_INFINITY = {"c": "INFINITY", "numpy": "np.inf", "math": "math.inf"}
_NAN = {"c": "NAN", "numpy": "np.nan", "math": "math.nan"}
#: every operation a program block holds
OPERATIONS = frozenset(_BINARY) | frozenset(_UNARY) | frozenset(_FUNCTIONS) | {"constpow"}


def number_text(value: float, dialect: str) -> str:
    """A double's text: repr (17 significant digits round trip), bracketed when negative; inf and nan named."""
    if math.isnan(value):
        return _NAN[dialect]
    if math.isinf(value):
        return _INFINITY[dialect] if value > 0 else f"(-{_INFINITY[dialect]})"
    return repr(value) if value >= 0 else f"({value!r})"


def _atom(arg, dialect: str) -> str:
    return arg if isinstance(arg, str) else number_text(arg, dialect)


def operation_text(operation: Operation, dialect: str) -> str:
    """The right-hand side of ``operation`` in ``dialect`` (one of :data:`DIALECTS`)."""
    which = DIALECTS.index(dialect)
    op, args = operation.op, [_atom(a, dialect) for a in operation.args]
    if op in _BINARY:
        return _BINARY[op][which].format(*args)
    if op in _UNARY:
        return _UNARY[op][which].format(*args)
    if op in _FUNCTIONS:
        if dialect == "numpy":
            return f"np.{_FUNCTIONS[op]}({args[0]})"
        return f"{'math.' if dialect == 'math' else ''}{op}({args[0]})"
    if op == "constpow":
        return _constant_power(args[0], float(operation.args[1]), dialect)
    raise ValueError(f"operation {op!r} has no text")


def _constant_power(base: str, exponent: float, dialect: str) -> str:
    """base**exponent for a constant exponent: a bracketed product for small integers, sqrt for 1/2."""
    if math.isfinite(exponent) and exponent == int(exponent) and 1 < abs(exponent) <= MAX_UNROLLED_POWER:
        product = "*".join([base] * int(abs(exponent)))
        return f"({product})" if exponent > 0 else f"(1.0/({product}))"
    if exponent == -1:
        return f"(1.0/{base})"
    root = {"c": "sqrt", "numpy": "np.sqrt", "math": "math.sqrt"}[dialect]
    if exponent == 0.5:
        return f"{root}({base})"
    if exponent == -0.5:
        return f"1.0/{root}({base})"
    return _BINARY["pow"][DIALECTS.index(dialect)].format(base, number_text(exponent, dialect))


def atom_expr(arg) -> sp.Expr:
    """A program's atom as sympy: a name (a temporary or gathered local) as a real Symbol, a number as an Integer
    where it is one exactly, else a 17-digit Float (inf and nan included)."""
    if isinstance(arg, str):
        return sp.Symbol(arg, real=True)
    if math.isfinite(arg) and arg == int(arg) and abs(arg) < 2**53:
        return sp.Integer(int(arg))
    return sp.Float(arg, 17)


_SYMPY_BINARY = {"add": lambda x, y: x + y, "sub": lambda x, y: x - y, "mul": lambda x, y: x * y,
                 "div": lambda x, y: x / y, "pow": sp.Pow, "constpow": sp.Pow, "atan2": sp.atan2,
                 "fmin": sp.Min, "fmax": sp.Max}
_SYMPY_UNARY = {"neg": lambda x: -x, "sq": lambda x: x**2, "twice": lambda x: 2 * x, "inv": lambda x: 1 / x,
                "sign": sp.sign, "fabs": sp.Abs, "sqrt": sp.sqrt, "exp": sp.exp, "log": sp.log, "sin": sp.sin,
                "cos": sp.cos, "tan": sp.tan, "asin": sp.asin, "acos": sp.acos, "atan": sp.atan, "sinh": sp.sinh,
                "cosh": sp.cosh, "tanh": sp.tanh, "asinh": sp.asinh, "acosh": sp.acosh, "atanh": sp.atanh}


def operation_expr(operation: Operation) -> sp.Expr:
    """The operation as a sympy expression of real symbols named as its arguments."""
    args = [atom_expr(a) for a in operation.args]
    table = _SYMPY_BINARY if len(args) == 2 else _SYMPY_UNARY
    return table[operation.op](*args)
