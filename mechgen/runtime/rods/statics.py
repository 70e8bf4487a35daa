"""Statics of a geometrically exact (Cosserat) rod as a boundary value problem on SE(3).

Conventions of mechgen.runtime.rods.liegroup (seed 001, Grazioso): poses H(s) = [[R, r], [0, 1]], s the
reference arc length in [0, L]; twist f = vee6(H^-1 H') = (nu, kappa); stress resultant sigma = (n, m), the
force and moment that the part beyond s exerts on the part before it, in the section frame. With the
quadratic energy of mechgen.symbolic.rod, sigma = K (f - f0), so f = f0 + K^-1 sigma. The equations are

    H' = H hat6(f),        sigma' = ad_f^T sigma - gbar(H),        gbar = (R^T q(r), R^T l(r)),

where q, l are the applied force and torque per unit length in the spatial frame (gravity, a centrifugal
load: N/m, N m/m). Component-wise: n' + kappa x n + R^T q = 0, m' + kappa x m + nu x n + R^T l = 0.
The seed writes the strong form as sigma' - ad_f^T sigma = g_ext with g_ext = -gbar (its external virtual
work carries the opposite sign, slides 26-28). Boundary terms: at the tip sigma(L) = (R^T F, R^T T) for a
dead tip force F and torque T (spatial frame); at the base sigma(0) is minus the applied base wrench.

Ends: ``clamped`` (pose fixed: H(0) = I at the base, the reference pose exp(L hat6 f0) at the tip),
``pinned`` (position fixed, moment free; at the base the twist angle about the rod's axis is held so that
a pinned-pinned rod has no rigid spin), ``free`` (no constraint; the wrench is the applied one). A rod
with neither end able to carry a moment about every axis and a force (free-free, pinned-free,
free-pinned) is unconstrained: :func:`check_ends` refuses it.

Two discretisations, both on the group (rotations never leave SO(3): each update is a product with an
exponential):

* :func:`shoot`: Munthe-Kaas RKMK4 (order 4) in s for (H, sigma) from the 12 unknowns at the base
  (H(0) = exp(xi0), sigma(0)), Newton on the 12 base + tip conditions; the Jacobian is the product of the
  steps' AD transfer matrices (:func:`shooting_jacobian`), or finite differences of the 13 trajectories
  integrated as one batch (``jacobian="fd"``).
* :func:`collocate`: Lie-group midpoint collocation on N elements (order 2): per element
  H_{i+1} = H_i exp(h f_m), (sigma_{i+1} - sigma_i)/h = ad_{f_m}^T sigma_m - gbar(H_i exp(h f_m / 2)),
  f_m = f0 + K^-1 sigma_m, sigma_m = (sigma_i + sigma_{i+1})/2; sparse Newton (scipy.sparse) with the
  element and end Jacobians by CasADi AD mapped over the elements (:func:`collocation_jacobian`), or
  finite differences over two colours of nodes (``jacobian="fd"``).

The AD pieces (mechgen.runtime.rods.local) are built once per process, whatever N; the distributed load's
Jacobian is the generated kernel's g_r (Rod.load_jacobian).

:func:`solve_statics` walks the load factor lam from 0 to 1 (natural-parameter continuation: the tip
wrench and the distributed load scaled by lam, the step halved on a failed Newton solve and grown after an
easy one); a path that cannot go on raises ConvergenceError with the last load factor reached.
Residuals are scaled: lengths by L, forces by EI/L^2, moments by EI/L (EI the smallest bending stiffness).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.rods.ends import ENDS, UNCONSTRAINED
from mechgen.runtime.rods.liegroup import coad6, exp_se3, inverse, jac_right_se3, log_se3, log_so3, vee3

sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


@dataclass(frozen=True)
class Rod:
    """A rod's numbers: length L (m), stiffness K (6 x 6, SPD), reference twist f0 (6), the distributed
    spatial load ``load(r) -> (n, 6)`` (force, torque per unit length at centre-line points r (n, 3); None:
    unloaded), the tip force and torque (spatial, dead: N, N m), the ends, and the load's Jacobian
    ``load_jacobian(r) -> (n, 6, 3)`` (d load/d r, 1/m; a generated kernel's g_r; None with a load: central
    differences of ``load``, see :func:`load_and_gradient`)."""

    L: float
    K: np.ndarray
    f0: np.ndarray = field(default_factory=lambda: np.array([1.0, 0, 0, 0, 0, 0]))
    load: Callable | None = None
    tip_force: np.ndarray = field(default_factory=lambda: np.zeros(3))
    tip_torque: np.ndarray = field(default_factory=lambda: np.zeros(3))
    base: str = "clamped"
    tip: str = "free"
    load_jacobian: Callable | None = None
    #: the load does not depend on the position (uniform gravity): the shooting's AD marches in CasADi
    load_uniform: bool = False

    @property
    def compliance(self) -> np.ndarray:
        """K^-1."""
        return np.linalg.inv(self.K)

    @property
    def scales(self) -> np.ndarray:
        """Scales of (translation, rotation, force, moment) residuals: (L, 1, EI/L^2, EI/L)."""
        ei = float(min(self.K[4, 4], self.K[5, 5]))
        return np.array([self.L, 1.0, ei / self.L**2, ei / self.L])


@dataclass(frozen=True)
class Solution:
    """A static state: nodes s (n), poses H (n, 4, 4), stress resultants sigma (n, 6), twists f (n, 6),
    the load factor reached and the Newton iterations of its last solve."""

    s: np.ndarray
    H: np.ndarray
    sigma: np.ndarray
    f: np.ndarray
    lam: float = 1.0
    iterations: int = 0


def check_ends(base: str, tip: str) -> None:
    """ValueError for an unknown end or a combination that leaves the rod unconstrained."""
    for name, end in (("base", base), ("tip", tip)):
        if end not in ENDS:
            raise ValueError(f"unknown {name} end {end!r}: one of {', '.join(ENDS)}")
    if (base, tip) in UNCONSTRAINED:
        raise ValueError(f"ends base = {base}, tip = {tip} leave the rod free to move rigidly")


def _expand(scales: np.ndarray) -> np.ndarray:
    """(L, 1, F, M) -> the 12 scales of (pose twist, wrench) = (L L L 1 1 1 F F F M M M)."""
    return np.repeat(scales, 3)


def twist_of(rod: Rod, sigma: np.ndarray) -> np.ndarray:
    """f = f0 + K^-1 sigma (batched over leading axes)."""
    return rod.f0 + sigma @ rod.compliance.T


def distributed(rod: Rod, H: np.ndarray, lam: float) -> np.ndarray:
    """gbar = lam (R^T q(r), R^T l(r)) at poses H (..., 4, 4): the applied wrench per length, section frame."""
    if rod.load is None or lam == 0.0:
        return np.zeros(H.shape[:-2] + (6,))
    shape = H.shape[:-2]
    r = H[..., :3, 3].reshape(-1, 3)
    g = np.asarray(rod.load(r), dtype=float).reshape(shape + (6,))
    Rt = np.swapaxes(H[..., :3, :3], -1, -2)
    return lam * np.concatenate([np.einsum("...ij,...j->...i", Rt, g[..., :3]),
                                 np.einsum("...ij,...j->...i", Rt, g[..., 3:])], axis=-1)


def load_and_gradient(rod: Rod, r: np.ndarray):
    """The spatial load g(r) (n, 6) and its Jacobian dg/dr (n, 6, 3) at points r (n, 3): rod.load_jacobian
    when given, else central differences of the pointwise load (step 1e-6 L: error ~1e-12 of its scale)."""
    r = np.asarray(r, dtype=float).reshape(-1, 3)
    n = len(r)
    if rod.load is None:
        return np.zeros((n, 6)), np.zeros((n, 6, 3))
    g = np.asarray(rod.load(r), dtype=float).reshape(n, 6)
    if rod.load_jacobian is not None:
        return g, np.asarray(rod.load_jacobian(r), dtype=float).reshape(n, 6, 3)
    d = 1e-6 * rod.L
    steps = d * np.eye(3)
    plus = np.asarray(rod.load((r[None] + steps[:, None]).reshape(-1, 3)), dtype=float).reshape(3, n, 6)
    minus = np.asarray(rod.load((r[None] - steps[:, None]).reshape(-1, 3)), dtype=float).reshape(3, n, 6)
    return g, np.transpose((plus - minus) / (2 * d), (1, 2, 0))


def _rhs(rod: Rod, H: np.ndarray, sigma: np.ndarray, lam: float):
    f = twist_of(rod, sigma)
    ds = np.einsum("...ij,...j->...i", coad6(f), sigma) - distributed(rod, H, lam)
    return f, ds


def _dexpinv(theta: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """J_r(theta)^-1 xi: the derivative of theta in H = H_n exp(theta) with H' = H hat(xi)."""
    return np.linalg.solve(jac_right_se3(theta), xi[..., None])[..., 0]


