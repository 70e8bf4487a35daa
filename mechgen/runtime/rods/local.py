"""The rods' local pieces in CasADi SX and their AD Jacobians, built once and mapped over the repetition.

Each builder returns a casadi.Function of one piece (a collocation element, an end condition, one RKMK4
step, a dynamics element or node) whose inputs are the numeric state of that piece and its unknowns'
increments (right perturbations H exp(dxi) of the poses, sigma + dsigma of the wrenches, in the residual's
scaled units), and whose output is the Jacobian of the piece's residual at zero increment. Callers map it
over elements or nodes (:func:`mapped`) and assemble the sparse or banded matrix. The residuals
themselves stay with the numpy solvers (statics.py, dynamics.py): these functions repeat their equations
(cited there) in SX, and tests hold the two to each other (the AD Jacobian against finite differences of
the numpy residual).

The dynamics pieces differentiate at the current increments z (not at zero): the step's unknowns are
the increments themselves.

Distributed loads are Python callables (or generated kernels) of the position; a piece takes their value
g0 and Jacobian G = dg/dr (6 x 3) at the piece's current point r0 and uses g0 + G (r - r0), exact to first
order, so the Jacobian at zero increment is exact.

The hot pieces (collocation and dynamics elements, dynamics nodes) run compiled (:func:`native`: CasADi's
C, built in mechgen's content-hashed compile cache); the RKMK4 transfer runs in CasADi's virtual machine
(its 1.5 MB of generated C would cost more to build than it saves), marched in one fold
(:func:`rkmk4_march`) when the load is uniform. Symbolic work is one piece's, whatever N is.
"""
from __future__ import annotations

import logging
from functools import lru_cache

import casadi as ca
import numpy as np

from mechgen.runtime.rods import ad

log = logging.getLogger("mechgen")

#: sizes of the packed inputs of the collocation element: nodes i, i+1 (R 9, p 3, sigma 6 each), the load's
#: value, Jacobian and point at the element's midpoint
COLLOCATION_ELEMENT_DATA = 18 + 18 + 6 + 18 + 3
#: h, L, lam, compliance (36), f0 (6), the 12 residual scales
COLLOCATION_PARAMS = 3 + 36 + 6 + 12


def _node(data, at: int):
    """(R, p, sigma) packed at offset ``at`` (R row-major)."""
    return ad.matrix(data[at:at + 9], 3, 3), data[at + 9:at + 12], data[at + 12:at + 18]


def _perturbed(node, dz, sc):
    """The node (R, p) exp(hat6(dz[:6] sc[:6])) and sigma + dz[6:] sc[6:] (scaled increments dz)."""
    R, p, sigma = node
    step = ad.exp_se3(dz[:6] * sc[:6])
    Rn, pn = ad.compose((R, p), step)
    return Rn, pn, sigma + dz[6:] * sc[6:]


def _load(lam, R, r, g0, G, r0):
    """gbar = lam (R^T q, R^T l) with (q, l) = g0 + G (r - r0)."""
    g = g0 + ad.matrix(G, 6, 3) @ (r - r0)
    return lam * ca.vertcat(R.T @ g[:3], R.T @ g[3:])


@lru_cache(maxsize=None)
def collocation_element() -> ca.Function:
    """Jacobian (12 x 24, row-major) of one midpoint-collocation element's 12 scaled rows (statics.py):

        pose   = log(exp(-h f_m) H_i^-1 H_{i+1}) / (L, 1),
        stress = ((sigma_{i+1} - sigma_i)/h - ad*_{f_m} sigma_m + gbar(H_i exp(h f_m/2))) L / (F, M),

    f_m = f0 + C sigma_m, sigma_m the mean, with respect to the scaled increments of nodes i and i+1."""
    data = ca.SX.sym("data", COLLOCATION_ELEMENT_DATA)
    par = ca.SX.sym("par", COLLOCATION_PARAMS)
    dz = ca.SX.sym("dz", 24)
    h, L, lam = par[0], par[1], par[2]
    C = ad.matrix(par[3:39], 6, 6)
    f0, sc = par[39:45], par[45:57]
    Ri, pi, si = _perturbed(_node(data, 0), dz[:12], sc)
    Rj, pj, sj = _perturbed(_node(data, 18), dz[12:], sc)
    sm = 0.5 * (si + sj)
    fm = f0 + C @ sm
    back = ad.exp_se3(-h * fm)
    X = ad.compose(ad.compose(back, ad.inverse((Ri, pi))), (Rj, pj))
    pose = ad.log_se3(*X) / sc[:6]
    Rm, pm = ad.compose((Ri, pi), ad.exp_se3(0.5 * h * fm))
    gbar = _load(lam, Rm, pm, data[36:42], data[42:60], data[60:63])
    stress = ((sj - si) / h - ad.coad6(fm, sm) + gbar) * L / sc[6:]
    residual = ca.vertcat(pose, stress)
    J = ca.substitute(ca.jacobian(residual, dz), dz, ca.DM.zeros(24))
    return ca.Function("rod_collocation_element_jacobian", [data, par], [ad.flat(J)])


