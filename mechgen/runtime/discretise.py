"""Discretising fields on s in [0, L]: jet tables at Gauss points, dof maps, constraint rows.

Every discretisation is a set of *elements*; a global basis is one element
spanning [0, L]. For element e, quadrature point q, jet a = (field, order) and
local dof l, ``tables[e, q, a, l]`` = D_s^order phi_l(s_eq) (zero outside the
field's block), so the jets at the points are j = tables @ x[dofs] and the
discretised energies are sums of w_eq * density(j_eq) (DESIGN.md: numeric over
the repetition). Fields are numbered field-major.

Quadrature (Gauss-Legendre per element), chosen from the basis when not given:
polynomial elements of degree P use P + 1 points (mass and stiffness products of
degree <= 2P exact); sine/cosine/beam bases with N functions use 2N + 8 points
(products oscillate up to wavenumber 2 N pi / L: 64 points for 60 sines leave a
15 % mass error, 128 give 1e-14); Legendre bases of N polynomials N + 1 points.
Fewer points than the minimum give an :class:`UnderIntegrationWarning`.

Elements are uniform, so every element has the same table: ``tables`` is then a
read-only broadcast view (stride 0 along the elements) of one reference table,
which the assembly recognises and uses (mechgen.runtime.assemble). Gauss rules and
global-basis tables are memoised (read-only arrays): the beam basis needs its
roots and a high-order normalisation rule, and a sweep or a refinement study
rebuilds the same discretisation many times.
"""
from __future__ import annotations

import warnings
from collections import OrderedDict
from contextlib import suppress
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from mechgen.runtime import bases
from mechgen.runtime.elements import reference

ELEMENTS = ("hermite", "quintic", "lagrange1", "lagrange2")
GLOBAL = ("sine", "cosine", "legendre", "beam")
DISCRETISATIONS = ELEMENTS + GLOBAL


class UnderIntegrationWarning(UserWarning):
    """The chosen quadrature integrates the basis products inexactly."""


@dataclass(frozen=True)
class Discretisation:
    """Jet tables, weights and dof maps of one discretisation of the fields."""

    kind: str
    size: int
    length: float
    fields: tuple[str, ...]
    jets: tuple[tuple[str, int], ...]
    points: np.ndarray
    weights: np.ndarray
    tables: np.ndarray
    dofs: np.ndarray
    ndof: int
    ends: dict

    @property
    def is_global(self) -> bool:
        """True for a global basis (one element, dense matrices)."""
        return self.kind in GLOBAL

    def field_dofs(self, field: str) -> np.ndarray:
        """Global dof numbers of ``field``."""
        per = self.ndof // len(self.fields)
        i = self.fields.index(field)
        return np.arange(i * per, (i + 1) * per)

    def row(self, field: str, order: int, at: float) -> np.ndarray:
        """The dense row c with c @ x = D_s^order u_field(at)."""
        out = np.zeros(self.ndof)
        per = self.ndof // len(self.fields)
        offset = self.fields.index(field) * per
        if self.is_global:
            table = _global_table(self.kind, np.array([at]), self.size, self.length, order,
                                  self.ends.get(field, ("free", "free")))
            out[offset:offset + per] = table[0, order]
            return out
        ref = reference(self.kind)
        nodes = self.size
        h = self.length / nodes
        e = min(int(at / h), nodes - 1)
        table = ref.tabulate(np.array([at / h - e]), order, np.array([h]))[0, 0, order]
        out[offset + _element_field_dofs(ref, e)] = table
        return out


def _element_field_dofs(ref, e) -> np.ndarray:
    """Local-to-global dofs of element e (an int: (ndof,); an array of elements: (len(e), ndof))."""
    per_node = len(ref.orders)
    start = np.asarray(e) * (len(ref.nodes) - 1) * per_node
    return start[..., None] + np.arange(ref.ndof) if np.ndim(start) else start + np.arange(ref.ndof)


_TABLES: OrderedDict = OrderedDict()  # memoised global-basis tables, least recently used first
_TABLES_MAX_BYTES = 64 << 20


def _global_table(kind, s, n, length, max_order, ends) -> np.ndarray:
    """D_s^k phi_j at the points s: (len(s), max_order + 1, n), memoised (read-only; 64 MiB in all at most)."""
    s = np.ascontiguousarray(s, dtype=float)
    key = (kind, s.tobytes(), int(n), float(length), int(max_order), tuple(ends))
    table = _TABLES.get(key)
    if table is not None:
        with suppress(KeyError):  # another thread may just have dropped it
            _TABLES.move_to_end(key)
        return table
    if kind in ("sine", "cosine"):
        table = bases.trig(kind, s, n, length, max_order)
    elif kind == "legendre":
        table = bases.legendre(s, n, length, max_order)
    else:
        table = bases.beam(s, n, length, max_order, ends)
    table.setflags(write=False)
    if table.nbytes <= _TABLES_MAX_BYTES // 8:
        _TABLES[key] = table
        while len(_TABLES) > 1 and sum(t.nbytes for t in list(_TABLES.values())) > _TABLES_MAX_BYTES:
            with suppress(KeyError):
                _TABLES.popitem(last=False)
    return table


