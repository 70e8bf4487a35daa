"""derive_ad: Lagrange's equations of a large lumped model by CasADi's algorithmic differentiation.

The same equations as :mod:`mechgen.symbolic.derive`, r = M a + h with

    p = dT/dv,   M = dp/dv,   h = (dp/dq) v + dp/dt - dT/dq + dV/dq + dR/dv - Q,

but T, V, R and Q are converted once to CasADi SX graphs (mechgen.symbolic.casadi_form: each distinct
subexpression one node) and every derivative is taken by AD on the graph: p by a reverse sweep, M by forward
sweeps over p, (dp/dq) v as one directional derivative (``jtimes``), the kernels' Jacobians likewise. The
work grows with the size of the model's graph times the number of coordinates, never with the expansion of
the energies (sympy differentiates each copy of a shared subexpression). The kernels are lowered from the SX
algorithm by mechgen.codegen.lower_ad into the same Kernel IR as the symbolic path.

Used (:func:`wants_ad`) for a plain lumped model (no modes, no continuum, chain, section or rod) of at least
:data:`AD_MIN_COORDINATES` coordinates or energies of more than :data:`AD_MIN_OPS` operations, whose
expressions all convert; ``Model.derivation`` forces either path.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import sympy as sp

from mechgen.symbolic.casadi_form import SXForm
from mechgen.symbolic.derive import TIME, Declared, declared_lumped
from mechgen.symbolic.initial import initial_column
from mechgen.symbolic.model import Model
from mechgen.symbolic.separable import declared_obstacle
from mechgen.symbolic.specialize import Specialization

#: a model with this many coordinates or more is derived by AD (the built-in models have at most 4)
AD_MIN_COORDINATES = 8
#: ... or one whose T + V has more operations than this (sympy's count_ops)
AD_MIN_OPS = 400


@dataclass(frozen=True)
class ADEquations:
    """A lumped model's equations as SX graphs, with the symbols and names the lowering needs (the same
    attributes as LumpedEquations where they mean the same)."""

    model: str
    coordinates: tuple[str, ...]
    q: tuple
    v: tuple
    a: tuple
    z: tuple
    params: tuple
    param_names: tuple[str, ...]
    internal_names: tuple[str, ...]
    #: SX column symbols of the kernel inputs: q, v, a, z, t, p
    inputs: dict
    #: SX of the declared pieces: T, V, R (scalars), Q, g (the internal rates) columns, outputs by name
    pieces: dict
    outputs: dict
    initial: sp.Matrix | None
    #: why the model is not fit for the splitting methods (None: it is), decided on the declared pieces
    separable_why: str | None
    #: whether v.dT/dv - 2 T is exactly zero (T homogeneous of degree 2 in v: :func:`homogeneous_degree`)
    quadratic: bool
    #: which of Q.v, v.dR/dv, -dL/dt are exactly zero (Q = 0, R = 0, no explicit t)
    zero_powers: tuple[bool, bool, bool]
    position: tuple = ()

    @property
    def t(self) -> sp.Symbol:
        """The time symbol."""
        return TIME

    def momentum(self) -> ca.SX:
        """p = dT/dv (one reverse sweep)."""
        return ca.gradient(self.pieces["T"], self.inputs["v"])

    def bias(self) -> ca.SX:
        """h = (dp/dq) v + dp/dt - dT/dq + dV/dq + dR/dv - Q: directional derivatives of p's graph, so h is a
        graph of the size of T's (M is never formed to obtain it)."""
        q, v, t = self.inputs["q"], self.inputs["v"], self.inputs["t"]
        T, V, R, Q = (self.pieces[k] for k in ("T", "V", "R", "Q"))
        p = self.momentum()
        return ca.jtimes(p, q, v) + ca.jacobian(p, t) - ca.gradient(T, q) + ca.gradient(V, q) + ca.gradient(R, v) - Q

    def mass(self) -> ca.SX:
        """M = dp/dv (n forward sweeps over p's graph)."""
        return ca.jacobian(self.momentum(), self.inputs["v"])

    def residual(self) -> ca.SX:
        """r = (dp/dv) a + h: the acceleration term as one more directional derivative (not M times a), so the
        Jacobians of r cost n sweeps over a graph of T's size, not over M's."""
        return ca.jtimes(self.momentum(), self.inputs["v"], self.inputs["a"]) + self.bias()


