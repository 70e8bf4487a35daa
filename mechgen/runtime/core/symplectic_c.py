"""The compiled symplectic time loop: :func:`evolve_system`, a splitting method run in C.

A separable system (a chain: H = sum v^2 / (2 m) + V(q)) on the C backend is stepped by one C
function (``mgs_run`` in mechgen/runtime/csrc/symplectic_loop.c, built once into the compile
cache as ``libmgsymplectic``) that calls the model's own ``force`` and ``outputs`` kernels through
their addresses: no Python runs per step. The steps of a splitting
(:mod:`mechgen.runtime.core.splitting`) are those of the numpy stepper
:func:`mechgen.runtime.core.splitting.evolve`, operation for operation, so the two agree to rounding.
The loop returns to Python every ``chunk`` steps (a caller's modal transform between chunks); the
total energy is written from C every ``stride`` steps. Without a compiler, or for kernels without a
C address, the numpy stepper runs instead (one log line).
"""
from __future__ import annotations

import ctypes
import logging
from functools import lru_cache

import numpy as np

from mechgen.errors import BuildError, CompilerUnavailable, KernelError
from mechgen.runtime import csrc
from mechgen.runtime.core.splitting import Splitting, evolve, method

log = logging.getLogger("mechgen")

SOURCE = csrc.path("symplectic_loop.c")
STEM = "mgsymplectic"
c_long, c_double, c_void_p = ctypes.c_long, ctypes.c_double, ctypes.c_void_p
LONG = np.dtype(f"i{ctypes.sizeof(c_long)}")


@lru_cache(maxsize=1)
def _library():
    """(the loaded loop library, None) or (None, why it is unavailable); built once per process."""
    from mechgen.buildlock import load_shared_once as load_shared  # compiled once across processes

    try:
        lib = load_shared(csrc.source(SOURCE), stem=STEM, ldflags=("-lm",), symbols=("mgs_run",))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("C symplectic loop unavailable (%s)", exc)
        return None, f"the C symplectic loop cannot be built ({exc})"
    lib.mgs_run.argtypes = [c_void_p, c_void_p, c_long, c_long, c_void_p, c_void_p, c_long, c_void_p, c_void_p,
                            c_void_p, c_double, c_long, c_long, c_long, c_void_p, c_void_p, c_void_p, c_void_p,
                            c_void_p]
    lib.mgs_run.restype = ctypes.c_int
    return lib, None


def forget_library() -> None:
    """Forget the loaded (or refused) library (tests change CC)."""
    _library.cache_clear()


def _ptr(arr: np.ndarray | None) -> int | None:
    return None if arr is None else arr.ctypes.data


def c_unavailable(system) -> str | None:
    """Why ``system`` cannot run in the C loop (None when it can)."""
    for name in ("force", "outputs"):
        if name not in system.kernels:
            return f"the system has no {name} kernel"
        if system.kernels[name].address is None:
            return f"kernel {name} has no C function address (backend {system.kernels[name].backend})"
        if [p["name"] for p in system.kernels[name].spec["inputs"]] != ["q", "v", "p"]:
            return f"kernel {name} has inputs other than (q, v, p)"
    return _library()[1]


def evolve_system(system, q, v, dt: float, n_steps: int, splitting: Splitting | str = "leapfrog", *,
                  minv=None, stride: int = 0, loop: str = "auto"):
    """Advance (q, v) of ``system`` by ``n_steps`` splitting steps of ``dt``; a(q) = minv * force(q).

    Returns (q, v, energies, used): the total energy at step 0 and every ``stride`` steps (empty for
    stride 0), and ``"c"`` or ``"numpy"``, the loop that ran. ``loop``: ``auto`` (C when possible),
    ``c`` (CompilerUnavailable otherwise) or ``numpy``.
    """
    split = method(splitting) if isinstance(splitting, str) else splitting
    q, v = np.array(q, float), np.array(v, float)
    inv = None if minv is None else np.ascontiguousarray(minv, float)
    why = c_unavailable(system) if loop != "numpy" else "numpy loop asked for"
    if why:
        if loop == "c":
            raise CompilerUnavailable(why)
        log.info("symplectic loop in numpy: %s", why)
        acc = system.force if inv is None else (lambda x: system.force(x) * inv)
        energy = lambda a, b: system.outputs(a, b)["energy"]  # noqa: E731
        q, v, rec = evolve(acc, q, v, dt, n_steps, split, stride=stride, observe=energy if stride else None)
        return q, v, np.asarray(rec, float), "numpy"
    lib = _library()[0]
    sizes = np.array([system.sites if system.is_lattice else 0], dtype=LONG)
    params = np.ascontiguousarray(system.params, float)
    outputs = system.kernels["outputs"].spec["outputs"]
    port = [p["name"] for p in outputs].index("energy")
    a = np.ascontiguousarray(split.a, float)
    b = np.ascontiguousarray(split.b, float)
    f = np.zeros(q.size)
    energies = np.zeros(n_steps // stride + 1 if stride > 0 else 1)
    done = np.zeros(1, dtype=LONG)
    rc = lib.mgs_run(system.kernels["force"].address, system.kernels["outputs"].address, len(outputs), port,
                     _ptr(sizes), _ptr(params), q.size, _ptr(q), _ptr(v), _ptr(inv), float(dt), int(n_steps),
                     int(stride), len(split.a), _ptr(a), _ptr(b), _ptr(f), _ptr(energies), _ptr(done))
    if rc == -1:
        raise KernelError(f"symplectic loop ({split.name}): the state became NaN/Inf by step {int(done[0]):,} of "
                          f"{n_steps:,} (t = {int(done[0]) * dt:.6g}; time step dt = {dt:g} too large?)")
    if rc:
        raise KernelError(f"symplectic loop ({split.name}): a kernel returned error code {rc} at step "
                          f"{int(done[0]):,}")
    return q, v, (energies if stride > 0 else np.zeros(0)), "c"


__all__ = ["c_unavailable", "evolve_system", "forget_library"]
