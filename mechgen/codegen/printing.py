"""Expression printers for the backends (C99, numpy, CasADi).

Small integer powers become bracketed products (``(x*x*x)``: exact and fast
without -ffast-math), x**(1/2) becomes sqrt, x**-n becomes (1.0/(...)). Numbers print
with 17 significant digits so a double survives the round trip.

A number whose double is not finite (a constant folded at specialisation that overflows, such as
1e200**2, or an integer beyond the double range) prints as the backend's infinity or NaN
(C99 ``INFINITY``/``NAN`` of ``math.h``; ``np.inf``/``np.nan`` in the numpy and CasADi modules,
which import numpy), never as a bare ``inf`` (a Python name). Other named constants (E, the
Euler-Mascheroni constant ...) print as their doubles. ``zoo`` (complex infinity, a division by
zero) and the imaginary unit have no real value: printing them is an error (the specialisation
refuses such laws first, :func:`mechgen.symbolic.specialize.check_finite`). Symbol names pass
:func:`mechgen.codegen.escape.code_identifier`.
"""
from __future__ import annotations

import math

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.pycode import PythonCodePrinter

MAX_UNROLLED_POWER = 8


def _double(value) -> float:
    """The double of a sympy or Python number; +-inf where it overflows (an integer beyond 1.8e308)."""
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


class _Numbers:
    """Number printing shared by the backends: ``_INF``/``_NAN`` name the backend's infinity and NaN."""

    _INF = "INFINITY"
    _NAN = "NAN"

    def _number(self, value: float) -> str:
        if math.isnan(value):
            return self._NAN
        if math.isinf(value):
            return self._INF if value > 0 else f"(-{self._INF})"
        return repr(value)

    def _print_Float(self, expr):
        return self._number(_double(expr))

    def _print_Integer(self, expr):
        return self._number(_double(expr))

    def _print_Infinity(self, expr):
        return self._number(math.inf)

    def _print_NegativeInfinity(self, expr):
        return self._number(-math.inf)

    def _print_NaN(self, expr):
        return self._NAN

    def _print_NumberSymbol(self, expr):
        return self._number(_double(expr))

    _print_Exp1 = _print_EulerGamma = _print_GoldenRatio = _print_Catalan = _print_TribonacciConstant = \
        _print_NumberSymbol

    def _print_ComplexInfinity(self, expr):
        raise ValueError("zoo (complex infinity: a division by zero) has no value in generated code")

    def _print_ImaginaryUnit(self, expr):
        raise ValueError("the imaginary unit I has no value in real generated code")

    def _print_Symbol(self, expr):
        from mechgen.codegen.escape import code_identifier

        return code_identifier(expr.name)

    def _rational(self, expr) -> str | None:
        """``p/q`` as two doubles when both are finite (the form kernels have always had), else None."""
        p, q = _double(expr.p), _double(expr.q)
        if math.isfinite(p) and math.isfinite(q):
            return f"{p!r}/{q!r}"
        return None


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


class CPrinter(_Numbers, C99CodePrinter):
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
        return self._rational(expr) or self._number(_double(expr))

    def _print_Pi(self, expr):
        return repr(float(sp.pi))

    def _print_signed_power(self, expr):
        x, n = (self._print(a) for a in expr.args)
        return f"copysign(pow(fabs({x}), {n}), {x})"

    def _print_abs_power(self, expr):
        x, n = (self._print(a) for a in expr.args)
        return f"pow(fabs({x}), {n})"

    def _print_SafeFunctionBase(self, expr):
        """A function with a finite limit (mechgen.symbolic.safe): its series | closed-form Piecewise."""
        return self._print(expr.lowered())


