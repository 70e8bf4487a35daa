"""Small motions of a constrained continuum about a steady state (an inextensible string about its balloon).

A model's pointwise constraint g(j) = 0 (mechgen.symbolic.constraint) is held by a
multiplier mu(s). About a steady state with jets j0 and multiplier mu0 (from its stress
resultants, n = mu0 dg/du_s, so mu0 = n . g_s / |g_s|^2: the Hamiltonian form's unknowns),
the Galerkin equations of the perturbation q, with multiplier perturbation tau, are

    M q'' + (D + G) q' + (K + K_c) q + B^T tau = 0,      B q = 0,
    K_c = sum_points w mu0 Phi^T g_jj Phi,               B_kl = sum_points w psi_k (g_j . Phi_l),

M, D, G, K from the model's energies (``linear`` kernel at j0), Phi the jets of the
basis at the Gauss points, and multiplier functions psi_k(s) = cos(k pi s / L),
k = 0 .. m - 1 (m = the basis size N per field by default: a constraint on the slopes
of sines lives in the cosines). The constraint is eliminated on the null space
Z (orthonormal, from the SVD of B): the matrices returned are Z^T A Z, dense.

A model whose strain energy depends on the slopes through a scalar strain g
(``model.strain_density``: V = W(g, u), so V_jj = W_g g_jj + W_gg g_j g_j^T) may take its
axial stiffness projected (runtime choice ``strain = "projected"``, a mixed Galerkin
stiffness of the Hellinger-Reissner kind): with W_g and W_gg fitted pointwise from the
linear kernel's V_jj on the jets g depends on,

    K = K_V - sum w W_gg Phi^T g_j g_j^T Phi + B^T C^-1 B,    C_kk' = sum w psi_k psi_k' / W_gg,

the tangential strain seen only through its projection on the cosines. As W_gg grows this
tends to the constrained discretisation above instead of locking; for a moderately stiff
string it converges faster in N than the pointwise stiffness (an in-plane sine series
cannot follow nearly inextensional motions of a curved string).
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense
from mechgen.runtime.fields.assemble import element_matrices, element_vectors_stack

sla = lazy_module("scipy.linalg")


def linear_about_bvp(system, bvp, result) -> dict:
    """M, D, G, K about a boundary-value steady state (``result`` of ``bvp``): the model's Galerkin
    linearisation at its jets, on the constraint's null space when the model holds one."""
    disc = system.disc
    jets = bvp.jets(result, disc.points, disc.jets)
    if "constraint" in system.kernels:
        return constrained_linear(system, bvp, result, jets)
    if system.choices.get("strain") == "projected":
        return projected_strain_linear(system, jets)
    return system.linear(jets=jets)


def _reduce_rows(reduction, B: np.ndarray) -> np.ndarray:
    """Rows over the full dofs -> rows over the reduced unknowns (B Z)."""
    if reduction.Z is None:
        return B
    if reduction.keep is not None:
        return B[:, reduction.keep]
    return np.asarray((reduction.Z.T @ B.T).T)


def steady_multiplier(system, bvp, result, points: np.ndarray, g_j: np.ndarray) -> np.ndarray:
    """mu0 = n . g_s / |g_s|^2 at ``points`` (any shape), from the stress resultants of a Hamiltonian steady state."""
    if bvp.form != "hamiltonian":
        raise InputError("a constrained continuum's steady multiplier comes from its stress resultants", key="form",
                         expected="the steady state with form = 'hamiltonian'")
    disc = system.disc
    y = bvp.unknowns(result, np.ravel(points))
    n = y[bvp.n:].T.reshape(np.shape(points) + (bvp.n,))
    slope = [disc.jets.index((f, 1)) if (f, 1) in disc.jets else None for f in bvp.fields]
    g_s = np.stack([g_j[..., a] if a is not None else np.zeros(np.shape(points)) for a in slope], axis=-1)
    return np.sum(n * g_s, axis=-1) / np.sum(g_s * g_s, axis=-1)


