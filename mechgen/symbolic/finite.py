"""Laws singular at the values a specialisation folds in: found where a declared function returns, named.

A parameter fixed by a scene is a number inside the declared functions (constant folding), so a
law such as W = p / beta with beta = 0 returns sympy's ``zoo`` (complex infinity), 0/0 returns
``nan``, sqrt of a negative value the imaginary unit. None of these is a real double a kernel could
compute with, and printed they are an error (C) or a silent NaN (Python). The rule: a declared
function's result may hold none of ``zoo``, ``nan``, ``oo``, ``-oo`` or ``I``; when it does, the
parameter whose value causes it is the one that, kept symbolic instead, gives a result without
them. An overflowing but finite constant (1e200**2 = 1e400, a sympy Float) is not refused here:
it is IEEE infinity in double arithmetic, as it would be at run time, and the printers write it
as the backend's infinity (:mod:`mechgen.codegen.printing`).
"""
from __future__ import annotations

import sympy as sp

from mechgen.symbolic.params import Namespace

#: what each refused atom means, for messages
NONFINITE = {sp.zoo: "zoo, complex infinity (a division by zero)", sp.nan: "nan (an undefined value, such as 0/0)",
             sp.oo: "oo (infinity)", -sp.oo: "-oo (minus infinity)", sp.I: "I (an imaginary value)"}


def nonfinite_in(value: object, depth: int = 0) -> list[str]:
    """What refused atoms (:data:`NONFINITE`) ``value`` holds: a sympy object, or a list/tuple/dict of them."""
    if isinstance(value, (sp.Basic, sp.MatrixBase)):
        if isinstance(value, sp.MatrixBase):
            return sorted({w for entry in value for w in nonfinite_in(entry, depth + 1)})
        return [what for atom, what in NONFINITE.items() if value.has(atom)]
    if depth > 3:
        return []
    if isinstance(value, dict):
        value = list(value.values())
    if isinstance(value, (list, tuple)):
        return sorted({w for v in value for w in nonfinite_in(v, depth + 1)})
    return []


def singular_parameter(fn, given: dict) -> tuple[str, object] | None:
    """(name, value) of the fixed parameter that makes ``fn(**given)`` non-finite, or None.

    Each number of the ``p`` namespace in turn is replaced by a real symbol of its name and ``fn``
    called again; the first whose result is then free of :data:`NONFINITE` atoms is the one.
    """
    p = given.get("p")
    if not isinstance(p, Namespace):
        return None
    names = p.names()
    for name in names:
        value = p[name]
        if not isinstance(value, sp.Number):
            continue
        items = {n: (sp.Symbol(name, real=True) if n == name else p[n]) for n in names}
        try:
            again = fn(**{**given, "p": Namespace(items)})
        except Exception:  # noqa: BLE001 - the law may not take a symbol here; then it is not this one
            continue
        if not nonfinite_in(again):
            return name, value
    return None


def number_text(value: object) -> str:
    """A folded value as the user wrote it: ``0.0`` for sympy's 0, ``100.0`` for 100."""
    try:
        return repr(float(value))
    except (TypeError, ValueError, OverflowError):
        return str(value)
