"""Steady states of a continuum as a two-point boundary value problem: the Euler-Lagrange equations in s.

For a steady state every time derivative vanishes. With densities of first order
in s, the effective potential density

    Pi(u, u_s, s) = V(u, u_s, s) - T(u, u_s, u_t = 0, s)

(strain energy minus the kinetic energy of the steady motion: in a rotating
frame, minus the centrifugal potential) is stationary, and Rayleigh
dissipation R(u, u_t) adds the generalized force dR/du_t at u_t = 0 (drag on a
steady motion seen from a moving frame). The steady equations are

    rho_f = d/ds(dPi/du_f,s) - dPi/du_f + dR/du_f,t |_(u_t = 0) = 0,

Lagrange's equations of a lumped system whose "time" is s, "coordinates" are
the fields and "velocities" their slopes u_s (mechgen.symbolic.derive): the
residual is linear in u_ss, so y = (u, u_s) obeys y' = (u_s, -H^-1 f) with
H = d2Pi/du_s2, and the generated residual and tangent kernels give the right
side and its exact Jacobian. Essential boundary conditions fix jets at the ends,
to values the model gives as expressions of its parameters (``fix(jet, at, value)``);
they are outputs ``bc_<field>_<order>_<end>`` of the generated outputs kernel, with
the model's declared outputs (functions of the jets: a tension, a stretch).
"""
from __future__ import annotations

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.derive import TIME, LumpedEquations, lagrange_residual
from mechgen.symbolic.field import POSITION, Jets, _constraints, _density
from mechgen.symbolic.model import Model, as_expr, call_declared
from mechgen.symbolic.specialize import Specialization, param_namespace


def _steady_env(model: Model, spec: Specialization):
    p_ns, free = param_namespace(model, spec)
    u = Jets(model.field_names)
    return u, {"u": u, "p": p_ns, "s": POSITION, "t": sp.Integer(0)}, p_ns, free


def derive_steady(model: Model, spec: Specialization) -> LumpedEquations:
    """The steady Euler-Lagrange equations of a continuum in s, with boundary values and outputs."""
    if model.continuum is None:
        raise ModelError(f"model {model.name} declares no field", file=model.file, expected="model.field(...)")
    if model.weak_fn is not None or model.point_terms:
        raise ModelError(f"steady boundary value problems of {model.name}: weak forms and point terms are not "
                         "supported", file=model.file, key="steady", expected="energy densities only")
    u, env, p_ns, free = _steady_env(model, spec)
    T = _density(model, model.kinetic_fn, "kinetic_density", env)
    V = _density(model, model.potential_fn, "potential_density", env)
    R = _density(model, model.dissipation_fn, "dissipation_density", env)
    if any(k > 1 or m > 1 for _, k, m in u.used):
        raise ModelError(f"steady equations of {model.name} need densities of first order in s and t",
                         file=model.file, key="steady", expected="jets u, u_s, u_t only")
    fields = model.field_names
    q = tuple(u.symbol(f, 0, 0) for f in fields)
    v = tuple(u.symbol(f, 1, 0) for f in fields)
    rates = tuple(u.symbol(f, 0, 1) for f in fields)
    a = tuple(sp.Symbol(f"{f}_ss", real=True) for f in fields)
    still = {s: 0 for (f, k, m), s in u.used.items() if m > 0}
    Pi = (V - T).xreplace(still).xreplace({POSITION: TIME})
    drag = [sp.diff(R, r).xreplace(still).xreplace({POSITION: TIME}) for r in rates]
    rho = [r + d for r, d in zip(lagrange_residual(Pi, sp.Integer(0), sp.Integer(0), q, v, a), drag)]
    outputs = {}
    for out in model.outputs:
        value = as_expr(call_declared(out.fn, **{k: env[k] for k in ("u", "p", "s")}), f"output {out.name}", model)
        outputs[out.name] = value.xreplace(still).xreplace({POSITION: TIME})
    for c in _constraints(model, p_ns):
        outputs[f"bc_{c.field}_{c.order}_{c.at}"] = sp.sympify(c.value)
    stray = set().union(*(sp.sympify(e).free_symbols for e in rho + list(outputs.values()))) - set(q + v + a + free)
    stray -= {TIME}
    if stray:
        raise ModelError(f"steady equations of {model.name} use {sorted(s.name for s in stray)}", file=model.file,
                         key="steady", expected="densities of the jets u, u_s and the parameters")
    return LumpedEquations(
        model=model.name, coordinates=tuple(fields), q=q, v=v, a=a, z=(), params=free,
        param_names=tuple(s.name for s in free), internal_names=(), kinetic=Pi, potential=sp.Integer(0),
        residual=sp.Matrix(rho), rates=sp.zeros(0, 1), outputs={**outputs, "potential_density": Pi},
    )