def constrained_linear(system, bvp, result, jets: np.ndarray, multipliers: int | None = None) -> dict:
    """Z^T {M, D, G, K + K_c} Z about the steady state (see the module docstring)."""
    disc, red = system.disc, system.reduction
    if red.multiplier_rows is not None:
        raise InputError("constrained continua take their boundary conditions by elimination or penalty",
                         key="constraints", expected="constraints = 'eliminate' or 'penalty'")
    mats = system.reduced_matrices("linear", ("M", "D", "G", "K"), None, None, None, 0.0, jets)
    require_dense(system.n, 8, "the dense linearisation about a constrained steady state")
    dense = {k: v.toarray() if hasattr(v, "toarray") else np.asarray(v) for k, v in mats.items()}
    local = system.pointwise("constraint", jets)
    na = len(disc.jets)
    g_j = np.asarray(local["g_j"]).reshape(disc.points.shape + (na,))
    g_jj = np.asarray(local["g_jj"]).reshape(disc.points.shape + (na, na))
    mu = steady_multiplier(system, bvp, result, disc.points, g_j)
    K_c = system.assembler.matrix(element_matrices(disc.tables, disc.weights, mu[..., None, None] * g_jj))
    K_c = red.matrix(K_c)
    dense["K"] = dense["K"] + (K_c.toarray() if hasattr(K_c, "toarray") else np.asarray(K_c))
    B = _multiplier_rows(system, g_j, int(multipliers or system.choices.get("N", 10)))
    Z = sla.null_space(B, rcond=1e-10)
    return {k: Z.T @ A @ Z for k, A in dense.items()}


def _multiplier_rows(system, values: np.ndarray, m: int) -> np.ndarray:
    """B_kl = sum_points w psi_k (values . Phi_l) over the reduced unknowns, psi_k = cos(k pi s / L), k < m (the m
    element-vector sets in one product)."""
    disc = system.disc
    psi = np.cos(np.arange(m).reshape((m,) + (1,) * disc.points.ndim) * np.pi * disc.points / disc.length)
    stack = element_vectors_stack(disc.tables, disc.weights, psi[..., None] * values)
    rows = [system.assembler.vector(vectors) for vectors in stack]
    return _reduce_rows(system.reduction, np.array(rows, float))


def projected_strain_linear(system, jets: np.ndarray, multipliers: int | None = None) -> dict:
    """M, D, G, K with the axial stiffness W_gg g_j g_j^T projected on the cosines (module docstring)."""
    disc, red = system.disc, system.reduction
    if "strain" not in system.kernels:
        raise InputError(f"{system.metadata.model} declares no strain measure", key="strain",
                         expected="strain = 'pointwise' (or a model with model.strain_density)")
    if red.multiplier_rows is not None:
        raise InputError("a projected strain takes its boundary conditions by elimination or penalty",
                         key="constraints", expected="constraints = 'eliminate' or 'penalty'")
    mats = system.reduced_matrices("linear", ("M", "D", "G", "K"), None, None, None, 0.0, jets)
    require_dense(system.n, 8, "the dense linearisation about a constrained steady state")
    dense = {k: v.toarray() if hasattr(v, "toarray") else np.asarray(v) for k, v in mats.items()}
    na = len(disc.jets)
    shape = disc.points.shape
    V_jj = np.asarray(system.pointwise("linear", jets)["K"]).reshape(shape + (na, na))
    local = system.pointwise("strain", jets)
    g_j = np.asarray(local["g_j"]).reshape(shape + (na,))
    g_jj = np.asarray(local["g_jj"]).reshape(shape + (na, na))
    on = np.flatnonzero(np.any(g_j != 0, axis=tuple(range(len(shape)))))
    block = np.ix_(on, on)
    a = g_jj[(...,) + block].reshape(shape + (-1,))
    b = (g_j[..., on, None] * g_j[..., None, on]).reshape(shape + (-1,))
    v = V_jj[(...,) + block].reshape(shape + (-1,))
    A = np.stack([a, b], axis=-1)  # V_jj = W_g g_jj + W_gg g_j g_j^T on the jets g depends on
    coef = np.linalg.solve(np.einsum("...ki,...kj->...ij", A, A), np.einsum("...ki,...k->...i", A, v)[..., None])
    misfit = np.abs(np.einsum("...ki,...i->...k", A, coef[..., 0]) - v).max() / max(np.abs(v).max(), 1e-300)
    W_gg = coef[..., 1, 0]
    if misfit > 1e-8 or not np.all(W_gg > 0):
        raise InputError(f"the stiffness of {system.metadata.model} is not W(g) of its strain measure here "
                         f"(misfit {misfit:.1e}, least W_gg {W_gg.min():.3g})", key="strain",
                         expected="strain = 'pointwise'")
    axial = W_gg[..., None, None] * g_j[..., :, None] * g_j[..., None, :]
    K_ax = red.matrix(system.assembler.matrix(element_matrices(disc.tables, disc.weights, axial)))
    m = int(multipliers or system.choices.get("N", 10))
    B = _multiplier_rows(system, g_j, m)
    psi = np.stack([np.cos(k * np.pi * disc.points / disc.length) for k in range(m)], axis=-1).reshape(-1, m)
    C = (psi * (disc.weights / W_gg).reshape(-1, 1)).T @ psi
    dense["K"] = dense["K"] - (K_ax.toarray() if hasattr(K_ax, "toarray") else np.asarray(K_ax)) \
        + B.T @ np.linalg.solve(C, B)
    return dense
