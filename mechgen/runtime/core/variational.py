"""Variational integrators generated from a model's own Lagrangian (Marsden & West 2001, Acta Numerica 10, 357).

The model's ``lagrangian`` kernel (mechgen.codegen.lower_lumped) gives, at (q, v, t),

    p = dL/dv = dT/dv,    F = dL/dq + Q - dR/dv    (Lagrange's equations: dp/dt = F),

and their Jacobians p_q, p_v, F_q, F_v, all derived from the declared T, V, R and forces Q (the kernel's ports
``mom``, ``F``, ``mom_q``, ``mom_v``, ``F_q``, ``F_v``: ``p`` is the parameters' input).

**Midpoint** (``stages = 1``, order 2). The discrete Lagrangian of one step h from q_k to q_{k+1} is

    L_d(q_k, q_{k+1}) = h L(q_m, v_m),   q_m = (q_k + q_{k+1}) / 2,   v_m = (q_{k+1} - q_k) / h,

and the discrete Lagrange-d'Alembert principle, with the forces and the dissipation evaluated at the midpoint
and given half to each end (f_d^- = f_d^+ = h/2 (Q - dR/dv)(q_m, v_m)), gives the discrete Euler-Lagrange
equations D2 L_d(q_{k-1}, q_k) + D1 L_d(q_k, q_{k+1}) + f_d^+(k-1) + f_d^-(k) = 0. In position-momentum form:

    p_k     = -D1 L_d(q_k, q_{k+1}) - f_d^- = p(q_m, v_m) - h/2 F(q_m, v_m, t_k + h/2),
    p_{k+1} =  D2 L_d(q_k, q_{k+1}) + f_d^+ = p(q_m, v_m) + h/2 F(q_m, v_m, t_k + h/2).

The first is solved for v_m (q_{k+1} = q_k + h v_m) by Newton with the generated Jacobian
d/dv_m = p_v + h/2 p_q - h/2 (F_v + h/2 F_q).

**Gauss-Legendre** (``stages = s``, order 2 s). The discrete Lagrangian of the Galerkin curve of degree s
through q_k, q_{k+1} with Gauss quadrature of s points gives the symplectic partitioned Runge-Kutta method
(Marsden & West, sec. 2.6; Hairer, Lubich & Wanner, Geometric Numerical Integration, VI.6.3) with Gauss
coefficients a_ij, b_i, c_i and stage velocities V_i:

    Q_i = q_k + h sum_j a_ij V_j,   P_i = p(Q_i, V_i),   P_i = p_k + h sum_j a_ij F(Q_j, V_j, t_k + c_j h),
    q_{k+1} = q_k + h sum_i b_i V_i,   p_{k+1} = p_k + h sum_i b_i F(Q_i, V_i, t_k + c_i h),

(the forces by the same quadrature: the discrete Lagrange-d'Alembert principle); s = 1 is the midpoint above.
Newton solves the s n stage equations R_i(V) = P_i - p_k - h sum_j a_ij F_j = 0 with the Jacobian

    dR_i/dV_j = h a_ij p_q(i) + d_ij p_v(i) - h^2 sum_l a_il a_lj F_q(l) - h a_ij F_v(j).

A conservative model keeps its energy error bounded (no drift) over exponentially long times, and a
momentum that a symmetry of L_d conserves (a cyclic coordinate's p, a rotation-invariant L's angular
momentum in Cartesian coordinates) is kept to round-off, since the discrete flow is symplectic and satisfies
the discrete Noether theorem. The velocity at a sample is the inverse Legendre transform of (q_k, p_k),
p(q_k, v_k, t_k) = p_k, by Newton on p_v.

Runtime module: numbers only (no sympy); units are the model's (t in its time unit, p in its momentum unit).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.core.budget import Budget, Progress
from mechgen.runtime.core.options import Options
from mechgen.runtime.core.variational_rules import (MAX_NEWTON, NEWTON_RTOL, STALL, Tableau, gauss_legendre,
                                                    newton_failure, nonfinite, singular)

#: steps between returns to Python (wall-time budget, finiteness, progress)
CHUNK = 4096


class Lagrangian:
    """The system's ``lagrangian`` kernel at one state: p, F and their Jacobians (copies, n x n matrices)."""

    def __init__(self, system) -> None:
        self.system = system
        self.n = system.n

    def __call__(self, q: np.ndarray, v: np.ndarray, t: float) -> tuple[np.ndarray, ...]:
        """(p, F, p_q, p_v, F_q, F_v) at (q, v, t)."""
        out = self.system.bound("lagrangian").evaluate(q=q, v=v, t=t)
        n = self.n
        return (out["mom"].reshape(n).copy(), out["F"].reshape(n).copy(), out["mom_q"].reshape(n, n).copy(),
                out["mom_v"].reshape(n, n).copy(), out["F_q"].reshape(n, n).copy(), out["F_v"].reshape(n, n).copy())

    def momentum(self, q: np.ndarray, v: np.ndarray, t: float) -> np.ndarray:
        """p = dL/dv at (q, v, t)."""
        return self(q, v, t)[0]