#: packed end data: the node (R 9, p 3, sigma 6), the held pose (R 9, p 3), the tip force and torque (6)
END_DATA = 18 + 12 + 6
#: L, lam, the 12 scales
END_PARAMS = 2 + 12


@lru_cache(maxsize=None)
def end_condition(where: str, end: str) -> ca.Function:
    """Jacobian (6 x 12, row-major) of the 6 scaled base or tip conditions (statics.base_residual and
    tip_residual) of an end ``clamped``, ``pinned`` or ``free`` with respect to that node's increments."""
    data = ca.SX.sym("data", END_DATA)
    par = ca.SX.sym("par", END_PARAMS)
    dz = ca.SX.sym("dz", 12)
    L, lam, sc = par[0], par[1], par[2:14]
    R, p, sigma = _perturbed(_node(data, 0), dz, sc)
    held = (ad.matrix(data[18:27], 3, 3), data[27:30])
    force, torque = data[30:33], data[33:36]
    if end == "clamped":
        rows = ad.log_se3(*ad.compose(ad.inverse(held), (R, p))) / sc[:6]
    elif where == "base" and end == "pinned":
        rows = ca.vertcat(p / L, ad.log_so3(R)[0], sigma[4:] / sc[10:])
    elif where == "base":
        rows = sigma / sc[6:]
    else:
        moment = (sigma[3:] - lam * R.T @ torque) / sc[9:]
        if end == "pinned":
            rows = ca.vertcat((p - held[1]) / L, moment)
        else:
            rows = ca.vertcat((sigma[:3] - lam * R.T @ force) / sc[6:9], moment)
    J = ca.substitute(ca.jacobian(rows, dz), dz, ca.DM.zeros(12))
    return ca.Function(f"rod_{where}_{end}_jacobian", [data, par], [ad.flat(J)])


#: packed data of one RKMK4 step: the node (R 9, p 3, sigma 6); the load's value (6), Jacobian (18) and
#: point (3) at each of the 4 stage poses
STEP_DATA = 18 + 4 * (6 + 18 + 3)
#: h, lam, compliance (36), f0 (6)
STEP_PARAMS = 2 + 36 + 6


def _rkmk4(node, h, lam, C, f0, load):
    """statics.rkmk4_step in SX from a node (R, p, sigma): the new (R, p, sigma). ``load(k, R, r)`` is
    stage k's gbar."""
    R, p, sigma = node

    def rhs(k, pose, sig):
        f = f0 + C @ sig
        return f, ad.coad6(f, sig) - load(k, pose[0], pose[1])

    x1, s1 = rhs(0, (R, p), sigma)
    t2 = 0.5 * h * x1
    P2 = ad.compose((R, p), ad.exp_se3(t2))
    x2, s2 = rhs(1, P2, sigma + 0.5 * h * s1)
    x2 = ad.dexp_inv_right(t2, x2)
    t3 = 0.5 * h * x2
    P3 = ad.compose((R, p), ad.exp_se3(t3))
    x3, s3 = rhs(2, P3, sigma + 0.5 * h * s2)
    x3 = ad.dexp_inv_right(t3, x3)
    t4 = h * x3
    P4 = ad.compose((R, p), ad.exp_se3(t4))
    x4, s4 = rhs(3, P4, sigma + h * s3)
    x4 = ad.dexp_inv_right(t4, x4)
    theta = h / 6 * (x1 + 2 * x2 + 2 * x3 + x4)
    Rn, pn = ad.compose((R, p), ad.exp_se3(theta))
    return Rn, pn, sigma + h / 6 * (s1 + 2 * s2 + 2 * s3 + s4)


