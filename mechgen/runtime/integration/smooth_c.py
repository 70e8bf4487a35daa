"""The compiled DOP853 loop for a smooth lumped model: the event loop with one mode and no guards.

A smooth model is the hybrid case without guards, so one compiled loop serves both
(mechgen.runtime.integration.events_c, ``runtime/csrc/hybrid_loop.c``): in C, for x = (q, v, z),

    dq/dt = v,   dv/dt = -M^-1 r(q, v, 0, z, t)   (M = dr/da from ``tangent``, LU with partial pivoting),
    dz/dt = rates(q, v, z, t),

stepped by DOP853 exactly as scipy.integrate.DOP853 steps it (the same coefficients, error norm, step
control and initial step; the samples at ``t_eval`` from its 7th-order dense output), calling the model's C
kernels by address: no Python runs between the steps. :class:`SmoothView` shows a smooth system to that
loop as a system of one mode (``smooth``) whose kernels are the plain ones; it holds the system and
changes nothing in it.
"""
from __future__ import annotations

import numpy as np

#: the kernels the loop calls, per mode
LOOP_KERNELS = ("residual", "tangent", "flow", "rates")


class SmoothView:
    """A smooth lumped system as the compiled event loop sees a hybrid one: one mode, no guards, no resets."""

    modes = ("smooth",)
    initial_mode = 0
    #: the loop's messages name no mode for it
    smooth = True
    is_lattice = False
    is_field = False

    def __init__(self, system, extra: int = 0, patterns: dict | None = None) -> None:
        self.system = system
        self.kernels = {f"{k}__0": system.kernels[k] for k in LOOP_KERNELS if k in system.kernels}
        self.m = system.m
        if extra:  # internal variables followed by integrated quantities: the energy_rates kernel's g
            self.kernels["rates__0"] = system.kernels["energy_rates"]
            self.m = system.m + extra
        #: the loop's memo (its kernel tables): a function of the kernels only, shared by the systems that share
        #: them (with_params copies); the parameters are read from ``system`` at every run
        self.patterns: dict = {} if patterns is None else patterns

    def __getattr__(self, name: str):  # n, m, params, metadata, backend: the system's
        return getattr(self.system, name)

    def guards(self, mode: int) -> tuple:
        return ()

    def mode(self, mode: int):
        return self.system


def view_of(system, extra: int = 0) -> SmoothView:
    """The system's loop view (``extra`` > 0: the state carries that many integrals after the internal variables,
    their rates from the ``energy_rates`` kernel). A new view of this very system each time (it reads the
    system's parameters), over a memo of kernel tables kept in the system's own memo (shared by its
    with_params copies, whose kernels are the same)."""
    return SmoothView(system, extra, system.patterns.setdefault(("c_loop", "smooth_view", extra), {}))


def smooth_loop_problem(system, rtol=1e-8, atol=1e-10, extra: int = 0) -> str | None:
    """Why the compiled loop cannot integrate ``system`` (None when it can): a smooth lumped system on the C
    backend, scalar tolerances, a C compiler for the loop's own library."""
    from mechgen.runtime.integration.events_c import c_loop_problem

    if hasattr(system, "modes"):
        return "the system has modes (the event loop runs it)"
    if system.is_lattice or system.is_field:
        return "the compiled loop integrates lumped systems only"
    if getattr(system, "backend", None) != "c":
        return f"the system's kernels are {getattr(system, 'backend', 'unknown')} ones, not compiled C"
    missing = [k for k in (("residual", "tangent") if system.n else ()) + (("rates",) if system.m else ())
               if k not in system.kernels]
    if missing:
        return f"the system has no {', '.join(missing)} kernel"
    return c_loop_problem(view_of(system, extra), "DOP853", rtol, atol)


def integrate_smooth_c(system, x0, t_end: float, options, *, extra: int = 0) -> tuple[np.ndarray, np.ndarray, dict]:
    """(t, x rows at the options' ``t_eval``, counts {steps, nfev}) of a smooth lumped system integrated by the
    compiled DOP853 loop (module doc; ``options``: mechgen.runtime.integration.run_options.RunOptions, ``method`` and
    ``loop`` not read; ``extra``: :func:`view_of`); failures raise the exceptions (and messages) of the event
    loop."""
    from mechgen.runtime.integration.events_c import integrate_hybrid_c

    traj = integrate_hybrid_c(view_of(system, extra), x0, t_end, mode=0, options=options)
    return traj.t, traj.x, {"steps": traj.steps, "nfev": traj.nfev}