class Powers:
    """The system's ``energy_rates`` kernel at the stages: the powers g = (Q.v, v.dR/dv, -dL/dt) of the energy
    balance (mechgen.analyses.energy_balance), whose integrals W advance by the step's own quadrature,
    W_{k+1} = W_k + h sum_i b_i g(Q_i, V_i, t_k + c_i h) (the Gauss method applied to W' = g: order 2 s)."""

    def __init__(self, system) -> None:
        self.system = system

    def increment(self, tab: Tableau, h: float, q: np.ndarray, t: float, V: np.ndarray) -> np.ndarray:
        """h sum_i b_i g(Q_i, V_i, t + c_i h), Q_i = q + h sum_j a_ij V_j (3 numbers)."""
        Q = q + h * tab.a @ V
        bound = self.system.bound("energy_rates")
        g = np.array([bound.evaluate(q=Q[i], v=V[i], t=t + tab.c[i] * h)["g"][:3].copy()  # the next call reuses it
                      for i in range(tab.stages)])
        return h * tab.b @ g


def converged(step: np.ndarray, previous: float, scale: float) -> bool:
    """Newton's stop: |step| <= NEWTON_RTOL scale, or a stall at round-off (|step| <= STALL scale and no longer
    halving)."""
    size = float(np.max(np.abs(step))) if step.size else 0.0
    return size <= NEWTON_RTOL * scale or (size <= STALL * scale and size > 0.5 * previous)


def legendre_velocity(lag: Lagrangian, q: np.ndarray, p: np.ndarray, t: float, guess: np.ndarray) -> np.ndarray:
    """v with p(q, v, t) = p (the inverse Legendre transform), by Newton on p_v from ``guess``."""
    v = np.array(guess, float)
    previous = math.inf
    for _ in range(MAX_NEWTON):
        mom, _, _, p_v, _, _ = lag(q, v, t)
        step = solve(p_v, mom - p, t)
        v -= step
        if converged(step, previous, max(float(np.max(np.abs(v))), 1e-300)):
            return v
        previous = float(np.max(np.abs(step)))
    raise ConvergenceError(f"variational: the velocity at t = {t:.6g} (p(q, v) = p) did not converge in "
                           f"{MAX_NEWTON} Newton steps (a singular mass matrix p_v?)")


