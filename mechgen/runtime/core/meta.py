"""Typed metadata of a compiled system, read once from the kernel meta.

The kernel meta is a JSON dict written by the lowering (codegen.lower_lumped, lower_lattice, the
pipeline's field facts) and stored beside every generated kernel. A compiled system keeps that dict
readable as ``system.meta`` (a read-only mapping, for compatibility) and offers this typed view as
``system.metadata``: the keys the analyses read, with their defaults in one place.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

KINDS = ("lumped", "field", "lattice")


@dataclass(frozen=True)
class SystemMeta:
    """What a compiled system's kernels say of their model.

    Attributes:
        model: the model's name (Model.name), None when the meta does not say.
        source: the canonical reference the pipeline recorded (mechgen.models.resolve), "" when none;
            :attr:`reference` falls back to ``model``.
        kind: "lumped", "field" or "lattice" ("lumped" when the meta does not say).
        params: the free parameters, in the order of ``system.params``.
        coordinates: the coordinate names (a lattice: the one coordinate of every site).
        internal: the internal variables' names.
        whirl: the (x, y) coordinate pair of a rotor's whirl (Model.whirl), None when the model has none; a
            lumped model with several stations: x1, y1, x2, y2, ...
        sites_param: a lattice's parameter for its number of sites, None otherwise.
        ends: a lattice's ends ("fixed", "free", ...), None otherwise.
    """

    model: str | None = None
    source: str = ""
    kind: str = "lumped"
    params: tuple[str, ...] = ()
    coordinates: tuple[str, ...] = ()
    internal: tuple[str, ...] = ()
    whirl: tuple[str, ...] | None = None
    sites_param: str | None = None
    ends: str | None = None

    @classmethod
    def of(cls, meta: Mapping) -> "SystemMeta":
        """The typed view of a kernel meta dict (missing keys take the defaults above)."""
        whirl = meta.get("whirl")
        return cls(model=meta.get("model"), source=meta.get("source") or "", kind=meta.get("kind") or "lumped",
                   params=tuple(meta.get("params", ())), coordinates=tuple(meta.get("coordinates", ())),
                   internal=tuple(meta.get("internal", ())), whirl=tuple(whirl) if whirl else None,
                   sites_param=meta.get("sites_param"), ends=meta.get("ends"))

    @property
    def reference(self) -> str | None:
        """The reference that finds the model again in any process: ``source``, else ``model``."""
        return self.source or self.model

    @property
    def is_lattice(self) -> bool:
        """True for chain models."""
        return self.kind == "lattice"
