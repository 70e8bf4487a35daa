"""A compiled hybrid system: one set of kernels per mode, the guards leaving each mode and the resets.

The kernels of mode i are named ``<kernel>__i`` (mechgen.codegen.lower_model.lower_hybrid); the system itself
answers for its *initial* mode under the plain names (``residual``, ``linear`` ...), so every
smooth analysis (modes, stability, steady) sees the model in the mode it starts in, and
:meth:`HybridSystem.mode` gives the plain :class:`~mechgen.runtime.core.system.System` of any mode.
Guards (``guards__i``) give g and dg/dt along the mode's flow; reset j (``reset__j``) the state after
the event; with the ``saltation`` kernels, ``guard_jacobian__i`` and ``reset_jacobian__j`` their derivatives
(:meth:`HybridSystem.saltation`). Immutable like every system.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.runtime.core.system import System


@dataclass(frozen=True)
class GuardInfo:
    """One guard of a mode: its name, direction (+1 rising, -1 falling, 0 both), whether it ends the run,
    the mode it enters (index, None when terminal) and its reset (index, None: the state is kept)."""

    name: str
    direction: int
    terminal: bool
    to: int | None
    reset: int | None


@dataclass(frozen=True, eq=False)
class HybridSystem(System):
    """A :class:`System` of a model with modes (mechgen.symbolic.hybrid); see the module doc."""

    def __post_init__(self) -> None:
        kernels = dict(self.kernels)
        hybrid = self.meta["hybrid"]
        initial = int(hybrid["initial"])
        for name in list(kernels):
            base, _, index = name.rpartition("__")
            if base and index == str(initial) and not base.startswith(("guard", "reset")):
                kernels.setdefault(base, kernels[name])
        object.__setattr__(self, "kernels", kernels)
        super().__post_init__()

    # -- structure ----------------------------------------------------------------
    @property
    def modes(self) -> tuple[str, ...]:
        """The mode names, in declaration order."""
        return tuple(self.meta["hybrid"]["modes"])

    @property
    def initial_mode(self) -> int:
        """Index of the mode a run starts in unless told otherwise."""
        return int(self.meta["hybrid"]["initial"])

    def guards(self, mode: int) -> tuple[GuardInfo, ...]:
        """The guards leaving ``mode`` (terminal ones first, then in declaration order)."""
        return tuple(GuardInfo(g["name"], int(g["direction"]), bool(g["terminal"]), g["to"], g["reset"])
                     for g in self.meta["hybrid"]["guards"][mode])

    def mode_index(self, name: str) -> int:
        """Index of the mode called ``name`` (ValueError when there is none)."""
        return self.modes.index(name)

    def mode(self, index: int) -> System:
        """The plain System of mode ``index`` at this system's parameters (its kernels under the plain names)."""
        suffix = f"__{index}"
        kernels = {name[: -len(suffix)]: k for name, k in self.kernels.items()
                   if name.endswith(suffix) and not name.startswith(("guard", "reset"))}
        view = System(kernels, dict(self.meta), self.params, 0, self.backend)
        object.__setattr__(view, "patterns", self.patterns.setdefault(("mode", index), {}))
        return view

    # -- evaluation -----------------------------------------------------------------
    def guard_values(self, mode: int, t: float, x: np.ndarray, dxdt: np.ndarray | None = None):
        """(g, g_t) of the guards leaving ``mode`` at state x; g_t needs dx/dt (zeros without it: g only)."""
        n = self.n
        name = f"guards__{mode}"
        if name not in self.kernels:
            return np.zeros(0), np.zeros(0)
        q, v, z = x[:n], x[n:2 * n], x[2 * n:]
        a = None if dxdt is None else dxdt[n:2 * n]
        out = self.bound(name).evaluate(q=q, v=v, a=a, z=z if self.m else None, t=t)
        return out["g"].copy(), out["g_t"].copy()

    def reset(self, index: int, t: float, x: np.ndarray) -> np.ndarray:
        """The state after reset ``index`` at state x (time t)."""
        n = self.n
        out = self.bound(f"reset__{index}").evaluate(q=x[:n], v=x[n:2 * n], z=x[2 * n:] if self.m else None, t=t)
        return out["x"].copy()

    def saltation(self, mode: int, guard: int, t: float, x: np.ndarray) -> np.ndarray:
        """The saltation matrix of the event of guard ``guard`` (its position in :meth:`guards`) leaving ``mode``
        at (t, x), x the state just before it (on the guard's surface):

            S = R_x + (f+ - R_x f- - R_t) g_x^T / (dg/dt),   dg/dt = g_x . f- + dg/dt|explicit,

        f- = dx/dt of ``mode`` at (t, x), x+ = R(x, t) the state after the reset (x itself without one), f+ =
        dx/dt of the mode entered at (t, x+); R_x, R_t from ``reset_jacobian__j`` (I and 0 without a reset), g_x
        from ``guard_jacobian__<mode>``. It maps a perturbation just before the event to the one just after it
        (Aizerman & Gantmacher 1958; Leine & Nijmeijer, Dynamics and Bifurcations of Non-Smooth Mechanical
        Systems, 2004, sec. 7.2): the monodromy of a hybrid periodic orbit is the product of the segments'
        state-transition matrices and these. The model must be compiled with the ``saltation`` kernels."""
        info = self.guards(mode)[guard]
        n, size = self.n, np.size(x)
        if f"guard_jacobian__{mode}" not in self.kernels:
            raise ValueError("the system has no saltation kernels (compile it with kernels including 'saltation')")
        f_minus = self.mode(mode).rhs(t, x)
        state = {"q": x[:n], "v": x[n:2 * n], "z": x[2 * n:] if self.m else None, "t": t}
        g_x = self.bound(f"guard_jacobian__{mode}").evaluate(**state)["g_x"].reshape(-1, size)[guard]
        _, rate = self.guard_values(mode, t, x, f_minus)
        if info.reset is None:
            R_x, R_t, x_plus = np.eye(size), np.zeros(size), np.asarray(x, float)
        else:
            out = self.bound(f"reset_jacobian__{info.reset}").evaluate(**state)
            R_x, R_t = out["R_x"].reshape(size, size).copy(), out["R_t"].ravel().copy()
            x_plus = self.reset(info.reset, t, x)
        f_plus = self.mode(mode if info.to is None else info.to).rhs(t, x_plus)
        return R_x + np.outer(f_plus - R_x @ f_minus - R_t, g_x) / rate[guard]
