"""derive: declared energies of a lumped model -> equations of motion and their Jacobians.

Lagrange's equations with Rayleigh dissipation R and non-conservative forces Q,
written as a residual in the accelerations a = dv/dt::

    r(q, v, a, z, t) = d/dt(dT/dv) - dT/dq + dV/dq + dR/dv - Q = M(q) a - f(q, v, z, t)

with d/dt(dT/dv) = (d2T/dv dv) a + (d2T/dv dq) v + d2T/dv dt. Internal variables
obey dz/dt = g(q, v, z, t). Everything downstream (time integration, Newton,
linearisation) uses r, g and their Jacobians:

    M = dr/da,  C = dr/dv,  K = dr/dq   (at a = 0: the linearised system M q'' + C q' + K q = 0)
    G = (C - C^T)/2 (gyroscopic),  D = (C + C^T)/2 (damping).

K holds the centrifugal terms (-d2T/dq2) and any circulatory part of Q.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.model import Model
from mechgen.symbolic.declared import as_expr, call_declared
from mechgen.symbolic.initial import initial_column
from mechgen.symbolic.params import Namespace
from mechgen.symbolic.rod import derive_rod
from mechgen.symbolic.specialize import Specialization, param_namespace

TIME = sp.Symbol("t", real=True)


@dataclass(frozen=True)
class LumpedEquations:
    """The derived equations of a lumped model under one specialisation."""

    model: str
    coordinates: tuple[str, ...]
    q: tuple[sp.Symbol, ...]
    v: tuple[sp.Symbol, ...]
    a: tuple[sp.Symbol, ...]
    z: tuple[sp.Symbol, ...]
    params: tuple[sp.Symbol, ...]
    param_names: tuple[str, ...]
    internal_names: tuple[str, ...]
    kinetic: sp.Expr
    potential: sp.Expr
    residual: sp.Matrix
    rates: sp.Matrix
    outputs: dict
    position: tuple[sp.Symbol, ...] = ()
    #: the declared initial state (mechgen.symbolic.initial), None when the model declares none
    initial: sp.Matrix | None = None
    #: the declared cross-section stiffness K (6 x 6, Model.section_stiffness), None when the model declares none
    section: sp.Matrix | None = None
    #: the declared rod's local pieces (mechgen.symbolic.rod.RodPieces, Model.rod), None when none is declared
    rod: object = None
    #: the powers of the energy balance (:func:`energy_powers`): Q.v, v.dR/dv, -dL/dt (a 3 x 1 Matrix)
    power: sp.Matrix | None = None
    #: v.dT/dv - 2 T: zero for a kinetic energy quadratic in v (:func:`energy_powers`)
    excess: sp.Expr | None = None
    #: M = d2T/dv dv and the bias h = r(q, v, 0, z, t) of r = M a + h, derived directly (:func:`lagrange_parts`);
    #: None when the residual was derived in another form (its pieces are then read off it, :meth:`split`)
    mass: sp.Matrix | None = None
    bias: sp.Matrix | None = None
    #: derivatives taken once and shared by the kernels that need them (bias_jacobian)
    memo: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def t(self) -> sp.Symbol:
        """The time symbol."""
        return TIME

    def jacobian(self, what: sp.Matrix, wrt: str) -> sp.Matrix:
        """d(what)/d(wrt) for wrt in 'q', 'v', 'a', 'z' (an empty matrix when wrt is empty)."""
        syms = getattr(self, wrt)
        if not syms:
            return sp.zeros(what.rows, 0)
        return what.jacobian(sp.Matrix(syms))

    def split(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(M, h) of the residual r = M a + h, r linear in a: M = dr/da, h = r(a = 0).

        Derived directly by :func:`derive_lumped` (no differentiation of the assembled residual, no
        substitution over it); read off the residual otherwise (a continuum's local density, a hybrid mode).
        """
        if self.mass is not None and self.bias is not None:
            return self.mass, self.bias
        at_rest = {ai: 0 for ai in self.a}
        return self.jacobian(self.residual, "a").subs(at_rest), self.residual.subs(at_rest)

    def bias_jacobian(self, wrt: str) -> sp.Matrix:
        """dh/d(wrt) of the bias h = r(a = 0), derived once per equations (the tangent and linear kernels share it)."""
        if wrt not in self.memo:
            self.memo[wrt] = self.jacobian(self.split()[1], wrt)
        return self.memo[wrt]

    def residual_jacobian(self, wrt: str) -> sp.Matrix:
        """dr/d(wrt) of r = M a + h: M for wrt = 'a', else d(M a)/d(wrt) + dh/d(wrt) (no a-terms differentiated
        twice; read off the assembled residual when the equations carry no split)."""
        if wrt == "a":
            return self.split()[0]
        if self.mass is None or self.bias is None or not self.a:
            return self.jacobian(self.residual, wrt)
        return self.jacobian(self.mass * sp.Matrix(self.a), wrt) + self.bias_jacobian(wrt)

    def linear_matrices(self) -> dict[str, sp.Matrix]:
        """M, D, G, K of the linearisation about (q, v, z) with a = 0: M = dr/da, C = dh/dv, K = dh/dq."""
        M = self.split()[0]
        C = self.bias_jacobian("v")
        K = self.bias_jacobian("q")
        return {"M": M, "D": (C + C.T) / 2, "G": (C - C.T) / 2, "K": K}

    def lagrangian(self) -> dict[str, sp.Matrix]:
        """The pieces a variational integrator needs (mechgen.runtime.core.variational), with their Jacobians:

            p = dT/dv (the momentum dL/dv, L = T - V),
            F = dL/dq + Q - dR/dv = -r(q, v, 0, z, t) + (dp/dq) v + dp/dt,

        so that Lagrange's equations read dp/dt = F. Keys ``mom`` (p: the parameters' port is named p), ``F`` and
        their Jacobians ``mom_q, mom_v, F_q, F_v`` = d(p, F)/d(q, v).
        """
        v = sp.Matrix(self.v)
        p = sp.Matrix([sp.diff(self.kinetic, s) for s in self.v])
        p_q = self.jacobian(p, "q")
        F = -self.split()[1] + p_q * v + p.diff(TIME)
        return {"mom": p, "F": F, "mom_q": p_q, "mom_v": self.jacobian(p, "v"), "F_q": self.jacobian(F, "q"),
                "F_v": self.jacobian(F, "v")}

    def force(self) -> sp.Matrix:
        """Potential force -dV/dq (for symplectic integration of separable systems)."""
        return -sp.Matrix([self.potential]).jacobian(sp.Matrix(self.q)).T


