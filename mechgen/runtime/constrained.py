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
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from mechgen.errors import InputError
from mechgen.runtime.assemble import element_matrices, element_vectors


def linear_about_bvp(system, bvp, result) -> dict:
    """M, D, G, K about a boundary-value steady state (``result`` of ``bvp``): the model's Galerkin
    linearisation at its jets, on the constraint's null space when the model holds one."""
    disc = system.disc
    jets = bvp.jets(result, disc.points, disc.jets)
    if "constraint" not in system.kernels:
        return system.linear(jets=jets)
    return constrained_linear(system, bvp, result, jets)


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
    mats = system._matrices("linear", ("M", "D", "G", "K"), None, None, None, 0.0, jets)
    dense = {k: v.toarray() if hasattr(v, "toarray") else np.asarray(v) for k, v in mats.items()}
    local = system._pointwise("constraint", jets)
    na = len(disc.jets)
    g_j = np.asarray(local["g_j"]).reshape(disc.points.shape + (na,))
    g_jj = np.asarray(local["g_jj"]).reshape(disc.points.shape + (na, na))
    mu = steady_multiplier(system, bvp, result, disc.points, g_j)
    K_c = system.assembler.matrix(element_matrices(disc.tables, disc.weights, mu[..., None, None] * g_jj))
    K_c = red.matrix(K_c)
    dense["K"] = dense["K"] + (K_c.toarray() if hasattr(K_c, "toarray") else np.asarray(K_c))
    m = int(multipliers or system.choices.get("N", 10))
    rows = []
    for k in range(m):
        psi = np.cos(k * np.pi * disc.points / disc.length)
        full = system.assembler.vector(element_vectors(disc.tables, disc.weights, psi[..., None] * g_j))
        rows.append(np.asarray(full, float))
    B = _reduce_rows(red, np.array(rows))
    Z = sla.null_space(B, rcond=1e-10)
    return {k: Z.T @ A @ Z for k, A in dense.items()}
