"""One-dimensional reference elements on xi in [0, 1], built from their interpolation conditions.

An element has nodes xi_i and, per node, the nodal values it carries: the value
(order 0) and, for Hermite elements, the slope (order 1). Its shape functions
are the polynomials N_l of degree (number of dofs - 1) with D^k N_l(xi_i) = delta,
found by inverting the conditions on monomials once. On an element of length h,
physical shape functions are phi_l(s) = h^k_l N_l(xi), k_l the order the dof
carries (a slope dof is dw/ds, so its shape function scales with h), and

    D_s^j phi_l = h^(k_l - j) D_xi^j N_l(xi).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.polynomial import polynomial as P


@dataclass(frozen=True)
class ReferenceElement:
    """Shape functions as monomial coefficients (columns), node positions and per-dof orders."""

    name: str
    nodes: tuple[float, ...]
    orders: tuple[int, ...]
    coefficients: np.ndarray
    continuity: int

    @property
    def ndof(self) -> int:
        """Dofs per element."""
        return len(self.orders) * len(self.nodes)

    @property
    def degree(self) -> int:
        """Polynomial degree of the shape functions."""
        return self.ndof - 1

    def tabulate(self, xi: np.ndarray, max_order: int, h: np.ndarray) -> np.ndarray:
        """D_s^j phi_l at xi for elements of lengths h: array (len(h), len(xi), max_order + 1, ndof)."""
        xi = np.asarray(xi, float)
        h = np.asarray(h, float).reshape(-1, 1, 1, 1)
        ref = np.empty((len(xi), max_order + 1, self.ndof))
        for j in range(max_order + 1):
            coef = P.polyder(self.coefficients, j, axis=0) if j else self.coefficients
            ref[:, j, :] = P.polyval(xi, coef).T if coef.size else 0.0
        dof_order = np.tile(np.asarray(self.orders), len(self.nodes))
        power = dof_order[None, None, None, :] - np.arange(max_order + 1)[None, None, :, None]
        return ref[None] * h**power


@lru_cache(maxsize=None)
def reference(name: str) -> ReferenceElement:
    """The reference element called ``name`` (lagrange1, lagrange2, hermite, quintic)."""
    nodes, orders, continuity = {
        "lagrange1": ((0.0, 1.0), (0,), 0),
        "lagrange2": ((0.0, 0.5, 1.0), (0,), 0),
        "hermite": ((0.0, 1.0), (0, 1), 1),
        "quintic": ((0.0, 0.5, 1.0), (0, 1), 1),
    }[name]
    n = len(nodes) * len(orders)
    conditions = np.zeros((n, n))
    row = 0
    for x in nodes:
        for k in orders:
            for m in range(k, n):
                conditions[row, m] = np.prod(np.arange(m - k + 1, m + 1)) * x ** (m - k)
            row += 1
    return ReferenceElement(name, nodes, orders, np.linalg.inv(conditions), continuity)


def timoshenko_shapes(xi: np.ndarray, h: np.ndarray, phi: np.ndarray, sign: int, max_order: int) -> np.ndarray:
    """Two-node Timoshenko element: D_s^j of (w, psi) for the dofs (w1, w2, psi1, psi2).

    The shape functions solve the static, unloaded equations kGA (w_ss - sign psi_s) = 0,
    EI psi_ss + sign kGA (w_s - sign psi) = 0 exactly (interdependent interpolation,
    Friedman & Kosmatka 1993): with s = xi h and phi = 12 EI / (kGA h^2),

        w = c0 + c1 xi + c2 xi^2 + c3 xi^3,   sign psi = (c1 + 2 c2 xi + 3 c3 xi^2 + c3 phi / 2) / h,

    c from the nodal values. phi = 0 gives the cubic Hermite beam with psi = sign w_s.
    Returns an array (len(h), len(xi), 2, max_order + 1, 4): [..., 0, j, :] for w, [..., 1, j, :] for psi.
    """
    xi = np.asarray(xi, float)
    h = np.asarray(h, float)
    phi = np.asarray(phi, float)
    ne, nq = len(h), len(xi)
    A = np.zeros((ne, 4, 4))
    A[:, 0, 0] = 1.0
    A[:, 1, 1], A[:, 1, 3] = 1.0, phi / 2
    A[:, 2, :] = 1.0
    A[:, 3, 1], A[:, 3, 2], A[:, 3, 3] = 1.0, 2.0, 3.0 + phi / 2
    S = np.zeros((ne, 4, 4))  # nodal conditions (w1, h psi~1, w2, h psi~2) from the dofs (w1, w2, psi1, psi2)
    S[:, 0, 0], S[:, 2, 1] = 1.0, 1.0
    S[:, 1, 2], S[:, 3, 3] = sign * h, sign * h
    C = np.linalg.solve(A, S)  # (e, monomial, dof)
    one, zero = np.ones(nq), np.zeros(nq)
    mono = [np.stack([one, xi, xi**2, xi**3], -1), np.stack([zero, one, 2 * xi, 3 * xi**2], -1),
            np.stack([zero, zero, 2 * one, 6 * xi], -1), np.stack([zero, zero, zero, 6 * one], -1)]
    out = np.zeros((ne, nq, 2, max_order + 1, 4))
    hh = h[:, None, None]
    for j in range(max_order + 1):
        out[:, :, 0, j] = np.einsum("qk,ekl->eql", mono[j], C) / hh**j
        # psi = sign (w_s + c3 phi / (2 h)); its derivatives are sign D_s^(j+1) w
        extra = (phi / 2)[:, None, None] * C[:, None, 3, :] if j == 0 else 0.0
        out[:, :, 1, j] = sign * (np.einsum("qk,ekl->eql", mono[j + 1], C) + extra) / hh ** (j + 1)
    return out
