"""dx/dt of a smooth lumped model in one compiled call (issue 32 item 2): ``System.rhs`` on the C backend.

The flow kernel (r at a = 0 and M = dr/da) and the solve M a = -r (Cholesky, LU where M is not positive
definite) run in C (``runtime/csrc/point_rhs.c``, built once per machine like the time loops); Python
copies the state into a buffer, makes one ctypes call and copies dx/dt out. :class:`PointRhs` is prepared once per
set of kernels (shared by the systems of other parameter values, like mechgen.runtime.core.system.BoundKernel) and
pointed at a system's parameters on every call. A model with internal variables, a chain, a continuum, another
backend or no C compiler keeps the Python path (``point_rhs`` returns None).
"""
from __future__ import annotations

import ctypes
import logging
from ctypes import POINTER, c_double, c_long, c_void_p
from functools import lru_cache

import numpy as np

from mechgen.errors import BuildError, CompilerUnavailable, KernelError
from mechgen.runtime import csrc

log = logging.getLogger(__name__)

SOURCE = csrc.path("point_rhs.c")
PORTS = 8
#: the kernel input names and their codes in point_rhs.c (MGP_IN_*)
CODES = {"q": 0, "v": 1, "a": 2, "z": 3, "t": 4, "p": 5}


class CPoint(ctypes.Structure):
    """The Python mirror of point_rhs.c's mgp_point."""

    _fields_ = [("flow", c_void_p), ("n", c_long), ("nin", c_long), ("r_index", c_long), ("M_index", c_long),
                ("kernel_rc", c_long), ("ports", c_long * PORTS), ("p", c_void_p), ("t", c_double),
                ("x", c_void_p), ("f", c_void_p), ("out", c_void_p * PORTS), ("zeros", c_void_p),
                ("work", c_void_p), ("piv", c_void_p), ("lu", c_long), ("tangent", c_void_p), ("tin", c_long),
                ("rq_index", c_long), ("rv_index", c_long), ("tports", c_long * PORTS),
                ("tout", c_void_p * PORTS), ("J", c_void_p)]


@lru_cache(maxsize=None)
def _library():
    """(the loaded library, None) or (None, why it is unavailable): built once per machine, loaded once."""
    from mechgen.buildlock import load_shared_once

    try:
        lib = load_shared_once(csrc.source(SOURCE), stem="mechgen_point_rhs", ldflags=("-lm",),
                               symbols=("mgp_rhs", "mgp_jacobian", "mgp_layout"))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("compiled point right-hand side unavailable (%s)", exc)
        return None, str(exc)
    lib.mgp_layout.argtypes, lib.mgp_layout.restype = [], c_long
    if lib.mgp_layout() != ctypes.sizeof(CPoint):
        return None, "point_rhs.c's layout differs from its Python mirror"
    lib.mgp_rhs.argtypes, lib.mgp_rhs.restype = [c_void_p], ctypes.c_int
    lib.mgp_jacobian.argtypes, lib.mgp_jacobian.restype = [c_void_p], ctypes.c_int
    return lib, None


def forget_library() -> None:
    """Forget the loaded (or refused) library: the next call builds or finds it again (tests change CC)."""
    _library.cache_clear()


