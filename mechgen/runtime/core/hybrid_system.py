"""A compiled hybrid system: one set of kernels per mode, the guards leaving each mode and the resets.

The kernels of mode i are named ``<kernel>__i`` (mechgen.pipeline.lower_hybrid); the system itself
answers for its *initial* mode under the plain names (``residual``, ``linear`` ...), so every
smooth analysis (modes, stability, steady) sees the model in the mode it starts in, and
:meth:`HybridSystem.mode` gives the plain :class:`~mechgen.runtime.core.system.System` of any mode.
Guards (``guards__i``) give g and dg/dt along the mode's flow; reset j (``reset__j``) the state after
the event. Immutable like every system.
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
            if base and index == str(initial) and not base.startswith(("guards", "reset")):
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
                   if name.endswith(suffix) and not name.startswith(("guards", "reset"))}
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
