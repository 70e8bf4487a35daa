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
Fewer points than the minimum are refused (InputError at params.quadrature, exit 2): the mass matrix would be
singular, and whether a solver notices depends on round-off (:class:`UnderIntegrationWarning`, which they used to
give, is kept for callers that name it).

Elements are uniform, so every element has the same table: ``tables`` is then a
read-only broadcast view (stride 0 along the elements) of one reference table,
which the assembly recognises and uses (mechgen.runtime.fields.assemble). Gauss rules and
global-basis tables are memoised (read-only arrays): the beam basis needs its
roots and a high-order normalisation rule, and a sweep or a refinement study
rebuilds the same discretisation many times.
"""
from __future__ import annotations

from collections import OrderedDict
from contextlib import suppress
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.fields import bases
from mechgen.runtime.fields.elements import reference, timoshenko_shapes
from mechgen.runtime.fields.mesh import Mesh, build_mesh, dof_map

ELEMENTS = ("hermite", "quintic", "lagrange1", "lagrange2", "timoshenko2")
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
    mesh: Mesh | None = None
    tabulate: Callable | None = None

    @property
    def is_global(self) -> bool:
        """True for a global basis (one element, dense matrices)."""
        return self.kind in GLOBAL

    def field_dofs(self, field: str) -> np.ndarray:
        """Global dof numbers of ``field``."""
        per = self.ndof // len(self.fields)
        i = self.fields.index(field)
        return np.arange(i * per, (i + 1) * per)

    def row(self, field: str, order: int, at: float, side: str = "right") -> np.ndarray:
        """The dense row c with c @ x = D_s^order u_field(at) (at a vertex: from the element to the ``side``)."""
        out = np.zeros(self.ndof)
        per = self.ndof // len(self.fields)
        offset = self.fields.index(field) * per
        if self.is_global:
            table = _global_table(self.kind, np.array([at]), self.size, self.length, order,
                                  self.ends.get(field, ("free", "free")))
            out[offset:offset + per] = table[0, order]
            return out
        mesh = self.mesh
        e = mesh.element_at(at, side)
        h = mesh.nodes[e + 1] - mesh.nodes[e]
        table = self.tabulate(np.array([e]), np.array([(at - mesh.nodes[e]) / h]))[0, 0]
        out[self.dofs[e]] = table[self.jets.index((field, order))]
        return out


def _elements(kind, size, length, fields, jets, xi, wi, max_order, ends, mesh, shear, joints) -> Discretisation:
    """Finite elements on ``mesh`` (default: ``size`` equal elements); see :func:`discretise`."""
    mesh = mesh or build_mesh(None, size, length)
    if kind == "timoshenko2":
        if max_order > 1:
            raise ValueError("the timoshenko2 element interpolates w (cubic) and psi (quadratic) for energies "
                             f"of first order in s; these energies need order {max_order}")
        nodes, orders, continuity = (0.0, 1.0), (0,), 0
    else:
        ref = reference(kind)
        nodes, orders, continuity = ref.nodes, ref.orders, ref.continuity
        if max_order > max(continuity, 0) + 1:
            raise ValueError(f"the {kind} element is C{continuity}: energies with derivatives of order "
                             f"{max_order} need a C{max_order - 1} discretisation (hermite or quintic, or a global basis)")
    h = np.diff(mesh.nodes)
    points = mesh.nodes[:-1, None] + xi[None, :] * h[:, None]
    weights = wi[None, :] * h[:, None]
    split = mesh.breaks if max_order <= 1 and max(orders) > 0 else None
    apart = mesh.interfaces if joints == "multiplier" else None
    base_dofs, per = dof_map(len(nodes), orders, mesh.elements, split, apart)
    nloc = base_dofs.shape[1]
    if kind == "timoshenko2":
        tabulate = _timoshenko_tabulator(fields, jets, h, shear, nloc)
    else:
        tabulate = _reference_tabulator(ref, fields, jets, h, max_order, nloc)
    if np.ptp(h) <= 1e-14 * h[0] and kind != "timoshenko2":
        tables = tabulate(np.zeros(1, int), xi)  # one table for every (equal) element
        tables.setflags(write=False)
        tables = np.broadcast_to(tables, points.shape + tables.shape[2:])
    else:
        tables = tabulate(np.arange(mesh.elements), xi)
    dofs = np.concatenate([base_dofs + i * per for i in range(len(fields))], axis=1)
    return Discretisation(kind, mesh.elements, float(mesh.nodes[-1]), fields, tuple(jets), points, weights, tables,
                          dofs, per * len(fields), ends, mesh, tabulate)


def _reference_tabulator(ref, fields, jets, h, max_order, nloc) -> Callable:
    """(elements, xi) -> tables (len(elements), len(xi), jets, dofs) of a reference element, fields independent."""

    def tabulate(elements: np.ndarray, xi: np.ndarray) -> np.ndarray:
        local = ref.tabulate(xi, max_order, h[elements])
        out = np.zeros(local.shape[:2] + (len(jets), nloc * len(fields)))
        for a, (f, k) in enumerate(jets):
            i = fields.index(f)
            out[:, :, a, i * nloc:(i + 1) * nloc] = local[:, :, k, :]
        return out

    return tabulate


def _timoshenko_tabulator(fields, jets, h, shear, nloc) -> Callable:
    """(elements, xi) -> tables of the two-node Timoshenko element: each pair (w, psi) shares its four dofs."""
    if shear is None:
        raise ValueError("the timoshenko2 element needs the model's shear pairs (model.shear_pair) and ratios")
    pairs, phi = shear
    paired = {f for w, psi, _ in pairs for f in (w, psi)}
    lone = [f for f in fields if f not in paired]
    if lone:
        raise ValueError(f"the timoshenko2 element pairs displacements with section rotations; fields {lone} are "
                         "in no shear pair (model.shear_pair)")

    def tabulate(elements: np.ndarray, xi: np.ndarray) -> np.ndarray:
        out = np.zeros((len(elements), len(xi), len(jets), nloc * len(fields)))
        for k, (w, psi, sign) in enumerate(pairs):
            shapes = timoshenko_shapes(xi, h[elements], phi[elements, k], sign, 1)
            iw, ip = fields.index(w), fields.index(psi)
            cols = np.r_[iw * nloc:(iw + 1) * nloc, ip * nloc:(ip + 1) * nloc]
            for a, (f, order) in enumerate(jets):
                if f in (w, psi):
                    out[:, :, a, cols] = shapes[:, :, 0 if f == w else 1, order, :]
        return out

    return tabulate


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
    if kind == "timoshenko2":
        return 4, 4  # cubic w, quadratic psi: products of degree <= 6 exact
    if kind in ELEMENTS:
        p = reference(kind).degree
        return p + 1, p + 1
    if kind == "legendre":
        return size + 1, size
    return 2 * size + 8, 2 * size + 2


def footprint(kind: str, size: int, nfields: int, njets: int, quadrature: int = 0) -> tuple[int, int, str]:
    """(bytes of discretising and assembling, bytes of the Gauss rule, what they hold): an estimate (float64).

    With nq Gauss points per element, na jets, nl dofs per element and field count nf:

    * a global basis of N functions (ndof = nf N, one element): jet tables nq na ndof, basis tables
      nq (na + 1) N per field, and the dense ndof x ndof matrices M, D, G, K with their element
      copies: 8 ndof^2;
    * N finite elements: per element nq (4 + 3 na + 4 na^2 + na nl) (points, jets, pointwise
      coefficients, tables) and 15 nl^2 (element matrices, the CSR pattern and its index map);
    * the Gauss rule (numpy's leggauss: the nq x nq companion matrix and its eigen-solver copy): 2 nq^2.

    Integers throughout (no overflow at N = 1e6 or 1e308).
    """
    size, nfields, njets = int(size), max(int(nfields), 1), max(int(njets), 1)
    if kind not in DISCRETISATIONS or size < 1:
        return 0, 0, "nothing"  # refused with its own message by discretise
    nq = int(quadrature) or minimum_points(kind, size)[0]
    gauss = dense_bytes(2, nq, nq)
    if kind in GLOBAL:
        ndof = nfields * size
        data = dense_bytes(nq, njets, ndof) + nfields * dense_bytes(nq, njets + 1, size) + dense_bytes(8, ndof, ndof)
        return data, gauss, f"the {kind} basis of {size} functions per field (dense {ndof} x {ndof} matrices)"
    per = 2 if kind == "timoshenko2" else reference(kind).ndof
    nl = per * nfields
    data = dense_bytes(size, nq * (4 + 3 * njets + 4 * njets**2 + njets * nl) + 15 * nl**2)
    return data, gauss, f"{size} {kind} elements ({size * nq} Gauss points, {nl} dofs per element)"


def check_size(kind: str, size: int, nfields: int, njets: int, quadrature: int = 0, *, key: str = "params.N") -> None:
    """Refuse (InputError at ``key`` (the size) or params.quadrature, exit 2) a discretisation that cannot fit in
    memory, before anything is allocated (mechgen.runtime.core.memory)."""
    data, gauss, what = footprint(kind, size, nfields, njets, quadrature)
    fix = f"a smaller {key.rpartition('.')[2]}"
    if kind in GLOBAL:
        fix += (", or finite elements (discretisation = 'lagrange2', 'hermite', ...: sparse matrices, the lowest "
                "modes by shift-invert)")
    require(data, what, key=key, expected=fix)
    nq = int(quadrature) or (minimum_points(kind, int(size))[0] if kind in DISCRETISATIONS else 0)
    require(gauss, f"the Gauss rule of {nq} points", key="params.quadrature" if quadrature else key,
            expected="fewer Gauss points" if quadrature else fix)


def end_conditions(constraints, field: str) -> tuple[str, str]:
    """'clamped' / 'pinned' / 'free' at (start, end) of a field from its constraints (for the beam basis)."""
    out = []
    for at in ("start", "end"):
        orders = {c[1] for c in constraints if c[0] == field and c[2] == at}
        out.append("clamped" if {0, 1} <= orders else "pinned" if 0 in orders else "free")
    return tuple(out)


def discretise(kind: str, size: int, length: float, fields, jets, *, quadrature: int = 0,
               constraints=(), mesh: Mesh | None = None, shear=None, joints: str = "assembly") -> Discretisation:
    """Tables of ``jets`` ((field, order) pairs) for ``size`` elements or basis functions per field.

    Elements may lie on a given ``mesh`` (segments and parts, mechgen.runtime.fields.mesh);
    ``timoshenko2`` needs ``shear`` = ([(w, psi, sign), ...], phi of shape (elements, pairs)).
    ``joints = "multiplier"`` keeps the segments apart (no dof shared at their interfaces);
    the caller then joins them by constraints.
    """
    if kind not in DISCRETISATIONS:
        raise ValueError(f"unknown discretisation {kind!r}")
    if size < 1:
        raise ValueError(f"discretisation size must be >= 1, got {size}")
    if not length > 0:
        raise ValueError(f"domain length must be > 0, got {length}")
    fields = tuple(fields)
    check_size(kind, size, len(fields), len(jets), quadrature)
    auto, minimum = minimum_points(kind, size)
    nq = quadrature or auto
    if nq < minimum:
        # refused, not warned: an under-integrated mass matrix is singular or nearly so, and whether a solver
        # notices depends on the BLAS kernel's round-off (a run that returns garbage under one kernel)
        raise InputError(f"{nq} Gauss points per element under-integrate the {kind} basis of size {size}: its mass "
                         "matrix would be singular", key="params.quadrature",
                         expected=f"at least {minimum} points (a Gauss rule of q points is exact to degree 2q - 1), "
                                  "or 0 for the automatic rule")
    xi, wi = _gauss(nq)
    max_order = max((k for _, k in jets), default=0)
    ends = {f: end_conditions(constraints, f) for f in fields}
    for f in fields:
        if kind == "sine" and "free" in ends[f]:
            raise ValueError(f"the sine basis forces {f} = 0 at both ends, but the boundary conditions leave {f} "
                             f"free at the {'start' if ends[f][0] == 'free' else 'end'}: choose legendre, beam, "
                             "cosine or finite elements")
    if kind not in GLOBAL:
        return _elements(kind, size, length, fields, jets, xi, wi, max_order, ends, mesh, shear, joints)
    points = (xi * length)[None, :]
    weights = (wi * length)[None, :]
    per = size
    tables = np.zeros((1, len(xi), len(jets), per * len(fields)))
    for a, (f, k) in enumerate(jets):
        i = fields.index(f)
        tables[0, :, a, i * per:(i + 1) * per] = _global_table(kind, points[0], size, length, max_order, ends[f])[:, k, :]
    base_dofs = np.arange(per)[None, :]
    dofs = np.concatenate([base_dofs + i * per for i in range(len(fields))], axis=1)
    return Discretisation(kind, size, float(length), fields, tuple(jets), points, weights, tables, dofs,
                          per * len(fields), ends)
