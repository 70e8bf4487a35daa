"""Continua on a 1D domain s in [0, L]: fields, their jets, densities, and derivation on the local piece.

A continuum model declares scalar fields u_f(s, t) and energy densities written
in the fields' *jets* at a point: ``u.w`` (w), ``u.w_s`` (dw/ds), ``u.w_ss``,
``u.w_t`` (dw/dt), ``u.w_st`` (d2w/ds dt), ``u.w_tt`` ... Densities are per unit
length: kinetic T(j, j_t, s, t), strain/potential V(j, s, t), Rayleigh
dissipation R(j, j_t), or, for a model that is not variational, a weak form
W(test, j, j_t, j_tt) linear in the test jets.

Derivation happens at one point, once (DESIGN.md, "symbolic on the local
piece"): with the jet vector j = (D^k u_f) over fields f and orders k, the
local residual of Lagrange's equations is

    rho_a = d/dt(dT/dj_t,a) - dT/dj_a + dV/dj_a + dR/dj_t,a   (+ dW/dtest_a),

so that the discretised residual is r = sum_g w_g B_g^T rho(B_g q, B_g q', B_g q'')
with B_g the basis table (jets x dofs) at quadrature point g. Its local
Jacobians d rho/dj_tt, d rho/dj_t, d rho/dj are the pointwise mass, damping +
gyroscopic and stiffness (incl. centrifugal and geometric) coefficients. The
local equations are a :class:`~mechgen.symbolic.derive.LumpedEquations` whose
"coordinates" are the jets and which takes the position s as an extra input;
every kernel kind of a lumped model (residual, tangent, linear, outputs, energy_rates: the power densities
of the energy balance, whose quadrature is the discretised system's) follows.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.derive import TIME, LumpedEquations, energy_powers, lagrange_residual
from mechgen.symbolic.model import Model
from mechgen.symbolic.declared import as_expr, call_declared
from mechgen.symbolic.names import jet_of
from mechgen.symbolic.params import Namespace
from mechgen.symbolic.specialize import Specialization, param_namespace

POSITION = sp.Symbol("s", real=True)
ENDS = ("start", "end")


@dataclass(frozen=True)
class Constraint:
    """An essential boundary condition: the jet ``D^order field`` equals ``value`` at ``at`` ('start' or 'end').

    Perturbations (modes, stability) and Galerkin unknowns satisfy it with value 0;
    steady boundary value problems (mechgen.symbolic.steady) use the value, an
    expression of the parameters.
    """

    field: str
    order: int
    at: str
    value: object = 0


def fix(jet: str, at: str, value=0) -> tuple:
    """Boundary condition helper for ``@model.boundary``: ``fix("w_s", "end")`` means w_s(L) = 0,
    ``fix("x", "end", 1)`` x(L) = 1 (a number or an expression of the parameters)."""
    return (jet, at) if isinstance(value, (int, float)) and value == 0 else (jet, at, value)


def fix_ends(bc: str, conditions: dict[str, tuple[str, ...]]) -> list[tuple[str, str]]:
    """Boundary conditions from a 'start-end' choice: ``fix_ends("clamped-free", {"clamped": ("w", "w_s"), ...})``."""
    start, end = bc.split("-")
    return [fix(jet, "start") for jet in conditions[start]] + [fix(jet, "end") for jet in conditions[end]]


class Jets(Namespace):
    """Jets of the declared fields at one point, created on first use.

    ``u.w`` is w, ``u.w_s`` dw/ds, ``u.w_sst`` d3w/ds2 dt; at most two time
    derivatives. Used jets are recorded as (field, space order, time order).
    """

    def __init__(self, fields: tuple[str, ...], prefix: str = "") -> None:
        object.__setattr__(self, "_fields", tuple(sorted(fields, key=len, reverse=True)))
        object.__setattr__(self, "_prefix", prefix)
        object.__setattr__(self, "_used", {})
        super().__init__({})

    @staticmethod
    def parse(name: str, fields) -> tuple[str, int, int] | None:
        """(field, space order, time order) of a jet name, or None (:func:`mechgen.symbolic.names.jet_of`)."""
        return jet_of(name, fields)

    def symbol(self, field: str, k: int, m: int) -> sp.Symbol:
        """The symbol of jet (field, k, m)."""
        key = (field, k, m)
        if key not in self._used:
            suffix = "s" * k + "t" * m
            self._used[key] = sp.Symbol(f"{self._prefix}{field}{'_' + suffix if suffix else ''}", real=True)
        return self._used[key]

    def __getattr__(self, name: str) -> sp.Symbol:
        if name.startswith("_"):
            raise AttributeError(name)
        jet = self.parse(name, self._fields)
        if jet is None:
            raise AttributeError(f"no jet {name!r}: fields are {', '.join(sorted(self._fields))}; a jet is a field "
                                 "name, optionally followed by '_' and s's then at most two t's (w_s, w_sst)")
        return self.symbol(*jet)

    __getitem__ = __getattr__

    @property
    def used(self) -> dict:
        """{(field, k, m): symbol} of every jet touched so far."""
        return dict(self._used)


@dataclass(frozen=True)
class FieldEquations:
    """The derived local piece of a continuum model.

    Attributes:
        local: pointwise equations; ``local.q`` are the jets ``jets`` in order,
            ``local.v``/``local.a`` their first/second time derivatives.
        jets: (field, space order) of each jet, fields in declaration order.
        fields: field names.
        length: name of the length parameter L.
        constraints: essential boundary conditions.
        points: pointwise equations of the end terms, by end ('start', 'end'), and of
            each part kind (placed by the scene), by kind.
        parts: parameter names (model-level, ``<kind>_<name>``) of each part kind.
        shear_pairs: (displacement, rotation, sign) of a Timoshenko-type model.
    """

    local: LumpedEquations
    jets: tuple[tuple[str, int], ...]
    fields: tuple[str, ...]
    length: str
    constraints: tuple[Constraint, ...]
    points: dict = field(default_factory=dict)
    parts: dict = field(default_factory=dict)
    shear_pairs: tuple = ()


def density_expr(model: Model, fn, what: str, env: dict) -> sp.Expr:
    """The density a model declared (``fn`` called with ``env``: jets and parameters) as a sympy
    expression, 0 when none is declared; ModelError naming the function when it reads something undeclared."""
    if not fn:
        return sp.Integer(0)
    try:
        value = call_declared(fn, **env)
    except AttributeError as exc:
        raise ModelError(f"{what} {fn.__name__} of model {model.name}: {exc}", file=model.file, key=fn.__name__,
                         expected="jets of the declared fields (u.w, u.w_s, u.w_t ...) and declared parameters") \
            from None
    return as_expr(value, what, model)


def boundary_constraints(model: Model, p_ns: Namespace) -> tuple[Constraint, ...]:
    """The model's ``@boundary`` list, ``fix(jet, 'start' | 'end'[, value])`` each, as checked Constraints."""
    if model.boundary_fn is None:
        return ()
    raw = call_declared(model.boundary_fn, p=p_ns)
    out = []
    for item in raw or ():
        if not (isinstance(item, tuple) and len(item) in (2, 3) and all(isinstance(x, str) for x in item[:2])):
            raise ModelError(f"boundary of model {model.name} returned {item!r}", file=model.file, key="boundary",
                             expected="a list of fix(jet, 'start' | 'end'[, value])")
        jet, at = item[:2]
        value = as_expr(item[2], "boundary value", model) if len(item) == 3 else sp.Integer(0)
        parsed = Jets.parse(jet, model.field_names)
        if parsed is None or parsed[2] or at not in ENDS:
            raise ModelError(f"boundary condition {item!r} of model {model.name} is not a spatial jet at an end",
                             file=model.file, key="boundary", expected="fix('w' or 'w_s' ..., 'start' or 'end')")
        out.append(Constraint(parsed[0], parsed[1], at, value))
    return tuple(out)


