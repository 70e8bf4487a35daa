"""The free periodic orbits of a conservative model: a one-parameter family, regularised by an unfolding parameter.

A conservative model (no forcing, no dissipation: its residual satisfies the power balance v . r(q, v, a) = dE/dt
for its energy E = T + V) has no isolated periodic orbits: they come in families (the backbone curve), each orbit
one member, so an autonomous method's Jacobian is singular along the family. Two changes make each orbit isolated
(Munoz-Almaraz, Freire, Galan, Doedel & Vanderbauwhede, Physica D 181, 2003):

* the orbit's *level* is prescribed: the displacement of coordinate p at t = 0 (where the phase condition puts an
  extremum of q_p), q_p(0) = level; the frequency (or period) stays an unknown;
* an unfolding parameter eps is an unknown beside it, entering the equations so that a periodic solution exists
  only at eps = 0. Harmonic balance and collocation add a viscous term to the model's residual,
  r(q, v, a, t) + eps v = 0 (eps: force per velocity on every coordinate): over one period the energy balance is
  0 = E(T) - E(0) = -eps int_0^T |v|^2 dt, so eps = 0 on any non-constant orbit. Shooting unfolds the return map
  instead, x(T; x0) - x0 + eps grad E(x0) = 0: the flow keeps E, so E(x0) = E(x0 - eps grad E(x0)), which holds
  near the family only at eps = 0 (grad E(x0) != 0 off an equilibrium). grad E comes from central differences of
  the model's ``energy`` output (:func:`energy_gradient`); its own dependence on x0 is left out of the Jacobian
  (an error proportional to eps, which vanishes at the solution: Newton keeps its quadratic convergence).

The square system is then R(u) + eps d(u) = 0, the phase condition, q_p(0) - level = 0, in the unknowns
(u, eps) with u the method's autonomous unknowns (coefficients and omega, node states and T, start state and T).
Solved, eps is zero to the solver's tolerance (it is reported: a check that the model is conservative).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.runtime.periodic.collocation import DEGREE, Collocation, interval_tables
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance
from mechgen.runtime.periodic.shooting import Shooting

#: relative step of grad E's central differences
ENERGY_STEP = 1e-6
#: power-balance test: |v . r - dE/dt| below this times the scale |v| (|r| + |M a|) counts as conservative
POWER_TOLERANCE = 1e-6


def energy_gradient(system, x: np.ndarray) -> np.ndarray:
    """grad E(x) (E the model's ``energy`` output, J; x = (q, v)) by central differences, step ENERGY_STEP
    (1 + |x_i|), in one batched call of the outputs kernel."""
    x = np.asarray(x, float)
    h = ENERGY_STEP * (1.0 + np.abs(x))
    steps = np.diag(h)
    X = np.vstack([x + steps, x - steps])
    E = np.asarray(system.outputs_series(np.zeros(X.shape[0]), X)["energy"], float)
    return (E[:x.size] - E[x.size:]) / (2 * h)


def power_gap(system, states: np.ndarray, accelerations: np.ndarray, times: np.ndarray) -> float:
    """max over the rows of |v . r(q, v, a, t) - dE/dt| / (|v| (|r| + |r_a a|) + tiny): the failure of the power
    balance of a conservative model, dE/dt = grad_q E . v + grad_v E . a by central differences of ``energy``
    (0 up to the differences' error, ~1e-10, for a conservative model; O(1) with damping or a forcing)."""
    n = system.n
    worst = 0.0
    for x, a, t in zip(states, accelerations, times):
        q, v = x[:n], x[n:2 * n]
        r = np.asarray(system.residual(q, v, a, t=float(t)), float).ravel()
        rate = float(energy_gradient(system, x) @ np.concatenate([v, a]))
        inertia = np.asarray(system.tangent(q, v, a, t=float(t))["r_a"], float).reshape(n, n) @ a
        scale = np.linalg.norm(v) * (np.linalg.norm(r) + np.linalg.norm(inertia)) + 1e-300
        worst = max(worst, abs(float(v @ r) - rate) / scale)
    return worst


@dataclass(frozen=True)
class Unfolded:
    """The free orbit of level ``level`` of ``problem`` (an autonomous HarmonicBalance, Collocation or Shooting of a
    conservative model), unknowns (u, eps) (module doc). Attributes other than these come from ``problem``."""

    problem: object
    level: float

    def __getattr__(self, name):
        if name in ("problem", "level"):
            raise AttributeError(name)
        return getattr(self.problem, name)

    def unknowns(self, *args) -> np.ndarray:
        """(the method's unknowns, eps = 0)."""
        return np.append(self.problem.unknowns(*args), 0.0)

    def split(self, u: np.ndarray):
        """The method's split of u less eps."""
        return self.problem.split(np.asarray(u)[:-1])

    def states_at(self, u: np.ndarray, times: np.ndarray) -> np.ndarray:
        """Collocation's states at ``times`` (u less eps)."""
        return self.problem.states_at(np.asarray(u)[:-1], times)

    def monodromy(self, u: np.ndarray) -> np.ndarray:
        """Collocation's monodromy of the orbit (u less eps: eps = 0 on the family's orbits)."""
        return self.problem.monodromy(np.asarray(u)[:-1])

    def level_row(self, size: int) -> np.ndarray:
        """The gradient of q_p(0) over the method's unknowns (``size`` of them): q_p(0) is linear in them."""
        row = np.zeros(size)
        p, b = self.problem.phase, self.problem
        if isinstance(b, HarmonicBalance):  # q_p(0) = U[0, p] + sum_k U[k, p]
            n, H = b.system.n, b.basis.harmonics
            row[[k * n + p for k in range(H + 1)]] = 1.0
        else:  # collocation's node 0, shooting's x0
            row[p] = 1.0
        return row

    def unfolding(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(d(u) the unfolding term, eps dd/du, dd) with eps = u[-1] (module doc)."""
        base, eps = np.asarray(u[:-1], float), float(u[-1])
        b = self.problem
        if isinstance(b, HarmonicBalance):
            return hb_unfolding(b, base, eps)
        if isinstance(b, Collocation):
            return collocation_unfolding(b, base, eps)
        return shooting_unfolding(b, base, eps)

    def residual(self, u: np.ndarray) -> np.ndarray:
        """(R(u) + eps d(u), the phase condition, q_p(0) - level)."""
        base = np.asarray(u[:-1], float)
        R = self.problem.residual(base) if hasattr(self.problem, "residual") else \
            self.problem.residual_jacobian(base)[0]
        d, _, _ = self.unfolding(u)
        R = R.copy()
        R[:d.size] += float(u[-1]) * d
        return np.append(R, self.level_row(base.size) @ base - self.level)

    def residual_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The residual (:meth:`residual`) and its Jacobian over (u, eps)."""
        base, eps = np.asarray(u[:-1], float), float(u[-1])
        R, J = self.problem.residual_jacobian(base)
        d, dd, _ = self.unfolding(u)
        R, J = R.copy(), J.copy()
        R[:d.size] += eps * d
        J[:d.size] += dd
        column = np.zeros((J.shape[0], 1))
        column[:d.size, 0] = d
        row = np.append(self.level_row(base.size), 0.0)
        return np.append(R, row[:-1] @ base - self.level), np.vstack([np.hstack([J, column]), row])


def hb_unfolding(b: HarmonicBalance, base: np.ndarray, eps: float) -> tuple:
    """P (eps v_s) of harmonic balance: d = omega D U (D = P G1, d/dtheta on the coefficients), its eps-weighted
    derivatives over (vec U, omega)."""
    U, omega = b.split(base)
    n = b.system.n
    D = b.basis.projector @ b.basis.slopes
    d = omega * (D @ U).ravel()
    dd = np.zeros((d.size, base.size))
    dd[:, :d.size] = eps * omega * np.kron(D, np.eye(n))
    dd[:, d.size] = eps * (D @ U).ravel()
    return d, dd, d


def collocation_unfolding(b: Collocation, base: np.ndarray, eps: float) -> tuple:
    """eps v at each Gauss point, added to the residual rows (not to dq/dtau - T v), and its derivative over the
    node states (eps l_j(zeta) I)."""
    X, T = b.split(base)
    n, m = b.system.n, DEGREE
    at = b.points(X, T)
    d = np.hstack([np.zeros_like(at["v"]), at["v"]]).ravel()
    _, L, _ = interval_tables()
    dd = np.zeros((d.size, base.size))
    index = b.node_index()
    for i in range(b.mesh):
        for k in range(m):
            c = i * m + k
            for j in range(m + 1):
                g = index[i, j] * 2 * n
                dd[c * 2 * n + n:(c + 1) * 2 * n, g + n:g + 2 * n] += eps * L[k, j] * np.eye(n)
    return d, dd, d


def shooting_unfolding(b: Shooting, base: np.ndarray, eps: float) -> tuple:
    """grad E(x0) on the closing segment's rows (x_{S-1}'s flow minus x0); its derivative over x0 left out (module
    doc)."""
    X, _ = b.starts(base)
    S, dim = X.shape
    d = np.zeros(S * dim)
    d[(S - 1) * dim:] = energy_gradient(b.system, X[0])
    return d, np.zeros((d.size, base.size)), d
