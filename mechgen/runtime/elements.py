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
