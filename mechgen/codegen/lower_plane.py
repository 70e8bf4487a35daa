"""Lowering of a plane continuum (mechgen.symbolic.plane.PlaneEquations): pointwise kernels and their meta.

The domain's kernels are those of a lumped model whose coordinates are the jets, with the position (x, y) as
the ``s`` input; each edge term gives ``<kernel>_at_<boundary>`` with the position (x, y, n_x, n_y). Every
kernel's ``meta["plane"]`` (:func:`plane_meta`) tells the runtime (mechgen.runtime.plane.system) the fields,
jets, domain and boundary conditions; nothing in it depends on the mesh.
"""
from __future__ import annotations

from dataclasses import replace

from mechgen.codegen.ir import KernelIR
from mechgen.codegen.lower_lumped import lower_lumped

#: every kernel a plane model can have
PLANE_KERNELS = ("residual", "tangent", "linear", "outputs")


def constant_mass(eqs) -> bool:
    """Whether d rho/dj_tt of the domain and of every edge term is free of the state and of time (a mass matrix
    the runtime may factor once per parameter vector)."""
    pieces = [eqs.local, *(local for _, local in eqs.edges.values())]
    return all(not (local.jacobian(local.residual, "a").free_symbols
                    & (set(local.q) | set(local.v) | set(local.a) | {local.t})) for local in pieces)


def plane_meta(eqs) -> dict:
    """Fields, groups, jets, domain (shape and size parameters), constraints and edge jets of a plane model."""
    return {"constant_mass": constant_mass(eqs), "fields": list(eqs.fields), "groups": {g: list(fs) for g, fs in eqs.groups},
            "jets": [list(j) for j in eqs.jets], "shape": eqs.domain.shape,
            "sizes": {role: name for role, name in eqs.domain.sizes},
            "constraints": [[c.field, c.boundary] for c in eqs.constraints],
            "edges": {name: [list(j) for j in jets] for name, (jets, _) in sorted(eqs.edges.items())},
            "outputs": sorted(eqs.local.outputs),
            "points": {name: list(xy) for name, xy in sorted(eqs.points.items())}}


def lower_plane(eqs, kernels, *, cse: bool = True) -> list[KernelIR]:
    """KernelIRs of the requested kernels of the domain and of each edge term, in canonical order."""
    wanted = [k for k in PLANE_KERNELS if k in kernels]
    irs = [lower_lumped(eqs.local, k, cse=cse) for k in wanted]
    irs += [replace(lower_lumped(local, k, cse=cse), name=f"{k}_at_{name}")
            for name, (_, local) in sorted(eqs.edges.items()) for k in wanted]
    meta = plane_meta(eqs)
    for ir in irs:
        ir.meta["plane"] = meta
    return irs
