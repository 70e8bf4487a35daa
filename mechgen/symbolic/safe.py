"""Functions with finite limits at a removable singularity, printed with a series branch.

The angle functions of the SO(3)/SE(3) exponentials (sin t / t, (1 - cos t)/t^2, ...) and the section
integrals of a curved rod (atanh(h)/h - 1 ...) are analytic at 0 but their closed forms are 0/0
there and lose digits near it (t - sin t loses eps/t^3). A :class:`SafeFunction` is one such function
of one argument x, kept as an opaque sympy function through derivation and CSE, with

* ``closed(x)``: the closed form (a sympy expression), used where |x| >= ``below``;
* ``coeffs``: exact Taylor coefficients at 0, f(x) = sum_k c_k x^k, used where |x| < ``below``;
* ``fdiff``: its derivative, a SafeFunction of the same kind (closed form differentiated, series too),
  so Jacobians of expressions holding it stay finite at 0.

When lowered (:meth:`SafeFunction.lowered`, what the printers of :mod:`mechgen.codegen.printing` write)
it becomes ``Piecewise((horner series, |x| < below), (closed(x_s), True))`` where ``x_s`` is x outside
the series interval and ``below`` inside it, so neither branch divides by zero (numpy and CasADi evaluate
both). ``closed_form(expr)`` replaces every SafeFunction by its closed form (for simplification), and a
number argument evaluates: exactly at 0, as the series or the closed form at a Float.
"""
from __future__ import annotations

import sympy as sp
from mpmath.libmp import prec_to_dps

_X = sp.Dummy("x", real=True)
_REGISTRY: dict[str, type] = {}


class SafeFunctionBase(sp.Function):
    """Base class of the functions made by :func:`safe_function` (see the module docstring).

    Named ``...Base`` so that sympy's printers dispatch its subclasses to ``_print_SafeFunctionBase`` (they
    skip the printing methods of Function subclasses named otherwise)."""

    nargs = 1
    _closed: sp.Expr = sp.Integer(0)   # in the dummy _X
    _coeffs: tuple = ()
    _below: sp.Expr = sp.Integer(1)
    _base: str = ""
    _order: int = 0

    @classmethod
    def eval(cls, x):
        if x.is_zero:
            return cls._coeffs[0] if cls._coeffs else sp.Integer(0)
        if x.is_Float:
            return cls._value(x, x._prec)
        return None

    @classmethod
    def _value(cls, x: sp.Float, prec: int) -> sp.Float:
        """The value at a Float (binary precision ``prec``), from its exact rational: the series inside its
        interval (truncation below 1e-20), else the closed form with 20 guard digits against cancellation."""
        exact, dps = sp.Rational(x), prec_to_dps(prec)
        if abs(exact) < cls._below:
            return sp.Float(sp.Add(*[c * exact**k for k, c in enumerate(cls._coeffs)]).evalf(dps + 5), dps)
        value = cls._closed.xreplace({_X: exact}).evalf(dps + 20)
        # outside the function's domain (a log of a negative number, a pole) the value stays complex or zoo,
        # which the specialisation refuses naming the parameter (mechgen.symbolic.finite)
        return sp.Float(value, dps) if value.is_real and value.is_finite else value

    def fdiff(self, argindex=1):
        return derivative_of(type(self))(self.args[0])

    @classmethod
    def coefficients(cls) -> tuple:
        """The exact Taylor coefficients c_0, c_1, ... at 0 (f(x) = sum_k c_k x^k)."""
        return cls._coeffs

    @classmethod
    def series_below(cls) -> sp.Expr:
        """The series interval's bound: the series is used where |x| < this."""
        return cls._below

    def closed(self) -> sp.Expr:
        """The closed form at this argument."""
        return self._closed.xreplace({_X: self.args[0]})

    def series(self) -> sp.Expr:
        """The truncated Taylor series at this argument, in Horner form."""
        x = self.args[0]
        out = sp.Integer(0)
        for c in reversed(self._coeffs):
            out = out * x + c
        return out

    def lowered(self) -> sp.Expr:
        """Piecewise((series, |x| < below), (closed form at a safe argument, True)): finite everywhere."""
        x = self.args[0]
        small = sp.Abs(x) < self._below
        # x outside the series interval, ``below`` inside; an Add, so that sympy does not fold the Piecewise
        # into the powers of the closed form (1/Piecewise((1, c), (x, True)) -> Piecewise((1, c), (1/x, True)))
        safe = x + sp.Piecewise((self._below - x, small), (0, True))
        return sp.Piecewise((self.series(), small), (self._closed.xreplace({_X: safe}), True))

    def _eval_evalf(self, prec):
        x = self.args[0].evalf(prec)
        if x.is_Number:
            return type(self)._value(x, prec)
        return None


#: the public name of the base class
SafeFunction = SafeFunctionBase


def safe_function(name: str, closed: sp.Lambda, coeffs, below) -> type:
    """The SafeFunction class ``name`` with closed form ``closed`` (a one-argument Lambda), Taylor coefficients
    ``coeffs`` (exact sympy numbers, c_0 first) and series interval |x| < ``below``; made once per name."""
    if name in _REGISTRY:
        return _REGISTRY[name]
    cls = type(name, (SafeFunctionBase,), {"_closed": closed(_X), "_coeffs": tuple(sp.sympify(c) for c in coeffs),
                                       "_below": sp.sympify(below), "_base": name, "_order": 0})
    _REGISTRY[name] = cls
    return cls


def derivative_of(cls: type) -> type:
    """The SafeFunction of d/dx of ``cls``: the closed form differentiated, the series term by term."""
    name = f"{cls._base}_d{cls._order + 1}"
    if name not in _REGISTRY:
        coeffs = tuple(k * c for k, c in enumerate(cls._coeffs))[1:]
        _REGISTRY[name] = type(name, (SafeFunctionBase,), {"_closed": sp.diff(cls._closed, _X), "_coeffs": coeffs,
                                                       "_below": cls._below, "_base": cls._base,
                                                       "_order": cls._order + 1})
    return _REGISTRY[name]


def closed_form(expr):
    """``expr`` (an expression or a Matrix) with every SafeFunction replaced by its closed form."""
    def one(e):
        return e.replace(lambda a: isinstance(a, SafeFunctionBase), lambda a: a.closed())
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(one)
    return one(sp.sympify(expr))


def lowered(expr):
    """``expr`` (an expression or a Matrix) with every SafeFunction replaced by its Piecewise (series | closed)."""
    def one(e):
        return e.replace(lambda a: isinstance(a, SafeFunctionBase), lambda a: a.lowered())
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(one)
    return one(sp.sympify(expr))