def rkmk4_step(rod: Rod, H: np.ndarray, sigma: np.ndarray, h: float, lam: float, *, stages: bool = False):
    """One Munthe-Kaas RK4 step in s (batched over leading axes): H_{n+1} = H_n exp(theta), theta from the
    classical RK4 on theta' = J_r(theta)^-1 f(H_n exp(theta), sigma), sigma by RK4 on R^6. With ``stages``
    also the 4 stage poses' positions (..., 4, 3), where the distributed load was evaluated."""
    x1, s1 = _rhs(rod, H, sigma, lam)
    t2 = 0.5 * h * x1
    H2 = H @ exp_se3(t2)
    x2, s2 = _rhs(rod, H2, sigma + 0.5 * h * s1, lam)
    x2 = _dexpinv(t2, x2)
    t3 = 0.5 * h * x2
    H3 = H @ exp_se3(t3)
    x3, s3 = _rhs(rod, H3, sigma + 0.5 * h * s2, lam)
    x3 = _dexpinv(t3, x3)
    t4 = h * x3
    H4 = H @ exp_se3(t4)
    x4, s4 = _rhs(rod, H4, sigma + h * s3, lam)
    x4 = _dexpinv(t4, x4)
    theta = h / 6.0 * (x1 + 2 * x2 + 2 * x3 + x4)
    out = H @ exp_se3(theta), sigma + h / 6.0 * (s1 + 2 * s2 + 2 * s3 + s4)
    if stages:
        return out + (np.stack([P[..., :3, 3] for P in (H, H2, H3, H4)], axis=-2),)
    return out