@lru_cache(maxsize=64)
def _gauss(nq: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [0, 1] (read-only)."""
    xg, wg = np.polynomial.legendre.leggauss(nq)
    xi, wi = (xg + 1) / 2, wg / 2
    xi.setflags(write=False)
    wi.setflags(write=False)
    return xi, wi


def minimum_points(kind: str, size: int) -> tuple[int, int]:
    """(automatic, minimum) Gauss points per element for a discretisation of this size."""
    if kind in ELEMENTS:
        p = reference(kind).degree
        return p + 1, p + 1
    if kind == "legendre":
        return size + 1, size
    return 2 * size + 8, 2 * size + 2


def end_conditions(constraints, field: str) -> tuple[str, str]:
    """'clamped' / 'pinned' / 'free' at (start, end) of a field from its constraints (for the beam basis)."""
    out = []
    for at in ("start", "end"):
        orders = {c[1] for c in constraints if c[0] == field and c[2] == at}
        out.append("clamped" if {0, 1} <= orders else "pinned" if 0 in orders else "free")
    return tuple(out)


def discretise(kind: str, size: int, length: float, fields, jets, *, quadrature: int = 0,
               constraints=()) -> Discretisation:
    """Tables of ``jets`` ((field, order) pairs) for ``size`` elements or basis functions per field."""
    if kind not in DISCRETISATIONS:
        raise ValueError(f"unknown discretisation {kind!r}")
    if size < 1:
        raise ValueError(f"discretisation size must be >= 1, got {size}")
    if not length > 0:
        raise ValueError(f"domain length must be > 0, got {length}")
    fields = tuple(fields)
    auto, minimum = minimum_points(kind, size)
    nq = quadrature or auto
    if nq < minimum:
        warnings.warn(f"{nq} Gauss points per element under-integrate the {kind} basis of size {size} "
                      f"(at least {minimum} needed)", UnderIntegrationWarning, stacklevel=2)
    xi, wi = _gauss(nq)
    max_order = max((k for _, k in jets), default=0)
    ends = {f: end_conditions(constraints, f) for f in fields}
    for f in fields:
        if kind == "sine" and "free" in ends[f]:
            raise ValueError(f"the sine basis forces {f} = 0 at both ends, but the boundary conditions leave {f} "
                             f"free at the {'start' if ends[f][0] == 'free' else 'end'}: choose legendre, beam, "
                             "cosine or finite elements")
    if kind in GLOBAL:
        points = (xi * length)[None, :]
        weights = (wi * length)[None, :]
        per = size
        local = {f: _global_table(kind, points[0], size, length, max_order, ends[f])[None] for f in fields}
        base_dofs = np.arange(per)[None, :]
    else:
        ref = reference(kind)
        if max_order > max(ref.continuity, 0) + 1:
            raise ValueError(f"the {kind} element is C{ref.continuity}: energies with derivatives of order "
                             f"{max_order} need a C{max_order - 1} discretisation (hermite or quintic, or a global basis)")
        h = np.full(size, length / size)
        starts = np.arange(size) * (length / size)
        points = starts[:, None] + xi[None, :] * h[:, None]
        weights = wi[None, :] * h[:, None]
        per = (size * (len(ref.nodes) - 1) + 1) * len(ref.orders)
        shared = ref.tabulate(xi, max_order, h[:1])
        local = {f: shared for f in fields}  # one table for every (equal) element
        base_dofs = _element_field_dofs(ref, np.arange(size))
    nloc = base_dofs.shape[1]
    tables = np.zeros((1,) + points.shape[1:] + (len(jets), nloc * len(fields)))
    for a, (f, k) in enumerate(jets):
        i = fields.index(f)
        tables[:, :, a, i * nloc:(i + 1) * nloc] = local[f][:, :, k, :]
    if tables.shape[0] != points.shape[0]:
        tables.setflags(write=False)
        tables = np.broadcast_to(tables, points.shape + tables.shape[2:])
    dofs = np.concatenate([base_dofs + i * per for i in range(len(fields))], axis=1)
    return Discretisation(kind, size, float(length), fields, tuple(jets), points, weights, tables, dofs,
                          per * len(fields), ends)