def _local(model: Model, fns: dict, env: dict, u: Jets, test: Jets) -> tuple:
    """Densities (or point terms) T, V, R, W of one piece."""
    T = density_expr(model, fns.get("kinetic"), "kinetic_density", env)
    V = density_expr(model, fns.get("potential"), "potential_density", env)
    R = density_expr(model, fns.get("dissipation"), "dissipation_density", env)
    W = density_expr(model, fns.get("weak"), "weak_form", {**env, "test": test})
    return T, V, R, W


def _residual(model: Model, pieces: tuple, jets, u: Jets, test: Jets) -> list[sp.Expr]:
    """rho_a of Lagrange's equations in the jets, plus dW/dtest_a of a weak form."""
    T, V, R, W = pieces
    q = tuple(u.symbol(f, k, 0) for f, k in jets)
    v = tuple(u.symbol(f, k, 1) for f, k in jets)
    a = tuple(u.symbol(f, k, 2) for f, k in jets)
    rho = lagrange_residual(T, V, R, q, v, a)
    if W != 0:
        tests = [test.symbol(f, k, 0) for f, k in jets]
        rho = [r + sp.diff(W, s) for r, s in zip(rho, tests)]
        leftover = W.subs({s: 0 for s in test.used.values()})
        if sp.expand(leftover) != 0 or any(sp.diff(W, s1, s2) != 0 for s1 in test.used.values()
                                           for s2 in test.used.values()):
            raise ModelError(f"weak form of {model.name} is not linear in the test jets", file=model.file,
                             key="weak_form", expected="a sum of test jets times expressions of the trial jets")
    return rho


