"""A state that carries the energy balance's integrals: the flows and hybrid systems the loops integrate then.

Along a solution of Lagrange's equations with forces Q and Rayleigh dissipation R the energy function
h = v.dT/dv - T + V obeys dh/dt = Q.v - v.dR/dv - dL/dt (mechgen.analyses.energy_balance). The three powers
come from the generated ``energy_rates`` kernel (its output ``g``: the internal rates dz/dt followed by Q.v,
v.dR/dv and -dL/dt), so appending their integrals to the state,

    x = (q, v, z, W_forces, D, W_explicit),   d/dt (W_forces, D, W_explicit) = (Q.v, v.dR/dv, -dL/dt),

lets the integrator that steps the motion integrate them too, under the same error control. The integrals do not
feed back into the motion. A hybrid system carries them across its events: a reset maps (q, v, z) and leaves the
integrals as they are (the energy a reset takes is accounted from the states on both sides of it).
"""
from __future__ import annotations

import numpy as np

#: the integrated powers appended to the state: the forces' work, the dissipated energy, the explicit work
INTEGRALS = 3


class AugmentedFlow:
    """dx/dt and its Jacobian for x = (q, v, z, W_forces, D, W_explicit) of a smooth system: its own, then the
    powers. Other attributes (n, m, kernels ...) are the system's: the state it describes is (q, v, z)."""

    def __init__(self, system) -> None:
        self.system = system
        self.size = 2 * system.n + system.m

    def __getattr__(self, name: str):
        return getattr(self.system, name)

    def powers(self, t: float, x: np.ndarray) -> np.ndarray:
        """(Q.v, v.dR/dv, -dL/dt) at (t, x) (a continuum's: its power densities integrated over the domain, with
        the end and part terms: mechgen.runtime.fields.operators.integrated_series)."""
        if self.system.is_field:
            from mechgen.runtime.fields.operators import integrated_series

            return integrated_series(self.system, "energy_rates", np.array([t]), np.asarray(x, float)[None])["g"][0]
        n, m = self.system.n, self.system.m
        g = self.system.bound("energy_rates").evaluate(q=x[:n], v=x[n:2 * n], z=x[2 * n:2 * n + m], t=t)["g"]
        return np.asarray(g[m:], float).copy()

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        state = x[:self.size]
        return np.concatenate([self.system.rhs(t, state), self.powers(t, state)])

    def jacobian(self, t: float, x: np.ndarray) -> np.ndarray:
        """The system's Jacobian bordered by zeros: the integrals do not feed back, and their rows' dependence
        on the state is left to the corrector (the Newton iteration still converges: those rows are explicit)."""
        J = np.zeros((self.size + INTEGRALS, self.size + INTEGRALS))
        inner = self.system.jacobian(t, x[:self.size])
        J[:self.size, :self.size] = inner.toarray() if hasattr(inner, "toarray") else inner
        return J


def balance_kernels(system) -> bool:
    """Whether every mode of a hybrid system has its ``energy_rates`` kernel (the integrals can be carried)."""
    return all(f"energy_rates__{i}" in system.kernels for i in range(len(system.modes)))


class BalancedHybrid:
    """A hybrid system whose state carries the three integrals across its modes and events (module doc), for both
    event loops: ``mode(i)`` is the mode's AugmentedFlow, guards read (q, v, z), resets pass the integrals on;
    the compiled loop sees each mode's rates kernel replaced by its ``energy_rates`` (dz/dt, then the powers) and
    ``carried`` = 3 trailing entries that resets keep. Everything else is the system's."""

    carried = INTEGRALS

    def __init__(self, system) -> None:
        self.system = system
        self.size = 2 * system.n + system.m
        kernels = dict(system.kernels)
        for i in range(len(system.modes)):
            kernels[f"rates__{i}"] = system.kernels[f"energy_rates__{i}"]
        self.kernels = kernels
        self.m = system.m + INTEGRALS
        #: the compiled loop's memo for this view (its tables differ from the plain system's: other rates kernels)
        self.patterns = system.patterns.setdefault(("balanced_hybrid",), {})

    def __getattr__(self, name: str):  # modes, guards, n, params, backend, metadata ...: the system's
        return getattr(self.system, name)

    def mode(self, index: int) -> AugmentedFlow:
        return AugmentedFlow(self.system.mode(index))

    def guard_values(self, mode: int, t: float, x: np.ndarray, dxdt: np.ndarray | None = None):
        k = self.size
        return self.system.guard_values(mode, t, x[:k], None if dxdt is None else dxdt[:k])

    def reset(self, index: int, t: float, x: np.ndarray) -> np.ndarray:
        k = self.size
        return np.concatenate([self.system.reset(index, t, x[:k]), x[k:]])
