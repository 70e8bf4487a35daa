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
the model's declared outputs (functions of the jets u, u_s and of the stress
resultants n = dV/du_s: a tension, a stretch).

The Hamiltonian (stress) form, for a model that declares its complementary
energy density C(u, n) = sup_{u_s} (n . u_s - V) (``model.complementary_density``;
n = dV/du_s, a string's tension vector): with the steady Hamiltonian

    H(u, n, s) = n . u_s - Pi = C(u, n, s) + T(u, u_t = 0, s)

(T at rest must not depend on the slopes), the same equations read

    u_s = dH/dn,    n_s = -dH/du - dR/du_t |_(u_t = 0, u_s = dH/dn),

a first-order system in y = (u, n) lowered as the ``rates`` / ``rates_tangent``
kernels of a lumped system with internal variables y and "time" s. No H^-1:
it stays well conditioned for stiff laws (p = beta (lambda - 1), beta -> 1e6)
and holds constrained ones that have no V at all (an inextensible string,
C = l0 |n|). H is conserved along s when nothing depends on s explicitly and
there is no drag (output ``hamiltonian``: the first integral).
"""
from __future__ import annotations

import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.derive import TIME, LumpedEquations, lagrange_residual
from mechgen.symbolic.field import POSITION, Jets, boundary_constraints, density_expr
from mechgen.symbolic.model import Model
from mechgen.symbolic.declared import as_expr, call_declared
from mechgen.symbolic.params import Namespace
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
    from mechgen.symbolic.constraint import constraint_of

    if constraint_of(model, spec) is not None:
        raise ModelError(f"the steady equations of {model.name} in displacement form: the model holds a pointwise "
                         "constraint (no strain energy to invert)", file=model.file, key="form",
                         expected="form = 'hamiltonian' (the stress form, from the complementary energy)")
    u, env, p_ns, free = _steady_env(model, spec)
    T = density_expr(model, model.kinetic_fn, "kinetic_density", env)
    V = density_expr(model, model.potential_fn, "potential_density", env)
    R = density_expr(model, model.dissipation_fn, "dissipation_density", env)
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
    stress = Namespace({f: sp.diff(V, sl) for f, sl in zip(fields, v)})  # n = dV/du_s
    outputs = {}
    for out in (o for o in model.outputs if not o.integrate):  # integrated outputs: Galerkin states only
        value = as_expr(call_declared(out.fn, n=stress, **{k: env[k] for k in ("u", "p", "s")}),
                        f"output {out.name}", model)
        outputs[out.name] = value.xreplace(still).xreplace({POSITION: TIME})
    for c in boundary_constraints(model, p_ns):
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


def conjugate_symbols(fields) -> tuple[sp.Symbol, ...]:
    """The stress resultants n_<field> conjugate to the slopes (the Hamiltonian form's momenta)."""
    return tuple(sp.Symbol(f"n_{f}", real=True) for f in fields)


def derive_steady_hamiltonian(model: Model, spec: Specialization) -> LumpedEquations:
    """The steady equations in Hamiltonian (stress) form y = (u, n), y_s = rates(y, s), with outputs."""
    if model.continuum is None or model.complementary_fn is None:
        raise ModelError(f"model {model.name} declares no complementary energy density", file=model.file,
                         key="complementary_density", expected="@model.complementary_density C(u, n, p)")
    if model.weak_fn is not None or model.point_terms:
        raise ModelError(f"steady boundary value problems of {model.name}: weak forms and point terms are not "
                         "supported", file=model.file, key="steady", expected="energy densities only")
    u, env, p_ns, free = _steady_env(model, spec)
    fields = model.field_names
    q = tuple(u.symbol(f, 0, 0) for f in fields)
    n_syms = conjugate_symbols(fields)
    n_ns = Namespace(dict(zip(fields, n_syms)))
    C = as_expr(call_declared(model.complementary_fn, u=u, n=n_ns, p=p_ns, s=POSITION),
                "complementary_density", model)
    T = density_expr(model, model.kinetic_fn, "kinetic_density", env)
    R = density_expr(model, model.dissipation_fn, "dissipation_density", env)
    if any(k > 1 or m > 1 for _, k, m in u.used):
        raise ModelError(f"steady equations of {model.name} need densities of first order in s and t",
                         file=model.file, key="steady", expected="jets u, u_s, u_t only")
    still = {s: 0 for (f, k, m), s in u.used.items() if m > 0}
    slope_syms = {s for (f, k, m), s in u.used.items() if k == 1 and m == 0}
    T0 = T.xreplace(still)
    for what, expr in (("complementary_density", C), ("kinetic_density at rest", T0)):
        if expr.free_symbols & slope_syms:
            raise ModelError(f"the Hamiltonian steady form of {model.name}: the {what} uses slopes", file=model.file,
                             key="complementary_density", expected="C(u, n) and T(u, u_t = 0) free of u_s")
    H = (C + T0).xreplace({POSITION: TIME})
    slopes = [sp.diff(H, nf) for nf in n_syms]
    to_slopes = {u.symbol(f, 1, 0): sl for f, sl in zip(fields, slopes)}
    rates = [u.symbol(f, 0, 1) for f in fields]
    drag = [sp.diff(R, r).xreplace(still).xreplace({POSITION: TIME}).xreplace(to_slopes) for r in rates]
    dn = [-sp.diff(H, qf) - d for qf, d in zip(q, drag)]
    outputs = {}
    for out in (o for o in model.outputs if not o.integrate):  # integrated outputs: Galerkin states only
        value = as_expr(call_declared(out.fn, n=n_ns, **{k: env[k] for k in ("u", "p", "s")}),
                        f"output {out.name}", model)
        outputs[out.name] = value.xreplace(still).xreplace({POSITION: TIME}).xreplace(to_slopes)
    for c in boundary_constraints(model, p_ns):
        if c.order > 0:
            raise ModelError(f"the Hamiltonian steady form of {model.name} fixes values only, not {c.field} of "
                             f"order {c.order}", file=model.file, key="boundary", expected="fix(field, end, value)")
        outputs[f"bc_{c.field}_{c.order}_{c.at}"] = sp.sympify(c.value)
    outputs["hamiltonian"] = H
    stray = set().union(*(sp.sympify(e).free_symbols for e in slopes + dn + list(outputs.values())))
    stray -= set(q + n_syms + free) | {TIME}
    if stray:
        raise ModelError(f"Hamiltonian steady equations of {model.name} use {sorted(s.name for s in stray)}",
                         file=model.file, key="complementary_density",
                         expected="densities of the jets u, u_s (outputs), n and the parameters")
    return LumpedEquations(
        model=model.name, coordinates=(), q=(), v=(), a=(), z=q + n_syms, params=free,
        param_names=tuple(s.name for s in free), internal_names=tuple(fields) + tuple(s.name for s in n_syms),
        kinetic=sp.Integer(0), potential=sp.Integer(0), residual=sp.zeros(0, 1),
        rates=sp.Matrix(slopes + dn), outputs=outputs,
    )


def steady_field_meta(model: Model, spec: Specialization) -> dict:
    """The runtime's description of a continuum (mechgen.codegen.lower_model.field_meta) when only its steady
    Hamiltonian form is built: fields, their values and slopes as jets, length, end conditions."""
    p_ns, _ = param_namespace(model, spec)
    constraints = boundary_constraints(model, p_ns)
    meta = {"fields": list(model.field_names), "jets": [[f, k] for k in (0, 1) for f in model.field_names],
            "length": model.continuum.length, "points": [], "constant_mass": True,
            "constraints": [[c.field, c.order, c.at] for c in constraints]}
    if any(c.value != 0 for c in constraints):
        meta["boundary_values"] = True
    return meta
