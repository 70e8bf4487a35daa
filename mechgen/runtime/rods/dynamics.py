"""Dynamics of a geometrically exact (Cosserat) rod: nodal SO(3) x R^3 elements, a Lie-group midpoint step.

Spatial discretisation (conventions of mechgen.runtime.rods.liegroup and .statics; seed 001, Grazioso).
N two-node elements of reference length h = L/N; node i carries a position x_i (spatial, m) and a rotation
R_i (section frame -> spatial). Element e joins nodes i = e and i + 1:

    Psi_e = log(R_i^T R_{i+1}),   R_e = R_i exp(Psi_e/2),   kappa_e = Psi_e/h,   nu_e = R_e^T (x_{i+1} - x_i)/h,

so f_e = (nu_e, kappa_e) is the deformation twist at the element's midpoint to O(h^2), objective (invariant
under a rigid motion) and exactly f0 on the reference configuration of a straight rod. The strain energy is
the midpoint rule of the continuum one, V = sum_e h/2 (f_e - f0)^T K (f_e - f0), with sigma_e = (n_e, m_e)
= K (f_e - f0). Its exact variation, with dx_i and body rotations R_i -> R_i exp(hat w_i), is

    dPsi_e = J_r(Psi_e)^-1 w_{i+1} - J_l(Psi_e)^-1 w_i,
    dV = sum_e (R_e n_e).(dx_{i+1} - dx_i) + a_e.(exp(Psi_e/2)^T w_i) + c_e.dPsi_e,
    a_e = h n_e x nu_e,   c_e = m_e + J_r(Psi_e/2)^T a_e / 2,

which gives the nodal internal forces F_i = -dV/dx_i (spatial, N) and body moments M_i = -dV/dw_i (N m).
The kinetic energy is lumped at the nodes with the mass per length M = diag(rhoA I_3, J_rho) (kg/m, kg m):
m_i = rhoA w_i, J_i = J_rho w_i with the nodal lengths w_i = h (h/2 at the ends),

    T = sum_i 1/2 m_i |v_i|^2 + 1/2 omega_i^T J_i omega_i      (omega_i: body angular velocity, rad/s).

Equations of motion per node: m_i v_i' = F_i + F_ext,i - c m_i v_i, J_i omega_i' + omega_i x J_i omega_i =
M_i + M_ext,i - c J_i omega_i (c: mass-proportional damping, 1/s). External loads: the distributed spatial
wrench q(x) (force, torque per length) lumped at the nodes (w_i q(x_i), the torque taken to the body frame),
a dead tip force F and torque T (spatial) on the last node.

Time step (implicit midpoint on SO(3) x R^3, order 2, A-stable on the linearisation): unknown increments
dx_i and theta_i (body frame) with

    x^{n+1} = x^n + dx,  R^{n+1} = R^n exp(hat theta),  v_mid = dx/dt,  omega_mid = theta/dt,
    v^{n+1} = 2 v_mid - v^n,  omega^{n+1} = 2 omega_mid - omega^n,

the equations of motion imposed at the midpoint configuration (x^n + dx/2, R^n exp(theta/2)) with the rates
(v^{n+1} - v^n)/dt and the midpoint velocities. The midpoint rule does not damp modes with omega dt >> 1 (its
amplification tends to -1): stiff shear and axial modes, once excited by a sudden load, ring. RodBody.alpha
> 1/2 turns the step into the theta-method on the group (configuration x^n + alpha dx, R^n exp(alpha theta);
v^{n+1} = (v_mid - (1 - alpha) v^n)/alpha; order 1; alpha = 1 backward Euler), which damps them: for
dynamic relaxation to a static state, or a stiff transient where the high modes are not wanted. Rotations are only ever multiplied by exponentials (never
integrated as angles or quaternions), so they stay orthonormal to round-off over any number of turns.
Kinetic energy of the rotation is conserved exactly by the gyroscopic term (omega_mid . omega_mid x J
omega_mid = 0); for the elastic energy the step is second-order (energy error O(dt^2), bounded, no drift).
The coupled increments are found by Newton's method on a banded system (node-major order, bandwidth 11)
whose Jacobian is CasADi's AD of the element energy's gradient and of the nodes' rows (mechgen.runtime.rods.
local; finite differences over three colours of nodes with ``jacobian="fd"``), factorised and kept over
iterations and steps while the corrections contract fast (simplified Newton). The refresh rule
(:meth:`_Solver.attempt`): the Jacobian is taken again at the current iterate as soon as one correction
contracts slower than REFRESH = 0.5, or the corrections still needed at the rate seen would cost more than a
new Jacobian (JACOBIAN_COST = 10 corrections; at any iteration, the first of a step included), or a kept
Jacobian's full correction fails the monotonicity test; only a Jacobian taken at the current iterate damps the step.
A step that does not converge even so is split in two, down to 2^-12 of dt, before a ConvergenceError names
the time reached.

Where a C compiler is there, a Newton iteration's whole residual (:meth:`Discrete.residual`: the weighted
configuration, element forces, loads, inertial, gyroscopic, damping and fixed rows), its correction from the
band factors with its size (:meth:`_Solver._solve`), a saved point's energies and turning angle
(:meth:`Discrete.saved_point`) and a step's new rotations (:func:`advance`) are one ctypes call each into
runtime/csrc/rod_elements.c on buffers made once (mechgen.runtime.rods.compiled): about 11 us a residual at
N = 40 against 45-55 us in numpy. So are a step's corrections between two Jacobians (:meth:`_Solver.attempt`'s
loop: rod_elements.c's mgr_corrections, the same operations in the same order, so the same iterates bit for bit;
1.15x the whole run at N = 20-40) where the loads need no Python. The numpy path (:meth:`Discrete.residual_numpy`,
scipy's dgbtrs) and the Python loop are the references they are tested against and run without a compiler.
"""
from __future__ import annotations

