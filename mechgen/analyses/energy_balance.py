"""The energy balance of a ``simulate`` run of a lumped model: a dissipative or forced run checked, not labelled.

Along a solution of Lagrange's equations with non-conservative forces Q and Rayleigh dissipation R
(mechgen.symbolic.derive.energy_powers), the energy function h = v.dT/dv - T + V obeys

    dh/dt = Q.v - v.dR/dv - dL/dt,        h = E + (v.dT/dv - 2 T),   E = T + V,

so with the work W(t) = int_0^t (Q.v - dL/dt) dt (the forces' work and that of an explicit time dependence of
T or V) and the dissipated energy D(t) = int_0^t v.dR/dv dt,

    energy_balance_error = max_t |h(t) - h(0) - W(t) + D(t)| / S,   S = max_t (|T| + |V|, |W|, D),

which is E(t) - E(0) - W(t) + D(t) when T is a quadratic form in v (the excess v.dT/dv - 2 T is zero). W and D
are integrated with the state, as three more components of dx/dt (the generated ``energy_rates`` kernel: the
internal rates followed by Q.v, v.dR/dv and -dL/dt), by the same integrator under the same error control, so
the figure measures the run's accuracy. A run is *conservative* when the three powers and the excess are zero
at every sample (exactly: a term the model does not declare is a generated zero): it reports ``energy_drift``
(mechgen.analyses.time_series); any other reports ``energy_balance_error``, ``work`` and ``dissipated`` (their
values at the end; in the trajectory too, when kept) instead.
"""
from __future__ import annotations

import numpy as np

#: the integrated powers appended to the state: the forces' work, the dissipated energy, the explicit work
EXTRA = 3


def accounted(system, method: str) -> bool:
    """Whether the run integrates the balance: a smooth lumped system with the energy_rates kernel, and an
    integrator that takes the augmented state (not CVODES, whose problem is built from the plain kernels)."""
    return ("energy_rates" in system.kernels and method != "cvodes" and not hasattr(system, "modes")
            and not system.is_lattice and not system.is_field)


class AugmentedFlow:
    """dx/dt and its Jacobian for x = (q, v, z, W_forces, D, W_explicit): the system's own, then the powers."""

    def __init__(self, system) -> None:
        self.system = system
        self.size = 2 * system.n + system.m

    def powers(self, t: float, x: np.ndarray) -> np.ndarray:
        n, m = self.system.n, self.system.m
        g = self.system.bound("energy_rates").evaluate(q=x[:n], v=x[n:2 * n], z=x[2 * n:2 * n + m], t=t)["g"]
        return np.asarray(g[m:], float).copy()

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        state = x[:self.size]
        return np.concatenate([self.system.rhs(t, state), self.powers(t, state)])

    def jacobian(self, t: float, x: np.ndarray) -> np.ndarray:
        """The system's Jacobian bordered by zeros: the integrals do not feed back, and their rows' dependence
        on the state is left to the corrector (the Newton iteration still converges: those rows are explicit)."""
        J = np.zeros((self.size + EXTRA, self.size + EXTRA))
        inner = self.system.jacobian(t, x[:self.size])
        J[:self.size, :self.size] = inner.toarray() if hasattr(inner, "toarray") else inner
        return J


def excess(system, t: np.ndarray, X: np.ndarray) -> np.ndarray:
    """v.dT/dv - 2 T at each sample (zero for a kinetic energy quadratic in v), in one batched call."""
    n = system.n
    kernel = system.kernels["energy_rates"]
    wanted = {port["name"] for port in kernel.spec["inputs"]}
    inputs = {"q": X[:, :n], "v": X[:, n:2 * n], "z": X[:, 2 * n:2 * n + system.m], "t": t[:, None],
              "p": system.params}
    return np.asarray(kernel.evaluate({k: v for k, v in inputs.items() if k in wanted})["excess"],
                      float).reshape(len(t))


def figures(system, t: np.ndarray, X: np.ndarray, series: dict) -> dict | None:
    """``energy_balance_error``, ``work``, ``dissipated`` (and their series, ``_work_series`` ...) of a run whose
    state carries the integrals (X: samples of the augmented state), or None when the run is conservative."""
    W = X[:, -3] + X[:, -1]
    D = X[:, -2]
    h = series["energy"] + excess(system, t, X)
    if not (np.any(X[:, -EXTRA:]) or np.any(h - series["energy"])):
        return None
    scale = max(float(np.max(np.abs(series["kinetic_energy"]) + np.abs(series["potential_energy"]))),
                float(np.max(np.abs(W))), float(np.max(np.abs(D))))
    error = h - h[0] - W + D
    return {"energy_balance_error": float(np.max(np.abs(error)) / scale) if scale > 0 else 0.0,
            "work": float(W[-1]), "dissipated": float(D[-1]), "_work_series": W, "_dissipated_series": D}
