"""Lowering a model's derived equations into Kernel IRs: the dispatch over kinds of model (lumped, AD-derived,
hybrid, chain, continuum, plane), each kernel's metadata (a continuum's fields, a hybrid model's modes, a
rotor's whirl pair) and the kernels beside the catalogue's (``initial``, a hybrid model's guards, resets and
saltation derivatives, a continuum's constraints and steady forms). mechgen.pipeline calls :func:`lower_model`
between derive and emit; the per-kind lowerings are :mod:`~mechgen.codegen.lower_lumped`,
:mod:`~mechgen.codegen.lower_ad`, :mod:`~mechgen.codegen.lower_lattice` and :mod:`~mechgen.codegen.lower_plane`.
sympy is imported inside the functions: mechgen.pipeline imports this module on every start.
"""
from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from mechgen.codegen.kernel_names import HAMILTONIAN_KERNELS, SALTATION, STEADY_KERNELS, all_kernels

if TYPE_CHECKING:
    from mechgen.codegen.ir import KernelIR
    from mechgen.symbolic.model import Model
    from mechgen.symbolic.specialize import Specialization


def lower_model(model: Model, spec: Specialization, eqs, kernels, *, cse: bool = True) -> list[KernelIR]:
    """The KernelIRs of a model's requested kernels: :func:`lower_all` on the derived equations ``eqs`` (None for
    a continuum asked only for its Hamiltonian steady form), a continuum's constraint kernels beside its linear
    one, and its steady boundary value problem's kernels (derived here, mechgen.symbolic.steady)."""
    from mechgen.codegen.lower_lumped import lower_lumped

    irs = [] if eqs is None else lower_all(model, eqs, kernels, cse=cse)
    if model.is_field and "linear" in kernels and eqs is not None:
        irs += constraint_kernels(model, spec, eqs, cse)
    steady = [k for k in STEADY_KERNELS if k in kernels] if model.is_field else []
    if steady:
        from mechgen.symbolic.steady import derive_steady

        form = derive_steady(model, spec)
        for k in steady:
            ir = replace(lower_lumped(form, k.removeprefix("bvp_"), cse=cse), name=k)
            ir.meta["field"] = field_meta(eqs)
            irs.append(with_whirl(model, [ir])[0])
    hamiltonian = [k for k in HAMILTONIAN_KERNELS if k in kernels] if model.is_field else []
    if hamiltonian:
        from mechgen.symbolic.steady import derive_steady_hamiltonian, steady_field_meta

        form = derive_steady_hamiltonian(model, spec)
        meta = steady_field_meta(model, spec) if eqs is None else field_meta(eqs)
        for k in hamiltonian:
            ir = replace(lower_lumped(form, k.removeprefix("hbvp_"), cse=cse), name=k)
            ir.meta["field"] = meta
            irs.append(ir)
    return irs


def lower_all(model: Model, eqs, kernels, *, cse: bool = True) -> list[KernelIR]:
    """KernelIRs of the requested kernels, in canonical order."""
    from mechgen.codegen.lower_lattice import lower_lattice
    from mechgen.codegen.lower_lumped import lower_lumped

    if model.is_field:
        wanted = [k for k in all_kernels(model) if k in kernels]
        irs = [lower_lumped(eqs.local, k, cse=cse) for k in wanted]
        irs += [replace(lower_lumped(local, k, cse=cse), name=f"{k}_at_{at}") for at, local in eqs.points.items()
                for k in wanted]
        meta = field_meta(eqs)
        for ir in irs:
            ir.meta["field"] = meta
        return with_whirl(model, irs)
    if model.is_plane:
        from mechgen.codegen.lower_plane import lower_plane

        return lower_plane(eqs, kernels, cse=cse)
    if model.is_hybrid:
        return with_whirl(model, lower_hybrid(model, eqs, kernels, cse=cse))
    from mechgen.codegen.lower_ad import lower_ad
    from mechgen.symbolic.derive_ad import ADEquations

    if isinstance(eqs, ADEquations):
        irs = [lower_ad(eqs, k) for k in all_kernels(model) if k in kernels]
        return with_whirl(model, irs + initial_kernel(eqs, kernels, cse))
    lower = lower_lattice if model.is_lattice else lower_lumped
    irs = [lower(eqs, k, cse=cse) for k in all_kernels(model) if k in kernels]
    return with_whirl(model, irs + initial_kernel(eqs, kernels, cse))


def initial_kernel(eqs, kernels, cse: bool) -> list[KernelIR]:
    """The ``initial`` kernel (the declared initial state, mechgen.symbolic.initial) beside a time response's."""
    from mechgen.codegen.lower_lumped import lower_matrices

    column = getattr(eqs, "initial", None)
    if column is None or not {"residual", "force", "lagrangian"} & set(kernels):
        return []
    return [lower_matrices(eqs, "initial", "the declared initial state (q, v, z)", {"x": column}, cse=cse)]


