"""derive for lattices: one site and one bond, never the whole chain.

A chain of N identical sites with coordinate u_i (i = 1..N) has

    T = sum_i T_s(u_i, u_i'),   V = sum_i V_s(u_i) + sum_bonds V_b(u_i, u_{i+1}),

with ghost sites u_0 = u_{N+1} = 0 for fixed ends, or u_{N+1} = u_1 when periodic.
The local pieces derived here (a site residual, a bond gradient and Hessian) are
the same for N = 8 and N = 100 000; the generated kernel loops over sites and bonds.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.model import Model
from mechgen.symbolic.declared import as_expr, call_declared
from mechgen.symbolic.params import Namespace
from mechgen.symbolic.specialize import Specialization, param_namespace


@dataclass(frozen=True)
class LatticeEquations:
    """Local pieces of a chain model under one specialisation.

    Site residual r_s = d/dt(dT_s/dv) - dT_s/du + dV_s/du (one entry per site);
    bond gradient dV_b/d(u_a, u_b) and Hessian (2 x 2) scatter into neighbours.
    """

    model: str
    coordinate: str
    sites: str
    ends: str
    site_q: sp.Symbol
    site_v: sp.Symbol
    site_a: sp.Symbol
    bond_q: tuple[sp.Symbol, sp.Symbol]
    params: tuple[sp.Symbol, ...]
    param_names: tuple[str, ...]
    site_kinetic: sp.Expr
    site_potential: sp.Expr
    bond_potential: sp.Expr

    @property
    def site_residual(self) -> sp.Expr:
        """r_s(u, v, a) of one site (kinetic and on-site terms)."""
        T, q, v, a = self.site_kinetic, self.site_q, self.site_v, self.site_a
        dT_dv = sp.diff(T, v)
        return sp.diff(dT_dv, v) * a + sp.diff(dT_dv, q) * v - sp.diff(T, q) + sp.diff(self.site_potential, q)

    def site_tangent(self) -> dict[str, sp.Expr]:
        """dr_s/du, dr_s/dv, dr_s/da of one site."""
        r = self.site_residual
        return {"q": sp.diff(r, self.site_q), "v": sp.diff(r, self.site_v), "a": sp.diff(r, self.site_a)}

    def bond_gradient(self) -> list[sp.Expr]:
        """dV_b/du_a, dV_b/du_b."""
        return [sp.diff(self.bond_potential, s) for s in self.bond_q]

    def bond_hessian(self) -> list[list[sp.Expr]]:
        """d2V_b/du_i du_j for i, j in (a, b)."""
        return [[sp.diff(g, s) for s in self.bond_q] for g in self.bond_gradient()]


def derive_lattice(model: Model, spec: Specialization) -> LatticeEquations:
    """Derive the local site and bond pieces of a chain model."""
    chain = model.chain_spec
    if chain is None:
        raise ModelError(f"model {model.name} declares no chain", file=model.file)
    if model.bond_potential_fn is None and model.site_potential_fn is None:
        raise ModelError(f"chain model {model.name} declares no potential", file=model.file,
                         expected="@model.bond_potential or @model.site_potential")
    name = chain.coordinate
    q, v, a = (sp.Symbol(f"{name}{suffix}", real=True) for suffix in ("", "_dot", "_ddot"))
    qa, qb = sp.Symbol(f"{name}_a", real=True), sp.Symbol(f"{name}_b", real=True)
    va, vb = sp.Symbol(f"{name}_a_dot", real=True), sp.Symbol(f"{name}_b_dot", real=True)
    p_ns, free = param_namespace(model, spec)
    site = Namespace({"q": q, "v": v})
    zero = sp.Integer(0)

    def local(fn, **kw):
        return as_expr(call_declared(fn, p=p_ns, **kw), fn.__name__, model) if fn else zero

    return LatticeEquations(
        model=model.name, coordinate=name, sites=chain.sites,
        ends=chain.ends if chain.ends in ("fixed", "periodic") else str(spec.values[chain.ends]),
        site_q=q, site_v=v, site_a=a, bond_q=(qa, qb), params=free, param_names=tuple(s.name for s in free),
        site_kinetic=local(model.site_kinetic_fn, s=site),
        site_potential=local(model.site_potential_fn, s=site),
        bond_potential=local(model.bond_potential_fn, a=Namespace({"q": qa, "v": va}),
                             b=Namespace({"q": qb, "v": vb})),
    )