def _powers(pieces: tuple, jets, u: Jets, test: Jets) -> tuple:
    """The energy balance's power densities (mechgen.symbolic.derive.energy_powers) of one piece: the jets are the
    coordinates, and a weak form's generalized force on jet a is Q_a = -dW/dtest_a (W is linear in the tests), so
    that the quadrature of Q.j_t is the discretised system's Q.v."""
    T, V, R, W = pieces
    q = tuple(u.symbol(f, k, 0) for f, k in jets)
    v = tuple(u.symbol(f, k, 1) for f, k in jets)
    Q = [-sp.diff(W, test.symbol(f, k, 0)) for f, k in jets]
    return energy_powers(T, V, R, Q, q=q, v=v)


def _equations(model: Model, pieces: tuple, rho: list, jets, u: Jets, free, test: Jets,
               integrated: dict | None = None) -> LumpedEquations:
    """One piece's equations; ``integrated``: the domain's integrated output densities (none at the ends)."""
    T, V = pieces[0], pieces[1]
    q = tuple(u.symbol(f, k, 0) for f, k in jets)
    power, excess = _powers(pieces, jets, u, test)
    return LumpedEquations(
        model=model.name, coordinates=tuple(s.name for s in q), q=q,
        v=tuple(u.symbol(f, k, 1) for f, k in jets), a=tuple(u.symbol(f, k, 2) for f, k in jets), z=(),
        params=free, param_names=tuple(s.name for s in free), internal_names=(), kinetic=T, potential=V,
        residual=sp.Matrix(rho) if rho else sp.zeros(0, 1), rates=sp.zeros(0, 1),
        outputs={**(integrated or {}), "kinetic_energy": T, "potential_energy": V, "energy": T + V},
        position=(POSITION,),
        power=power, excess=excess,
    )


def derive_field(model: Model, spec: Specialization) -> FieldEquations:
    """Derive the pointwise residual of a continuum model (and of its end terms) from its densities."""
    cont = model.continuum
    if cont is None:
        raise ModelError(f"model {model.name} declares no field", file=model.file, expected="model.field(...)")
    p_ns, free = param_namespace(model, spec)
    u, test = Jets(model.field_names), Jets(model.field_names, prefix="test_")
    env = {"u": u, "p": p_ns, "s": POSITION, "t": TIME}
    fns = {"kinetic": model.kinetic_fn, "potential": model.potential_fn, "dissipation": model.dissipation_fn,
           "weak": model.weak_fn}
    domain = _local(model, fns, env, u, test)
    integrated = {o.name: density_expr(model, o.fn, f"output {o.name}", env) for o in model.outputs if o.integrate}
    ends = {}
    for at in sorted(model.point_terms):
        here = dict(env)
        if at in model.parts:
            here["part"] = Namespace({n: p_ns[f"{at}_{n}"] for n in model.parts[at]})
        ends[at] = _local(model, model.point_terms[at], here, u, test)
    orders = {f: -1 for f in model.field_names}
    constraints = boundary_constraints(model, p_ns)
    for f, k, _ in list(u.used) + list(test.used) + [(c.field, c.order, 0) for c in constraints]:
        orders[f] = max(orders[f], k)
    unused = [f for f, k in orders.items() if k < 0]
    if unused:
        raise ModelError(f"fields {unused} of model {model.name} appear in no density", file=model.file,
                         key="field", expected="every declared field used by an energy or weak form")
    if any(key[2] > 2 for key in u.used):
        raise ModelError(f"densities of {model.name} use more than two time derivatives", file=model.file)
    jets = tuple((f, k) for f in model.field_names for k in range(orders[f] + 1))
    local = _equations(model, domain, _residual(model, domain, jets, u, test), jets, u, free, test, integrated)
    points = {at: _equations(model, pieces, _residual(model, pieces, jets, u, test), jets, u, free, test)
              for at, pieces in ends.items()}
    parts = {kind: [f"{kind}_{n}" for n in names] for kind, names in model.parts.items()}
    return FieldEquations(local, jets, tuple(model.field_names), cont.length, constraints, points, parts,
                          tuple(model.shear_pairs))