def _state_symbols(model: Model, spec: Specialization):
    names = [c for c in model.coordinate_names if spec.active is None or c in spec.active]
    q = tuple(sp.Symbol(n, real=True) for n in names)
    v = tuple(sp.Symbol(f"{n}_dot", real=True) for n in names)
    a = tuple(sp.Symbol(f"{n}_ddot", real=True) for n in names)
    frozen = {n: sp.Integer(0) for n in model.coordinate_names if n not in names}
    q_ns = Namespace({**{n: s for n, s in zip(names, q)}, **frozen})
    v_ns = Namespace({**{n: s for n, s in zip(names, v)}, **frozen})
    z = tuple(sp.Symbol(i.name, real=True) for i in model.internals)
    z_ns = Namespace({i.name: s for i, s in zip(model.internals, z)})
    return tuple(names), q, v, a, z, q_ns, v_ns, z_ns


def _scalar(value: object, what: str, model: Model) -> sp.Expr:
    return as_expr(value, what, model)


def _forces(model: Model, names, env, fn=None) -> list[sp.Expr]:
    fn = model.forces_fn if fn is None else fn
    if fn is None:
        return [sp.Integer(0)] * len(names)
    raw = call_declared(fn, **env)
    if not isinstance(raw, dict):
        raw = dict(zip(model.coordinate_names, raw))
    unknown = set(raw) - set(model.coordinate_names)
    if unknown:
        raise ModelError(f"forces name unknown coordinates {sorted(unknown)}", file=model.file, key="forces",
                         expected=f"keys among {', '.join(model.coordinate_names)}")
    return [_scalar(raw.get(n, 0), "forces", model) for n in names]


