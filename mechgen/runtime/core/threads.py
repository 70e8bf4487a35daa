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

import importlib.abc
import os
import sys
import threading
from contextlib import nullcontext

#: at most this many unknowns: one BLAS thread (a dense 512 x 512 LU is ~0.1 GFLOP, a few ms on one core)
SMALL = 512
#: environment variables through which a user chooses the BLAS threads themselves
USER_CHOICE = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def user_chose_threads() -> bool:
    """Whether the environment sets the BLAS thread count (then mechgen never changes it)."""
    return any(os.environ.get(name) for name in USER_CHOICE)


def controller():
    """The threadpoolctl controller of the loaded BLAS/OpenMP libraries, built once per set of libraries.

    numpy and scipy each ship their own OpenBLAS; scipy's is loaded only when scipy.linalg (or sparse) is
    first imported, which mechgen does at first use (``lazy_import``), so a small scene may never load it. A
    limit applies only to the libraries loaded when it is set: the controller is rebuilt when scipy's library
    has appeared since, and a library loaded while a limit is in force joins that limit (:func:`library_loaded`).
    Built once, a limit costs microseconds; a fresh ``threadpool_limits`` rescans the process's libraries each
    time (1-20 ms, per analysis and per sweep point).
    """
    global _CONTROLLER, _CONTROLLER_KEY
    key = _scipy_loaded()
    if _CONTROLLER is None or key != _CONTROLLER_KEY:
        import numpy  # noqa: F401  (numpy's BLAS)
        from threadpoolctl import ThreadpoolController

        _CONTROLLER, _CONTROLLER_KEY = ThreadpoolController(), key
    return _CONTROLLER


def _scipy_loaded() -> bool:
    return "scipy.linalg" in sys.modules or "scipy.sparse.linalg" in sys.modules


class OneThreadBlas:
    """A context in which every loaded BLAS runs on one thread, and one that loads inside it too.

    The contexts in force at once (nested, or entered from several threads) share one limit: the first to
    enter saves the libraries' thread counts and sets one thread, the last to leave restores the saved counts.
    (Each restoring the counts it had found, two threads leaving out of order restored each other's: the later
    one left every library on one thread for the rest of the process.)
    """

    def __enter__(self):
        with _LOCK:
            if not _IN_FORCE:
                _SHARED["limits"] = [controller().limit(limits=1, user_api="blas")]
                _SHARED["key"] = _CONTROLLER_KEY
                if not _SHARED["key"]:
                    sys.meta_path.insert(0, _WATCH)
            _IN_FORCE.append(self)
        return self

    def __exit__(self, *exc) -> None:
        with _LOCK:
            _IN_FORCE.remove(self)
            if not _IN_FORCE:
                for limit in reversed(_SHARED["limits"]):
                    limit.restore_original_limits()
                _SHARED["limits"] = []
                if _WATCH in sys.meta_path:
                    sys.meta_path.remove(_WATCH)


def library_loaded() -> None:
    """scipy.linalg or scipy.sparse.linalg (which bring scipy's own BLAS) was just imported: the limit in force
    takes it in, so that scipy's dense work inside a one-thread limit runs on one thread as numpy's does."""
    with _LOCK:
        if _IN_FORCE and _scipy_loaded() != _SHARED["key"]:
            _SHARED["limits"].append(controller().limit(limits=1, user_api="blas"))
            _SHARED["key"] = _CONTROLLER_KEY


class _NotifyingLoader:
    """A module's own loader, and :func:`library_loaded` once the module has run."""

    def __init__(self, loader) -> None:
        self._loader = loader

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module) -> None:
        self._loader.exec_module(module)
        library_loaded()

    def __getattr__(self, name: str):
        return getattr(self._loader, name)


class _ScipyWatch(importlib.abc.MetaPathFinder):
    """On ``sys.meta_path`` only while a one-thread limit is in force and scipy's BLAS is not loaded yet: the
    import of scipy.linalg or scipy.sparse.linalg (scipy's OpenBLAS) is found as usual, and its loader tells
    the limits when it has run."""

    WATCHED = ("scipy.linalg", "scipy.sparse.linalg")

    def find_spec(self, name, path, target=None):
        if name not in self.WATCHED:
            return None
        for finder in [f for f in sys.meta_path if f is not self]:  # the finders that would have found it
            spec = finder.find_spec(name, path, target) if hasattr(finder, "find_spec") else None
            if spec is not None:
                if spec.loader is not None:
                    spec.loader = _NotifyingLoader(spec.loader)
                return spec
        return None


def blas_threads_for(unknowns: int):
    """A context in which BLAS runs on one thread when ``unknowns`` <= SMALL (else, or when the
    user chose, a context that changes nothing)."""
    if unknowns > SMALL or user_chose_threads():
        return nullcontext()
    return OneThreadBlas()


def single_thread_worker() -> None:
    """Process-pool initializer: this worker's BLAS (numpy's and scipy's) on one thread, for the worker's
    lifetime (scipy.linalg is imported here, so that its library is there to limit)."""
    if user_chose_threads():
        return
    import scipy.linalg  # noqa: F401

    global _WORKER_LIMIT
    _WORKER_LIMIT = controller().limit(limits=1, user_api="blas")


_CONTROLLER = None
_CONTROLLER_KEY = False
_WORKER_LIMIT = None
_IN_FORCE: list[OneThreadBlas] = []
#: the limit the contexts in force share: its threadpoolctl limits (the first set on entry, then one per library
#: loaded since) and whether scipy's BLAS was loaded when it was last extended
_SHARED: dict = {"limits": [], "key": False}
_LOCK = threading.RLock()
_WATCH = _ScipyWatch()
