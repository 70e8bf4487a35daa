"""Typed field facts of a compiled continuum, read once from the kernel meta's ``"field"`` dict.

The lowering (mechgen.codegen.lower_model.field_meta) writes beside every kernel of a continuum what the runtime
needs of its local piece: the fields, the jets the energy uses, the length parameter, the end terms and part kinds,
the essential conditions, the shear pairs of a Timoshenko-type energy. :class:`FieldMeta` is that dict as a frozen
value with its defaults in one place; ``FieldSystem.field_meta`` holds it, and ``FieldSystem.info`` keeps the dict
itself readable for analyses and users.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping


@dataclass(frozen=True)
class FieldMeta:
    """What a continuum's kernels say of its discretisable piece.

    Attributes:
        fields: the field names, in dof order.
        jets: (field, order) of every jet the energy uses (order: the number of s-derivatives).
        length: the name of the length parameter (m, or the model's length unit).
        constraints: (field, order, "start" | "end") of every essential end condition.
        points: the end terms' names ("start", "end"), each with kernels ``<kernel>_at_<name>``.
        parts: (kind, parameter short names) of every part kind the model declares.
        shear_pairs: (w, psi, sign) of every shear pair (Model.shear_pair), for the timoshenko2 element.
        constant_mass: True when d rho / d j_tt depends on no state (M factorised once in time integration).
        boundary_values: True when an essential condition prescribes a value other than zero.
    """

    fields: tuple[str, ...]
    jets: tuple[tuple[str, int], ...]
    length: str
    constraints: tuple[tuple[str, int, str], ...] = ()
    points: tuple[str, ...] = ()
    parts: tuple[tuple[str, tuple[str, ...]], ...] = ()
    shear_pairs: tuple[tuple, ...] = ()
    constant_mass: bool = False
    boundary_values: bool = False

    @classmethod
    def of(cls, info: Mapping) -> "FieldMeta":
        """The typed view of a kernel meta's ``"field"`` dict (optional keys missing take the defaults above)."""
        return cls(fields=tuple(info["fields"]), jets=tuple((f, int(k)) for f, k in info["jets"]),
                   length=info["length"], constraints=tuple((f, int(k), at) for f, k, at in info["constraints"]),
                   points=tuple(info.get("points", ())),
                   parts=tuple((kind, tuple(names)) for kind, names in info.get("parts", {}).items()),
                   shear_pairs=tuple(tuple(p) for p in info.get("shear_pairs", ())),
                   constant_mass=bool(info.get("constant_mass")), boundary_values=bool(info.get("boundary_values")))

    @property
    def part_kinds(self) -> tuple[str, ...]:
        """The declared part kinds, in the meta's (sorted) order."""
        return tuple(kind for kind, _ in self.parts)

    @property
    def njets(self) -> int:
        """How many jets each point carries."""
        return len(self.jets)
