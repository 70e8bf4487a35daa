"""A model's initial state as a function of its parameters (a projectile striking at speed p.Vs).

Declared with ``@model.initial`` as a function of ``p`` (and ``t``) returning a dict of state names,
a coordinate ``x``, its velocity ``x_dot`` or an internal variable, to values; names it leaves out start
at 0. It becomes the kernel ``initial`` (output ``x``: the state (q, v, z), 2n + m entries), so that a
sweep, a fit or a scene run at other parameter values starts where the model says without an
expression per run; a scene's ``q0`` / ``v0`` entries replace the ones they name.
"""
from __future__ import annotations

import sympy as sp

from mechgen.errors import ModelError


def initial_column(model, p_ns, coordinates, internal_names) -> sp.Matrix | None:
    """The initial state of ``model`` as a column of 2n + m expressions of the parameters ``p_ns`` (the active
    ``coordinates``, then their velocities, then the internal variables); None when none is declared."""
    from mechgen.symbolic.declared import as_expr, call_declared

    fn = getattr(model, "initial_fn", None)
    if fn is None:
        return None
    values = call_declared(fn, p=p_ns, t=sp.Integer(0))
    names = list(coordinates) + [f"{c}_dot" for c in coordinates] + list(internal_names)
    if not isinstance(values, dict):
        raise ModelError(f"initial state of model {model.name} is a {type(values).__name__}", file=model.file,
                         key="initial", expected="a dict of coordinate, velocity (<x>_dot) or internal names")
    column = [sp.Integer(0)] * len(names)
    frozen = set(model.coordinate_names) - set(coordinates)
    for key, value in values.items():
        if key in frozen or (isinstance(key, str) and key.endswith("_dot") and key[:-4] in frozen):
            continue  # an inactive coordinate stays at rest
        if key not in names:
            raise ModelError(f"initial state of model {model.name} sets {key!r}, which is not a coordinate, "
                             "velocity or internal variable", file=model.file, key="initial",
                             expected="keys among " + ", ".join(names))
        column[names.index(key)] = as_expr(value, "initial", model)
    return sp.Matrix(column)