def lagrange_residual(T: sp.Expr, V: sp.Expr, R: sp.Expr, q, v, a) -> list[sp.Expr]:
    """Lagrange's equations r_i = d/dt(dT/dv_i) - dT/dq_i + dV/dq_i + dR/dv_i, linear in a.

    d/dt(dT/dv_i) = sum_j (d2T/dv_i dv_j) a_j + (d2T/dv_i dq_j) v_j + d2T/dv_i dt.
    """
    zero = sp.Integer(0)
    res = []
    for i, vi in enumerate(v):
        dT_dv = sp.diff(T, vi)
        ddt = sum((sp.diff(dT_dv, vj) * aj for vj, aj in zip(v, a)), zero)
        ddt += sum((sp.diff(dT_dv, qj) * vj for qj, vj in zip(q, v)), zero) + sp.diff(dT_dv, TIME)
        res.append(ddt - sp.diff(T, q[i]) + sp.diff(V, q[i]) + sp.diff(R, vi))
    return res


def lagrange_parts(T: sp.Expr, V: sp.Expr, R: sp.Expr, q, v) -> tuple[sp.Matrix, list[sp.Expr]]:
    """M and h of Lagrange's equations r = M a + h (:func:`lagrange_residual`), each derivative taken once.

        M_ij = d2T/dv_i dv_j  (symmetric: the upper triangle is derived and mirrored),
        h_i = sum_j (d2T/dv_i dq_j) v_j + d2T/dv_i dt - dT/dq_i + dV/dq_i + dR/dv_i.

    The velocity terms are the directional derivative of p_i = dT/dv_i along v, never a time derivative of
    the whole momentum, and nothing is expanded: the work is n first derivatives of T and n^2 of the p_i.
    """
    n = len(v)
    p = [sp.diff(T, vi) for vi in v]
    M = sp.zeros(n, n)
    for i in range(n):
        for j in range(i, n):
            M[i, j] = M[j, i] = sp.diff(p[i], v[j])
    zero = sp.Integer(0)
    h = [sum((sp.diff(p[i], qj) * vj for qj, vj in zip(q, v)), zero) + sp.diff(p[i], TIME) - sp.diff(T, q[i])
         + sp.diff(V, q[i]) + sp.diff(R, v[i]) for i in range(n)]
    return M, h


def energy_powers(T: sp.Expr, V: sp.Expr, R: sp.Expr, Q: list, q, v) -> tuple[sp.Matrix, sp.Expr]:
    """The terms of the energy balance along a solution of Lagrange's equations (the residual above minus Q).

    With p = dT/dv, multiplying the residual by v gives, for the energy function h = v.p - T + V,

        dh/dt = Q.v - v.dR/dv - dL/dt,      L = T - V  (dL/dt: the explicit time derivative),

    and h = E + (v.p - 2 T) with E = T + V: the excess v.p - 2 T is zero when T is a quadratic form in v
    (Euler), so that dE/dt = (power of the forces) - (dissipated power) + (power of an explicit time
    dependence). Returns ([Q.v, v.dR/dv, -dL/dt], v.p - 2 T).
    """
    zero = sp.Integer(0)
    forces = sum((Qi * vi for Qi, vi in zip(Q, v)), zero)
    dissipated = sum((vi * sp.diff(R, vi) for vi in v), zero)
    explicit = sp.diff(V, TIME) - sp.diff(T, TIME)
    excess = sp.expand(sum((vi * sp.diff(T, vi) for vi in v), zero) - 2 * T)
    return sp.Matrix([forces, dissipated, explicit]), excess


def _energy(model: Model, scope, what: str, env) -> sp.Expr:
    """The model-wide energy ``what`` plus the mode's own (``scope``: a ModeScope or None)."""
    total = sp.Integer(0)
    for owner in (model, scope):
        fn = getattr(owner, f"{what}_fn", None) if owner is not None else None
        if fn is not None:
            total += _scalar(call_declared(fn, **env), what, model)
    return total


@dataclass(frozen=True)
class Declared:
    """What a lumped model declares, evaluated on the state symbols: the energies T, V, Rayleigh's R, the
    generalized forces Q, the internal rates, the outputs (energies included) and the parameter namespace."""

    names: tuple[str, ...]
    q: tuple
    v: tuple
    a: tuple
    z: tuple
    free: tuple
    p_ns: Namespace
    T: sp.Expr
    V: sp.Expr
    R: sp.Expr
    Q: list
    rates: list
    outputs: dict