class PointRhs:
    """f(t, x) = (v, -M^-1 r(q, v, 0, t)) of one system's flow kernel in one compiled call (module doc), and where
    the system has a tangent kernel its Jacobian df/dx = ((0, I), -M^-1 (r_q, r_v)) in another (:meth:`jacobian`)."""

    def __init__(self, system, lib) -> None:
        kernel = system.kernels["flow"]
        n = system.n
        names = [p["name"] for p in kernel.spec["inputs"]]
        outs = [p["name"] for p in kernel.spec["outputs"]]
        self.n, self.model = n, system.metadata.model
        self.x, self.f = np.zeros(2 * n), np.zeros(2 * n)
        self.params = np.array(system.params, dtype=float)
        self._source = system.params
        self.buffers = [np.zeros(n if name == "r" else n * n) for name in outs]
        self.zeros, self.work = np.zeros(2 * n), np.zeros(n * n)
        self.piv = np.zeros(n, dtype=np.dtype(c_long))
        s = CPoint(flow=kernel.address, n=n, nin=len(names), r_index=outs.index("r"), M_index=outs.index("M"),
                   p=self.params.ctypes.data, t=0.0, x=self.x.ctypes.data, f=self.f.ctypes.data,
                   zeros=self.zeros.ctypes.data, work=self.work.ctypes.data, piv=self.piv.ctypes.data)
        for i, name in enumerate(names):
            s.ports[i] = CODES[name]
        for i, buf in enumerate(self.buffers):
            s.out[i] = buf.ctypes.data
        self.struct = s
        self.J = self._point_tangent(system, s)
        self._address = ctypes.addressof(s)
        self._call, self._jacobian = lib.mgp_rhs, lib.mgp_jacobian

    def _point_tangent(self, system, s: CPoint) -> np.ndarray | None:
        """Point the struct at the tangent kernel and its output buffers; the Jacobian's buffer, or None where the
        system has no usable tangent kernel (its Jacobian then runs in Python)."""
        tangent = system.kernels.get("tangent")
        if tangent is None or tangent.address is None:
            return None
        names = [p["name"] for p in tangent.spec["inputs"]]
        outs = [p["name"] for p in tangent.spec["outputs"]]
        if not {"r_q", "r_v"} <= set(outs) or any(n not in CODES for n in names) or len(names) > PORTS \
                or len(outs) > PORTS:
            return None
        n = self.n
        self.tangent_buffers = [np.zeros(max(n * n, 1)) for _ in outs]
        s.tangent, s.tin, s.rq_index, s.rv_index = tangent.address, len(names), outs.index("r_q"), outs.index("r_v")
        for i, name in enumerate(names):
            s.tports[i] = CODES[name]
        for i, buf in enumerate(self.tangent_buffers):
            s.tout[i] = buf.ctypes.data
        J = np.zeros((2 * n, 2 * n))
        s.J = J.ctypes.data
        return J

    def use(self, params: np.ndarray) -> None:
        """Evaluate with ``params`` from now on (copied into the buffer the struct points to)."""
        if params is not self._source:
            self.params[...] = params
            self._source = params

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        self.x[...] = x
        self.struct.t = t
        rc = self._call(self._address)
        if rc:
            raise self._failure(rc, t, x)
        return self.f.copy()

    def jacobian(self, t: float, x: np.ndarray) -> np.ndarray:
        """d(dx/dt)/dx at (t, x): a copy of the compiled call's 2n x 2n result (requires :attr:`J`)."""
        self.x[...] = x
        self.struct.t = t
        rc = self._jacobian(self._address)
        if rc:
            raise self._failure(rc, t, x)
        return self.J.copy()

    def _failure(self, rc: int, t: float, x) -> Exception:
        """The exception the Python path raises in the same case (numpy's LinAlgError for a singular M, which the
        integrators diagnose; KernelError otherwise)."""
        if rc == 1:
            return np.linalg.LinAlgError("Singular matrix")
        if rc == 3:
            return KernelError(f"kernel flow of {self.model} returned error code {self.struct.kernel_rc}")
        return KernelError(f"kernel residual/tangent of {self.model} gave NaN/Inf at t = {t}, x = {np.asarray(x)[:6]}")


def point_rhs(system) -> PointRhs | None:
    """The system's compiled one-call right-hand side, pointed at its parameters; None where the Python path runs
    (module doc)."""
    key = ("point_rhs",)
    if key not in system.patterns:
        system.patterns[key] = _prepare(system)
    fast = system.patterns[key]
    if fast is not None:
        fast.use(system.params)
    return fast


def _prepare(system) -> PointRhs | None:
    flow = system.kernels.get("flow")
    if (system.backend != "c" or flow is None or flow.address is None or system.m or system.is_lattice
            or not system.n or any(p["name"] not in CODES for p in flow.spec["inputs"])
            or sorted(p["name"] for p in flow.spec["outputs"]) != ["M", "r"] or len(flow.spec["inputs"]) > PORTS):
        return None
    lib, _ = _library()
    return None if lib is None else PointRhs(system, lib)