def lower_hybrid(model: Model, eqs, kernels, *, cse: bool = True) -> list[KernelIR]:
    """The kernels of a hybrid model (mechgen.symbolic.hybrid_derive.HybridEquations): each requested kernel per mode
    (``<kernel>__i``) and, with a residual or force, the guards of each mode and the resets; every kernel's
    meta holds the modes and guards (``meta["hybrid"]``)."""
    import sympy as sp

    from mechgen.codegen.lower_lumped import lower_lumped, lower_matrices

    wanted = [k for k in all_kernels(model) if k in kernels and k != SALTATION]
    irs = [replace(lower_lumped(mode_eqs, k, cse=cse), name=f"{k}__{i}")
           for k in wanted for i, mode_eqs in enumerate(eqs.equations)]
    if SALTATION in kernels:
        irs += saltation_kernels(eqs, cse)
    if {"residual", "force"} & set(kernels):
        for i, (mode_eqs, guards) in enumerate(zip(eqs.equations, eqs.guards)):
            if not guards:
                continue
            g = sp.Matrix([ge.g for ge in guards])
            g_t = sp.Matrix([ge.g_t for ge in guards])
            irs.append(lower_matrices(mode_eqs, f"guards__{i}", f"guards leaving mode {i} and their rates",
                                      {"g": g, "g_t": g_t}, cse=cse, accel=True))
        for j, column in enumerate(eqs.resets):
            irs.append(lower_matrices(eqs.equations[0], f"reset__{j}", f"state after reset {j}", {"x": column},
                                      cse=cse))
    irs += initial_kernel(eqs.equations[0], kernels, cse)
    meta = eqs.meta()
    for ir in irs:
        ir.meta["hybrid"] = meta
    return irs


def saltation_kernels(eqs, cse: bool) -> list[KernelIR]:
    """The derivatives of a hybrid model's events, for the saltation matrices of its periodic orbits
    (mechgen.runtime.core.hybrid_system.HybridSystem.saltation): ``guard_jacobian__i`` g_x = dg/dx of the
    guards leaving mode i (x = (q, v, z)), ``reset_jacobian__j`` R_x = dx+/dx and R_t = dx+/dt of reset j."""
    import sympy as sp

    from mechgen.codegen.lower_lumped import lower_matrices
    from mechgen.symbolic.derive import TIME

    first = eqs.equations[0]
    x = sp.Matrix(list(first.q) + list(first.v) + list(first.z))
    irs = []
    for i, (mode_eqs, guards) in enumerate(zip(eqs.equations, eqs.guards)):
        if guards:
            g = sp.Matrix([ge.g for ge in guards])
            irs.append(lower_matrices(mode_eqs, f"guard_jacobian__{i}", f"dg/dx of the guards leaving mode {i}",
                                      {"g_x": g.jacobian(x)}, cse=cse))
    for j, column in enumerate(eqs.resets):
        irs.append(lower_matrices(first, f"reset_jacobian__{j}", f"dx+/dx and dx+/dt of reset {j}",
                                  {"R_x": column.jacobian(x), "R_t": column.diff(TIME)}, cse=cse))
    return irs


def constraint_kernels(model: Model, spec: Specialization, eqs, cse: bool) -> list[KernelIR]:
    """The ``constraint`` and ``strain`` kernels (g_j, g_jj) of a continuum that declares them, beside its linear one."""
    from mechgen.codegen.lower_lumped import lower_matrices
    from mechgen.symbolic.constraint import constraint_matrices, constraint_of

    irs = []
    for name, fn, doc in (("constraint", model.constraint_fn, "the pointwise constraint g(jets) = 0"),
                          ("strain", model.strain_fn, "the axial strain measure g(jets)")):
        g = constraint_of(model, spec, fn)
        if g is not None:
            ir = lower_matrices(eqs.local, name, f"derivatives of {doc}", constraint_matrices(g, eqs.local, model),
                                cse=cse)
            ir.meta["field"] = field_meta(eqs)
            irs.append(ir)
    return irs


def field_meta(eqs) -> dict:
    """What the runtime needs to know of a continuum: fields, jets, length, ends, parts, constraints."""
    state = set(eqs.local.q + eqs.local.v) | {eqs.local.t}
    constant_mass = all(not (local.jacobian(local.residual, "a").free_symbols & state)
                        for local in [eqs.local, *eqs.points.values()])
    meta = {"fields": list(eqs.fields), "jets": [list(j) for j in eqs.jets],
            "length": eqs.length, "points": sorted(at for at in eqs.points if at not in eqs.parts),
            "constant_mass": constant_mass, "constraints": [[c.field, c.order, c.at] for c in eqs.constraints]}
    if eqs.parts:
        meta["parts"] = {k: list(v) for k, v in sorted(eqs.parts.items())}
    if eqs.shear_pairs:
        meta["shear_pairs"] = [list(p) for p in eqs.shear_pairs]
    if any(c.value != 0 for c in eqs.constraints):
        meta["boundary_values"] = True
    return meta


def with_whirl(model: Model, irs: list[KernelIR]) -> list[KernelIR]:
    """Record the model's whirl pair (Model.whirl_pair) in every kernel's meta."""
    if model.whirl:
        for ir in irs:
            ir.meta["whirl"] = list(model.whirl)
    return irs