def declared_lumped(model: Model, spec: Specialization, mode: str | None = None) -> Declared:
    """The declared pieces of a lumped model (of one mode of a hybrid model: the model-wide terms plus the
    mode's, mechgen.symbolic.hybrid), before any derivative is taken."""
    if model.is_lattice:
        raise ModelError(f"model {model.name} is a lattice; use derive_lattice", file=model.file)
    scope = model.mode_scopes[mode] if mode is not None else None
    names, q, v, a, z, q_ns, v_ns, z_ns = _state_symbols(model, spec)
    p_ns, free = param_namespace(model, spec)
    env = {"q": q_ns, "v": v_ns, "z": z_ns, "p": p_ns, "t": TIME}
    T = _energy(model, scope, "kinetic", env)
    V = _energy(model, scope, "potential", env)
    R = _energy(model, scope, "dissipation", env)
    Q = _forces(model, names, env)
    if scope is not None and scope.forces_fn is not None:
        Q = [a_ + b_ for a_, b_ in zip(Q, _forces(model, names, env, scope.forces_fn))]
    laws = scope.rates if scope is not None else {}
    rates = [_scalar(call_declared(laws.get(i.name, i.rate), **env), f"rate of {i.name}", model)
             for i in model.internals]
    own = scope.outputs if scope is not None else {}
    outputs = {o.name: _scalar(call_declared(own.get(o.name, o.fn), **env), f"output {o.name}", model)
               for o in model.outputs}
    outputs.update(kinetic_energy=T, potential_energy=V, energy=T + V)
    return Declared(tuple(names), q, v, a, z, free, p_ns, T, V, R, Q, rates, outputs)


def derive_lumped(model: Model, spec: Specialization, mode: str | None = None, *,
                  declared: Declared | None = None) -> LumpedEquations:
    """Derive the residual, internal rates and outputs of a lumped model (of one mode of a hybrid model:
    the model-wide terms plus the mode's, mechgen.symbolic.hybrid); ``declared``: its declared pieces when
    already evaluated (:func:`declared_lumped`)."""
    d = declared if declared is not None else declared_lumped(model, spec, mode)
    names, q, v, a = d.names, d.q, d.v, d.a
    M, h = lagrange_parts(d.T, d.V, d.R, q, v)
    bias = sp.Matrix([hi - Qi for hi, Qi in zip(h, d.Q)]) if names else sp.zeros(0, 1)
    res = list(M * sp.Matrix(a) + bias) if names else []
    power, excess = energy_powers(d.T, d.V, d.R, d.Q, v=v, q=q)
    return LumpedEquations(
        model=model.name, coordinates=names, q=q, v=v, a=a, z=d.z, params=d.free,
        param_names=tuple(s.name for s in d.free), internal_names=tuple(i.name for i in model.internals),
        kinetic=d.T, potential=d.V, residual=sp.Matrix(res) if res else sp.zeros(0, 1),
        rates=sp.Matrix(d.rates) if d.rates else sp.zeros(0, 1), outputs=d.outputs,
        initial=initial_column(model, d.p_ns, names, tuple(i.name for i in model.internals)),
        section=(section := _section(model, d.p_ns)),
        rod=derive_rod(model, d.p_ns, section, d.free), power=power, excess=excess, mass=M, bias=bias,
    )


def _section(model: Model, p_ns) -> sp.Matrix | None:
    """The declared section stiffness K(p) as a symmetric 6 x 6 Matrix (Model.section_stiffness), or None."""
    if model.section_fn is None:
        return None
    raw = call_declared(model.section_fn, p=p_ns)
    try:
        K = sp.Matrix(raw)
    except (TypeError, ValueError, sp.SympifyError):
        K = None
    if K is None or K.shape != (6, 6):
        raise ModelError(f"section_stiffness of model {model.name} returned {type(raw).__name__}",
                         file=model.file, key="section_stiffness", expected="a 6 x 6 matrix of the parameters")
    K = K.applyfunc(lambda e: _scalar(e, "section_stiffness", model))
    if any(sp.simplify(K[i, j] - K[j, i]) != 0 for i in range(6) for j in range(i)):
        raise ModelError(f"section_stiffness of model {model.name} is not symmetric", file=model.file,
                         key="section_stiffness", expected="K = K^T (a stiffness derived from an energy)")
    return K
