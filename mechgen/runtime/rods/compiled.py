"""The rod's midpoint-step residual and a saved point's energies in one compiled call each.

``runtime/csrc/rod_elements.c``'s ``mgr_residual`` evaluates the whole of
:meth:`mechgen.runtime.rods.dynamics.Discrete.residual` (the weighted configuration x + alpha dx, R exp(alpha
theta), the element forces, the lumped loads and dead tip wrench, the inertial, gyroscopic and damping rows and
the fixed rows) for a batch of increments; ``mgr_record`` the elastic and kinetic energies and the turning
angle of a saved state. :class:`StepResidual` holds the buffers and the filled ``mgr_step`` structure of one
rod and batch size, made once: a call copies the state and the increments in, makes one ctypes call and copies
the residual and the external wrench out (the caller keeps them across later calls). The numpy path of
dynamics.Discrete stays the reference and the fallback without a compiler; a load that depends on the
position is evaluated in Python at x + alpha dx (it is a Python callable) and handed over lumped.
"""
from __future__ import annotations

import ctypes
from ctypes import c_double, c_long, c_void_p

import numpy as np


class CStep(ctypes.Structure):
    """The Python mirror of rod_elements.c's mgr_step (field for field)."""

    _fields_ = [("n", c_long), ("batch", c_long), ("load_stride", c_long),
                ("h", c_double), ("alpha", c_double), ("dt", c_double), ("rhoA", c_double), ("damping", c_double),
                ("K", c_void_p), ("f0", c_void_p), ("J", c_void_p), ("weights", c_void_p), ("fixed_unit", c_void_p),
                ("fixed", c_void_p), ("x", c_void_p), ("R", c_void_p), ("v", c_void_p), ("w", c_void_p),
                ("z", c_void_p), ("load", c_void_p), ("tip", c_void_p),
                ("xm", c_void_p), ("Rm", c_void_p), ("F", c_void_p), ("Mb", c_void_p),
                ("r", c_void_p), ("Fx", c_void_p), ("Mx", c_void_p)]


class CNewton(ctypes.Structure):
    """The Python mirror of rod_elements.c's mgr_newton (field for field)."""

    _fields_ = [("size", c_long), ("kl", c_long), ("ku", c_long), ("ab", c_void_p), ("ipiv", c_void_p),
                ("scale", c_void_p), ("tol", c_double), ("refresh", c_double), ("jacobian_cost", c_double),
                ("passes", c_long), ("here", c_long), ("z", c_void_p), ("r", c_void_p), ("Fx", c_void_p),
                ("Mx", c_void_p), ("dz", c_void_p), ("dz_size", c_double), ("zt", c_void_p), ("dzt", c_void_p),
                ("solves", c_long)]


#: mgr_corrections' outcomes
CONVERGED, NEED_JACOBIAN, FAILED = 0, 1, 2


def declare(lib) -> bool:
    """Set the argument types of mgr_residual, mgr_record, mgr_rotate, mgr_band_solve and mgr_corrections on
    ``lib``; False when a C structure's size differs from its mirror (:class:`CStep`, :class:`CNewton`: then the
    numpy path runs)."""
    lib.mgr_layout.argtypes, lib.mgr_layout.restype = [], c_long
    lib.mgr_newton_layout.argtypes, lib.mgr_newton_layout.restype = [], c_long
    if lib.mgr_layout() != ctypes.sizeof(CStep) or lib.mgr_newton_layout() != ctypes.sizeof(CNewton):
        return False
    lib.mgr_corrections.argtypes = [ctypes.POINTER(CStep), ctypes.POINTER(CNewton)]
    lib.mgr_corrections.restype = ctypes.c_int
    lib.mgr_residual.argtypes, lib.mgr_residual.restype = [ctypes.POINTER(CStep)], ctypes.c_int
    lib.mgr_record.argtypes = [c_long, c_double, c_double] + [c_void_p] * 10
    lib.mgr_record.restype = ctypes.c_int
    lib.mgr_rotate.argtypes, lib.mgr_rotate.restype = [c_long] + [c_void_p] * 3, ctypes.c_int
    lib.mgr_band_solve.argtypes, lib.mgr_band_solve.restype = [c_long] * 3 + [c_void_p] * 5, c_double
    return True


