"""Harmonic balance for a periodic orbit of a smooth lumped model: the unknowns, the residual and its Jacobian.

Each coordinate is a truncated Fourier series of H harmonics (mechgen.runtime.periodic.fourier: U, (2H + 1) x n),
sampled at N = 8 (H + 1) phases theta_s = omega t_s (alternating frequency-time): the samples

    q_s = (G0 U)_s,   v_s = omega (G1 U)_s,   a_s = omega^2 (G2 U)_s,   t_s = theta_s / omega,

go through the generated ``residual`` kernel r(q, v, a, t) in ONE batched call (all N samples), and the Galerkin
projection of r onto the harmonics is the residual:

    R(U) = P r(q_s, v_s, a_s, t_s)        ((2H + 1) x n, the Fourier coefficients of r: force units).

Its exact Jacobian comes from the ``tangent`` kernel (dr/dq, dr/dv, dr/da at the N samples, one batched call):

    dR[k, i]/dU[l, j] = sum_s P[k, s] (r_q[s, i, j] G0[s, l] + omega r_v[s, i, j] G1[s, l]
                                       + omega^2 r_a[s, i, j] G2[s, l]).

Forced: omega is the forcing's angular frequency (rad/s) and u = vec U. Autonomous: omega is unknown,
u = (vec U, omega), and the phase condition b_1(q_p) = U[H + 1, p] = 0 (no sine part in the first harmonic of
coordinate p) closes the system; its extra column is dR/domega = P (r_v G1 U + 2 omega r_a G2 U) (the residual of
an autonomous model does not depend on t). Nothing here grows the symbolic work with H: the kernels are the model's
own, evaluated over the samples. ``frequency_derivative`` gives dR/domega of a forced orbit at fixed model
parameters by central differences (step 1e-6 omega: the samples' times move with omega, which the tangent kernel
has no derivative for).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.runtime.periodic.fourier import FourierBasis


@dataclass(frozen=True)
class HarmonicBalance:
    """The harmonic balance problem of ``system`` on ``basis`` (module doc): ``omega`` the forcing's angular
    frequency (None: autonomous), ``phase`` the coordinate p of the phase condition."""

    system: object
    basis: FourierBasis
    omega: float | None
    phase: int = 0

    @property
    def autonomous(self) -> bool:
        """Whether the frequency is an unknown."""
        return self.omega is None

    def unknowns(self, U: np.ndarray, omega: float) -> np.ndarray:
        """u from coefficients and frequency."""
        return np.append(U.ravel(), omega) if self.autonomous else np.asarray(U, float).ravel().copy()

    def split(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(U, omega) of the unknowns."""
        n = self.system.n
        if self.autonomous:
            return u[:-1].reshape(self.basis.size, n), float(u[-1])
        return u.reshape(self.basis.size, n), float(self.omega)

    def samples(self, U: np.ndarray, omega: float) -> dict:
        """The kernels' batched inputs at the N phases: q, v, a (N x n), t (N x 1), p."""
        b = self.basis
        return {"q": b.values @ U, "v": omega * (b.slopes @ U), "a": omega**2 * (b.curvatures @ U),
                "t": (b.theta / omega)[:, None], "p": self.system.params}

    def evaluate(self, kernel: str, inputs: dict) -> dict:
        """One batched call of ``kernel`` with the inputs its ports take."""
        k = self.system.kernels[kernel]
        wanted = {port["name"] for port in k.spec["inputs"]}
        return k.evaluate({key: value for key, value in inputs.items() if key in wanted})

    def residual(self, u: np.ndarray) -> np.ndarray:
        """R(u) (module doc), with the phase condition appended when autonomous."""
        U, omega = self.split(u)
        n, N = self.system.n, self.basis.theta.size
        r = np.asarray(self.evaluate("residual", self.samples(U, omega))["r"], float).reshape(N, n)
        R = (self.basis.projector @ r).ravel()
        return np.append(R, U[self.basis.harmonics + 1, self.phase]) if self.autonomous else R

    def residual_jacobian(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R(u), dR/du) (module doc)."""
        U, omega = self.split(u)
        b, n = self.basis, self.system.n
        N, size = b.theta.size, b.size
        tan = self.evaluate("tangent", self.samples(U, omega))
        rq, rv, ra = (np.asarray(tan[k], float).reshape(N, n, n) for k in ("r_q", "r_v", "r_a"))
        P = b.projector
        J = (np.einsum("ks,sij,sl->kilj", P, rq, b.values, optimize=True)
             + omega * np.einsum("ks,sij,sl->kilj", P, rv, b.slopes, optimize=True)
             + omega**2 * np.einsum("ks,sij,sl->kilj", P, ra, b.curvatures, optimize=True))
        J = J.reshape(size * n, size * n)
        R = self.residual(u)
        if not self.autonomous:
            return R, J
        dv, da = b.slopes @ U, b.curvatures @ U
        column = P @ (np.einsum("sij,sj->si", rv, dv) + 2 * omega * np.einsum("sij,sj->si", ra, da))
        row = np.zeros(u.size)
        row[(b.harmonics + 1) * n + self.phase] = 1.0
        return R, np.vstack([np.hstack([J, column.reshape(-1, 1)]), row])

    def frequency_derivative(self, u: np.ndarray) -> np.ndarray:
        """dR/domega of a forced orbit at fixed parameters (central differences, module doc)."""
        h = 1e-6 * self.omega
        up = HarmonicBalance(self.system, self.basis, self.omega + h, self.phase).residual(u)
        down = HarmonicBalance(self.system, self.basis, self.omega - h, self.phase).residual(u)
        return (up - down) / (2 * h)

    def start_state(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """(x(0) = (q(0), v(0)), T) of the orbit the coefficients describe."""
        U, omega = self.split(u)
        H = self.basis.harmonics
        k = np.arange(1, H + 1)
        q0 = U[0] + U[1:H + 1].sum(axis=0)
        v0 = omega * (k[:, None] * U[H + 1:]).sum(axis=0)
        return np.concatenate([q0, v0]), 2 * np.pi / omega


def hill_exponents(problem: HarmonicBalance, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lambda, weights): the Floquet exponents of the orbit u by Hill's method, and each one's share of its
    eigenvector on the first harmonics (the sorting's key).

    A perturbation dq = exp(lambda t) p(t), p with the orbit's H harmonics (coefficients P), of the linearised
    r_q dq + r_v dq' + r_a dq'' = 0 gives the quadratic eigenproblem (Galerkin on the harmonics)

        (A0 + lambda A1 + lambda^2 A2) P = 0,
        A0 = P(r_q G0 + omega r_v G1 + omega^2 r_a G2),  A1 = P(r_v G0 + 2 omega r_a G1),  A2 = P(r_a G0),

    (A0 is the harmonic balance Jacobian at fixed omega), solved as a generalised eigenproblem of twice its size.
    Each exponent appears once per harmonic shift (lambda + i k omega); the physical 2n are those whose eigenvectors
    weigh most on the harmonics |k| <= 1 and the mean (``weights``: that share of |P|^2), the sorting of Lazarus &
    Thomas (2010) that keeps the physical multipliers."""
    U, omega = problem.split(u)
    b, n = problem.basis, problem.system.n
    N, size = b.theta.size, b.size
    tan = problem.evaluate("tangent", problem.samples(U, omega))
    rq, rv, ra = (np.asarray(tan[k], float).reshape(N, n, n) for k in ("r_q", "r_v", "r_a"))

    def galerkin(M, G):
        return np.einsum("ks,sij,sl->kilj", b.projector, M, G, optimize=True).reshape(size * n, size * n)

    A0 = galerkin(rq, b.values) + omega * galerkin(rv, b.slopes) + omega**2 * galerkin(ra, b.curvatures)
    A1 = galerkin(rv, b.values) + 2 * omega * galerkin(ra, b.slopes)
    A2 = galerkin(ra, b.values)
    m = size * n
    eye, zero = np.eye(m), np.zeros((m, m))
    left = np.block([[zero, eye], [-A0, -A1]])
    right = np.block([[eye, zero], [zero, A2]])
    import scipy.linalg as sla

    lam, vectors = sla.eig(left, right)
    P = vectors[:m].reshape(size, n, -1)
    H = b.harmonics
    low = np.abs(P[0]) ** 2 + np.abs(P[1]) ** 2 + np.abs(P[H + 1]) ** 2
    weights = low.sum(axis=0) / np.maximum((np.abs(P) ** 2).sum(axis=(0, 1)), 1e-300)
    return lam, weights


def hill_multipliers(problem: HarmonicBalance, u: np.ndarray) -> np.ndarray:
    """The 2n Floquet multipliers exp(lambda T) of the exponents with the largest ``weights``
    (:func:`hill_exponents`), ordered as mechgen.runtime.periodic.floquet.ordered."""
    lam, weights = hill_exponents(problem, u)
    finite = np.isfinite(lam)
    lam, weights = lam[finite], weights[finite]
    keep = np.argsort(-weights, kind="stable")[:2 * problem.system.n]
    _, omega = problem.split(u)
    from mechgen.runtime.periodic.floquet import ordered

    return ordered(np.exp(lam[keep] * 2 * np.pi / omega))
