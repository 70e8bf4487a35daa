"""A compiled continuum's global residual and matrices: element sums, end terms and parts, then the reduction.

With x = Z q (mechgen.runtime.fields.conditions) and B_e the jet tables of element e at its Gauss points
(weights W_e):

    r(q, q', q'') = Z^T (sum_e B_e^T W_e rho(B_e x, B_e x', B_e x'') + sum_p B_p^T rho_p + alpha C^T C x),
    A = Z^T (sum_e B_e^T W_e a_e B_e + sum_p B_p^T a_p B_p) Z  for a = d rho / dj (K), d rho / dj_t (D, G),
    d rho / dj_tt (M),

the sums over p running over the end terms and placed parts at their positions (B_p: the jets at s = x_p).
The functions take a :class:`~mechgen.runtime.fields.continuum.FieldSystem`.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.fields.assemble import element_matrices, element_vectors
from mechgen.runtime.fields.conditions import constraint_rows, row_penalties
from mechgen.runtime.fields.constrain import binding
from mechgen.runtime.fields.point_kernels import coefficients, ends, full_states, jets_of, pointwise

sps = lazy_module("scipy.sparse")


def point_terms(terms, shape) -> sps.csr_matrix:
    """sum_p B_p^T C_p B_p of the end terms and placed parts, as one sparse matrix of ``shape``.

    B_p (jets x dofs, CSR) touches a few dofs only: each product is formed densely on those
    (B_p restricted to its nonzero columns) and all of them are scattered at once (duplicates
    summed), instead of two sparse products and a sparse sum per part and matrix.
    """
    rows, cols, vals = [], [], []
    for B, C in terms:
        idx = np.unique(B.indices)
        Bd = B.toarray()[:, idx]
        rows.append(np.repeat(idx, idx.size))
        cols.append(np.tile(idx, idx.size))
        vals.append((Bd.T @ np.asarray(C) @ Bd).ravel())
    return sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=shape)


def full_matrices(system, kernel: str, names, full, jets, t: float) -> dict:
    """sum_e B_e^T W_e a_e B_e + sum_p B_p^T a_p B_p over all dofs for each output ``a`` in ``names`` of a
    tangent-type kernel at the full states ``full`` (their jets ``jets``), no boundary conditions."""
    disc = system.disc
    local = pointwise(system, kernel, *jets, t=t)
    mats = {}
    for k in names:
        coeff = coefficients(system, local[k])
        pairs = [tuple(ab) for ab in np.argwhere(np.any(coeff != 0, axis=(0, 1)))]
        mats[k] = system.assembler.matrix(element_matrices(disc.tables, disc.weights, coeff, pairs))
    at_points = list(ends(system, kernel, full, t))
    if at_points:
        for k in names:
            extra = point_terms([(B, coefficients(system, loc[k])[0]) for B, loc in at_points], mats[k].shape)
            mats[k] = mats[k] + (extra if sps.issparse(mats[k]) else extra.toarray())
    return mats


def reduced_matrices(system, kernel: str, names, q, v, a, t: float, jets=None) -> dict:
    """Reduced global matrices ``names`` of a tangent-type kernel at the state (q, v, a) (``jets``: the base
    state's jets at the Gauss points in place of q's); the penalty term alpha C^T C joins the stiffness."""
    full = full_states(system, (q, v, a))
    j = jets_of(system, full)
    if jets is not None:
        j[0] = np.asarray(jets, float)
    mats = full_matrices(system, kernel, names, full, j, t)
    stiff = {"linear": "K", "tangent": "r_q"}[kernel]
    reduced = {k: system.reduction.matrix(mats[k], row_penalties(system) if k == stiff else 0.0, border=k == stiff)
               for k in names}
    for k, m in reduced.items():
        require_finite(system, kernel, k, m)
    return reduced


def require_finite(system, kernel: str, name: str, matrix) -> None:
    """KernelError when an assembled matrix holds NaN/Inf (a kernel overflowed, or the element sums did:
    a length such as 1e200 gives EI/h^3 = 0 and rhoA h = inf), naming the matrix and the values that set it."""
    data = matrix.data if sps.issparse(matrix) else np.asarray(matrix)
    if np.isfinite(data).all():
        return
    length = system.field_meta.length
    values = {**system.param_values(), **{k: v for k, v in system.fixed.items() if isinstance(v, (int, float))},
              length: system.value(length)}
    shown = ", ".join(f"{n} = {v:.6g}" for n, v in values.items() if isinstance(v, float) and v != 0
                      and not 1e-150 < abs(v) < 1e150) or "none beyond 1e+/-150"
    raise KernelError(f"the assembled {name} of {system.metadata.model} (kernel {kernel!r}) holds "
                      f"{int(np.size(data) - np.isfinite(data).sum())} NaN/Inf entries: a value overflows double "
                      f"precision in the element sums (extreme values: {shown})")


def full_residual(system, full, t: float) -> np.ndarray:
    """sum_e B^T W rho + sum_ends B_at^T rho_at over all dofs (no boundary conditions)."""
    disc = system.disc
    j = jets_of(system, full)
    rho = pointwise(system, "residual", *j, t=t)["r"]
    r = system.assembler.vector(element_vectors(disc.tables, disc.weights, rho))
    for B, loc in ends(system, "residual", full, t):
        r = r + B.T @ loc["r"][0]
    return r


def residual(system, q, v=None, a=None, t: float = 0.0) -> np.ndarray:
    """r(q, q', q'') = Z^T (sum_e B^T W rho + sum_ends B_at^T rho_at + penalty C^T C x)."""
    full = full_states(system, (q, v, a))
    red = system.reduction
    return red.vector(full_residual(system, full, t) + red.penalty_force(full[0], row_penalties(system)), q)


def reactions(system, q, t: float = 0.0) -> list[dict]:
    """Boundary reactions of an equilibrium: the Lagrange multipliers lambda of C x = 0, r(x) + C^T lambda = 0
    at x = Z q in least squares; each in the unit of the force conjugate to its jet (w: N, w_s: N m)."""
    kept, rows = [], []
    for key, row, scale in zip(*constraint_rows(system)):
        if binding(row, scale):
            kept.append(key)
            rows.append(row)
    if not rows:
        return []
    r = full_residual(system, full_states(system, (q, None, None)), t)
    lam = np.linalg.lstsq(np.array(rows).T, -r, rcond=None)[0]
    return [{"jet": f + ("_" + "s" * k if k else ""), "at": at, "value": float(v)}
            for (f, k, at), v in zip(kept, lam)]
