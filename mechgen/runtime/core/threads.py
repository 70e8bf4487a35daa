"""BLAS threads sized to the problem (threadpoolctl, used the way scikit-learn uses it).

OpenBLAS wakes and spin-waits its thread pool on every call. On the matrices of a lumped model or
a coarse continuum (tens to a few hundred unknowns) that costs more than the arithmetic: the Laval
rotor's scene spends 1.3 s of CPU with the default threads against 0.5 s on one, and on a busy
2-core machine a Campbell sweep ran 58 times slower. So dense work on at most :data:`SMALL`
unknowns runs on one BLAS thread; larger problems keep the library's default, and so does a user
who sets ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` or ``MKL_NUM_THREADS`` (that choice is kept
exactly). Sweep worker processes run on one thread each (the parallelism is the workers).
"""
from __future__ import annotations

import os
from contextlib import nullcontext

#: at most this many unknowns: one BLAS thread (a dense 512 x 512 LU is ~0.1 GFLOP, a few ms on one core)
SMALL = 512
#: environment variables through which a user chooses the BLAS threads themselves
USER_CHOICE = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def user_chose_threads() -> bool:
    """Whether the environment sets the BLAS thread count (then mechgen never changes it)."""
    return any(os.environ.get(name) for name in USER_CHOICE)


def controller():
    """The threadpoolctl controller of the loaded BLAS/OpenMP libraries, built once per process.

    numpy and scipy each ship their own OpenBLAS; scipy's is loaded only when scipy.linalg is first
    imported, and a limit applies only to the libraries loaded when it is set, so scipy.linalg is
    imported first (else the first analysis of a process, which imports it inside the limit, would run
    scipy's dense work on the default threads). Built once, a limit costs microseconds; a fresh
    ``threadpool_limits`` rescans the process's libraries each time (1-20 ms, per analysis and per
    sweep point).
    """
    global _CONTROLLER
    if _CONTROLLER is None:
        import numpy  # noqa: F401  (numpy's BLAS)
        import scipy.linalg  # noqa: F401  (scipy's own BLAS, see above)
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def blas_threads_for(unknowns: int):
    """A context in which BLAS runs on one thread when ``unknowns`` <= SMALL (else, or when the
    user chose, a context that changes nothing)."""
    if unknowns > SMALL or user_chose_threads():
        return nullcontext()
    return controller().limit(limits=1, user_api="blas")


def single_thread_worker() -> None:
    """Process-pool initializer: this worker's BLAS (numpy's and scipy's) on one thread, for the worker's
    lifetime."""
    if user_chose_threads():
        return
    global _WORKER_LIMIT
    _WORKER_LIMIT = controller().limit(limits=1, user_api="blas")


_CONTROLLER = None
_WORKER_LIMIT = None