def integrate(rod: Rod, H0: np.ndarray, sigma0: np.ndarray, steps: int, lam: float, keep: bool = False):
    """RKMK4 from s = 0 to L in ``steps`` equal steps; the end state, or every node with ``keep``."""
    h = rod.L / steps
    H, sigma = H0, sigma0
    path = [(H, sigma)] if keep else None
    for _ in range(steps):
        H, sigma = rkmk4_step(rod, H, sigma, h, lam)
        if keep:
            path.append((H, sigma))
    if keep:
        return np.stack([p[0] for p in path], axis=-3), np.stack([p[1] for p in path], axis=-2)
    return H, sigma


def reference_tip(rod: Rod) -> np.ndarray:
    """The unloaded tip pose exp(L hat6 f0) (a clamped tip is held there)."""
    return exp_se3(rod.L * rod.f0)


def base_residual(rod: Rod, H0: np.ndarray, sigma0: np.ndarray) -> np.ndarray:
    """The 6 base conditions, scaled (batched)."""
    sc = _expand(rod.scales)
    if rod.base == "clamped":
        return log_se3(H0) / sc[:6]
    if rod.base == "pinned":
        twist = log_so3(H0[..., :3, :3])[..., :1]
        return np.concatenate([H0[..., :3, 3] / rod.L, twist, sigma0[..., 4:] / sc[10:]], axis=-1)
    return sigma0 / sc[6:]


def tip_residual(rod: Rod, HL: np.ndarray, sigmaL: np.ndarray, lam: float) -> np.ndarray:
    """The 6 tip conditions, scaled (batched)."""
    sc = _expand(rod.scales)
    if rod.tip == "clamped":
        return log_se3(inverse(reference_tip(rod)) @ HL) / sc[:6]
    Rt = np.swapaxes(HL[..., :3, :3], -1, -2)
    moment = (sigmaL[..., 3:] - lam * Rt @ rod.tip_torque) / sc[9:]
    if rod.tip == "pinned":
        return np.concatenate([(HL[..., :3, 3] - reference_tip(rod)[:3, 3]) / rod.L, moment], axis=-1)
    force = (sigmaL[..., :3] - lam * Rt @ rod.tip_force) / sc[6:9]
    return np.concatenate([force, moment], axis=-1)