class StepResidual:
    """mgr_residual on the buffers of one rod (``disc``: a dynamics.Discrete) and ``batch`` increments."""

    def __init__(self, disc, lib, batch: int) -> None:
        body, rod = disc.body, disc.body.rod
        n = disc.elements + 1
        self.lib, self.n, self.batch = lib, n, batch
        keep = self.keep = {
            "K": np.ascontiguousarray(rod.K, dtype=float), "f0": np.ascontiguousarray(rod.f0, dtype=float),
            "J": np.ascontiguousarray(body.J_rho, dtype=float),
            "weights": np.ascontiguousarray(disc.weights, dtype=float),
            "fixed_unit": np.ascontiguousarray(disc.fixed_unit, dtype=float),
            "fixed": np.ascontiguousarray(disc.fixed, dtype=float),
            "tip": np.concatenate([rod.tip_force, rod.tip_torque]).astype(float),
            "x": np.zeros((n, 3)), "R": np.zeros((n, 3, 3)), "v": np.zeros((n, 3)), "w": np.zeros((n, 3)),
            "z": np.zeros((batch, n, 6)), "xm": np.zeros((batch, n, 3)), "Rm": np.zeros((batch, n, 3, 3)),
            "F": np.zeros((batch, n, 3)), "Mb": np.zeros((batch, n, 3)), "r": np.zeros((batch, n, 6)),
            "Fx": np.zeros((batch, n, 3)), "Mx": np.zeros((batch, n, 3)), "load": np.zeros((batch, n, 6))}
        s = self.s = CStep(n=n, batch=batch, load_stride=6 * n, h=disc.h, alpha=body.alpha, dt=1.0,
                           rhoA=body.rhoA, damping=body.damping)
        for name, array in keep.items():
            setattr(s, name, array.ctypes.data)
        self.uniform = disc.uniform_load
        if self.uniform is not None:
            keep["uniform"] = np.ascontiguousarray(self.uniform, dtype=float)
            s.load, s.load_stride = keep["uniform"].ctypes.data, 0
        elif rod.load is None:
            s.load = None
        self.ref = ctypes.byref(s)

    def load(self, st, dt: float) -> None:
        """Copy the state ``st`` at the step's start and its length dt (s) into the buffers."""
        k = self.keep
        np.copyto(k["x"], st.x)
        np.copyto(k["R"], st.R)
        np.copyto(k["v"], st.v)
        np.copyto(k["w"], st.w)
        self.s.dt = dt

    def __call__(self, st, z: np.ndarray, dt: float, load: np.ndarray | None = None):
        """(r (batch, n, 6), Fx, Mx (batch, n, 3)), fresh arrays, at increments z (batch, n, 6) from state ``st``
        over dt (s); ``load``: the lumped position-dependent load at x + alpha dx (batch, n, 6), when there is one."""
        k = self.keep
        self.load(st, dt)
        np.copyto(k["z"], z)
        if load is not None:
            np.copyto(k["load"], load)
        self.lib.mgr_residual(self.ref)
        return k["r"].copy(), k["Fx"].copy(), k["Mx"].copy()


class Corrections:
    """mgr_corrections (simplified Newton's loop within one step, between two Jacobians) on the residual of a
    :class:`StepResidual` of batch 1 and buffers of its own, made once per rod."""

    def __init__(self, step: StepResidual, scale: np.ndarray, band: int) -> None:
        if step.batch != 1:
            raise ValueError("the compiled corrections take one increment at a time (batch 1)")
        n = step.n
        self.step, self.lib, self.n = step, step.lib, n
        self.scale = np.ascontiguousarray(scale, dtype=float)
        self.z, self.r, self.dz, self.zt, self.dzt = (np.zeros((n, 6)) for _ in range(5))
        self.Fx, self.Mx = np.zeros((n, 3)), np.zeros((n, 3))
        self.w = CNewton(size=6 * n, kl=band, ku=band, scale=self.scale.ctypes.data, z=self.z.ctypes.data,
                         r=self.r.ctypes.data, Fx=self.Fx.ctypes.data, Mx=self.Mx.ctypes.data, dz=self.dz.ctypes.data,
                         zt=self.zt.ctypes.data, dzt=self.dzt.ctypes.data)
        self.ref = ctypes.byref(self.w)

    def start(self, st, dt: float, iterate: tuple, rule: tuple) -> None:
        """A step's attempt from state ``st`` over dt at the ``iterate`` (z, r, Fx, Mx: the increments, their
        residual and external wrench) under the ``rule`` (tol, refresh, jacobian_cost, passes: the tolerance, the
        refresh rule's constants and the most passes of the loop; dynamics._Solver.attempt)."""
        self.step.load(st, dt)
        for buf, a in zip((self.z, self.r, self.Fx, self.Mx), iterate):
            np.copyto(buf, a)
        w = self.w
        w.tol, w.refresh, w.jacobian_cost, w.passes = rule

    def run(self, lu: np.ndarray, piv: np.ndarray, dz: np.ndarray, size: float, here: bool) -> tuple[int, int]:
        """(outcome, band solves done) of the loop from the correction dz of ``size`` at the current iterate, with
        the band factors (lu, piv) of LAPACK dgbtrf (taken at the iterate when ``here``). On CONVERGED ``z`` holds
        the increments and ``Fx``, ``Mx`` the wrench; on NEED_JACOBIAN ``z`` and ``r`` the iterate to take it at."""
        w = self.w
        np.copyto(self.dz, dz.reshape(self.n, 6))
        w.ab, w.ipiv, w.dz_size, w.here, w.solves = lu.ctypes.data, piv.ctypes.data, size, int(here), 0
        outcome = self.lib.mgr_corrections(self.step.ref, self.ref)
        return int(outcome), int(w.solves)