def _transfer(node, stage, par):
    """One RKMK4 step from the packed node (18) with the stages' load data (4 x 27): the new node packed
    (18) and the step's 12 x 12 transfer in local coordinates (flat, row-major)."""
    h, lam, C, f0 = par[0], par[1], ad.matrix(par[2:38], 6, 6), par[38:44]
    dz = ca.SX.sym("dz", 12)
    zero = ca.DM.zeros(12)
    R, p, sigma = _node(node, 0)
    Rp, pp = ad.compose((R, p), ad.exp_se3(dz[:6]))

    def load(k, Rs, rs):
        at = 27 * k
        return _load(lam, Rs, rs, stage[at:at + 6], stage[at + 6:at + 24], stage[at + 24:at + 27])

    Rn, pn, sn = _rkmk4((Rp, pp, sigma + dz[6:]), h, lam, C, f0, load)
    nxt = ca.substitute(ca.vertcat(ad.flat(Rn), pn, sn), dz, zero)
    Rb, pb = ad.matrix(nxt[:9], 3, 3), nxt[9:12]
    local = ca.vertcat(ad.log_se3(*ad.compose(ad.inverse((Rb, pb)), (Rn, pn))), sn)
    return nxt, ad.flat(ca.substitute(ca.jacobian(local, dz), dz, zero))


@lru_cache(maxsize=None)
def rkmk4_transfer() -> ca.Function:
    """The 12 x 12 (row-major) derivative of one RKMK4 step in local coordinates: the step maps
    (H exp(dxi), sigma + dsigma) to (H' exp(dxi'), sigma' + dsigma'); this is d(dxi', dsigma')/d(dxi,
    dsigma) at zero (unscaled: lengths and radians, forces and moments). Data: the node, then the stages'."""
    data = ca.SX.sym("data", STEP_DATA)
    par = ca.SX.sym("par", STEP_PARAMS)
    return ca.Function("rod_rkmk4_transfer", [data, par], [_transfer(data[:18], data[18:], par)[1]])


@lru_cache(maxsize=None)
def rkmk4_march(steps: int) -> ca.Function:
    """``steps`` RKMK4 steps under a position-independent load (its value g0 in the data of every stage,
    G = 0) as one CasADi fold: (node 18, stage data 108, params) -> the nodes after each step (18 x steps)
    and each step's transfer (144 x steps, as :func:`rkmk4_transfer`)."""
    node, stage = ca.SX.sym("node", 18), ca.SX.sym("stage", STEP_DATA - 18)
    par = ca.SX.sym("par", STEP_PARAMS)
    one = ca.Function("rod_rkmk4_step", [node, stage, par], list(_transfer(node, stage, par)))
    return one.mapaccum("rod_rkmk4_march", steps)


#: packed data of a dynamics element: nodes i and i+1, each position (3), rotation (9, row-major) and
#: increments (dx, theta) (6)
ELEMENT_DATA = 2 * (3 + 9 + 6)
#: h, alpha, K (36), f0 (6)
ELEMENT_PARAMS = 2 + 36 + 6