# --------------------------------------------------------------------------- shooting

def shooting_residual(rod: Rod, z: np.ndarray, steps: int, lam: float) -> np.ndarray:
    """Residual of the 12 scaled base unknowns z = (xi0 / (L, 1), sigma0 / (F, M)) (batched over rows)."""
    sc = _expand(rod.scales)
    H0 = exp_se3(z[..., :6] * sc[:6])
    sigma0 = z[..., 6:] * sc[6:]
    HL, sL = integrate(rod, H0, sigma0, steps, lam)
    return np.concatenate([base_residual(rod, H0, sigma0), tip_residual(rod, HL, sL, lam)], axis=-1)


def _newton(residual_and_jacobian, z, *, tol: float, max_iter: int, solve=np.linalg.solve, update=None,
            contraction: float = 0.5):
    """Newton with full steps that must contract: |dz_k| <= contraction |dz_(k-1)|, else None (a continuation
    step then halves: a Newton iteration that wanders, or a damped one, can land on another branch of
    equilibria, e.g. a looped elastica). Returns (z, iterations) or None."""
    update = update or (lambda z, dz: z + dz)
    last = np.inf
    for it in range(max_iter + 1):
        r, J = residual_and_jacobian(z)
        norm = np.linalg.norm(r)
        if not np.isfinite(norm):
            return None
        if norm < tol:
            return z, it
        if it == max_iter:
            return None
        try:
            dz = -solve(J, r)
        except (np.linalg.LinAlgError, RuntimeError):
            return None
        size = np.linalg.norm(dz)
        if not np.isfinite(size) or size > contraction * last:
            return None
        last = size
        z = update(z, dz)
    return None


def shooting_jacobian(rod: Rod, z: np.ndarray, steps: int, lam: float):
    """The shooting residual at the scaled base unknowns z and its 12 x 12 Jacobian by AD of the pieces:

        J = [E_0 T_0; E_L Phi_(N-1) ... Phi_0 T_0],

    T_0 = diag(J_r(xi_0) S_pose, S_wrench) takes z to the base's local increments (exp(xi + d) =
    exp(xi) exp(J_r(xi) d)), Phi_k the AD transfer of RKMK4 step k in local coordinates
    (local.rkmk4_transfer, mapped over the steps at the nodes integrated by numpy; for an unloaded rod or a
    uniform load local.rkmk4_march integrates and differentiates in one CasADi fold), E_0, E_L the AD
    Jacobians of the base and tip conditions (local.end_condition) divided by the scales of their
    increments."""
    from mechgen.runtime.rods import local

    sc = _expand(rod.scales)
    xi0 = z[:6] * sc[:6]
    H0, sigma0 = exp_se3(xi0), z[6:] * sc[6:]
    h = rod.L / steps
    par = np.concatenate([[h, lam], rod.compliance.ravel(), rod.f0])
    if rod.load is None or rod.load_uniform:
        # one CasADi fold integrates and differentiates every step (the load's value is the same everywhere)
        stage = np.zeros((4, 27))
        if rod.load is not None:
            stage[:, :6] = load_and_gradient(rod, np.zeros((1, 3)))[0][0]
        marched, transfers = local.rkmk4_march(steps)(_pack_node(H0, sigma0), stage.ravel(), par)
        marched = np.asarray(marched).T
        phi = np.asarray(transfers).T.reshape(steps, 12, 12)
        H = np.zeros((steps + 1, 4, 4))
        H[0], H[1:, :3, :3], H[1:, :3, 3], H[1:, 3, 3] = H0, marched[:, :9].reshape(-1, 3, 3), marched[:, 9:12], 1.0
        sigma = np.vstack([sigma0, marched[:, 12:]])
    else:
        H, sigma = integrate(rod, H0, sigma0, steps, lam, keep=True)
        nodes = _pack_node(H[:-1], sigma[:-1])
        points = rkmk4_step(rod, H[:-1], sigma[:-1], h, lam, stages=True)[2].reshape(steps * 4, 3)
        g0, G = load_and_gradient(rod, points)
        loads = np.concatenate([g0, G.reshape(-1, 18), points], axis=1).reshape(steps, 108)
        data = np.concatenate([nodes, loads], axis=1)
        phi = np.asarray(local.mapped(local.rkmk4_transfer(), steps)(data.T, par)).T.reshape(steps, 12, 12)
    P = np.eye(12)
    for k in range(steps):
        P = phi[k] @ P
    T0 = np.zeros((12, 12))
    T0[:6, :6] = jac_right_se3(xi0) * sc[:6]
    T0[6:, 6:] = np.diag(sc[6:])
    end_par = np.concatenate([[rod.L, lam], sc])
    wrench = np.concatenate([rod.tip_force, rod.tip_torque])
    rows = []
    for where, end, node, held, transfer in (("base", rod.base, 0, np.eye(4), T0),
                                             ("tip", rod.tip, -1, reference_tip(rod), P @ T0)):
        end_data = np.concatenate([_pack_node(H[node], sigma[node]), held[:3, :3].ravel(), held[:3, 3], wrench])
        E = np.asarray(local.end_condition(where, end)(end_data, end_par)).reshape(6, 12)
        rows.append((E / sc) @ transfer)
    r = np.concatenate([base_residual(rod, H[0], sigma[0]), tip_residual(rod, H[-1], sigma[-1], lam)])
    return r, np.vstack(rows)