def homogeneous_degree(expr: sp.Expr, symbols: set) -> int | None:
    """The degree d with expr(s x) = s^d expr(x) in ``symbols`` x, read off the tree without expanding it; None
    when the tree does not show one (a sum of terms of different degrees, a function of the symbols).

    By Euler's theorem a kinetic energy of degree 2 in v has v.dT/dv = 2 T exactly.
    """
    memo: dict = {}

    def degree(e):
        if e in memo:
            return memo[e]
        if not e.free_symbols & symbols:
            d = 0
        elif e in symbols:
            d = 1
        elif e.is_Add:
            ds = {degree(a) for a in e.args}
            d = ds.pop() if len(ds) == 1 else None
        elif e.is_Mul:
            ds = [degree(a) for a in e.args]
            d = None if None in ds else sum(ds)
        elif e.is_Pow and e.exp.is_Integer and e.exp > 0:
            b = degree(e.base)
            d = None if b is None else b * int(e.exp)
        else:
            d = None
        memo[e] = d
        return d

    return degree(sp.sympify(expr))


def wants_ad(model: Model, declared: Declared) -> bool:
    """Whether the model is to be derived by AD: forced by Model.derivation, else a plain lumped model that is large
    (coordinates or operations). Whether its expressions convert is known from the one conversion
    (:func:`derive_lumped_ad` raises NotConvertible, and the model is derived symbolically)."""
    how = getattr(model, "derivation_mode", "auto")
    plain = not (model.is_hybrid or model.is_field or model.is_lattice or model.section_fn is not None
                 or model.rod_spec is not None)
    if how == "symbolic" or not plain or not declared.names:
        return False
    if how == "auto" and len(declared.names) < AD_MIN_COORDINATES \
            and sp.count_ops(declared.T) + sp.count_ops(declared.V) <= AD_MIN_OPS:
        return False
    return True


def _convert(d: Declared):
    """SX symbols of the inputs and the SX of every declared piece."""
    inputs = {"q": ca.SX.sym("q", len(d.q)), "v": ca.SX.sym("v", len(d.v)), "a": ca.SX.sym("a", len(d.a)),
              "z": ca.SX.sym("z", len(d.z)), "t": ca.SX.sym("t"), "p": ca.SX.sym("p", len(d.free))}
    symbols = {s: inputs[port][i] for port, syms in (("q", d.q), ("v", d.v), ("a", d.a), ("z", d.z), ("p", d.free))
               for i, s in enumerate(syms)}
    symbols[TIME] = inputs["t"]
    form = SXForm(symbols)
    column = lambda exprs: ca.vertcat(*[form(e) for e in exprs]) if exprs else ca.SX(0, 1)  # noqa: E731
    pieces = {"T": form(d.T), "V": form(d.V), "R": form(d.R), "Q": column(d.Q), "g": column(d.rates)}
    outputs = {name: form(e) for name, e in d.outputs.items()}
    return inputs, pieces, outputs


def derive_lumped_ad(model: Model, spec: Specialization, declared: Declared | None = None) -> ADEquations:
    """The equations of a lumped model as SX graphs (:class:`ADEquations`); NotConvertible where an expression
    holds a function CasADi's path does not convert."""
    d = declared if declared is not None else declared_lumped(model, spec)
    inputs, pieces, outputs = _convert(d)
    others = (TIME, *d.z)
    zero = sp.Integer(0)
    return ADEquations(
        model=model.name, coordinates=d.names, q=d.q, v=d.v, a=d.a, z=d.z, params=d.free,
        param_names=tuple(s.name for s in d.free), internal_names=tuple(i.name for i in model.internals),
        inputs=inputs, pieces=pieces, outputs=outputs,
        initial=initial_column(model, d.p_ns, d.names, tuple(i.name for i in model.internals)),
        separable_why=declared_obstacle(d.T, d.V, d.R, d.Q, d.q, d.v, others, d.names),
        quadratic=homogeneous_degree(d.T, set(d.v)) == 2,
        zero_powers=(all(e == zero for e in d.Q), d.R == zero, TIME not in (d.T.free_symbols | d.V.free_symbols)),
    )