def stage_system(lag: Lagrangian, tab: Tableau, h: float, q: np.ndarray, p: np.ndarray, t: float,
                 V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stage residuals R (s n), their Jacobian dR/dV (s n x s n) and the stage forces F (s x n) at V (s x n)."""
    s, n = V.shape
    Q = q + h * tab.a @ V
    P, F = np.empty((s, n)), np.empty((s, n))
    pq, pv, Fq, Fv = (np.empty((s, n, n)) for _ in range(4))
    for i in range(s):
        P[i], F[i], pq[i], pv[i], Fq[i], Fv[i] = lag(Q[i], V[i], t + tab.c[i] * h)
    R = P - p - h * tab.a @ F
    a = tab.a
    J = (h * np.einsum("ij,iab->iajb", a, pq) + np.einsum("ij,iab->iajb", np.eye(s), pv)
         - h * h * np.einsum("il,lj,lab->iajb", a, a, Fq) - h * np.einsum("ij,jab->iajb", a, Fv))
    return R.reshape(-1), J.reshape(s * n, s * n), F


def step(lag: Lagrangian, tab: Tableau, h: float, q: np.ndarray, p: np.ndarray, t: float,
         V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """One step from (q_k, p_k) at t_k: (q_{k+1}, p_{k+1}, the stage velocities V, Newton iterations).

    Newton from ``V`` (the previous step's stage velocities); the accepted V is the last point evaluated, so that
    q_{k+1} and p_{k+1} come from one consistent set of stages (its residual: the last correction, below
    NEWTON_RTOL of the velocity scale).
    """
    V = np.array(V, float)
    previous = math.inf
    for it in range(1, MAX_NEWTON + 1):
        R, J, F = stage_system(lag, tab, h, q, p, t, V)
        delta = solve(J, R, t).reshape(V.shape)
        if not np.all(np.isfinite(delta)):
            raise nonfinite(t)
        if converged(delta, previous, max(float(np.max(np.abs(V))), 1e-300)) or not np.any(delta):
            return q + h * tab.b @ V, p + h * tab.b @ F, V, it
        V -= delta
        previous = float(np.max(np.abs(delta)))
    raise newton_failure(t, h)


def solve(J: np.ndarray, r: np.ndarray, t: float) -> np.ndarray:
    """J^-1 r; a singular J (a coordinate without inertia: dp/dv singular) is a ConvergenceError naming t."""
    try:
        return np.linalg.solve(J, r)
    except np.linalg.LinAlgError:
        raise singular(t) from None


def python_stepper(lag: Lagrangian, tab: Tableau, h: float, powers: Powers | None = None) -> Callable:
    """``advance(q, p, V, W, k0, count, total, save_every)``: ``count`` steps from global step k0 in Python,
    returning (q, p, V, W, Newton iterations, samples): (t, q, p, velocity guess b.V, W) after every step that is
    a multiple of save_every or the ``total``-th; W (3) the energy balance's integrals (Powers; unchanged without
    ``powers``). The rules of the compiled loop, mechgen.runtime.core.variational_c."""
    def advance(q, p, V, W, k0: int, count: int, total: int, save_every: int):
        samples, iterations = [], 0
        for k in range(k0, k0 + count):
            q_old = q
            q, p, V, used = step(lag, tab, h, q, p, k * h, V)
            if powers is not None:
                W = W + powers.increment(tab, h, q_old, k * h, V)
            iterations += used
            if (k + 1) % save_every == 0 or k + 1 == total:
                samples.append(((k + 1) * h, q, p, tab.b @ V, W))
        return q, p, V, W, iterations, samples
    return advance


@dataclass(frozen=True)
class VariationalRun:
    """Samples of a variational run every ``save_every`` steps (and at the last): times ``t``, coordinates ``q``,
    velocities ``v`` (the inverse Legendre transform of p), discrete momenta ``p`` (samples x n) and ``energy``
    (when an energy function was given, else empty), ``w`` the energy balance's integrals (samples x 3: the forces'
    work, the dissipated energy, the explicit work; None when not integrated); ``h`` the step, ``steps``,
    ``newton`` iterations in all, ``loop`` the loop that ran (``c`` or ``python``)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    p: np.ndarray
    energy: np.ndarray
    h: float
    steps: int
    newton: int
    loop: str
    w: np.ndarray | None = None


def steps_for(t_end: float, dt: float) -> tuple[int, float]:
    """(steps, h): the fewest equal steps h = t_end / steps no longer than dt (t_end is reached exactly)."""
    steps = max(1, math.ceil(t_end / dt * (1.0 - 1e-12)))
    return steps, t_end / steps


