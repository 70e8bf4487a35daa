"""Meshes of s in [0, L] built from segments and parts; element dof maps with breaks.

A scene may lay a continuum out as a sequence of uniform *segments* (a stepped
shaft: each with its own length, number of elements and parameter values) and
place lumped *parts* (disks, bearings) at points. The mesh puts a vertex at
every segment interface and every part, and those interior vertices are
*breaks*: where the coefficients or point loads jump, the exact solution of a
first-order (Timoshenko-type) energy has kinks (EI psi_s and kGA (u_s - psi) are
continuous, not psi_s and u_s), so C1 elements there get one derivative dof on
each side and only the values are shared (direct assembly of substructures).
Energies with second derivatives (Euler-Bernoulli) keep C1 continuity everywhere.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Segment:
    """A uniform piece of the domain: its length, element count and parameter values."""

    length: float
    elements: int
    values: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Part:
    """A lumped part of kind ``kind`` at s = ``at`` with its parameter values (short names)."""

    kind: str
    at: float
    values: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Layout:
    """Segments (empty: one uniform segment of the model's length) and parts of a continuum."""

    segments: tuple[Segment, ...] = ()
    parts: tuple[Part, ...] = ()

    @property
    def length(self) -> float | None:
        """Total length of the segments (None without segments)."""
        return float(sum(s.length for s in self.segments)) if self.segments else None


@dataclass(frozen=True)
class Mesh:
    """Vertices, the segment of each element, the interior break vertices and the segment interfaces."""

    nodes: np.ndarray
    segment: np.ndarray
    breaks: np.ndarray
    interfaces: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    @property
    def elements(self) -> int:
        """Number of elements."""
        return len(self.nodes) - 1

    def element_at(self, s: float, side: str = "right") -> int:
        """The element containing s (at an interior vertex: the one to the ``side``, 'right' or 'left')."""
        k = np.searchsorted(self.nodes, s, side="right" if side == "right" else "left") - 1
        return int(np.clip(k, 0, self.elements - 1))


def build_mesh(layout: Layout | None, size: int, length: float) -> Mesh:
    """The mesh of ``layout``: its segments' elements, or ``size`` equal elements on [0, length].

    Raises ValueError when a part is not at a vertex (a clear message names the nearest ones).
    """
    layout = layout or Layout()
    if layout.segments:
        pieces, ids, start = [np.zeros(1)], [], 0.0
        for k, seg in enumerate(layout.segments):
            pieces.append(start + seg.length * np.arange(1, seg.elements + 1) / seg.elements)
            ids.append(np.full(seg.elements, k))
            start += seg.length
        nodes, segment = np.concatenate(pieces), np.concatenate(ids)
        interfaces = np.cumsum([s.elements for s in layout.segments])[:-1]
    else:
        nodes, segment, interfaces = np.linspace(0.0, length, size + 1), np.zeros(size, int), np.zeros(0, int)
    total = nodes[-1]
    at_parts = []
    for part in layout.parts:
        if not -1e-12 * total <= part.at <= total * (1 + 1e-12):
            raise ValueError(f"part {part.kind} at s = {part.at:g} lies outside the domain [0, {total:g}]")
        k = int(np.argmin(np.abs(nodes - part.at)))
        if abs(nodes[k] - part.at) > 1e-9 * total:
            near = ", ".join(f"{x:g}" for x in nodes[max(k - 1, 0):k + 2])
            raise ValueError(f"part {part.kind} at s = {part.at:g} is not at a mesh vertex (nearest: {near}); "
                             "choose segment lengths and element counts that put a vertex there")
        at_parts.append(k)
    breaks = np.array(sorted({int(k) for k in list(interfaces) + at_parts if 0 < k < len(nodes) - 1}), int)
    return Mesh(nodes, segment, breaks, np.asarray(interfaces, int))


def dof_map(nodes_per_element: int, orders: tuple[int, ...], elements: int,
            split: np.ndarray | None = None, apart: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Local-to-global dofs (elements, nodes * len(orders)) of one field, and the field's dof count.

    Element e shares its first vertex with element e - 1; at a vertex in ``split``
    only the order-0 dofs are shared, and the derivative dofs of the two sides are
    separate; at a vertex in ``apart`` nothing is shared (substructures joined by
    constraints).
    """
    per_node = len(orders)
    nloc = nodes_per_element * per_node
    apart_set = {int(v) for v in (apart if apart is not None else ())}
    if (split is None or not len(split)) and not apart_set:
        start = np.arange(elements) * (nodes_per_element - 1) * per_node
        count = (elements * (nodes_per_element - 1) + 1) * per_node
        return start[:, None] + np.arange(nloc), count
    split_set = {int(v) for v in (split if split is not None else ())}
    dofs = np.empty((elements, nloc), np.int64)
    nxt = 0
    previous_end: list[int] = []
    for e in range(elements):
        row = []
        for k in range(nodes_per_element):
            for i, order in enumerate(orders):
                if k == 0 and e > 0 and e not in apart_set and not (order > 0 and e in split_set):
                    row.append(previous_end[i])
                else:
                    row.append(nxt)
                    nxt += 1
        dofs[e] = row
        previous_end = row[-per_node:]
    return dofs, nxt