import ctypes
import logging
import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.linalg import lapack

from mechgen.errors import ConvergenceError
from mechgen.runtime import csrc
from mechgen.runtime.rods import compiled as compiled_step
from mechgen.runtime.rods.liegroup import cross3, exp_so3, hat3, jac_left_so3, jac_left_so3_inv, log_so3
from mechgen.runtime.rods.statics import Rod
from mechgen.runtime.rods.ends import ENDS

#: band half-width of the node-major Jacobian: a node's 6 equations reach the 6 unknowns of each neighbour
BAND = 11
log = logging.getLogger("mechgen")
MAX_SPLITS = 12
#: simplified Newton's largest accepted contraction rate |dz_k+1|/|dz_k|: above it the Jacobian is taken again at
#: the current iterate whatever the corrections still needed (a kept Jacobian that at best halves the error is far
#: off the current one)
REFRESH = 0.5
#: what a Jacobian costs, in corrections (each a residual and a band solve): N = 40, 0.45 ms against 0.045 ms
#: measured. Below REFRESH, the Jacobian is taken again when the corrections a kept one still needs
#: (:func:`stale_corrections`) cost more.
JACOBIAN_COST = 10.0
#: attempt's corrections in one C call between two Jacobians where they can be (False: the Python loop, their
#: reference)
COMPILED_CORRECTIONS = True


def stale_corrections(rate: float, size: float, tol: float) -> float:
    """How many more corrections a kept Jacobian needs, at contraction ``rate``, from a correction of ``size``
    until the error estimate size rate^k rate / (1 - rate) is below ``tol``: log(tol (1 - rate) / (size rate)) /
    log(rate) (infinite for rate >= 1)."""
    if rate >= 1.0:
        return float("inf")
    if rate <= 0.0 or size <= 0.0:
        return 0.0
    return max(math.log(tol * (1.0 - rate) / (size * rate)) / math.log(rate), 0.0)


SOURCE = csrc.path("rod_elements.c")


@lru_cache(maxsize=1)
def element_library():
    """The loaded rod-element library, or None (no compiler: the numpy path runs; one log line)."""
    from mechgen.buildlock import load_shared_once as load_shared  # compiled once across processes
    from mechgen.errors import BuildError, CompilerUnavailable

    try:
        lib = load_shared(csrc.source(SOURCE), stem="mgrod", ldflags=("-lm",),
                          symbols=("mgr_internal", "mgr_residual", "mgr_record", "mgr_rotate", "mgr_band_solve",
                                   "mgr_layout", "mgr_corrections", "mgr_newton_layout"))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("C rod elements unavailable (%s): numpy forces", exc)
        return None
    c_long, c_double, c_void_p = ctypes.c_long, ctypes.c_double, ctypes.c_void_p
    lib.mgr_internal.argtypes = [c_long, c_long, c_double, c_double] + [c_void_p] * 9
    lib.mgr_internal.restype = ctypes.c_int
    if not compiled_step.declare(lib):
        log.info("rod_elements.c's mgr_step differs from its Python mirror: numpy forces")
        return None
    return lib


def forget_library() -> None:
    """Forget the loaded (or refused) library (tests change CC)."""
    element_library.cache_clear()


@dataclass(frozen=True)
class RodBody:
    """A rod with its mass per length: the statics Rod (L, K, f0, loads, ends) and M = diag(rhoA I, J_rho)
    (6 x 6, kg/m and kg m), the mass-proportional damping c (1/s)."""

    rod: Rod
    M: np.ndarray
    damping: float = 0.0
    #: the step's weight alpha in [1/2, 1]: 1/2 the midpoint rule (energy-conserving, order 2), above it the
    #: theta-method's numerical dissipation of the stiff modes (order 1), 1 backward Euler
    alpha: float = 0.5

    @property
    def rhoA(self) -> float:
        return float(self.M[0, 0])

    @property
    def J_rho(self) -> np.ndarray:
        return np.asarray(self.M[3:, 3:], dtype=float)


def check_inertia(M: np.ndarray) -> str | None:
    """None when M = diag(rhoA I_3, J) with rhoA > 0 and J symmetric positive definite; else what is wrong."""
    M = np.asarray(M, dtype=float)
    if M.shape != (6, 6) or not np.all(np.isfinite(M)):
        return "the mass per length M is not a finite 6 x 6 matrix"
    if np.any(M[:3, 3:] != 0.0) or np.any(M[3:, :3] != 0.0):
        return "M couples translation and rotation (a section whose mass centre is off the centre line)"
    rhoA = M[0, 0]
    if not rhoA > 0.0 or np.max(np.abs(M[:3, :3] - rhoA * np.eye(3))) > 1e-12 * rhoA:
        return f"the translational mass per length is not rhoA I with rhoA > 0 (M_uu = {M[:3, :3].tolist()})"
    J = M[3:, 3:]
    if np.max(np.abs(J - J.T)) > 1e-12 * np.max(np.abs(J)) or np.linalg.eigvalsh(J)[0] <= 0.0:
        return f"the rotational inertia per length J is not symmetric positive definite (J = {J.tolist()})"
    return None