@lru_cache(maxsize=None)
def dynamics_element() -> ca.Function:
    """d(F_i, Mb_i, F_i+1, Mb_i+1)/d(z_i, z_i+1) (12 x 12, row-major) of one rod element (dynamics.py): its
    internal forces and body moments at the configuration x + alpha dx, R exp(alpha theta), as the exact
    gradient (AD) of the element's strain energy

        V_e = h/2 (f_e - f0)^T K (f_e - f0),  f_e = (R_e^T (x_i+1 - x_i)/h, Psi/h),
        Psi = log(R_i^T R_i+1),  R_e = R_i exp(Psi/2),

    under x -> x + dx, R -> R exp(hat w), differentiated once more (AD) in the increments z."""
    data = ca.SX.sym("data", ELEMENT_DATA)
    par = ca.SX.sym("par", ELEMENT_PARAMS)
    h, alpha = par[0], par[1]
    K, f0 = ad.matrix(par[2:38], 6, 6), par[38:44]
    z = ca.vertcat(data[12:18], data[30:36])
    e = ca.SX.sym("e", 12)

    def node(at, zk, ek):
        x = data[at:at + 3] + alpha * zk[:3] + ek[:3]
        R = ad.matrix(data[at + 3:at + 12], 3, 3) @ ad.exp_so3(alpha * zk[3:]) @ ad.exp_so3(ek[3:])
        return x, R

    xi, Ri = node(0, z[:6], e[:6])
    xj, Rj = node(18, z[6:], e[6:])
    Psi = ad.log_so3(Ri.T @ Rj)
    Re = Ri @ ad.exp_so3(0.5 * Psi)
    eps = ca.vertcat(Re.T @ (xj - xi) / h, Psi / h) - f0
    V = 0.5 * h * ca.dot(eps, K @ eps)
    forces = -ca.substitute(ca.gradient(V, e), e, ca.DM.zeros(12))
    return ca.Function("rod_dynamics_element_jacobian", [data, par], [ad.flat(ca.jacobian(forces, z))])


#: packed data of a dynamics node: rotation (9), velocity (3), body angular velocity (3), increments (6),
#: nodal length (1), the load's value (6), Jacobian (18) and point (3) at the weighted configuration, the
#: node's dead tip force and torque (6; zero but at the tip) and its position (3)
NODE_DATA = 9 + 3 + 3 + 6 + 1 + 6 + 18 + 3 + 6 + 3
#: dt, alpha, rhoA, damping c, J_rho (9)
NODE_PARAMS = 4 + 9


@lru_cache(maxsize=None)
def dynamics_node() -> ca.Function:
    """d r_node / d z (6 x 6, row-major) of a node's inertial, damping and external rows (dynamics.py):

        r_t = m ((v_mid - v)/(alpha dt) + c v_mid) - w g_q(x_a) - F_tip,
        r_r = w (((om_mid - om)/(alpha dt) + c om_mid) J + om_mid x J om_mid) - R_a^T (w g_l(x_a) + T_tip),

    v_mid = dx/dt, om_mid = theta/dt, x_a = x + alpha dx, R_a = R exp(alpha theta), m = rhoA w."""
    data = ca.SX.sym("data", NODE_DATA)
    par = ca.SX.sym("par", NODE_PARAMS)
    dt, alpha, rhoA, c = par[0], par[1], par[2], par[3]
    J = ad.matrix(par[4:13], 3, 3)
    R, v, w = ad.matrix(data[:9], 3, 3), data[9:12], data[12:15]
    z, weight = data[15:21], data[21]
    g0, G, r0 = data[22:28], ad.matrix(data[28:46], 6, 3), data[46:49]
    force, torque, x = data[49:52], data[52:55], data[55:58]
    xa = x + alpha * z[:3]
    Ra = R @ ad.exp_so3(alpha * z[3:])
    g = g0 + G @ (xa - r0)
    vm, wm = z[:3] / dt, z[3:] / dt
    rt = rhoA * weight * ((vm - v) / (alpha * dt) + c * vm) - weight * g[:3] - force
    rr = weight * (J @ ((wm - w) / (alpha * dt) + c * wm) + ca.cross(wm, J @ wm)) - Ra.T @ (weight * g[3:] + torque)
    return ca.Function("rod_dynamics_node_jacobian", [data, par], [ad.flat(ca.jacobian(ca.vertcat(rt, rr), z))])


#: flags for CasADi's generated C (its own style: not held to mechgen's -Werror -pedantic); -O1 builds
#: the 0.3-0.4 MB sources in 2-4 s and runs within 20 % of -O2
CFLAGS = ("-std=c99", "-O1", "-fPIC", "-shared")


