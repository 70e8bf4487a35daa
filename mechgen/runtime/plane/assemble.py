"""Assembly of plane continua from factored tables: the jet table B is never materialised.

The jets of a plane model are, per field c, its value and its two first derivatives, so that
B[e, g, (c, k), (l, d)] = delta_cd T_k[e, g, l] with T_0 = N (shape values), T_1 = dN/dx, T_2 = dN/dy.
With weights w[e, g] (quadrature weight x |det J|) and pointwise coefficients rho[e, g, a],
C[e, g, a, b] from a generated kernel (jets a = (c, k), b = (d, k')):

    j[e, g, a]                    = sum_l T_k[e, g, l] x[dof(e, l, c)],
    r_e[l, c]                     = sum_g w sum_k T_k[e, g, l] rho[e, g, (c, k)],
    K_e[(l, c), (m, d)]           = sum_g w T_k[e, g, l] C[e, g, (c, k), (d, k')] T_k'[e, g, m],

one batched matrix product per (a, b) pair whose coefficient is not identically zero. Dofs are
interleaved: dof(e, l, c) = node(e, l) * nfields + c. Memory: T is (elements, points, nodes) per order
against (elements, points, jets, nodes x fields) for B, nfields x fewer.
"""
from __future__ import annotations

import numpy as np

ORDER_INDEX = {"": 0, "x": 1, "y": 2}


def order_tables(values: np.ndarray, gradients: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T_0, T_1, T_2) as (e, g, l) arrays from shape values N (g, l) or (e, g, l) and gradients (e, g, l, 2)."""
    values = np.broadcast_to(values, gradients.shape[:3]) if values.ndim == 2 else values
    return values, gradients[..., 0], gradients[..., 1]


def jet_index(jets, fields) -> list[tuple[int, int]]:
    """(field index c, order index k) of each jet (field, order)."""
    return [(list(fields).index(f), ORDER_INDEX[k]) for f, k in jets]


def point_jets(T, index, local: np.ndarray) -> np.ndarray:
    """j[e, g, a] from the element dofs ``local`` (e, nodes, fields)."""
    ne, ng, _ = T[0].shape
    out = np.empty((ne, ng, len(index)))
    for a, (c, k) in enumerate(index):
        out[:, :, a] = np.einsum("egl,el->eg", T[k], local[:, :, c], optimize=True)
    return out


def element_vectors(T, index, weights: np.ndarray, rho: np.ndarray, nfields: int) -> np.ndarray:
    """r_e[l * nfields + c] = sum_g w sum_k T_k rho_(c, k)."""
    ne, _, nl = T[0].shape
    out = np.zeros((ne, nl, nfields))
    for a, (c, k) in enumerate(index):
        out[:, :, c] += np.einsum("egl,eg->el", T[k], weights * rho[:, :, a], optimize=True)
    return out.reshape(ne, nl * nfields)


def element_matrices(T, index, weights: np.ndarray, coeff: np.ndarray, nfields: int) -> np.ndarray:
    """K_e[(l, c), (m, d)] = sum_g w T_k[l] C_(c,k),(d,k') T_k'[m], only over jets with a non-zero coefficient
    (:func:`mechgen.runtime.plane.elements.blocked_element_matrices`: a block of cells at a time, one batched
    product each; 3x quicker at 10^6 unknowns than a product per (a, b) pair)."""
    from mechgen.runtime.plane.elements import blocked_element_matrices

    return blocked_element_matrices([T[k] for _, k in index], [c for c, _ in index], weights, coeff, nfields)