@dataclass(frozen=True)
class VariationalOptions(Options):
    """How a variational run goes (run_variational).

    Attributes:
        stages: Gauss-Legendre stages s (order 2s; 1 is the midpoint rule).
        save_every: a sample every this many steps (and at the end).
        energy: ``(q, v, t) -> float`` evaluated at the samples, or None.
        balance: integrate the energy balance's powers too (Powers; the system's ``energy_rates`` kernel).
        budget: refuses the step count up front and checks the wall time every CHUNK steps, or None.
        progress, desc: a progress bar in steps and its label.
        loop: "auto" (the compiled loop, mechgen.runtime.core.variational_c, when the kernels are C), "python" or
            "c".
    """

    stages: int = 1
    save_every: int = 1
    energy: Callable | None = None
    balance: bool = False
    budget: Budget | None = None
    progress: bool = False
    desc: str = "variational"
    loop: str = "auto"


def run_variational(system, q0, v0, t_end: float, dt: float, *, options: VariationalOptions | None = None,
                    **changes) -> VariationalRun:
    """Integrate from (q0, v0) at t = 0 to t_end with the Gauss-Legendre variational integrator of
    ``options.stages`` (module doc), equal steps h = t_end / ceil(t_end / dt); samples every ``save_every`` steps
    and at the end (VariationalOptions; its fields may also be given as keywords). A Newton failure or a NaN/Inf
    state ends the run (ConvergenceError naming the time)."""
    from mechgen.runtime.core.variational_c import compiled_stepper

    opt = VariationalOptions.of(options, **changes)
    steps, h = steps_for(t_end, dt)
    if opt.budget is not None:
        opt.budget.refuse(steps, f"nothing (refused before starting: t_end / dt = {steps:,} steps)")
    lag, tab = Lagrangian(system), gauss_legendre(opt.stages)
    q, v, W = np.array(q0, float), np.array(v0, float), np.zeros(3)
    p = lag.momentum(q, v, 0.0)
    V = np.tile(v, (tab.stages, 1))
    rec = Recorder(lag, opt.energy, steps, opt.save_every, q.size)
    rec.add(0.0, q, p, v, W)
    advance = (compiled_stepper(system, tab, h, balance=opt.balance, required=opt.loop == "c")
               if opt.loop != "python" else None)
    used = "python" if advance is None else "c"
    advance = advance or python_stepper(lag, tab, h, Powers(system) if opt.balance else None)
    newton, done = 0, 0
    with Progress(steps, desc=opt.desc, unit="step", enabled=opt.progress) as bar:
        while done < steps:
            count = min(CHUNK, steps - done)
            q, p, V, W, iterations, samples = advance(q, p, V, W, done, count, steps, opt.save_every)
            for sample in samples:
                rec.add(*sample)
            newton, done = newton + iterations, done + count
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(p))):
                raise nonfinite(done * h)
            if opt.budget is not None:
                opt.budget.check_time(lambda: f"t = {done * h:.6g} of t_end = {t_end:.6g} after {done:,} steps")
            bar.to(done)
    return rec.run(h, steps, newton, used, opt.balance)


class Recorder:
    """The samples of a run: (t, q, p) as given, v by the inverse Legendre transform, the energy at (q, v, t)."""

    def __init__(self, lag: Lagrangian, energy: Callable | None, steps: int, save_every: int, n: int) -> None:
        count = steps // save_every + 2
        self.lag, self.energy = lag, energy
        self.t, self.w = np.empty(count), np.empty((count, 3))
        self.q, self.v, self.p = np.empty((count, n)), np.empty((count, n)), np.empty((count, n))
        self.e: list[float] = []
        self.k = 0

    def add(self, t: float, q: np.ndarray, p: np.ndarray, guess: np.ndarray, w: np.ndarray) -> None:
        """Record the state (q, p) and the balance's integrals w at time t (v from p, Newton from ``guess``)."""
        v = legendre_velocity(self.lag, q, p, t, guess)
        self.t[self.k], self.q[self.k], self.v[self.k], self.p[self.k], self.w[self.k] = t, q, v, p, w
        if self.energy is not None:
            self.e.append(float(self.energy(q, v, t)))
        self.k += 1

    def run(self, h: float, steps: int, newton: int, loop: str, balance: bool) -> VariationalRun:
        """The finished record (``w`` only when the balance was integrated)."""
        k = self.k
        return VariationalRun(self.t[:k], self.q[:k], self.v[:k], self.p[:k], np.asarray(self.e), h, steps, newton,
                              loop, self.w[:k] if balance else None)
