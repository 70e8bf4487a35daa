"""Plane continua: fields on a 2D domain, their jets, densities, and derivation on the local piece.

A plane model declares scalar fields u_f(x, y, t) (the components of a displacement, or one
transverse deflection) on a domain (:func:`disk`, :func:`annulus`, :func:`rectangle`,
:func:`slit_plate`, :func:`plate_with_hole`) and energy densities written in the fields'
*jets* at a point: ``u.ux`` (u_x), ``u.ux_x`` (du_x/dx), ``u.ux_y`` (du_x/dy), ``u.ux_t``,
``u.ux_xt`` (d2u_x/dx dt), ``u.ux_tt``. Densities are per unit area (per unit thickness for
plane stress and plane strain): kinetic T, strain/potential V, Rayleigh dissipation R, or a
weak form W linear in the test jets; edge terms per unit length of a named boundary
(:meth:`mechgen.symbolic.model.Model.edge_potential`, a traction t as V_e = -t.u).

Derivation happens at one point, once (DESIGN.md, "symbolic on the local piece"), exactly as on
an interval (:mod:`mechgen.symbolic.field`): with the jet vector j = (D^k u_f), D^k in
{1, d/dx, d/dy},

    rho_a = d/dt(dT/dj_t,a) - dT/dj_a + dV/dj_a + dR/dj_t,a   (+ dW/dtest_a),

so that the discretised residual is r = sum_e sum_g w_g |det J| B_eg^T rho(B_eg q, ...), B_eg the
(jets x dofs) table of element e at quadrature point g; d rho/dj is the pointwise tangent (the
elasticity tensor of a linear law). The kernels take the position (x, y) (and on an edge the
outward unit normal (n_x, n_y)) as their ``s`` input; nothing here grows with the mesh.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.derive import TIME, LumpedEquations, energy_powers, lagrange_residual
from mechgen.symbolic.field import density_expr
from mechgen.symbolic.model import Model
from mechgen.symbolic.declared import call_declared
from mechgen.symbolic.params import Namespace
from mechgen.symbolic.plane_domain import (BOUNDARIES, ELEMENTS, RIGID, SHAPES, Domain, PlaneSpec,  # noqa: F401
                                           annulus, disk, plate_with_hole, rectangle, slit_plate)
from mechgen.symbolic.specialize import Specialization, param_namespace

X, Y = sp.Symbol("x", real=True), sp.Symbol("y", real=True)
#: the outward unit normal of an edge, the edge kernels' third and fourth position inputs
NORMAL = (sp.Symbol("n_x", real=True), sp.Symbol("n_y", real=True))
#: a plane jet's suffix after ``<field>_``: at most one space derivative (C0 Lagrange elements), then time
PLANE_SUFFIX = re.compile(r"([xy]?)(t{0,2})\Z")
ORDERS = ("", "x", "y")
def plane_jet(name: str, fields) -> tuple[str, str, int] | None:
    """(field, space order '' | 'x' | 'y', time order) of a jet name such as ``ux_xt``, or None."""
    for f in sorted(fields, key=len, reverse=True):
        if name == f:
            return f, "", 0
        if name.startswith(f + "_"):
            m = PLANE_SUFFIX.match(name[len(f) + 1:])
            if m and m.group(0):
                return f, m.group(1), len(m.group(2))
    return None


class PlaneJets(Namespace):
    """Jets of the declared fields at one point, created on first use (``u.ux_y`` is du_x/dy).

    Used jets are recorded as (field, space order, time order).
    """

    def __init__(self, fields: tuple[str, ...], prefix: str = "") -> None:
        object.__setattr__(self, "_fields", tuple(fields))
        object.__setattr__(self, "_prefix", prefix)
        object.__setattr__(self, "_used", {})
        super().__init__({})

    def symbol(self, f: str, order: str, m: int) -> sp.Symbol:
        """The symbol of jet (field, order, time order)."""
        key = (f, order, m)
        if key not in self._used:
            suffix = order + "t" * m
            self._used[key] = sp.Symbol(f"{self._prefix}{f}{'_' + suffix if suffix else ''}", real=True)
        return self._used[key]

    def __getattr__(self, name: str) -> sp.Symbol:
        if name.startswith("_"):
            raise AttributeError(name)
        jet = plane_jet(name, self._fields)
        if jet is None or jet[2] > 2:
            raise AttributeError(f"no jet {name!r}: fields are {', '.join(self._fields)}; a plane jet is a field "
                                 "name, optionally followed by '_', x or y, then at most two t's (ux_x, ux_yt)")
        return self.symbol(*jet)

    __getitem__ = __getattr__

    @property
    def used(self) -> dict:
        """{(field, order, m): symbol} of every jet touched so far."""
        return dict(self._used)


def gradient(u: PlaneJets, *fields: str) -> sp.Matrix:
    """H_ij = d u_i / d x_j of the fields (u_1, u_2) = ``fields``: the displacement gradient (2 x 2)."""
    return sp.Matrix([[u.symbol(f, "x", 0), u.symbol(f, "y", 0)] for f in fields])


@dataclass(frozen=True)
class PlaneConstraint:
    """u_f = 0 on the named boundary (an essential condition; held at 0 by every analysis)."""

    field: str
    boundary: str


@dataclass(frozen=True)
class PlaneEquations:
    """The derived local pieces of a plane model.

    Attributes:
        local: pointwise equations in the domain; ``local.q`` are the jets ``jets`` in order, the position (x, y).
        jets: (field, order) of each jet of the domain kernels.
        fields: field names; groups: named groups of fields.
        domain: the generated shape and its size parameters.
        constraints: essential boundary conditions.
        edges: {boundary: (jets, equations)} of each edge term, position (x, y, n_x, n_y), jets values only.
    """

    local: LumpedEquations
    jets: tuple[tuple[str, str], ...]
    fields: tuple[str, ...]
    groups: tuple[tuple[str, tuple[str, ...]], ...]
    domain: Domain
    constraints: tuple[PlaneConstraint, ...]
    edges: dict = field(default_factory=dict)
    #: the edge terms that are point terms: {name: (x, y)} (numbers or parameter names)
    points: dict = field(default_factory=dict)


def plane_constraints(model: Model, p_ns: Namespace) -> tuple[PlaneConstraint, ...]:
    """The model's ``@boundary`` list, ``fix(field or group, boundary)`` each, as checked PlaneConstraints."""
    if model.boundary_fn is None:
        return ()
    spec = model.plane_spec
    groups = dict(spec.groups)
    out = []
    for item in call_declared(model.boundary_fn, p=p_ns) or ():
        ok = isinstance(item, tuple) and len(item) == 2 and all(isinstance(x, str) for x in item)
        if not ok or item[0] not in (*spec.fields, *groups) or item[1] not in (*spec.domain.boundaries, RIGID):
            raise ModelError(f"boundary condition {item!r} of model {model.name} is not a field held at zero on a "
                             "boundary of its domain", file=model.file, key="boundary",
                             expected=f"fix(one of {', '.join((*spec.fields, *groups))}, one of "
                                      f"{', '.join(spec.domain.boundaries)} or {RIGID!r}); prescribed values are "
                                      "not supported")
        for f in groups.get(item[0], (item[0],)):
            out.append(PlaneConstraint(f, item[1]))
    return tuple(dict.fromkeys(out))


