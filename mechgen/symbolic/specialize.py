"""Scene specialisation: which parameters are numbers, which stay symbols.

Parameters fixed by a scene are substituted *before* derivation (constant
folding), so a term multiplied by a zero parameter never reaches a kernel.
Parameters listed as free stay symbolic and become a kernel input ``p``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.model import Model
from mechgen.symbolic.names import check_model_names
from mechgen.symbolic.params import Namespace


@dataclass(frozen=True)
class Specialization:
    """Parameter values fixed by a scene, the free parameters and the active coordinates.

    Attributes:
        values: fixed values by parameter name (numbers, sizes, choice strings).
        free: numeric parameters kept symbolic, in model declaration order.
        active: coordinates kept; ``None`` keeps all (others are frozen at zero).
        free_values: starting values of the free parameters (kernel inputs, not folded).
        runtime: names of runtime-only choices (Param.runtime): in ``values`` for the
            numerics, left out of the derivation and of :meth:`key`, so that a new mesh
            size or discretisation reuses the same kernels.
    """

    values: dict = field(default_factory=dict)
    free: tuple[str, ...] = ()
    active: tuple[str, ...] | None = None
    free_values: dict = field(default_factory=dict, compare=False)
    runtime: tuple[str, ...] = ()

    def key(self) -> str:
        """A canonical text of the specialisation (part of the cache key; runtime choices left out)."""
        vals = ",".join(f"{k}={self.values[k]!r}" for k in sorted(self.values) if k not in self.runtime)
        return f"values[{vals}] free[{','.join(self.free)}] active[{','.join(self.active or ())}]"


def all_free(model: Model) -> Specialization:
    """Every numeric parameter symbolic; choices and sizes at their defaults."""
    check_model_names(model)
    values = {p.name: p.default for p in model.param_list if not p.is_numeric}
    free = tuple(p.name for p in model.param_list if p.is_numeric)
    return Specialization(values=values, free=free, runtime=tuple(p.name for p in model.param_list if p.runtime))


def specialize(model: Model, values: dict, *, free: tuple[str, ...] = (), active=None) -> Specialization:
    """Build a :class:`Specialization` from resolved scene values.

    Every numeric parameter not in ``free`` is fixed (to ``values`` or its default);
    the parameters of part kinds (:meth:`Model.part`) are always free. The model's names are
    checked first (:func:`mechgen.symbolic.names.check_model_names`).
    """
    check_model_names(model)
    free = tuple(free) + tuple(n for n in model.part_params() if n not in free)
    fixed: dict = {}
    free_values: dict = {}
    for prm in model.param_list:
        if prm.name in free:
            if not prm.is_numeric:
                raise ModelError(f"parameter {prm.name!r} selects code and cannot be free", file=model.file,
                                 key=prm.name, expected="a numeric parameter")
            free_values[prm.name] = values.get(prm.name, prm.default)
            continue
        fixed[prm.name] = values.get(prm.name, prm.default)
    ordered_free = tuple(p.name for p in model.param_list if p.name in free)
    if active is not None:
        unknown = [c for c in active if c not in model.coordinates_all]
        if unknown:
            raise ModelError(f"unknown active coordinates {unknown}", file=model.file, key="active",
                             expected=f"names among {', '.join(model.coordinates_all)}")
        active = tuple(c for c in model.coordinates_all if c in active)
    for prm in model.param_list:
        value = values.get(prm.name, prm.default)
        if prm.below is not None and prm.is_numeric and not float(value) < prm.below:
            raise ModelError(f"parameter {prm.name} = {value!r} of model {model.name} is not below {prm.below!r}",
                             file=model.file, key=prm.name, expected=f"a value below {prm.below!r}")
    runtime = tuple(p.name for p in model.param_list if p.runtime)
    return Specialization(values=fixed, free=ordered_free, active=active, free_values=free_values, runtime=runtime)


def exact_number(value: float | int) -> sp.Expr:
    """A sympy number equal to the double ``value`` bit for bit (integers stay exact)."""
    if float(value).is_integer() and abs(value) < 2**53:
        return sp.Integer(int(value))
    return sp.Float(float(value), precision=53)


def param_namespace(model: Model, spec: Specialization) -> tuple[Namespace, tuple[sp.Symbol, ...]]:
    """The ``p`` namespace handed to declared functions, and the free symbols in order.

    Every derivation starts here, so the model's names are checked here again (a Specialization
    made by hand skips :func:`specialize`).
    """
    check_model_names(model)
    items: dict = {}
    free_syms = []
    for prm in model.param_list:
        if prm.runtime:
            continue
        if prm.name in spec.free:
            items[prm.name] = prm.symbol
            free_syms.append(prm.symbol)
        elif prm.is_numeric:
            items[prm.name] = exact_number(spec.values[prm.name])
        else:
            items[prm.name] = spec.values.get(prm.name, prm.default)
    return Namespace(items), tuple(free_syms)
