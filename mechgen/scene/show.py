"""``mechgen show MODEL``: the derived equations and matrices, as text."""
from __future__ import annotations

import sympy as sp

from mechgen import models
from mechgen.pipeline import derive
from mechgen.symbolic.specialize import all_free


def _lumped(eqs) -> list[str]:
    lines = [f"coordinates q = {list(eqs.coordinates)}; velocities v = dq/dt; accelerations a = dv/dt",
             f"internal variables z = {list(eqs.internal_names)}" if eqs.z else "no internal variables",
             f"T = {eqs.kinetic}", f"V = {eqs.potential}", "", "residual r = d/dt(dT/dv) - dT/dq + dV/dq + dR/dv - Q:"]
    lines += [f"  r[{n}] = {sp.simplify(e)}" for n, e in zip(eqs.coordinates, eqs.residual)]
    if eqs.z:
        lines += [f"  d{n}/dt = {e}" for n, e in zip(eqs.internal_names, eqs.rates)]
    lines.append("")
    lines.append("linearisation at q = 0, v = 0 (M q'' + (D + G) q' + K q = 0):")
    rest = {s: 0 for s in eqs.q + eqs.v + eqs.z}
    for name, mat in eqs.linear_matrices().items():
        lines.append(f"{name} =")
        lines += ["  " + line for line in sp.pretty(sp.simplify(mat.subs(rest)), use_unicode=False).splitlines()]
    if getattr(eqs, "section", None) is not None:
        lines += ["", "cross-section stiffness K (Model.section_stiffness; [K_uu, K_uw; K_wu, K_ww]):"]
        lines += [f"  K[{i},{j}] = {eqs.section[i, j]}" for i in range(6) for j in range(i, 6) if eqs.section[i, j] != 0]
    rod = getattr(eqs, "rod", None)
    if rod is not None:
        lines += ["", "Cosserat rod (Model.rod; sigma = K (f - f0), f = vee6(H^-1 H') = (nu, kappa)):",
                  f"  L = {rod.length}", f"  f0 = {list(rod.f0)}",
                  f"  distributed load (spatial force, torque per length at r = (r_1, r_2, r_3)) = {list(rod.load)}"]
    return lines


def _hybrid(eqs) -> list[str]:
    """Each mode's equations, then the guards leaving it and the resets."""
    direction = {1: "rising", -1: "falling", 0: "both"}
    lines = [f"modes {list(eqs.modes)} (starts in {eqs.modes[eqs.initial]})"]
    for name, mode_eqs, guards in zip(eqs.modes, eqs.equations, eqs.guards):
        lines += ["", f"== mode {name}"] + _lumped(mode_eqs) + ["guards leaving it:"]
        for ge in guards:
            to = "end of run" if ge.guard.terminal else f"-> {ge.guard.to}"
            reset = f", reset {ge.reset}" if ge.reset is not None else ""
            lines.append(f"  {ge.guard.name}: g = {ge.g} ({direction[ge.guard.direction]}) {to}{reset}")
    for j, column in enumerate(eqs.resets):
        lines.append(f"reset {j}: (q, v, z) -> {list(column)}")
    return lines


def _lattice(eqs) -> list[str]:
    return [f"chain of {eqs.sites} sites, coordinate {eqs.coordinate}, {eqs.ends} ends",
            f"site kinetic T_s = {eqs.site_kinetic}", f"site potential V_s = {eqs.site_potential}",
            f"bond potential V_b = {eqs.bond_potential}", f"site residual r_s = {eqs.site_residual}",
            f"bond gradient = {eqs.bond_gradient()}", f"bond Hessian = {eqs.bond_hessian()}"]


def _field(eqs) -> list[str]:
    local = eqs.local
    lines = [f"fields {list(eqs.fields)} on s in [0, {eqs.length}]; jets j = {list(local.coordinates)}",
             f"kinetic density T = {local.kinetic}", f"potential density V = {local.potential}",
             "boundary conditions: " + (", ".join(f"D^{c.order} {c.field} = 0 at the {c.at}" for c in eqs.constraints)
                                        or "none (natural)"),
             "", "local residual rho_a = d/dt(dT/dj_t,a) - dT/dj_a + dV/dj_a + dR/dj_t,a  (r = sum_g w_g B_g^T rho):"]
    lines += [f"  rho[{n}] = {sp.simplify(e)}" for n, e in zip(local.coordinates, local.residual)]
    lines += ["", "pointwise coefficients at the zero state (M = sum B^T m B, ...):"]
    rest = {s: 0 for s in local.q + local.v}
    for name, mat in local.linear_matrices().items():
        lines.append(f"{name.lower()} =")
        lines += ["  " + line for line in sp.pretty(sp.simplify(mat.subs(rest)), use_unicode=False).splitlines()]
    if getattr(eqs, "section", None) is not None:
        lines += ["", "cross-section stiffness K (Model.section_stiffness; [K_uu, K_uw; K_wu, K_ww]):"]
        lines += [f"  K[{i},{j}] = {eqs.section[i, j]}" for i in range(6) for j in range(i, 6) if eqs.section[i, j] != 0]
    return lines


def show_model(name: str) -> str:
    """Text of a model's parameters, derived residual and linear matrices (all parameters symbolic).

    ``name``: a built-in or entry-point name, a path to a model file (from the current directory)
    or ``package.module:attribute`` (mechgen.models.resolve).
    """
    source = models.resolve(name)
    model = source.load()
    eqs = derive(model, all_free(model))
    lines = [f"model {model.name}: {model.summary()}", f"from {source.origin}: {source.file or source.key}",
             "parameters:"]
    lines += [f"  {p.name:10s} = {p.default!r:10} {p.unit:10s} {p.doc}" for p in model.param_list]
    lines.append("")
    from mechgen.symbolic.derive_ad import ADEquations

    if isinstance(eqs, ADEquations):  # graphs, not expressions
        lines += [f"derived by algorithmic differentiation ({len(eqs.q)} coordinates; Model.derivation): the "
                  "equations of motion are CasADi graphs and are not printed"]
    elif model.is_hybrid:
        lines += _hybrid(eqs)
    else:
        lines += _field(eqs) if model.is_field else _lattice(eqs) if model.is_lattice else _lumped(eqs)
    lines.append("")
    lines.append("outputs: " + ", ".join(model.output_names))
    return "\n".join(lines)
