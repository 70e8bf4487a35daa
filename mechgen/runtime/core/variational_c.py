"""The compiled loop of the variational integrator: :func:`compiled_stepper`.

A system on the C backend is stepped by one C function (``mgv_run`` in
mechgen/runtime/csrc/variational_loop.c, built once into the compile cache as ``libmgvariational``)
that calls the model's own ``lagrangian`` kernel through its address: no Python runs per step. Its rules
are those of the Python stepper (mechgen.runtime.core.variational.python_stepper): the same stage
equations, Jacobian, Newton stop (NEWTON_RTOL, STALL, MAX_NEWTON), accepted point and records; the two
agree to rounding (LU with partial pivoting here, LAPACK's there). Without a compiler, or for kernels
without a C address, None is returned and the Python stepper runs (one log line).
"""
from __future__ import annotations

import ctypes
import logging
from functools import lru_cache
from typing import Callable

import numpy as np

from mechgen.errors import BuildError, CompilerUnavailable, KernelError
from mechgen.runtime import csrc
from mechgen.runtime.core.variational_rules import (MAX_NEWTON, NEWTON_RTOL, STALL, Tableau, newton_failure,
                                                    nonfinite, singular)

log = logging.getLogger("mechgen")

SOURCE = csrc.path("variational_loop.c")
STEM = "mgvariational"
INPUTS = ["q", "v", "z", "t", "p"]
OUTPUTS = ["mom", "F", "mom_q", "mom_v", "F_q", "F_v"]
RATES = ["g", "excess"]
c_long, c_double, c_void_p = ctypes.c_long, ctypes.c_double, ctypes.c_void_p
LONG = np.dtype(f"i{ctypes.sizeof(c_long)}")


@lru_cache(maxsize=1)
def _library():
    """(the loaded loop library, None) or (None, why it is unavailable); built once per process."""
    from mechgen.buildlock import load_shared_once as load_shared  # compiled once across processes

    try:
        lib = load_shared(csrc.source(SOURCE), stem=STEM, ldflags=("-lm",), symbols=("mgv_run",))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("C variational loop unavailable (%s)", exc)
        return None, f"the C variational loop cannot be built ({exc})"
    lib.mgv_run.argtypes = ([c_void_p, c_void_p, c_void_p, c_long, c_long, c_void_p, c_void_p, c_void_p, c_double]
                            + [c_long] * 4 + [c_double, c_double, c_long] + [c_void_p] * 14)
    lib.mgv_run.restype = ctypes.c_int
    return lib, None


def c_unavailable(system, balance: bool = False) -> str | None:
    """Why ``system`` cannot run in the C loop (None when it can); ``balance``: with its energy_rates kernel too."""
    if balance:
        rates = system.kernels.get("energy_rates")
        if rates is None or rates.address is None:
            return "kernel energy_rates is missing or has no C function address"
        if [p["name"] for p in rates.spec["inputs"]] != INPUTS or [p["name"] for p in rates.spec["outputs"]] != RATES:
            return "kernel energy_rates has other ports than (q, v, z, t, p) -> (g, excess)"
    kernel = system.kernels.get("lagrangian")
    if kernel is None:
        return "the system has no lagrangian kernel"
    if kernel.address is None:
        return f"kernel lagrangian has no C function address (backend {kernel.backend})"
    if [p["name"] for p in kernel.spec["inputs"]] != INPUTS or [p["name"] for p in kernel.spec["outputs"]] != OUTPUTS:
        return "kernel lagrangian has other ports than (q, v, z, t, p) -> (mom, F, mom_q, mom_v, F_q, F_v)"
    if system.m:
        return "the system has internal variables"
    return _library()[1]


def _ptr(arr: np.ndarray) -> int:
    return arr.ctypes.data


def compiled_stepper(system, tab: Tableau, h: float, *, balance: bool = False,
                     required: bool = False) -> Callable | None:
    """``advance(q, p, V, W, k0, count, total, save_every)`` running ``mgv_run`` (the Python stepper's contract;
    ``balance``: W integrated with the energy_rates kernel), or None when the C loop cannot run
    (CompilerUnavailable instead with ``required``)."""
    why = c_unavailable(system, balance)
    if why:
        if required:
            raise CompilerUnavailable(why)
        log.info("variational loop in Python: %s", why)
        return None
    lib, n, s = _library()[0], system.n, tab.stages
    m = s * n
    work, piv = np.zeros(4 * m + 4 * s * n * n + m * m), np.zeros(m, dtype=LONG)
    A, b, c = (np.ascontiguousarray(x, float) for x in (tab.a, tab.b, tab.c))
    params = np.ascontiguousarray(system.params, float)
    address = system.kernels["lagrangian"].address
    rates = system.kernels["energy_rates"].address if balance else None

    def advance(q, p, V, W, k0: int, count: int, total: int, save_every: int):
        q, p, V, W = (np.array(x, float, order="C") for x in (q, p, V, W))
        cap = count // save_every + 2
        rq, rp, rv, rt = np.zeros((cap, n)), np.zeros((cap, n)), np.zeros((cap, n)), np.zeros(cap)
        rw = np.zeros((cap, 3))
        nrec, done, newton = (np.zeros(1, dtype=LONG) for _ in range(3))
        rc = lib.mgv_run(address, rates, _ptr(params), n, s, _ptr(A), _ptr(b), _ptr(c), h, k0, count, total,
                         save_every, NEWTON_RTOL, STALL, MAX_NEWTON, _ptr(q), _ptr(p), _ptr(V), _ptr(W), _ptr(work),
                         _ptr(piv), _ptr(rq), _ptr(rp), _ptr(rv), _ptr(rw), _ptr(rt), _ptr(nrec), _ptr(done),
                         _ptr(newton))
        t = (k0 + int(done[0])) * h
        if rc == -1:
            raise nonfinite(t)
        if rc == -3:
            raise singular(t)
        if rc == -2:
            raise newton_failure(t, h)
        if rc:
            raise KernelError(f"variational loop: kernel lagrangian returned error code {rc} in the step from "
                              f"t = {t:.6g}")
        samples = [(float(rt[i]), rq[i], rp[i], rv[i], rw[i]) for i in range(int(nrec[0]))]
        return q, p, V, W, int(newton[0]), samples
    return advance


__all__ = ["c_unavailable", "compiled_stepper"]
