"""Model parameters: name, default, unit, description.

A parameter is either numeric (a float, or an integer *size* such as the
number of chain sites, which never enters an expression) or a *choice* among
strings (a constitutive law, a boundary condition), which selects code paths
at declaration time and never enters an expression either.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.names import check_identifier, declaring_file


@dataclass(frozen=True)
class Param:
    """A model parameter.

    Args:
        name: identifier used in scenes (``--set name=value``) and JSON.
        default: default value (float, int for sizes, str for choices).
        unit: unit string for documentation ("kg", "N/m", "" for nondimensional).
        doc: one-line description.
        integer: the parameter is an integer (implied for sizes).
        size: the parameter is a runtime size (number of sites); never symbolic.
        choices: allowed strings for a choice parameter.
        positive: the parameter must be > 0 (also used as a sympy assumption).
        runtime: a choice of the numerics only (a continuum's discretisation, N ...):
            declared functions never see it, so it never changes a derivation.
        below: an exclusive upper bound the value must stay under (checked when a
            scene or a specialisation sets it), e.g. 1 for a length parameter
            lambda0 = (l0 - h)/l0 that would make l0 negative.
        minimum, maximum: inclusive bounds of the value (a Poisson ratio from -1 to 0.5,
            a size's largest sensible count), checked when a scene sets it
            (mechgen.scene.bounds). Bounds are facts for validation only: they are no
            sympy assumptions and never change a derivation.
    """

    name: str
    default: float | int | str
    unit: str = ""
    doc: str = ""
    integer: bool = False
    size: bool = False
    choices: tuple[str, ...] | None = None
    positive: bool = False
    runtime: bool = False
    below: float | None = None
    minimum: float | None = None
    maximum: float | None = None
    symbol: sp.Symbol = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_identifier(self.name, what="parameter")
        if self.size:
            object.__setattr__(self, "integer", True)
        self._check_bounds()
        if isinstance(self.default, str) and not self.choices:
            object.__setattr__(self, "choices", (self.default,))
        assumptions = {"real": True}
        if self.positive:
            assumptions["positive"] = True
        object.__setattr__(self, "symbol", sp.Symbol(self.name, **assumptions))

    def _check_bounds(self) -> None:
        """A numeric default is a finite number (an integer for a size); ``below``, ``minimum`` and
        ``maximum`` are finite numbers, minimum <= maximum, and the default keeps every bound
        (ModelError naming the declaring file)."""
        import math

        def error(message: str, key: str, expected: str) -> ModelError:
            return ModelError(f"parameter {self.name}: {message}", file=declaring_file(), key=f"{self.name}.{key}",
                              expected=expected)

        default = self.default
        if not isinstance(default, str):
            if isinstance(default, bool) or not isinstance(default, (int, float)) or not math.isfinite(default):
                raise error(f"default {default!r} is not a finite number or a string", "default",
                            "a finite number (a string for a choice)")
            if self.integer and not float(default).is_integer():
                raise error(f"default {default!r} is not an integer", "default", "an integer default for a size")
            if self.positive and not default > 0:
                raise error(f"default {default!r} is not positive", "default", "a default > 0 (positive=True)")
        if self.below is not None and (isinstance(self.below, bool) or not isinstance(self.below, (int, float))
                                       or not math.isfinite(self.below)):
            raise error(f"below = {self.below!r} is not a finite number", "below", "a finite number or None")
        if self.below is not None and not isinstance(default, str) and not default < self.below:
            raise error(f"default {default!r} is not below {self.below!r}", "default", f"a default below {self.below!r}")
        for what in ("minimum", "maximum"):
            bound = getattr(self, what)
            if bound is not None and (isinstance(bound, bool) or not isinstance(bound, (int, float))
                                      or not math.isfinite(bound)):
                raise error(f"{what} = {bound!r} is not a finite number", what, "a finite number or None")
        low, high = self.minimum, self.maximum
        if low is not None and high is not None and not low <= high:
            raise error(f"minimum {low!r} is above maximum {high!r}", "minimum", "minimum <= maximum")
        if not isinstance(self.default, str):
            if (low is not None and self.default < low) or (high is not None and self.default > high):
                raise error(f"default {self.default!r} is outside [{low!r}, {high!r}]", "default",
                            "a default within the declared minimum and maximum")

    @property
    def is_choice(self) -> bool:
        """True for string-valued parameters (selectors, not numbers)."""
        return self.choices is not None

    @property
    def is_numeric(self) -> bool:
        """True for parameters that may appear in expressions (a runtime number, such as a plane mesh's size h,
        never does)."""
        return not self.is_choice and not self.size and not self.runtime


class UnknownEntry(AttributeError, KeyError):
    """A name a :class:`Namespace` does not hold (``p.kk`` where no parameter kk is declared).

    An AttributeError (and, for ``ns["kk"]``, a KeyError) that knows the namespace, the
    name asked for and the names it holds, so that the caller of a declared function can
    say which function asked for what (:func:`mechgen.symbolic.declared.call_declared`).
    """

    def __init__(self, namespace: "Namespace", name: str) -> None:
        self.namespace, self.name, self.known = namespace, name, namespace.names()
        super().__init__(f"no entry {name!r}; known: {', '.join(self.known) or '(none)'}")

    def __str__(self) -> str:
        return self.args[0]


class Namespace:
    """Attribute and index access to a fixed, ordered set of named values.

    ``ns.x`` and ``ns["x"]`` and ``ns[0]`` give the same entry; ``list(ns)``
    iterates the values in declaration order. An unknown name raises
    :class:`UnknownEntry`.
    """

    def __init__(self, items: dict[str, object]) -> None:
        object.__setattr__(self, "_items", dict(items))
        object.__setattr__(self, "_order", list(items))

    def __getattr__(self, name: str) -> object:
        if name.startswith("_"):  # copy and pickle probe for dunders (and _items before it is set)
            raise AttributeError(name)
        try:
            return self._items[name]
        except KeyError:
            raise UnknownEntry(self, name) from None

    def __getitem__(self, key: int | str) -> object:
        if isinstance(key, int):
            return self._items[self._order[key]]
        try:
            return self._items[key]
        except KeyError:
            raise UnknownEntry(self, key) from None

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError("namespaces are read-only")

    def __iter__(self):
        return iter(self._items[k] for k in self._order)

    def __len__(self) -> int:
        return len(self._order)

    def names(self) -> list[str]:
        """Entry names in declaration order."""
        return list(self._order)