def shooting_jacobian_fd(rod: Rod, z: np.ndarray, steps: int, lam: float):
    """The shooting residual and its Jacobian by forward differences (step 1e-7 max(1, |z_k|)): the 13
    trajectories integrated as one batch."""
    d = 1e-7 * np.maximum(1.0, np.abs(z))
    r = shooting_residual(rod, np.vstack([z, z + np.diag(d)]), steps, lam)
    return r[0], ((r[1:] - r[0]) / d[:, None]).T


def shoot(rod: Rod, steps: int, lam: float, z0: np.ndarray, *, tol: float = 1e-10, max_iter: int = 30,
          jacobian: str = "ad"):
    """Newton on the scaled base unknowns at load factor lam: (z, iterations), or None without convergence.
    ``jacobian``: ``ad`` (:func:`shooting_jacobian`) or ``fd`` (forward differences of the 12 unknowns, the
    13 trajectories integrated as one batch)."""
    def rj(z):
        if jacobian == "ad":
            return shooting_jacobian(rod, z, steps, lam)
        return shooting_jacobian_fd(rod, z, steps, lam)

    with np.errstate(all="ignore"):
        return _newton(rj, np.asarray(z0, dtype=float), tol=tol, max_iter=max_iter)


def shooting_state(rod: Rod, z: np.ndarray, steps: int, lam: float, iterations: int = 0) -> Solution:
    """The nodes of the shot trajectory from the scaled unknowns z."""
    sc = _expand(rod.scales)
    H, sigma = integrate(rod, exp_se3(z[:6] * sc[:6]), z[6:] * sc[6:], steps, lam, keep=True)
    return Solution(np.linspace(0.0, rod.L, steps + 1), H, sigma, twist_of(rod, sigma), lam, iterations)


# --------------------------------------------------------------------------- collocation

def midpoints(rod: Rod, H: np.ndarray, sigma: np.ndarray):
    """Per element of the collocation: sigma_m = (sigma_i + sigma_i+1)/2, f_m = f0 + K^-1 sigma_m and the
    midpoint pose H_i exp(h f_m / 2) (batched over leading axes)."""
    h = rod.L / (H.shape[-3] - 1)
    sm = 0.5 * (sigma[..., 1:, :] + sigma[..., :-1, :])
    fm = twist_of(rod, sm)
    return sm, fm, H[..., :-1, :, :] @ exp_se3(0.5 * h * fm)


