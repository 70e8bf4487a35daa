"""Calling what a model declares: :func:`call_declared` calls a user's function with the arguments it names and turns
every failure inside it into a ModelError naming the model file's line; :func:`as_expr` checks that a result is
one scalar sympy expression. Kept apart from :mod:`mechgen.symbolic.model` so that the derivations and the
extensions (rods, plane continua, hybrid modes, initial states) call declarations without importing the Model."""
from __future__ import annotations

import inspect
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import sympy as sp

from mechgen.errors import MechgenError, ModelError
from mechgen.symbolic.finite import nonfinite_in, number_text, singular_parameter
from mechgen.symbolic.params import Namespace, UnknownEntry

if TYPE_CHECKING:
    from mechgen.symbolic.model import Model


def _not_scalar(value: object) -> str | None:
    """What a non-scalar result is (a list, a Matrix ...), or None for a scalar."""
    if isinstance(value, (list, tuple, dict, set)) or isinstance(value, sp.MatrixBase):
        return f"a {type(value).__name__} of {len(value)} {'entry' if len(value) == 1 else 'entries'}"
    if hasattr(value, "shape") and getattr(value, "shape", ()) != ():
        return f"an array of shape {tuple(value.shape)}"
    return None


#: the Model attribute holding the function a scalar result comes from (for the line in messages)
_DECLARED_BY = {"kinetic": "kinetic_fn", "potential": "potential_fn", "dissipation": "dissipation_fn",
                "kinetic_density": "kinetic_fn", "potential_density": "potential_fn",
                "dissipation_density": "dissipation_fn", "complementary_density": "complementary_fn",
                "constraint_density": "constraint_fn", "weak_form": "weak_fn"}


def as_expr(value: object, what: str, model: "Model") -> sp.Expr:
    """A declared function's result as a sympy expression (numbers allowed, text never parsed)."""
    shape = _not_scalar(value)
    if shape is not None:
        fn = getattr(model, _DECLARED_BY.get(what, ""), None) if _DECLARED_BY.get(what) else None
        file, at = _declared_at(fn) if callable(fn) else (model.file, "")
        raise ModelError(f"{at}{what} of model {model.name} returned {shape}, not a scalar", file=file or model.file,
                         key=what,
                         expected="one scalar sympy expression or number (an energy or density is a single number "
                                  "at each state; sum the terms)")
    if isinstance(value, bool) or not isinstance(value, (int, float, sp.Basic)):
        raise ModelError(f"{what} of model {model.name} returned {type(value).__name__}", file=model.file,
                         key=what, expected="a sympy expression or a number")
    if isinstance(value, (int, float)):
        return sp.Float(value, precision=53) if isinstance(value, float) else sp.Integer(value)
    if not isinstance(value, sp.Expr):
        raise ModelError(f"{what} of model {model.name} returned a {type(value).__name__}, not a scalar",
                         file=model.file, key=what, expected="a scalar sympy expression")
    return value


#: what each argument of a declared function holds, for messages
_ARG_KINDS = {"p": "parameter", "q": "coordinate", "v": "velocity", "z": "internal variable", "part": "part parameter",
              "u": "jet", "n": "stress resultant", "out": "output", "s": "site entry", "a": "site entry",
              "b": "site entry"}


def _declared_at(fn: Callable, tb=None) -> tuple[str | None, str]:
    """(file, "line N, in name: ") of a declared function; the line of ``tb`` inside it, else its ``def``."""
    code = getattr(fn, "__code__", None)
    if code is None:
        return None, f"in {getattr(fn, '__name__', fn)!s}: "
    line = code.co_firstlineno
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == code.co_filename:
            line = tb.tb_lineno
        tb = tb.tb_next
    file = code.co_filename if Path(code.co_filename).is_file() else None
    return file, f"line {line}, in {fn.__name__}: "


