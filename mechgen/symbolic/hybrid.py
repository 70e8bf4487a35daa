"""Hybrid models: named modes, each with its own energies, forces and internal laws, and guards between them.

A hybrid model is a lumped model whose equations switch (contact that starts and ends, a projectile
that stops). Declared on a :class:`~mechgen.symbolic.model.Model`::

    flight = model.mode("flight", initial=True)
    contact = model.mode("contact")

    @contact.potential                       # added to the model-wide energies in that mode only
    def spring(q, p):
        return p.k / 2 * q.x**2

    @flight.guard(to="contact", direction="rising")
    def touch(q):                            # an event when g = x crosses 0 upwards
        return q.x

    @contact.guard(to="flight", direction="falling", reset=lambda v, p: {"x_dot": -p.e * v.x})
    def release(q):
        return q.x

    @model.terminal(direction="falling")     # in every mode: stop the run
    def at_rest(v):
        return v.x

In mode ``i`` the equations are those of :func:`mechgen.symbolic.derive.derive_lumped` with the
model-wide terms plus the mode's own (energies and forces add; an internal variable obeys the
mode's law, else the model-wide one, else it is frozen: dz/dt = 0). A guard g(q, v, z, p, t) with a
direction fires when g changes sign that way; its total time derivative along the mode's flow,

    dg/dt = g_q . v + g_v . a + g_z . dz/dt + g_t,

is generated with it (kernel ``guards__i``: outputs ``g`` and ``g_t``). A reset is a map of the
state ``(q, v, z) -> (q+, v+, z+)`` applied at the event (kernel ``reset__j``; entries it does not
name are kept), returned as a dict of names (a coordinate ``x``, its velocity ``x_dot``, an
internal variable) or as a tuple ``(q+, v+[, z+])`` of lists as long as the state's parts.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.names import check_identifier

#: guard directions: the sign change that fires the guard
DIRECTIONS = {"rising": 1, "falling": -1, "both": 0}


@dataclass(frozen=True)
class Guard:
    """An event function leaving mode ``source`` (None: every mode) for mode ``to`` (None: terminal)."""

    name: str
    fn: Callable
    source: str | None
    to: str | None
    direction: int
    reset: Callable | None = None
    terminal: bool = False


def _direction(value: str, model) -> int:
    if value not in DIRECTIONS:
        raise ModelError(f"guard direction {value!r} of model {model.name}", file=model.file, key="guard.direction",
                         expected="one of: " + ", ".join(DIRECTIONS))
    return DIRECTIONS[value]


@dataclass
class ModeScope:
    """The declarations of one mode: the same decorators as :class:`~mechgen.symbolic.model.Model`, scoped."""

    model: object
    name: str
    kinetic_fn: Callable | None = None
    potential_fn: Callable | None = None
    dissipation_fn: Callable | None = None
    forces_fn: Callable | None = None
    rates: dict = field(default_factory=dict)
    outputs: dict = field(default_factory=dict)

    def output(self, name: str, fn: Callable) -> None:
        """This mode's value of an output declared for the model (a contact force: zero in flight, declared
        so for the model, its law in the contact mode)."""
        if name not in {o.name for o in self.model.outputs}:
            raise ModelError(f"mode {self.name} of model {self.model.name} gives output {name!r}, which the model "
                             "does not declare", file=self.model.file, key=f"mode {self.name}.output",
                             expected="an output declared with model.output(...) first")
        self.outputs[name] = fn

    def kinetic(self, fn: Callable) -> Callable:
        """Decorator: kinetic energy T(q, v, z, p, t) added in this mode."""
        self.kinetic_fn = fn
        return fn

    def potential(self, fn: Callable) -> Callable:
        """Decorator: potential energy V(q, z, p, t) added in this mode (a contact spring)."""
        self.potential_fn = fn
        return fn

    def dissipation(self, fn: Callable) -> Callable:
        """Decorator: Rayleigh dissipation R(q, v, z, p) added in this mode, force -dR/dv."""
        self.dissipation_fn = fn
        return fn

    def forces(self, fn: Callable) -> Callable:
        """Decorator: generalized forces {coordinate: Q(q, v, z, p, t)} added in this mode."""
        self.forces_fn = fn
        return fn

    def internal(self, name: str, rate: Callable, *, initial: float = 0.0, doc: str = "") -> None:
        """An internal variable's law dz/dt = rate(q, v, z, p, t) in this mode.

        The variable is part of the state in every mode; declared here first, it is frozen
        (dz/dt = 0) in the modes that give it no law.
        """
        self.model.hybrid_internal(name, initial=initial, doc=doc)
        self.rates[name] = rate

    def guard(self, *, to: str, direction: str = "both", reset: Callable | None = None) -> Callable:
        """Decorator: an event function g(q, v, z, p, t) whose sign change (``direction``: rising, falling,
        both) leaves this mode for mode ``to``, after ``reset`` (a map of the state, see the module doc)."""
        def register(fn: Callable) -> Callable:
            self.model.add_guard(Guard(_guard_name(fn, self.model), fn, self.name, to,
                                       _direction(direction, self.model), reset))
            return fn
        return register

    def terminal(self, *, direction: str = "both") -> Callable:
        """Decorator: an event function that ends the run in this mode (a projectile at rest)."""
        def register(fn: Callable) -> Callable:
            self.model.add_guard(Guard(_guard_name(fn, self.model), fn, self.name, None,
                                       _direction(direction, self.model), None, True))
            return fn
        return register

    @property
    def declares_energy(self) -> bool:
        """Whether the mode adds an energy or a force of its own."""
        return any(f is not None for f in (self.kinetic_fn, self.potential_fn, self.dissipation_fn, self.forces_fn))


def _guard_name(fn: Callable, model) -> str:
    return check_identifier(getattr(fn, "__name__", "guard"), what="guard", file=model.file)


def check_hybrid(model) -> None:
    """Raise ModelError (naming the model file and the item) for a guard in a model without modes, modes in
    a continuum or chain, a guard naming an unknown mode, two guards of one name in a mode, or a mode
    without energies. Called for every model before its derivation (mechgen.pipeline.derive)."""
    modes = list(model.mode_scopes)
    if not modes:
        if model.guards:
            g = model.guards[0]
            raise ModelError(f"guard {g.name!r} of model {model.name} is declared but the model has no modes",
                             file=model.file, key=f"guard {g.name}", expected="model.mode(...) declarations first")
        return
    if model.continuum is not None or model.chain_spec is not None:
        kind = "continuum" if model.continuum is not None else "chain"
        raise ModelError(f"mode {modes[0]!r} of model {model.name}: modes are for lumped models, and this one is a "
                         f"{kind}", file=model.file, key=f"mode {modes[0]}",
                         expected="a model of coordinates (no fields, no chain)")
    seen = set()
    for g in model.guards:
        for end, label in ((g.source, "leaves"), (g.to, "enters")):
            if end is not None and end not in modes:
                raise ModelError(f"guard {g.name!r} of model {model.name} {label} mode {end!r}, which is not "
                                 "declared", file=model.file, key=f"guard {g.name}",
                                 expected="a mode among " + ", ".join(modes))
        if (g.source, g.name) in seen:
            raise ModelError(f"guard name {g.name!r} is used twice in mode {g.source} of model {model.name}",
                             file=model.file, key=f"guard {g.name}", expected="one guard per name and mode")
        seen.add((g.source, g.name))
    if not model.coordinate_names:  # internal variables only (a driven contact): no energies, no inertia
        return
    common = any(f is not None for f in (model.kinetic_fn, model.potential_fn, model.dissipation_fn,
                                         model.forces_fn))
    for name, scope in model.mode_scopes.items():
        if not (common or scope.declares_energy):
            raise ModelError(f"mode {name!r} of model {model.name} has no energies or forces", file=model.file,
                             key=f"mode {name}", expected="a kinetic or potential energy, dissipation or forces "
                             "declared for the model or for the mode")
    if model.kinetic_fn is None and not all(s.kinetic_fn for s in model.mode_scopes.values()):
        missing = [n for n, s in model.mode_scopes.items() if s.kinetic_fn is None]
        raise ModelError(f"mode {missing[0]!r} of model {model.name} has no kinetic energy (no inertia: its "
                         "accelerations are undefined)", file=model.file, key=f"mode {missing[0]}",
                         expected="@model.kinetic, or @<mode>.kinetic in every mode")


def guards_of(model, mode: str) -> list[Guard]:
    """The guards active in ``mode``: terminal ones first (they win a tie), then in declaration order."""
    active = [g for g in model.guards if g.source in (None, mode)]
    return [g for g in active if g.terminal] + [g for g in active if not g.terminal]


def reset_state(model, guard: Guard, values: object, coords, q, v, z) -> list[sp.Expr]:
    """The state (q+, v+, z+) after ``guard``'s reset, from the reset function's result ``values``
    (``coords``: the active coordinates' names, in the order of ``q``)."""
    coords = list(coords)
    internal = [i.name for i in model.internals]
    new = list(q) + list(v) + list(z)
    where = f"reset of guard {guard.name}"
    if isinstance(values, dict):
        names = coords + [f"{c}_dot" for c in coords] + internal
        for key, value in values.items():
            if key not in names:
                raise ModelError(f"{where} of model {model.name} sets {key!r}, which is not a coordinate, "
                                 "velocity or internal variable", file=model.file, key=where,
                                 expected="keys among " + ", ".join(names))
            new[names.index(key)] = value
        return new
    if isinstance(values, (list, tuple)):
        parts = [("coordinates", len(q)), ("velocities", len(v)), ("internal variables", len(z))]
        if len(values) not in (2, 3) or any(not isinstance(p, (list, tuple, sp.MatrixBase)) for p in values):
            raise ModelError(f"{where} of model {model.name} returned {len(values)} entries", file=model.file,
                             key=where, expected="a dict of names, or (q+, v+) or (q+, v+, z+) as lists")
        out = []
        for part, (label, size) in zip(values, parts):
            if len(part) != size:
                raise ModelError(f"{where} of model {model.name} returns {len(part)} {label} for a state of "
                                 f"{size}: a reset cannot change the number of coordinates", file=model.file,
                                 key=where, expected=f"{size} {label}")
            out += list(part)
        return out + new[len(out):]
    raise ModelError(f"{where} of model {model.name} returned {type(values).__name__}", file=model.file, key=where,
                     expected="a dict of names, or (q+, v+) or (q+, v+, z+) as lists")
