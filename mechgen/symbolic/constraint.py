"""Pointwise constraints of a continuum, g(jets) = 0 (an inextensible string), for small motions about a steady state.

With the multiplier field mu(s) the energy is mu g. About a steady state (jets j0,
multiplier mu0) the perturbation j' obeys the linearised constraint and feels the
geometric stiffness of the multiplier:

    dg/dj (j0) . j' = 0,        K_c = mu0 d2g/dj2 (j0)        (per unit length).

The ``constraint`` kernel gives both at the Gauss points: g_j (jets) and g_jj
(jets x jets), in the jets of the field's local equations (mechgen.symbolic.field).
A model's axial strain measure (``model.strain_density``, a string's (lambda^2 - 1)/2)
gets the same derivatives in the ``strain`` kernel: the Galerkin stiffness can then
project the strain on a smaller space (mechgen.runtime.steady.constrained, ``projected``).
"""
from __future__ import annotations

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.derive import LumpedEquations
from mechgen.symbolic.field import POSITION, Jets
from mechgen.symbolic.model import Model
from mechgen.symbolic.declared import as_expr, call_declared
from mechgen.symbolic.specialize import Specialization, param_namespace


def constraint_of(model: Model, spec: Specialization, fn=None) -> sp.Expr | None:
    """g(u, p) of the model's constraint (or of ``fn``: its strain measure) under ``spec``; None when it declares
    none or it is identically 0."""
    fn = model.constraint_fn if fn is None else fn
    if fn is None or model.continuum is None:
        return None
    p_ns, _ = param_namespace(model, spec)
    u = Jets(model.field_names)
    g = as_expr(call_declared(fn, u=u, p=p_ns, s=POSITION), "constraint_density", model)
    if g == 0:
        return None
    if any(k > 1 or m > 0 for _, k, m in u.used):
        raise ModelError(f"constraint of {model.name} uses {sorted(s.name for s in u.used.values())}",
                         file=model.file, key="constraint_density", expected="the jets u and u_s only")
    return g


def constraint_matrices(g: sp.Expr, local: LumpedEquations, model: Model) -> dict[str, sp.Matrix]:
    """g_j (1 x jets) and g_jj (jets x jets) in the local equations' jets ``local.q``."""
    jets = sp.Matrix(local.q)
    stray = g.free_symbols - set(local.q) - set(local.params) - {POSITION}
    if stray:
        raise ModelError(f"constraint of {model.name} uses {sorted(s.name for s in stray)}, which no energy uses",
                         file=model.file, key="constraint_density",
                         expected="jets that the energy densities use too")
    grad = sp.Matrix([g]).jacobian(jets)
    return {"g_j": grad, "g_jj": grad.T.jacobian(jets)}