def _symbols_in(value: object, depth: int = 0) -> set:
    """Free sympy symbols of a value, of a Namespace's entries, or of a list/tuple/dict of them."""
    if isinstance(value, (sp.Basic, sp.MatrixBase)):
        return set(value.free_symbols)
    if depth > 3:
        return set()
    if isinstance(value, Namespace):
        lazy = isinstance(getattr(type(value), "used", None), property)  # Jets: entries made on first use
        items = list(value.used.values()) if lazy else list(value)
        return set().union(*(_symbols_in(v, depth + 1) for v in items)) if items else set()
    if isinstance(value, dict):
        value = list(value.values())
    if isinstance(value, (list, tuple)):
        return set().union(*(_symbols_in(v, depth + 1) for v in value)) if value else set()
    return set()


def call_declared(fn: Callable, **available: object) -> object:
    """Call a declared function with the arguments it names among ``available``.

    Errors are the model's: a name the arguments do not hold (``p.kk``), an exception raised
    inside the function, or a result with sympy symbols no argument provided (a ``sp.Symbol``
    made in the model file) raise :class:`ModelError` naming the function's file, its line
    and what was declared.
    """
    names = list(inspect.signature(fn).parameters)
    unknown = [n for n in names if n not in available]
    if unknown:
        file, at = _declared_at(fn)
        raise ModelError(f"{at}function {fn.__name__} asks for {unknown}, which this declaration does not provide",
                         file=file, key=fn.__name__, expected=f"parameters among {sorted(available)}")
    given = {n: available[n] for n in names}
    try:
        result = fn(**given)
    except MechgenError:
        raise
    except UnknownEntry as exc:
        label = next((n for n, v in given.items() if v is exc.namespace), None)
        file, at = _declared_at(fn, exc.__traceback__)
        kind = _ARG_KINDS.get(label or "", "name")
        asked = f"{label}.{exc.name}" if label else repr(exc.name)
        raise ModelError(f"{at}{asked} is not a declared {kind}", file=file, key=asked,
                         expected=f"one of the declared {kind}s: {', '.join(exc.known) or '(none)'}") from None
    except Exception as exc:  # the model's own code failed on symbols
        file, at = _declared_at(fn, exc.__traceback__)
        raise ModelError(f"{at}{type(exc).__name__}: {exc}", file=file, key=getattr(fn, "__name__", None),
                         expected="a declared function that computes an expression of its arguments") from None
    stray = _symbols_in(result) - set().union(*(_symbols_in(v) for v in available.values()))
    if stray:
        file, at = _declared_at(fn)
        listed = ", ".join(sorted(str(s) for s in stray))
        raise ModelError(f"{at}the result uses {'symbols' if len(stray) > 1 else 'the symbol'} {listed}, which "
                         f"none of its arguments ({', '.join(names) or 'none'}) holds", file=file,
                         key=getattr(fn, "__name__", None),
                         expected=f"expressions of {', '.join(f'{n}.<name>' for n in names) or 'numbers'} only (a "
                                  "sympy Symbol made in the model file is not a parameter: declare it with Param)")
    bad = nonfinite_in(result)
    if bad:
        raise _singular(fn, given, bad)
    return result


def _singular(fn: Callable, given: dict, bad: list[str]) -> ModelError:
    """The error for a declared function whose result holds zoo, nan, oo or I (mechgen.symbolic.finite)."""
    file, at = _declared_at(fn)
    name = getattr(fn, "__name__", "the function")
    found = singular_parameter(fn, given)
    if found is None:
        return ModelError(f"{at}{name} is singular at the fixed parameter values: its result holds "
                          f"{'; '.join(bad)}", file=file, key=name,
                          expected="parameter values at which the declared expressions are finite and real")
    param, value = found
    return ModelError(f"{at}{name} is singular at parameter {param} = {number_text(value)}: its result holds "
                      f"{'; '.join(bad)}", file=file, key=f"params.{param}",
                      expected=f"a value of {param} at which {name} is finite and real")
