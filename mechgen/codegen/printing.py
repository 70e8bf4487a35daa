"""Expression printers for the backends (C99, numpy, CasADi).

Small integer powers become bracketed products (``(x*x*x)``: exact and fast
without -ffast-math), x**(1/2) becomes sqrt, x**-n becomes (1.0/(...)). Numbers print
with 17 significant digits so a double survives the round trip.
"""
from __future__ import annotations

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.pycode import PythonCodePrinter

MAX_UNROLLED_POWER = 8


def _power_text(printer, expr: sp.Pow) -> str | None:
    base, exp = expr.as_base_exp()
    if exp.is_Integer and 1 < abs(int(exp)) <= MAX_UNROLLED_POWER:
        b = printer.parenthesize(base, sp.printing.precedence.PRECEDENCE["Mul"])
        prod = "*".join([b] * abs(int(exp)))
        # parenthesised: the Mul printer places a Pow after '/' unbracketed (Pow binds tighter), and
        # a/(b*b) printed as a/b*b would be (a/b)*b
        return f"({prod})" if exp > 0 else f"(1.0/({prod}))"
    if exp == -1:
        return f"(1.0/{printer.parenthesize(base, sp.printing.precedence.PRECEDENCE['Mul'])})"
    return None


class CPrinter(C99CodePrinter):
    """C99 printer for kernel expressions (doubles only)."""

    def _print_Pow(self, expr):
        text = _power_text(self, expr)
        if text is not None:
            return text
        base, exp = expr.as_base_exp()
        if exp == sp.Rational(1, 2):
            return f"sqrt({self._print(base)})"
        if exp == sp.Rational(-1, 2):
            return f"1.0/sqrt({self._print(base)})"
        return f"pow({self._print(base)}, {self._print(sp.Float(exp) if exp.is_Rational else exp)})"

    def _print_Rational(self, expr):
        return f"{float(expr.p)!r}/{float(expr.q)!r}"

    def _print_Integer(self, expr):
        return f"{float(expr)!r}"

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Pi(self, expr):
        return repr(float(sp.pi))


class NumpyPrinter(PythonCodePrinter):
    """Printer for vectorised numpy code (module imported as ``np``)."""

    _module = "np"
    _functions = {"sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log",
                  "sqrt", "Abs", "sign", "Max", "Min"}
    _np_names = {"asin": "arcsin", "acos": "arccos", "atan": "arctan", "atan2": "arctan2", "Abs": "abs",
                 "Max": "maximum", "Min": "minimum"}

    def _print_Function(self, expr):
        fname = type(expr).__name__
        if fname not in self._functions:
            raise NotImplementedError(f"function {fname} has no {self._module} translation")
        args = ", ".join(self._print(a) for a in expr.args)
        if fname in ("Max", "Min") and len(expr.args) > 2:
            raise NotImplementedError("Max/Min of more than two arguments")
        return f"{self._module}.{self._np_names.get(fname, fname)}({args})"

    _print_sin = _print_cos = _print_tan = _print_asin = _print_acos = _print_atan = _print_Function
    _print_atan2 = _print_sinh = _print_cosh = _print_tanh = _print_exp = _print_log = _print_Function
    _print_Abs = _print_sign = _print_Max = _print_Min = _print_Function

    def _print_Pow(self, expr, rational=False):
        text = _power_text(self, expr)
        if text is not None:
            return text
        base, exp = expr.as_base_exp()
        if exp == sp.Rational(1, 2):
            return f"{self._module}.sqrt({self._print(base)})"
        return f"{self.parenthesize(base, 60)}**{self.parenthesize(sp.Float(exp) if exp.is_Rational else exp, 60)}"

    def _print_Rational(self, expr):
        return f"({float(expr.p)!r}/{float(expr.q)!r})"

    def _print_Integer(self, expr):
        return f"{float(expr)!r}"

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Pi(self, expr):
        return f"{self._module}.pi"


class CasadiPrinter(NumpyPrinter):
    """Printer for CasADi SX construction code (module imported as ``ca``)."""

    _module = "ca"
    _np_names = {"asin": "asin", "acos": "acos", "atan": "atan", "atan2": "atan2", "Abs": "fabs",
                 "Max": "fmax", "Min": "fmin", "sign": "sign"}

    def _print_Pi(self, expr):
        return repr(float(sp.pi))


def c_code(expr: sp.Expr) -> str:
    """C99 text of an expression."""
    return CPrinter().doprint(expr)


def numpy_code(expr: sp.Expr) -> str:
    """numpy text of an expression."""
    return NumpyPrinter().doprint(expr)


def casadi_code(expr: sp.Expr) -> str:
    """CasADi text of an expression."""
    return CasadiPrinter().doprint(expr)