class NumpyPrinter(_Numbers, PythonCodePrinter):
    """Printer for vectorised numpy code (module imported as ``np``)."""

    _module = "np"
    _INF = "np.inf"
    _NAN = "np.nan"
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

    def _print_signed_power(self, expr):
        x, n = (self._print(a) for a in expr.args)
        m = self._module
        return f"({m}.sign({x})*{m}.{self._np_names['Abs'] if 'Abs' in self._np_names else 'abs'}({x})**({n}))"

    def _print_abs_power(self, expr):
        x, n = (self._print(a) for a in expr.args)
        m = self._module
        return f"({m}.{self._np_names['Abs'] if 'Abs' in self._np_names else 'abs'}({x})**({n}))"

    def _print_Pow(self, expr, rational=False):
        text = _power_text(self, expr)
        if text is not None:
            return text
        base, exp = expr.as_base_exp()
        if exp == sp.Rational(1, 2):
            return f"{self._module}.sqrt({self._print(base)})"
        return self._general_power(base, sp.Float(exp) if exp.is_Rational else exp)

    def _general_power(self, base, exp) -> str:
        """base**exp for an exponent that is neither a small integer nor 1/2."""
        return f"{self.parenthesize(base, 60)}**{self.parenthesize(exp, 60)}"

    def _print_Rational(self, expr):
        text = self._rational(expr)
        return f"({text})" if text else self._number(_double(expr))

    def _print_Pi(self, expr):
        return f"{self._module}.pi"

    def _print_SafeFunctionBase(self, expr):
        """A function with a finite limit (mechgen.symbolic.safe): its series | closed-form Piecewise."""
        return self._print(expr.lowered())

    _IF = "np.where"

    def _print_Piecewise(self, expr):
        """Elementwise: np.where(c1, e1, np.where(c2, e2, ...)) (CasADi: ca.if_else); the last condition is True."""
        *pieces, (last, cond) = expr.args
        if cond != sp.true:
            raise NotImplementedError("a Piecewise without a final True branch has no value everywhere")
        text = self._print(last)
        for e, c in reversed(pieces):
            text = self._choice(self._print(c), self._print(e), text)
        return text

    def _choice(self, cond: str, then: str, otherwise: str) -> str:
        """The text of "then where cond, else otherwise"."""
        return f"{self._IF}({cond}, {then}, {otherwise})"

    def _print_Relational(self, expr):
        lhs, rhs = (self.parenthesize(a, 40) for a in (expr.lhs, expr.rhs))
        return f"({lhs} {expr.rel_op} {rhs})"


class MathPrinter(NumpyPrinter):
    """Printer for one point on Python floats (module ``math``): the numpy backend's single-point path, where a
    numpy call per operation on 1-element arrays would cost ten times the arithmetic. A domain error raises
    (ValueError, ArithmeticError) instead of giving nan or inf: the caller then runs the numpy path, whose values
    and diagnostics stand."""

    _module = "math"
    _INF = "math.inf"
    _NAN = "math.nan"
    _np_names = {"Abs": "fabs"}

    def _print_Function(self, expr):
        fname = type(expr).__name__
        args = [self._print(a) for a in expr.args]
        if fname in ("Max", "Min"):
            if len(args) != 2:
                raise NotImplementedError("Max/Min of more than two arguments")
            return f"{fname.lower()}({args[0]}, {args[1]})"
        if fname == "sign":
            return f"(({args[0]} > 0) - ({args[0]} < 0))"
        return super()._print_Function(expr)

    _print_sin = _print_cos = _print_tan = _print_asin = _print_acos = _print_atan = _print_Function
    _print_atan2 = _print_sinh = _print_cosh = _print_tanh = _print_exp = _print_log = _print_Function
    _print_Abs = _print_sign = _print_Max = _print_Min = _print_Function

    def _print_signed_power(self, expr):
        x, n = (self._print(a) for a in expr.args)
        return f"math.copysign(math.pow(math.fabs({x}), {n}), {x})"

    def _print_abs_power(self, expr):
        x, n = (self._print(a) for a in expr.args)
        return f"math.pow(math.fabs({x}), {n})"

    def _general_power(self, base, exp) -> str:
        """math.pow: a negative base with a fractional exponent raises (Python's ** would give a complex)."""
        return f"math.pow({self._print(base)}, {self._print(exp)})"

    def _choice(self, cond: str, then: str, otherwise: str) -> str:
        return f"({then} if {cond} else {otherwise})"


def math_code(expr: sp.Expr) -> str:
    """Python text of an expression on floats (module ``math``)."""
    return MathPrinter().doprint(expr)


class CasadiPrinter(NumpyPrinter):
    """Printer for CasADi SX construction code (module imported as ``ca``; numpy as ``np``, whose ``np.inf`` and
    ``np.nan`` are the non-finite constants)."""

    _module = "ca"
    _IF = "ca.if_else"
    _np_names = {"asin": "asin", "acos": "acos", "atan": "atan", "atan2": "atan2", "Abs": "fabs",
                 "Max": "fmax", "Min": "fmin", "sign": "sign"}

    def _print_Pi(self, expr):
        return repr(float(sp.pi))


_C_PRINTER: list = []


def c_code(expr: sp.Expr) -> str:
    """C99 text of an expression (one printer, made once: a CodePrinter resets its state in every doprint, and
    making one costs more than printing a small expression)."""
    if not _C_PRINTER:
        _C_PRINTER.append(CPrinter())
    return _C_PRINTER[0].doprint(expr)


def numpy_code(expr: sp.Expr) -> str:
    """numpy text of an expression."""
    return NumpyPrinter().doprint(expr)


def casadi_code(expr: sp.Expr) -> str:
    """CasADi text of an expression."""
    return CasadiPrinter().doprint(expr)