@lru_cache(maxsize=None)
def native(name: str) -> ca.Function:
    """The piece built by this module's function ``name``, compiled: CasADi's C code generation of it,
    built in mechgen's compile cache (content-hashed; a second process loads it) and loaded back with
    casadi.external; 6-8 times faster than CasADi's virtual machine. Without a compiler (or a build that
    fails) the SX function itself, after one log line: same numbers, slower."""
    from mechgen.codegen.build import build_shared
    from mechgen.errors import BuildError, CompilerUnavailable

    function = NATIVE[name]()
    generator = ca.CodeGenerator(f"{function.name()}.c", {"with_header": False})
    generator.add(function)
    try:
        path = build_shared(generator.dump(), stem=function.name(), cflags=CFLAGS, ldflags=("-lm",))
        return ca.external(function.name(), str(path))
    except (CompilerUnavailable, BuildError, OSError, RuntimeError) as exc:
        log.info("compiled rod piece %s unavailable (%s): CasADi's virtual machine evaluates it", name, exc)
        return function


@lru_cache(maxsize=64)
def mapped(function: ca.Function, count: int) -> ca.Function:
    """``function`` mapped over ``count`` columns of its first input (the others broadcast)."""
    return function.map(count)


@lru_cache(maxsize=64)
def mapped_shared(function: ca.Function, count: int) -> ca.Function:
    """``function`` mapped over ``count`` columns of its first input, its second input (the parameters) one
    column shared by all."""
    return function.map(count, [False, True], [False], {})


class Batched:
    """``function`` (data column, parameter column) -> one output column, evaluated over ``count`` data
    columns on numpy buffers bound once (CasADi's FunctionBuffer: no conversion of arguments or results,
    which cost more than the evaluation itself, about 0.3 ms a call at 40 columns). One per user: the
    buffers are reused, so an instance is not for concurrent calls."""

    def __init__(self, function: ca.Function, count: int):
        self.function = mapped_shared(function, count)
        if function.nnz_in(0) != function.numel_in(0) or function.nnz_in(1) != function.numel_in(1):
            raise ValueError(f"{function.name()}: Batched needs dense inputs")
        self.data = np.zeros((count, function.nnz_in(0)))   # column-major (rows, count) = row-major (count, rows)
        self.par = np.zeros(function.nnz_in(1))
        self.out = np.zeros((count, function.nnz_out(0)))     # the output's structural nonzeros
        self.rows = function.numel_out(0)
        self.at = np.asarray(function.sparsity_out(0).find(), dtype=np.intp)   # their places in the column
        self.buffer = None
        if hasattr(self.function, "buffer"):            # a CasADi without FunctionBuffer: the ordinary call
            self.buffer, self.run = self.function.buffer()
            self.buffer.set_arg(0, memoryview(self.data))
            self.buffer.set_arg(1, memoryview(self.par))
            self.buffer.set_res(0, memoryview(self.out))

    def __call__(self, data: np.ndarray, par: np.ndarray) -> np.ndarray:
        """The outputs (count, output rows; structural zeros filled in) at ``data`` (count, rows) and
        ``par``; a new array."""
        if self.buffer is None:
            return np.asarray(self.function(np.asarray(data, dtype=float).T, np.asarray(par, dtype=float))).T.copy()
        self.data[...] = data
        self.par[...] = par
        self.run()
        if self.buffer.ret() != 0:
            raise RuntimeError(f"CasADi function {self.function.name()} failed (return code {self.buffer.ret()})")
        full = np.zeros((self.out.shape[0], self.rows))
        full[:, self.at] = self.out
        return full


#: the pieces worth compiling (the RKMK4 transfer's 1.5 MB of C would take longer to build than it saves)
NATIVE = {"collocation_element": collocation_element, "dynamics_element": dynamics_element,
          "dynamics_node": dynamics_node}

__all__ = ["native", "NATIVE", "CFLAGS", "collocation_element", "end_condition", "dynamics_element", "dynamics_node", "ELEMENT_DATA",
           "ELEMENT_PARAMS", "NODE_DATA", "NODE_PARAMS", "rkmk4_transfer", "rkmk4_march", "mapped", "mapped_shared", "Batched", "STEP_DATA",
           "STEP_PARAMS", "COLLOCATION_ELEMENT_DATA", "COLLOCATION_PARAMS",
           "END_DATA", "END_PARAMS"]