@dataclass
class State:
    """Nodal positions x (n, 3), rotations R (n, 3, 3), velocities v (n, 3), body angular velocities w (n, 3)."""

    x: np.ndarray
    R: np.ndarray
    v: np.ndarray
    w: np.ndarray

    def copy(self) -> "State":
        return State(self.x.copy(), self.R.copy(), self.v.copy(), self.w.copy())


def reference_state(body: RodBody, elements: int) -> State:
    """The reference configuration at rest: nodes at H(s) = exp(s hat6 f0) (straight along x for the default f0)."""
    from mechgen.runtime.rods.liegroup import exp_se3

    s = np.linspace(0.0, body.rod.L, elements + 1)
    H = exp_se3(s[:, None] * body.rod.f0[None, :])
    n = elements + 1
    return State(H[:, :3, 3].copy(), H[:, :3, :3].copy(), np.zeros((n, 3)), np.zeros((n, 3)))


def _mv(A, b):
    return np.einsum("...ij,...j->...i", A, b)


def _mtv(A, b):
    return np.einsum("...ji,...j->...i", A, b)


@dataclass(frozen=True)
class Discrete:
    """The discretised rod: h, nodal lengths, masses and inertias, fixed degrees of freedom (n, 6)."""

    body: RodBody
    elements: int
    base: str = "clamped"
    tip: str = "free"
    h: float = field(init=False)
    weights: np.ndarray = field(init=False)
    fixed: np.ndarray = field(init=False)

    def __post_init__(self):
        n = self.elements + 1
        h = self.body.rod.L / self.elements
        wts = np.full(n, h)
        wts[0] = wts[-1] = h / 2
        fixed = np.zeros((n, 6), dtype=bool)
        for node, end in ((0, self.base), (-1, self.tip)):
            if end not in ENDS:
                raise ValueError(f"unknown end {end!r}: one of {', '.join(ENDS)}")
            if end in ("clamped", "pinned"):
                fixed[node, :3] = True
            if end == "clamped":
                fixed[node, 3:] = True
        object.__setattr__(self, "h", h)
        object.__setattr__(self, "weights", wts)
        object.__setattr__(self, "fixed", fixed)
        # what the C call and the band Jacobian read at every step, made once
        object.__setattr__(self, "_K_c", np.ascontiguousarray(self.body.rod.K, dtype=float))
        object.__setattr__(self, "_f0_c", np.ascontiguousarray(self.body.rod.f0, dtype=float))
        object.__setattr__(self, "_pattern", self._band_pattern())
        object.__setattr__(self, "_blocks", self._block_pattern())
        object.__setattr__(self, "_evaluators", {})       # the AD Jacobian's buffers (_batched)
        rod = self.body.rod
        # a uniform load (gravity) lumped once: w_i g, and its torque part (None when zero)
        uniform = torque = None
        if rod.load is not None and rod.load_uniform:
            uniform = np.asarray(rod.load(np.zeros((1, 3))), dtype=float).reshape(6) * wts[:, None]
            torque = uniform[:, 3:] if np.any(uniform[:, 3:]) else None
        object.__setattr__(self, "uniform_load", uniform)
        if uniform is not None:                           # the band Jacobian's g(x) (per length) and dg/dx = 0
            g = np.asarray(rod.load(np.zeros((1, 3))), dtype=float).reshape(6)
            object.__setattr__(self, "_uniform_gradient", (np.tile(g, (n, 1)), np.zeros((n, 6, 3))))
        object.__setattr__(self, "_uniform_torque", torque)
        body = self.body
        unit = np.concatenate([np.full(3, body.rhoA * h), np.full(3, float(np.max(np.diag(body.J_rho))) * h)])
        object.__setattr__(self, "fixed_unit", unit / body.alpha)

    # ------------------------------------------------------------------ energy and forces
    # Every array below may carry leading batch axes (..., n, 3): the finite-difference Jacobian evaluates
    # all 18 perturbed residuals in one call.
    def strains(self, x: np.ndarray, R: np.ndarray):
        """Per element: Psi (..., N, 3), the midpoint rotation R_e (..., N, 3, 3), the twist f_e (..., N, 6)."""
        Ri = R[..., :-1, :, :]
        Psi = log_so3(np.swapaxes(Ri, -1, -2) @ R[..., 1:, :, :])
        Re = Ri @ exp_so3(0.5 * Psi)
        nu = _mtv(Re, x[..., 1:, :] - x[..., :-1, :]) / self.h
        return Psi, Re, np.concatenate([nu, Psi / self.h], axis=-1)

    def elastic_energy(self, x: np.ndarray, R: np.ndarray) -> float:
        """V = sum_e h/2 (f_e - f0)^T K (f_e - f0) (J)."""
        eps = self.strains(x, R)[2] - self.body.rod.f0
        return float(0.5 * self.h * np.einsum("ei,ij,ej->", eps, self.body.rod.K, eps))

    def internal(self, x: np.ndarray, R: np.ndarray):
        """Nodal internal forces F (..., n, 3, spatial) and body moments Mb (..., n, 3): minus the exact
        gradient of V; and the elements' stress resultants sigma (..., N, 6)."""
        h, K = self.h, self.body.rod.K
        Psi, Re, f = self.strains(x, R)
        sigma = (f - self.body.rod.f0) @ K
        n_, m_ = sigma[..., :3], sigma[..., 3:]
        Fe = _mv(Re, n_)
        F = np.zeros_like(x)
        F[..., :-1, :] += Fe
        F[..., 1:, :] -= Fe
        a = h * cross3(n_, f[..., :3])
        c = m_ + 0.5 * _mtv(jac_left_so3(-0.5 * Psi), a)          # J_r(Psi/2)^T a / 2
        Rh = np.swapaxes(R[..., :-1, :, :], -1, -2) @ Re           # exp(Psi/2)
        Jl_inv = jac_left_so3_inv(Psi)
        Jr_inv = Jl_inv + hat3(Psi)                                # J_r^-1 = J_l^-1(-Psi) = I + W/2 + b W^2
        Mb = np.zeros_like(x)
        Mb[..., :-1, :] -= _mv(Rh, a) - _mtv(Jl_inv, c)            # -dV/dw_i
        Mb[..., 1:, :] -= _mtv(Jr_inv, c)                          # -dV/dw_{i+1}
        return F, Mb, sigma

    def weighted_internal(self, st: State, z: np.ndarray, *, compiled: bool = True):
        """The configuration x + alpha dx, R exp(alpha theta) at increments z (..., n, 6) and its internal
        forces and moments: in C (runtime/csrc/rod_elements.c, the same operations) when a compiler
        is there, else numpy (:meth:`internal`)."""
        al = self.body.alpha
        lib = element_library() if compiled else None
        if lib is None:
            xm = st.x + al * z[..., :3]
            Rm = st.R @ exp_so3(al * z[..., 3:])
            F, Mb, _ = self.internal(xm, Rm)
            return xm, Rm, F, Mb
        zc = np.ascontiguousarray(z, dtype=float)
        lead = zc.shape[:-1]
        batch = int(np.prod(lead[:-1])) if len(lead) > 1 else 1
        x = np.ascontiguousarray(st.x, dtype=float)
        R = np.ascontiguousarray(st.R, dtype=float)
        xm = np.empty(lead + (3,))
        Rm = np.empty(lead + (3, 3))
        F = np.empty(lead + (3,))
        Mb = np.empty(lead + (3,))
        lib.mgr_internal(batch, lead[-1], self.h, al, self._K_c.ctypes.data, self._f0_c.ctypes.data, x.ctypes.data,
                         R.ctypes.data, zc.ctypes.data, xm.ctypes.data, Rm.ctypes.data, F.ctypes.data, Mb.ctypes.data)
        return xm, Rm, F, Mb

    def external(self, x: np.ndarray, R: np.ndarray):
        """Lumped distributed load and the dead tip wrench: nodal spatial forces and body moments."""
        rod = self.body.rod
        F = np.zeros_like(x)
        Mb = np.zeros_like(x)
        if self.uniform_load is not None:
            F += self.uniform_load[:, :3]
            if self._uniform_torque is not None:
                Mb += _mtv(R, self._uniform_torque)
        elif rod.load is not None:
            g = np.asarray(rod.load(x.reshape(-1, 3)), dtype=float).reshape(x.shape[:-1] + (6,))
            g = g * self.weights[:, None]
            F += g[..., :3]
            Mb += _mtv(R, g[..., 3:])
        F[..., -1, :] += rod.tip_force
        if np.any(rod.tip_torque):
            Mb[..., -1, :] += _mtv(R[..., -1, :, :], rod.tip_torque)
        return F, Mb

    def saved_point(self, st: State, axis: np.ndarray, *, compiled: bool = True) -> tuple[float, float]:
        """(T + V, the turning angle about the unit ``axis``) of a state to be saved (J, rad): one C call
        (rod_elements.c's mgr_record) when a compiler is there, else :meth:`kinetic_energy`,
        :meth:`elastic_energy` and statics.turning_angle."""
        lib = element_library() if compiled else None
        if lib is None:
            from mechgen.runtime.rods.statics import turning_angle

            H = np.zeros((len(st.x), 4, 4))
            H[:, :3, :3], H[:, :3, 3] = st.R, st.x
            return (self.kinetic_energy(st.v, st.w) + self.elastic_energy(st.x, st.R), turning_angle(H, axis))
        rec = self._evaluators.get("record")
        if rec is None:
            rec = self._evaluators["record"] = compiled_step.Recorder(self, lib)
        V, T, turn = rec(st, axis)
        return T + V, turn

    def kinetic_energy(self, v: np.ndarray, w: np.ndarray) -> float:
        """T = sum_i m_i |v_i|^2/2 + w_i^T J_i w_i/2 (J)."""
        J = self.body.J_rho
        return float(0.5 * np.sum(self.weights * (self.body.rhoA * np.sum(v * v, axis=1)
                                                  + np.einsum("ni,ij,nj->n", w, J, w))))

    # ------------------------------------------------------------------ the midpoint step
    def residual(self, st: State, z: np.ndarray, dt: float, *, compiled: bool = True):
        """Midpoint equations at increments z = (dx, theta) (..., n, 6); also the external wrench there: in one
        C call (rod_elements.c's mgr_residual, mechgen.runtime.rods.compiled) when a compiler is there, else
        numpy (:meth:`residual_numpy`, the reference)."""
        lib = element_library() if compiled else None
        if lib is None:
            return self.residual_numpy(st, z, dt)
        n = self.elements + 1
        lead = z.shape[:-2]
        batch = int(np.prod(lead)) if lead else 1
        step = self._evaluators.get(("residual", batch))
        if step is None:
            step = self._evaluators[("residual", batch)] = compiled_step.StepResidual(self, lib, batch)
        load = None
        rod = self.body.rod
        if rod.load is not None and self.uniform_load is None:
            xa = st.x + self.body.alpha * z[..., :3]
            load = np.asarray(rod.load(xa.reshape(-1, 3)), dtype=float).reshape(xa.shape[:-1] + (6,))
            load = load * self.weights[:, None]
        r, Fx, Mx = step(st, z, dt, load)
        return r.reshape(z.shape), Fx.reshape(lead + (n, 3)), Mx.reshape(lead + (n, 3))

    def residual_numpy(self, st: State, z: np.ndarray, dt: float):
        """:meth:`residual` in numpy: the element forces by :meth:`weighted_internal` (itself in C where it can),
        the loads by :meth:`external`, the rows (the midpoint equations of the module doc) in numpy."""
        dx, th = z[..., :3], z[..., 3:]
        al = self.body.alpha
        xm, Rm, F, Mb = self.weighted_internal(st, z)
        Fx, Mx = self.external(xm, Rm)
        c = self.body.damping
        vm, wm = dx / dt, th / dt
        m = self.body.rhoA * self.weights[:, None]
        Jw = wm @ self.body.J_rho.T
        rt = m * ((vm - st.v) / (al * dt) + c * vm) - F - Fx
        rr = self.weights[:, None] * (((wm - st.w) / (al * dt) + c * wm) @ self.body.J_rho.T + cross3(wm, Jw)) - Mb - Mx
        r = np.concatenate([rt, rr], axis=-1)
        r[..., self.fixed] = (z * self._fixed_scale(dt))[..., self.fixed]
        return r, Fx, Mx

    def _fixed_scale(self, dt: float) -> np.ndarray:
        """Rows of fixed degrees of freedom: z itself, scaled like the inertia rows (m / (alpha dt^2))."""
        return self.fixed_unit / dt**2

    def _band_pattern(self):
        """Index arrays of the colour-grouped finite differences: perturbation b = 6 colour + k moves unknown k
        of the nodes p = colour mod 3; entry (b, q, a) of its residual change is J[6q + a, 6p + k]."""
        n = self.elements + 1
        p = np.arange(n)[:, None, None, None]                       # perturbed node
        k = np.arange(6)[None, :, None, None]                       # its unknown
        q = p + np.arange(-1, 2)[None, None, :, None]               # the nodes it reaches
        a = np.arange(6)[None, None, None, :]                       # their equations
        p, k, q, a = (np.broadcast_to(v, (n, 6, 3, 6)) for v in (p, k, q, a))
        keep = (q >= 0) & (q < n)
        p, k, q, a = p[keep], k[keep], q[keep], a[keep]
        b = 6 * (p % 3) + k
        col = 6 * p + k
        return b, q, a, p, k, col, 2 * BAND + 6 * q + a - col

    def _block_pattern(self):
        """Flat band-storage indices (row 2 BAND + i - j, column j) of the element blocks (N, 12, 12: nodes e,
        e + 1) and the node blocks (n, 6, 6), and the element blocks' fixed rows (N, 12)."""
        n, size = self.elements + 1, 6 * (self.elements + 1)

        def flat(first, width):
            rows = first[:, None, None] + np.arange(width)[None, :, None]
            cols = first[:, None, None] + np.arange(width)[None, None, :]
            return ((2 * BAND + rows - cols) * size + cols).ravel()

        element_rows = 6 * np.arange(n - 1)[:, None] + np.arange(12)[None, :]
        return flat(6 * np.arange(n - 1), 12), flat(6 * np.arange(n), 6), self.fixed.ravel()[element_rows]

    def jacobian_band(self, st: State, z: np.ndarray, dt: float, r0: np.ndarray | None = None, *,
                      method: str = "ad") -> np.ndarray:
        """The residual's Jacobian in LAPACK band storage (3 BAND + 1 rows).

        ``ad``: CasADi AD of the element's energy gradient (local.dynamics_element, mapped over the
        elements) and of the node's inertial and external rows (local.dynamics_node), the load's Jacobian
        from Rod.load_jacobian: exact to round-off. ``fd``: forward differences over three colours of nodes
        (a node's residual depends on its neighbours only), all 18 in one batched call, from r0."""
        if method == "fd":
            return self._jacobian_band_fd(st, z, dt, r0)
        if method != "ad":
            raise ValueError(f"unknown Jacobian method {method!r}: ad or fd")
        from mechgen.runtime.rods.statics import load_and_gradient

        body, rod = self.body, self.body.rod
        n, al = z.shape[0], body.alpha
        R = st.R.reshape(n, 9)
        nodes = np.concatenate([st.x, R, z], axis=1)
        par = np.concatenate([[self.h, al], self._K_c.ravel(), self._f0_c])
        Je = -self._batched("dynamics_element", n - 1)(np.concatenate([nodes[:-1], nodes[1:]], axis=1),
                                                         par).reshape(n - 1, 12, 12)
        xa = st.x + al * z[:, :3]
        if self.uniform_load is not None:              # the same value everywhere, no gradient: made once
            g0, G = self._uniform_gradient
        else:
            g0, G = load_and_gradient(rod, xa)
        tip = np.zeros((n, 6))
        tip[-1] = np.concatenate([rod.tip_force, rod.tip_torque])
        data = np.concatenate([R, st.v, st.w, z, self.weights[:, None], g0, G.reshape(n, 18), xa, tip, st.x], axis=1)
        npar = np.concatenate([[dt, al, body.rhoA, body.damping], body.J_rho.ravel()])
        Jn = self._batched("dynamics_node", n)(data, npar).reshape(n, 6, 6)
        element_at, node_at, element_fixed = self._blocks
        Je[element_fixed] = 0.0                      # rows of fixed unknowns: z itself, scaled
        Jn[self.fixed] = 0.0
        diag = np.broadcast_to(self._fixed_scale(dt), (n, 6))
        i, a = np.nonzero(self.fixed)
        Jn[i, a, a] = diag[i, a]
        size = 6 * n
        ab = np.bincount(element_at, Je.ravel(), minlength=(3 * BAND + 1) * size)
        ab += np.bincount(node_at, Jn.ravel(), minlength=(3 * BAND + 1) * size)
        return ab.reshape(3 * BAND + 1, size)

    def _batched(self, name: str, count: int):
        """The compiled rod piece ``name`` (local.native) over ``count`` columns, on buffers of this rod's own
        (local.Batched), made at its first use."""
        got = self._evaluators.get((name, count))
        if got is None:
            from mechgen.runtime.rods import local

            got = self._evaluators[(name, count)] = local.Batched(local.native(name), count)
        return got

    def _jacobian_band_fd(self, st: State, z: np.ndarray, dt: float, r0: np.ndarray | None) -> np.ndarray:
        n = z.shape[0]
        if r0 is None:
            r0 = self.residual(st, z, dt)[0]
        b, q, a, p, k, col, row = self._pattern
        scale = np.concatenate([np.full(3, self.h), np.ones(3)])
        eps = 1e-7 * (scale[None, :] + np.abs(z))                      # (n, 6)
        Z = np.broadcast_to(z, (18, n, 6)).copy()
        for colour in range(3):
            nodes = np.arange(colour, n, 3)
            for kk in range(6):
                Z[6 * colour + kk, nodes, kk] += eps[nodes, kk]
        dR = self.residual(st, Z, dt)[0] - r0
        ab = np.zeros((3 * BAND + 1, 6 * n))
        ab[row, col] = dR[b, q, a] / eps[p, k]
        return ab