def _pieces(model: Model, fns: dict, env: dict, u: PlaneJets, test: PlaneJets) -> tuple:
    """Densities T, V, R, W of one piece (the domain, or an edge)."""
    T = density_expr(model, fns.get("kinetic"), "kinetic_density", env)
    V = density_expr(model, fns.get("potential"), "potential_density", env)
    R = density_expr(model, fns.get("dissipation"), "dissipation_density", env)
    W = density_expr(model, fns.get("weak"), "weak_form", {**env, "test": test})
    return T, V, R, W


def _residual(model: Model, pieces: tuple, jets, u: PlaneJets, test: PlaneJets) -> list[sp.Expr]:
    """rho_a of Lagrange's equations in the jets, plus dW/dtest_a of a weak form (refused unless linear in tests)."""
    T, V, R, W = pieces
    q, v, a = ([u.symbol(f, k, m) for f, k in jets] for m in range(3))
    rho = lagrange_residual(T, V, R, q, v, a)
    if W != 0:
        tests = list(test.used.values())
        if sp.expand(W.subs({s: 0 for s in tests})) != 0 or any(sp.diff(W, s1, s2) != 0 for s1 in tests
                                                                  for s2 in tests):
            raise ModelError(f"weak form of {model.name} is not linear in the test jets", file=model.file,
                             key="weak_form", expected="a sum of test jets times expressions of the trial jets")
        rho = [r + sp.diff(W, test.symbol(f, k, 0)) for r, (f, k) in zip(rho, jets)]
    return rho