def collocation_residual(rod: Rod, H: np.ndarray, sigma: np.ndarray, lam: float) -> np.ndarray:
    """Rows (base 6, elements 12 N, tip 6), scaled; H (..., N+1, 4, 4), sigma (..., N+1, 6) unscaled."""
    n = H.shape[-3] - 1
    h = rod.L / n
    sc = _expand(rod.scales)
    sm, fm, Hm = midpoints(rod, H, sigma)
    pose = log_se3(exp_se3(-h * fm) @ inverse(H[..., :-1, :, :]) @ H[..., 1:, :, :]) / sc[:6]
    stress = ((sigma[..., 1:, :] - sigma[..., :-1, :]) / h - np.einsum("...ij,...j->...i", coad6(fm), sm)
              + distributed(rod, Hm, lam)) * (rod.L / sc[6:])
    elements = np.concatenate([pose, stress], axis=-1).reshape(H.shape[:-3] + (12 * n,))
    return np.concatenate([base_residual(rod, H[..., 0, :, :], sigma[..., 0, :]), elements,
                           tip_residual(rod, H[..., -1, :, :], sigma[..., -1, :], lam)], axis=-1)


def perturbed(rod: Rod, H, sigma, dz: np.ndarray):
    """(H_i exp(dxi_i), sigma_i + dsigma_i) for scaled increments dz (..., N+1, 12)."""
    sc = _expand(rod.scales)
    return H @ exp_se3(dz[..., :6] * sc[:6]), sigma + dz[..., 6:] * sc[6:]


def _pack_node(H: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """(R row-major 9, p 3, sigma 6) per node: the layout of mechgen.runtime.rods.local."""
    return np.concatenate([H[..., :3, :3].reshape(H.shape[:-2] + (9,)), H[..., :3, 3], sigma], axis=-1)


def collocation_jacobian(rod: Rod, H, sigma, lam: float, r0: np.ndarray | None = None, *,
                         method: str = "ad", eps: float = 1e-7) -> sps.csr_matrix:
    """d collocation_residual / d z at the state (H, sigma), z the scaled right increments of every node.

    ``ad``: CasADi's algorithmic derivative of the element and end pieces (mechgen.runtime.rods.local),
    mapped over the elements: exact to round-off. ``fd``: forward differences (step eps) over two colours
    of nodes (an element touches one even and one odd node), from the residual r0 at the state: O(eps)."""
    if method == "fd":
        return _collocation_jacobian_fd(rod, H, sigma, lam, r0, eps)
    if method != "ad":
        raise ValueError(f"unknown Jacobian method {method!r}: ad or fd")
    from mechgen.runtime.rods import local

    n = H.shape[0] - 1
    sc = _expand(rod.scales)
    _, _, Hm = midpoints(rod, H, sigma)
    g0, G = load_and_gradient(rod, Hm[:, :3, 3])
    nodes = _pack_node(H, sigma)
    data = np.concatenate([nodes[:-1], nodes[1:], g0, G.reshape(n, 18), Hm[:, :3, 3]], axis=1)
    par = np.concatenate([[rod.L / n, rod.L, lam], rod.compliance.ravel(), rod.f0, sc])
    blocks = np.asarray(local.mapped(local.native("collocation_element"), n)(data.T, par)).T.reshape(n, 12, 24)
    end_par = np.concatenate([[rod.L, lam], sc])
    wrench = np.concatenate([rod.tip_force, rod.tip_torque])
    ends = []
    for where, end, node, held in (("base", rod.base, 0, np.eye(4)), ("tip", rod.tip, n, reference_tip(rod))):
        end_data = np.concatenate([nodes[node], held[:3, :3].ravel(), held[:3, 3], wrench])
        ends.append(np.asarray(local.end_condition(where, end)(end_data, end_par)).reshape(6, 12))
    e = np.arange(n)
    rows = [np.broadcast_to(np.arange(6)[:, None], (6, 12)).ravel(),
            (6 + 12 * e[:, None, None] + np.arange(12)[None, :, None] + 0 * np.arange(24)).ravel(),
            np.broadcast_to(6 + 12 * n + np.arange(6)[:, None], (6, 12)).ravel()]
    cols = [np.broadcast_to(np.arange(12), (6, 12)).ravel(),
            (12 * e[:, None, None] + 0 * np.arange(12)[None, :, None] + np.arange(24)).ravel(),
            np.broadcast_to(12 * n + np.arange(12), (6, 12)).ravel()]
    vals = [ends[0].ravel(), blocks.ravel(), ends[1].ravel()]
    size = 12 * (n + 1)
    return sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size))


