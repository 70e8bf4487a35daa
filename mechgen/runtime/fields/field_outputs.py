"""What a compiled continuum reports of a state: integrated outputs, field values at points, nodal values.

The outputs (energies and the model's integrated outputs) are sum_e sum_g w_g o(j_g) + sum_p o_p(j_p): the
pointwise ``outputs`` kernel at the Gauss points plus the end terms and parts. Field values u_f = S_f x come from the
basis rows at the points; nodal values (a rotor's whirl stations) are dofs of the element discretisations.
The functions take a :class:`~mechgen.runtime.fields.continuum.FieldSystem`.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError, KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.fields.elements import reference
from mechgen.runtime.fields.point_kernels import ends, full_states, jets_of, pointwise

sps = lazy_module("scipy.sparse")


def outputs(system, q, v=None, t: float = 0.0) -> dict[str, float]:
    """Energies: integrals of the kinetic and potential densities plus the end terms."""
    disc = system.disc
    full = full_states(system, (q, v))
    j = jets_of(system, full)
    local = pointwise(system, "outputs", *j, t=t)
    values = {k: float(np.sum(disc.weights * arr[..., 0])) for k, arr in local.items()}
    for _, loc in ends(system, "outputs", full + [None], t):
        for k, arr in loc.items():
            values[k] += float(arr.ravel()[0])
    bad = [k for k, val in values.items() if not np.isfinite(val)]
    if bad:
        raise KernelError(f"outputs of {system.metadata.model} are NaN/Inf: {', '.join(bad)}")
    return values


def nodal_dofs(system, fields) -> list[np.ndarray]:
    """Full-dof numbers of the nodal values of ``fields`` at every mesh vertex (element discretisations)."""
    disc = system.disc
    if disc.mesh is None:
        raise InputError(f"whirl stations need finite elements; {disc.kind} is a global basis",
                         key="discretisation", expected="an element discretisation (quintic, timoshenko2, ...)")
    nloc = disc.dofs.shape[1] // len(disc.fields)
    nodes = 2 if disc.kind == "timoshenko2" else len(reference(disc.kind).nodes)
    last = nloc - nloc // nodes  # the value dof of an element's last node
    out = []
    for f in fields:
        i = disc.fields.index(f)
        block = disc.dofs[:, i * nloc:(i + 1) * nloc]
        out.append(np.concatenate([block[:, 0], block[-1:, last]]))
    return out


def nodal_indices(system, fields) -> tuple[np.ndarray, ...] | None:
    """Reduced-unknown indices of the nodal values of ``fields`` at the vertices where none is eliminated
    (None when the unknowns are not a selection of dofs)."""
    red = system.reduction
    if red.Z is not None and red.keep is None:
        return None
    index = np.arange(red.ndof) if red.keep is None else np.full(red.ndof, -1)
    if red.keep is not None:
        index[red.keep] = np.arange(len(red.keep))
    mapped = [index[dofs] for dofs in nodal_dofs(system, fields)]
    kept = np.all([m >= 0 for m in mapped], axis=0)
    return tuple(m[kept] for m in mapped)


def nodal_rows(system, fields) -> np.ndarray:
    """R with R q = the nodal values of ``fields`` (stacked field by field) for reduced unknowns q."""
    red = system.reduction
    dofs = np.concatenate(nodal_dofs(system, fields))
    require(dense_bytes(len(dofs), red.n) + (dense_bytes(red.ndof, red.n) if red.Z is not None else 0),
            f"the dense map of {red.n} unknowns to {len(dofs)} nodal values", key="params.N")
    if red.Z is None:
        R = np.zeros((len(dofs), red.n))
        R[np.arange(len(dofs)), dofs] = 1.0
        return R
    Z = red.Z.toarray() if sps.issparse(red.Z) else np.asarray(red.Z)
    return Z[dofs]


def field_values(system, q, points: np.ndarray, order: int = 0) -> dict[str, np.ndarray]:
    """D_s^order of every field at ``points`` for the reduced state q (one state per column allowed):
    u_f = S_f x with x = Z q the full dof vector and S_f the sparse basis rows at the points."""
    disc = system.disc
    q = np.asarray(q, dtype=float)
    x = system.reduction.expand(q) if q.ndim == 1 else np.column_stack([system.reduction.expand(c) for c in q.T])
    return {f: np.asarray(sps.vstack([sps.csr_matrix(disc.row(f, order, float(p))) for p in points]) @ x)
            for f in disc.fields}