@dataclass
class Trajectory:
    """Saved times t, states (tip position, energies), the work of the loads and damping, the final state."""

    t: list = field(default_factory=list)
    tip: list = field(default_factory=list)
    tip_rotation: list = field(default_factory=list)
    energy: list = field(default_factory=list)
    work: list = field(default_factory=list)
    shapes: list = field(default_factory=list)
    final: State | None = None
    steps: int = 0
    newton_iterations: int = 0
    jacobians: int = 0
    splits: int = 0
    #: the most Newton solves one step attempt took (a failed attempt, before its split, included)
    most_step_iterations: int = 0


class _Solver:
    """Newton on the midpoint equations with a factorised band Jacobian kept across iterations and steps
    while it serves (the refresh rule: :meth:`attempt`)."""

    def __init__(self, disc: Discrete, tol: float, max_iter: int, jacobian: str = "ad"):
        self.disc, self.tol, self.max_iter, self.jacobian = disc, tol, max_iter, jacobian
        self.lu = None
        self.band = None                                 # the compiled solve with the factors (_factor)
        self.dt = None
        self.iterations = 0
        self.jacobians = 0
        self.most = 0                                    # the most solves of one step attempt
        size = 6 * (disc.elements + 1)
        self.scale = np.tile(np.concatenate([np.full(3, disc.body.rod.L), np.ones(3)]), size // 6)

    def _factor(self, st: State, z: np.ndarray, dt: float, r0: np.ndarray) -> None:
        ab = self.disc.jacobian_band(st, z, dt, r0, method=self.jacobian)
        lu, piv, info = lapack.dgbtrf(ab, BAND, BAND)
        if info != 0:
            raise ConvergenceError(f"the rod's step Jacobian is singular (LAPACK dgbtrf info {info})")
        self.lu, self.piv, self.dt = lu, piv, dt
        self.jacobians += 1
        lib = element_library()
        self.band = None if lib is None else compiled_step.BandSolve.of(lib, lu, piv, BAND, self.scale)

    def _solve(self, r: np.ndarray) -> tuple[np.ndarray, float]:
        """The correction dz = -J^-1 r (shaped like r) and its size max |dz_i| / scale_i (units of L and rad): in
        one C call (rod_elements.c's mgr_band_solve, LAPACK dgbtrs' operations) where the library is there."""
        self.iterations += 1
        if self.band is not None:
            dz, size = self.band(r)
            return dz.reshape(r.shape), size
        dz = lapack.dgbtrs(self.lu, BAND, BAND, -r.ravel(), self.piv)[0].reshape(r.shape)
        return dz, self._norm(dz)

    def _norm(self, dz: np.ndarray) -> float:
        return float(np.max(np.abs(dz.ravel()) / self.scale))

    def step(self, st: State, dt: float, z0: np.ndarray):
        """:meth:`attempt`, counting its solves in ``most``."""
        start = self.iterations
        try:
            return self.attempt(st, dt, z0)
        finally:
            self.most = max(self.most, self.iterations - start)

    def attempt(self, st: State, dt: float, z0: np.ndarray):
        """The converged increments z and the midpoint external wrench, or None when Newton fails.

        Newton's corrections dz = -J^-1 r(z) use a factorised Jacobian J taken at some iterate, possibly of an
        earlier step (simplified Newton), and the refresh rule is: J is taken again at the current iterate z
        whenever (a) the corrections contract slower than REFRESH, |dz_k+1| > REFRESH |dz_k|, at any iteration
        (the first one of a step included), or the corrections J still needs at the rate seen (stale_corrections)
        would cost more than JACOBIAN_COST, or (b) the full correction fails the monotonicity test below, unless
        J was already taken at this z. With J taken at z, (b) is Deuflhard's damped Newton (natural monotonicity
        test): lam dz is accepted when the next correction, J^-1 r(z + lam dz) with the same J, is at most
        (1 - lam/4) |dz|, else lam is halved (down to 1/64; below it the step fails and is split). So a stale J
        never damps nor slows a step for more than one iteration: a stiff step costs a handful of corrections
        and one or two Jacobians. Converged when the estimated error after the last correction,
        |dz| rate/(1 - rate), is below tol (units of L and rad)."""
        z = z0.copy()
        r, Fx, Mx = self.disc.residual(st, z, dt)
        here = self.lu is None or self.dt != dt          # J taken at the current iterate z
        if here:
            self._factor(st, z, dt, r)
        dz, size = self._solve(r)
        if not np.isfinite(size):
            self.lu = None
            return None
        if size < 0.01 * self.tol:
            return z, Fx, Mx
        loop = self._compiled_loop()
        if loop is not None:
            return self._corrections_compiled(loop, st, dt, (z, r, Fx, Mx), (dz, size, here))
        for _ in range(self.max_iter):
            lam, zt, rt, Fxt, Mxt, dzt, new = self._damped(st, dt, z, dz, size, here)
            if lam is None:
                if here:
                    break
                self._factor(st, z, dt, r)                 # a stale Jacobian: take it again here
                here = True
                dz, size = self._solve(r)
                continue
            z, r, Fx, Mx, here = zt, rt, Fxt, Mxt, False
            rate = new / max(size, 1e-300)
            if lam == 1.0 and (new < 0.01 * self.tol or (rate < 1.0 and new * rate / (1.0 - rate) < self.tol)):
                # the last correction is taken (its size bounds the error of z); the wrench of the loads is
                # the one at z, off by O(|dzt|)
                return z + dzt, Fx, Mx
            if rate > REFRESH or stale_corrections(rate, new, self.tol) > JACOBIAN_COST:
                self._factor(st, z, dt, r)
                here = True
                dzt, new = self._solve(r)
            dz, size = dzt, new
        self.lu = None
        return None

    def _compiled_loop(self):
        """The compiled loop of :meth:`attempt` (compiled_step.Corrections) where the residual and the band solve
        are compiled and the loads need no Python (a position-dependent load is a Python callable), else None."""
        disc = self.disc
        if not COMPILED_CORRECTIONS or self.band is None or (disc.body.rod.load is not None
                                                              and disc.uniform_load is None):
            return None
        got = disc._evaluators.get("corrections")
        if got is None:
            step = disc._evaluators.get(("residual", 1))
            if step is None:
                return None
            got = disc._evaluators["corrections"] = compiled_step.Corrections(step, self.scale, BAND)
        return got

    def _corrections_compiled(self, loop, st: State, dt: float, iterate: tuple, correction: tuple):
        """:meth:`attempt`'s loop in one C call between two Jacobians (rod_elements.c's mgr_corrections: the same
        operations in the same order, so the same iterates as the Python loop bit for bit), from the ``iterate``
        (z, r, Fx, Mx) and its ``correction`` (dz, its size, whether the factors were taken at z)."""
        loop.start(st, dt, iterate, (self.tol, REFRESH, JACOBIAN_COST, self.max_iter))
        dz, size, here = correction
        while True:
            outcome, solves = loop.run(self.lu, self.piv, dz, size, here)
            self.iterations += solves
            if outcome == compiled_step.CONVERGED:
                return loop.z.copy(), loop.Fx.copy(), loop.Mx.copy()
            if outcome == compiled_step.FAILED:
                self.lu = None
                return None
            z, r = loop.z.copy(), loop.r.copy()      # NEED_JACOBIAN: take it at the current iterate
            self._factor(st, z, dt, r)
            here = True
            dz, size = self._solve(r)

    def _damped(self, st: State, dt: float, z: np.ndarray, dz: np.ndarray, size: float, here: bool):
        """The first lam = 1, 1/2, ... >= 1/64 whose next correction passes |dz(z + lam dz)| <= (1 - lam/4)
        |dz| (lam = 1 only when the Jacobian is stale: ``here`` False), with the trial's z, r, Fx, Mx, dz and
        |dz|; lam None when none passes."""
        lam = 1.0
        while True:
            zt = z + lam * dz
            rt, Fxt, Mxt = self.disc.residual(st, zt, dt)
            dzt, new = self._solve(rt)
            if np.isfinite(new) and new <= (1.0 - lam / 4.0) * size:
                return lam, zt, rt, Fxt, Mxt, dzt, new
            lam *= 0.5
            if not here or lam < 1.0 / 64.0:
                return None, None, None, None, None, None, None


def advance(disc: Discrete, st: State, z: np.ndarray, dt: float, Fx, Mx) -> tuple[State, float]:
    """The state after increments z, and the work of the external loads and damping over the step (J)."""
    dx, th = z[:, :3], z[:, 3:]
    vm, wm = dx / dt, th / dt
    c = disc.body.damping
    m = disc.body.rhoA * disc.weights
    work = float(np.sum(Fx * dx) + np.sum(Mx * th))
    if c:
        work -= c * float(np.sum(m * np.sum(vm * dx, axis=1))
                          + np.sum(disc.weights * np.einsum("ni,ij,nj->n", th, disc.body.J_rho, wm)))
    al = disc.body.alpha
    lib = element_library()
    R = st.R @ exp_so3(th) if lib is None else compiled_step.rotate(lib, st.R, th)
    new = State(st.x + dx, R, (vm - (1.0 - al) * st.v) / al, (wm - (1.0 - al) * st.w) / al)
    return new, work


def simulate(disc: Discrete, state: State, *, dt: float, t_end: float, save_every: int = 1,
             shape_every: int = 0, tol: float = 1e-10, max_iter: int = 40, axis=(0.0, 0.0, 1.0),
             jacobian: str = "ad") -> Trajectory:
    """March the midpoint step from ``state`` at t = 0 to ``t_end`` with steps ``dt`` (s), saving every
    ``save_every`` steps (and the shape every ``shape_every`` saves, 0: never; the final one always).
    ``jacobian``: the step Jacobian by AD (``ad``) or finite differences (``fd``), :meth:`Discrete.jacobian_band`."""
    if jacobian not in ("ad", "fd"):
        raise ValueError(f"unknown Jacobian method {jacobian!r}: ad or fd")
    steps = max(int(np.ceil(t_end / dt - 1e-9)), 0)
    solver = _Solver(disc, tol, max_iter, jacobian)
    out = Trajectory()
    st = state.copy()
    work = 0.0
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)

    def record(t: float, saves: int):
        out.t.append(t)
        out.tip.append(st.x[-1].copy())
        energy, turn = disc.saved_point(st, axis)
        out.tip_rotation.append(turn)
        out.energy.append(energy)
        out.work.append(work)
        if shape_every and saves % shape_every == 0:
            out.shapes.append(st.x.copy())

    record(0.0, 0)
    z_prev = z_prev2 = None
    for k in range(1, steps + 1):
        h = min(dt, t_end - (k - 1) * dt)
        if z_prev is None:
            z0 = np.concatenate([h * st.v, h * st.w], axis=1)
        elif z_prev2 is None or h != dt:
            z0 = z_prev * (h / dt)
        else:
            z0 = 2.0 * z_prev - z_prev2        # linear extrapolation of the increments: O(dt^3) off
        z_prev2 = z_prev
        st, dw, z_prev = _step_split(disc, solver, st, h, z0, out, (k - 1) * dt)
        work += dw
        out.steps += 1
        if k % save_every == 0 or k == steps:
            record(min(k * dt, t_end), k // save_every)
    out.final = st
    out.newton_iterations, out.jacobians = solver.iterations, solver.jacobians
    out.most_step_iterations = solver.most
    if shape_every and (steps // save_every) % shape_every:   # the final shape always (once)
        out.shapes.append(st.x.copy())
    return out


def _step_split(disc, solver, st, dt, z0, out, t, depth: int = 0):
    """One step of dt, split in halves (recursively) when Newton does not converge."""
    got = solver.step(st, dt, z0)
    if got is not None:
        z, Fx, Mx = got
        new, work = advance(disc, st, z, dt, Fx, Mx)
        return new, work, z
    if depth >= MAX_SPLITS:
        raise ConvergenceError(f"the rod's midpoint step did not converge at t = {t:.6g} s even with the step "
                               f"split {MAX_SPLITS} times (dt = {dt:.3g} s)")
    out.splits += 1
    half = 0.5 * dt
    mid, w1, z1 = _step_split(disc, solver, st, half, 0.5 * z0, out, t, depth + 1)
    end, w2, z2 = _step_split(disc, solver, mid, half, z1, out, t + half, depth + 1)
    return end, w1 + w2, 2.0 * z2


def linear_frequencies(disc: Discrete, count: int = 6, eps: float = 1e-4) -> np.ndarray:
    """The lowest ``count`` natural frequencies (rad/s) of small motions about the reference configuration:
    the tangent stiffness -d(F, Mb)/d(x, w) by central differences, against the lumped mass, fixed degrees of
    freedom removed (a dense symmetric eigenproblem: for tests and moderate N)."""
    from scipy.linalg import eigh

    st = reference_state(disc.body, disc.elements)
    n = disc.elements + 1
    free = ~disc.fixed.ravel()

    def forces(dq: np.ndarray) -> np.ndarray:
        dq = dq.reshape(n, 6)
        F, Mb, _ = disc.internal(st.x + dq[:, :3], st.R @ exp_so3(dq[:, 3:]))
        return np.concatenate([F, Mb], axis=1).ravel()

    size = 6 * n
    Kt = np.zeros((size, size))
    for j in range(size):
        e = np.zeros(size)
        e[j] = eps
        Kt[:, j] = -(forces(e) - forces(-e)) / (2 * eps)
    Kt = 0.5 * (Kt + Kt.T)
    mass = np.zeros((n, 6, 6))
    mass[:, :3, :3] = disc.body.rhoA * np.eye(3)
    mass[:, 3:, 3:] = disc.body.J_rho
    mass *= disc.weights[:, None, None]
    Mfull = np.zeros((size, size))
    for i in range(n):
        Mfull[6 * i:6 * i + 6, 6 * i:6 * i + 6] = mass[i]
    lam = eigh(Kt[np.ix_(free, free)], Mfull[np.ix_(free, free)], eigvals_only=True)
    return np.sqrt(np.clip(lam, 0.0, None))[:count]


__all__ = ["RodBody", "Discrete", "State", "Trajectory", "reference_state", "simulate", "advance",
           "linear_frequencies", "check_inertia", "ENDS", "BAND"]