class Recorder:
    """mgr_record on buffers of one rod (``disc``: a dynamics.Discrete), made once."""

    def __init__(self, disc, lib) -> None:
        body, rod = disc.body, disc.body.rod
        n = disc.elements + 1
        self.lib, self.n, self.h, self.rhoA = lib, n, disc.h, body.rhoA
        self.x, self.R, self.v, self.w = np.zeros((n, 3)), np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3))
        self.axis, self.out = np.zeros(3), np.zeros(3)
        self.keep = [np.ascontiguousarray(a, dtype=float) for a in (rod.K, rod.f0, body.J_rho, disc.weights)]
        self.pointers = [a.ctypes.data for a in (*self.keep, self.axis, self.x, self.R, self.v, self.w, self.out)]

    def __call__(self, st, axis: np.ndarray) -> tuple[float, float, float]:
        """(V, T, turning) of state ``st``: the elastic energy sum_e h/2 (f_e - f0)^T K (f_e - f0) and the kinetic
        energy sum_i w_i (rhoA |v_i|^2 + w_i^T J w_i)/2 (J), the turning angle about the unit ``axis`` (rad;
        statics.turning_angle: sum_e axis . R_e0 log(R_e0^T R_e1))."""
        for buf, a in ((self.x, st.x), (self.R, st.R), (self.v, st.v), (self.w, st.w), (self.axis, axis)):
            np.copyto(buf, a)
        self.lib.mgr_record(self.n, self.h, self.rhoA, *self.pointers)
        return float(self.out[0]), float(self.out[1]), float(self.out[2])


class BandSolve:
    """dz = -J^-1 r and max |dz_i| / scale_i in one call (mgr_band_solve) with LAPACK dgbtrf's band factors of J."""

    def __init__(self, lib, lu: np.ndarray, piv: np.ndarray, band: int, scale: np.ndarray) -> None:
        self.lib, self.lu, self.piv, self.band = lib, lu, piv, band
        self.scale = np.ascontiguousarray(scale, dtype=float)
        self.r, self.dz = np.zeros(lu.shape[1]), np.zeros(lu.shape[1])
        self.args = (lu.shape[1], band, band, lu.ctypes.data, piv.ctypes.data, self.r.ctypes.data,
                     self.scale.ctypes.data, self.dz.ctypes.data)

    @classmethod
    def of(cls, lib, lu: np.ndarray, piv: np.ndarray, band: int, scale: np.ndarray) -> "BandSolve | None":
        """The solver on these factors, or None where their layout is not LAPACK's (column-major lu of 3 band + 1
        rows, 32-bit pivots): then scipy's dgbtrs runs."""
        if lu.flags.f_contiguous and lu.shape[0] == 3 * band + 1 and piv.dtype == np.int32 and piv.flags.c_contiguous:
            return cls(lib, lu, piv, band, scale)
        return None

    def __call__(self, r: np.ndarray) -> tuple[np.ndarray, float]:
        np.copyto(self.r, r.reshape(-1))
        size = self.lib.mgr_band_solve(*self.args)
        return self.dz.copy(), float(size)


def rotate(lib, R: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """R_i exp(hat theta_i) (n, 3, 3) by mgr_rotate, for rotations R (n, 3, 3) and rotation vectors theta (n, 3)."""
    R = np.ascontiguousarray(R, dtype=float)
    theta = np.ascontiguousarray(theta, dtype=float)
    out = np.empty_like(R)
    lib.mgr_rotate(len(R), R.ctypes.data, theta.ctypes.data, out.ctypes.data)
    return out


__all__ = ["BandSolve", "CNewton", "CONVERGED", "Corrections", "CStep", "FAILED", "NEED_JACOBIAN", "StepResidual",
           "declare", "Recorder", "rotate"]