def _equations(model: Model, pieces: tuple, jets, u: PlaneJets, test: PlaneJets, free, position) -> LumpedEquations:
    """The pointwise equations of one piece as a LumpedEquations whose coordinates are the jets."""
    T, V, R, W = pieces
    q, v, a = (tuple(u.symbol(f, k, m) for f, k in jets) for m in range(3))
    Q = [-sp.diff(W, test.symbol(f, k, 0)) for f, k in jets]
    power, excess = energy_powers(T, V, R, Q, q=q, v=v)
    rho = _residual(model, pieces, jets, u, test)
    return LumpedEquations(
        model=model.name, coordinates=tuple(s.name for s in q), q=q, v=v, a=a, z=(), params=free,
        param_names=tuple(s.name for s in free), internal_names=(), kinetic=T, potential=V,
        residual=sp.Matrix(rho) if rho else sp.zeros(0, 1), rates=sp.zeros(0, 1),
        outputs={"kinetic_energy": T, "potential_energy": V, "energy": T + V}, position=position,
        power=power, excess=excess)


def _jets_of(used, fields, constraints=()) -> tuple[tuple[str, str], ...]:
    """The jets of a piece: per field in order, its value if used (or held on a boundary), and both first
    derivatives if either is used (the element tables hold the gradient)."""
    orders = {f: set() for f in fields}
    for f, k, _ in used:
        orders[f].update({k} if k == "" else {"x", "y"})
    for c in constraints:
        orders[c.field].add("")
    return tuple((f, k) for f in fields for k in ORDERS if k in orders[f])


def derive_plane(model: Model, spec: Specialization) -> PlaneEquations:
    """Derive the pointwise residual of a plane model (and of its edge terms) from its densities."""
    plane = model.plane_spec
    p_ns, free = param_namespace(model, spec)
    u, test = PlaneJets(plane.fields), PlaneJets(plane.fields, prefix="test_")
    env = {"u": u, "p": p_ns, "x": X, "y": Y, "t": TIME}
    fns = {"kinetic": model.kinetic_fn, "potential": model.potential_fn, "dissipation": model.dissipation_fn,
           "weak": model.weak_fn}
    domain = _pieces(model, fns, env, u, test)
    constraints = plane_constraints(model, p_ns)
    jets = _jets_of(list(u.used) + list(test.used), plane.fields, constraints)
    unused = [f for f in plane.fields if not any(j[0] == f for j in jets)]
    if unused:
        raise ModelError(f"fields {unused} of model {model.name} appear in no density", file=model.file,
                         key="plane", expected="every declared field used by an energy or weak form")
    local = _equations(model, domain, jets, u, test, free, (X, Y))
    outputs = {o.name: density_expr(model, o.fn, f"output {o.name}", env) for o in model.outputs}
    if {(f, k) for f, k, _ in u.used} - set(jets):
        raise ModelError(f"an output of model {model.name} reads a jet no density uses", file=model.file,
                         key="output", expected="outputs in the jets the energies use")
    local = replace(local, outputs={**local.outputs, **outputs})
    edges = {}
    for name in sorted(model.edge_terms):
        eu, etest = PlaneJets(plane.fields), PlaneJets(plane.fields, prefix="test_")
        here = {"u": eu, "p": p_ns, "x": X, "y": Y, "t": TIME, "n": Namespace(dict(zip(("x", "y"), NORMAL)))}
        pieces = _pieces(model, model.edge_terms[name], here, eu, etest)
        if any(k != "" for _, k, _ in (*eu.used, *etest.used)):
            raise ModelError(f"edge term on {name!r} of model {model.name} uses a derivative", file=model.file,
                             key=f"edge.{name}", expected="values of the fields only (u.ux, u.uy, u.ux_t)")
        edge_jets = _jets_of(list(eu.used) + list(etest.used), plane.fields)
        edges[name] = (edge_jets, _equations(model, pieces, edge_jets, eu, etest, free, (X, Y, *NORMAL)))
    return PlaneEquations(local, jets, plane.fields, plane.groups, plane.domain, constraints, edges,
                          dict(model.plane_points))