def _collocation_jacobian_fd(rod: Rod, H, sigma, lam: float, r0, eps: float) -> sps.csr_matrix:
    n = H.shape[0] - 1
    if r0 is None:
        r0 = collocation_residual(rod, H, sigma, lam)
    nodes = np.arange(n + 1)
    batch = np.zeros((24, n + 1, 12))
    for colour in (0, 1):
        for j in range(12):
            batch[12 * colour + j, nodes % 2 == colour, j] = eps
    Hp, sp_ = perturbed(rod, H[None], sigma[None], batch)
    dr = (collocation_residual(rod, Hp, sp_, lam) - r0) / eps          # (24, rows)
    rows, cols, vals = [], [], []
    for colour in (0, 1):
        for j in range(12):
            d = dr[12 * colour + j]
            for node in nodes[nodes % 2 == colour]:
                touched = []
                if node == 0:
                    touched.append(np.arange(6))
                if node == n:
                    touched.append(6 + 12 * n + np.arange(6))
                if node > 0:
                    touched.append(6 + 12 * (node - 1) + np.arange(12))
                if node < n:
                    touched.append(6 + 12 * node + np.arange(12))
                idx = np.concatenate(touched)
                rows.append(idx)
                cols.append(np.full(idx.size, 12 * node + j))
                vals.append(d[idx])
    size = 12 * (n + 1)
    return sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size))


def collocate(rod: Rod, guess: Solution, lam: float, *, tol: float = 1e-10, max_iter: int = 30,
              jacobian: str = "ad"):
    """Sparse Newton for the midpoint collocation from ``guess`` (its nodes fix N): a Solution or None.
    ``jacobian``: ad or fd (:func:`collocation_jacobian`)."""
    n = guess.H.shape[0] - 1
    base = (guess.H, guess.sigma)

    def state(z):
        return perturbed(rod, base[0], base[1], z.reshape(n + 1, 12))

    def rj(z):
        H, sigma = state(z)
        r = collocation_residual(rod, H, sigma, lam)
        return r, collocation_jacobian(rod, H, sigma, lam, r, method=jacobian)

    def update(z, dz):
        # increments compose on the right of the current poses: re-base them so that exp stays small
        H, sigma = state(z)
        Hn, sn = perturbed(rod, H, sigma, dz.reshape(n + 1, 12))
        base_h = base[0]
        zz = np.zeros_like(z).reshape(n + 1, 12)
        sc = _expand(rod.scales)
        zz[:, :6] = log_se3(inverse(base_h) @ Hn) / sc[:6]
        zz[:, 6:] = (sn - base[1]) / sc[6:]
        return zz.ravel()

    with np.errstate(all="ignore"):
        out = _newton(rj, np.zeros(12 * (n + 1)), tol=tol, max_iter=max_iter, solve=_sparse_solve, update=update)
    if out is None:
        return None
    H, sigma = state(out[0])
    return Solution(np.linspace(0.0, rod.L, n + 1), H, sigma, twist_of(rod, sigma), lam, out[1])


def _sparse_solve(J, r):
    x = spla.spsolve(J.tocsc(), r)
    if not np.all(np.isfinite(x)):
        raise np.linalg.LinAlgError("singular collocation Jacobian")
    return x


def straight(rod: Rod, n: int) -> Solution:
    """The unloaded reference state on n + 1 nodes: H(s) = exp(s hat6 f0), sigma = 0."""
    s = np.linspace(0.0, rod.L, n + 1)
    H = exp_se3(s[:, None] * rod.f0)
    sigma = np.zeros((n + 1, 6))
    return Solution(s, H, sigma, twist_of(rod, sigma), 0.0, 0)


# --------------------------------------------------------------------------- continuation in the load

@dataclass(frozen=True)
class Path:
    """The states along the load path (lam ascending to 1; the last one is the answer)."""

    states: tuple[Solution, ...]

    @property
    def final(self) -> Solution:
        """The state at the full load."""
        return self.states[-1]


def solve_statics(rod: Rod, *, method: str = "shooting", elements: int = 40, steps: int = 10,
                  min_step: float = 1e-4, tol: float = 1e-10, progress: Callable | None = None,
                  jacobian: str = "ad") -> Path:
    """Continuation in the load factor lam from 0 to 1 in ``steps`` initial steps (halved on a failure or a
    jump off the branch (:func:`_smooth`), grown by 1.5 after a solve in <= 4 Newton iterations, at most
    2/steps). ``elements``: RKMK4 steps of
    the shooting, or collocation elements. ``jacobian``: ``ad`` (CasADi AD of the local pieces) or ``fd``
    (finite differences; kept as the reference and for comparison). ConvergenceError names the last load
    factor reached."""
    if jacobian not in ("ad", "fd"):
        raise ValueError(f"unknown Jacobian method {jacobian!r}: ad or fd")
    check_ends(rod.base, rod.tip)
    if method not in ("shooting", "collocation"):
        raise ValueError(f"unknown method {method!r}")
    lam, dlam, dmax = 0.0, 1.0 / steps, 2.0 / steps
    if method == "shooting":
        z = np.zeros(12)
        out = shoot(rod, elements, 0.0, z, tol=tol, jacobian=jacobian)
        if out is None:
            raise ConvergenceError("rod statics: no unloaded state (shooting)")
        z, prev = out[0], None
        states = [shooting_state(rod, z, elements, 0.0, out[1])]
    else:
        states = [straight(rod, elements)]
        prev = None
    rate = None
    while lam < 1.0:
        target = min(1.0, lam + dlam)
        if method == "shooting":
            guess = z if prev is None else z + (z - prev[0]) * (target - lam) / (lam - prev[1])
            prev_back = prev
            out = shoot(rod, elements, target, guess, tol=tol, jacobian=jacobian)
            ok = out is not None
            if ok:
                prev, z = (z, lam), out[0]
                states.append(shooting_state(rod, z, elements, target, out[1]))
                iters = out[1]
        else:
            sol = collocate(rod, states[-1], target, tol=tol, jacobian=jacobian)
            ok = sol is not None
            if ok:
                states.append(sol)
                iters = sol.iterations
        if ok and not _smooth(states, target - lam, rate):
            states.pop()
            if method == "shooting":
                z, prev = prev[0], prev_back
            ok = False
        if not ok:
            dlam *= 0.5
            if dlam < min_step:
                raise ConvergenceError(f"rod statics ({method}) did not converge beyond load factor {lam:.6g} "
                                       f"(the last load reached; step below {min_step:g}: Newton failed or left "
                                       "the branch)")
            continue
        rate = _change(states[-2], states[-1]) / (target - lam)
        lam = target
        if progress is not None:
            progress(lam)
        if iters <= 4:
            dlam = min(1.5 * dlam, dmax)
    return Path(tuple(states))


def _change(a: Solution, b: Solution) -> float:
    """The largest move of a node between two states, in units of L (poses compared at the same nodes)."""
    L = a.s[-1]
    if a.H.shape != b.H.shape:
        return 0.0
    return float(np.max(np.linalg.norm(b.H[:, :3, 3] - a.H[:, :3, 3], axis=-1)) / L)


def _smooth(states: list, dlam: float, rate: float | None) -> bool:
    """Whether the newest state follows the branch: its nodes moved at most 3 times as far per unit load as
    over the previous step (plus 2 % of L). A larger move is a jump to another branch of equilibria (shooting
    is ill-conditioned at large loads, and Newton may converge to a looped elastica); the step is halved."""
    if rate is None:
        return True
    return _change(states[-2], states[-1]) <= 3.0 * rate * dlam + 0.02


# --------------------------------------------------------------------------- measures

def turning_angle(H: np.ndarray, axis) -> float:
    """The rotation from the first to the last node about a spatial axis, unwrapped (beyond 2 pi): the sum of
    the node-to-node rotation vectors, spatial frame, projected on the unit ``axis``."""
    R = H[:, :3, :3]
    inc = log_so3(np.swapaxes(R[:-1], -1, -2) @ R[1:])
    spatial = np.einsum("nij,nj->ni", R[:-1], inc)
    a = np.asarray(axis, dtype=float)
    return float(np.sum(spatial @ (a / np.linalg.norm(a))))


__all__ = ["Rod", "Solution", "Path", "check_ends", "solve_statics", "shoot", "collocate", "integrate",
           "collocation_residual", "collocation_jacobian", "shooting_residual", "shooting_jacobian",
           "shooting_jacobian_fd", "perturbed",
           "midpoints", "load_and_gradient",
           "rkmk4_step", "turning_angle", "straight", "vee3"]
