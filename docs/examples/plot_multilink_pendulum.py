"""
A 16-link pendulum: a large multibody model derived by algorithmic differentiation
==================================================================================

:math:`n = 16` rigid massless links of length :math:`l` (m) hang from a pivot, a point mass :math:`m`
(kg) at the end of each; :math:`\\theta_i` (rad) is link :math:`i`'s angle from the downward vertical. The
model is written as a user writes it, each mass's velocity the previous one's plus a link's:

.. math::

    \\dot x_k = \\dot x_{k-1} + l \\cos\\theta_k\\,\\dot\\theta_k, \\quad
    \\dot y_k = \\dot y_{k-1} + l \\sin\\theta_k\\,\\dot\\theta_k, \\qquad
    T = \\frac m2 \\sum_k (\\dot x_k^2 + \\dot y_k^2), \\quad
    V = m g \\sum_k y_k, \\quad y_k = -l \\sum_{i \\le k} \\cos\\theta_i .

With 16 coordinates mechgen derives it by CasADi's algorithmic differentiation (the user guide's *Large
models*): p = dT/dv by a reverse sweep, M = dp/dv, the velocity terms as a directional derivative, so the
build grows with the model, not with the expansion of T.

Reference: the closed-form equations of motion of the chain (e.g. Lagrange's equations of a planar chain of
point masses, any analytical-mechanics text),

.. math::

    \\sum_j m l^2 c_{ij} \\left[\\cos(\\theta_i - \\theta_j)\\, \\ddot\\theta_j
    + \\sin(\\theta_i - \\theta_j)\\, \\dot\\theta_j^2\\right] + m g l\\, c_{ii} \\sin\\theta_i = 0,
    \\qquad c_{ij} = n - \\max(i, j),

written out by hand below with numpy; the accelerations are compared at random states, then a 2 s swing
from a tilted straight chain is integrated (scipy's DOP853 on ``system.rhs``) and its energy checked.
``system.rhs`` and ``system.jacobian`` are each one compiled call (M, the bias term and the Cholesky solve in
C; the Jacobian :math:`\partial \ddot\theta / \partial(\theta, \dot\theta) = -M^{-1}(r_q, r_v)` from
the tangent kernel at the found acceleration, with the same factor of M): the Jacobian is checked against
central differences of the closed form, and handed to scipy's Radau.
"""
import time

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mechgen
from mechgen.bench.multibody import pendulum_model

n, m, l, g = 16, 1.0, 1.0, 9.81


def closed_form(theta, w):
    """The accelerations from the closed-form equations above."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    c = n - np.maximum(i, j)
    d = theta[:, None] - theta[None, :]
    M = m * l**2 * c * np.cos(d)
    f = m * l**2 * (c * np.sin(d)) @ w**2 + m * g * l * (n - np.arange(n)) * np.sin(theta)
    return np.linalg.solve(M, -f)


start = time.perf_counter()
system = mechgen.compile(pendulum_model(n), kernels=["flow", "outputs"])
print(f"first build of the flow and output kernels ({n} links): {time.perf_counter() - start:.1f} s "
      "(a second process finds them in the cache)")

rng = np.random.default_rng(0)
errors = []
for _ in range(5):
    theta, w = rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
    a, _ = system.acceleration(theta, w)
    ref = closed_form(theta, w)
    errors.append(np.abs(a - ref).max() / np.abs(ref).max())
print(f"accelerations against the closed form, max relative error over 5 random states: {max(errors):.1e}")

x0 = np.concatenate([np.full(n, 0.6), np.zeros(n)])
sol = solve_ivp(system.rhs, (0.0, 2.0), x0, method="DOP853", rtol=1e-10, atol=1e-10, dense_output=True)
energy = np.array([system.outputs(x[:n], x[n:])["energy"] for x in sol.y.T])
drift = np.abs(energy - energy[0]).max() / np.abs(energy[0])
print(f"2 s swing: {sol.t.size} steps, relative energy drift {drift:.1e}")

kernels = mechgen.compile(pendulum_model(n), kernels=["flow", "tangent", "outputs"])
theta, w = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
J = kernels.jacobian(0.0, np.concatenate([theta, w]))
h = 1e-6
fd = np.column_stack([(closed_form(*np.split(np.concatenate([theta, w]) + h * e, 2))
                       - closed_form(*np.split(np.concatenate([theta, w]) - h * e, 2))) / (2 * h)
                      for e in np.eye(2 * n)])
print(f"Jacobian against central differences of the closed form (h = 1e-6): "
      f"{np.abs(J[n:] - fd).max() / np.abs(fd).max():.1e} (the differences' own error, truncation and round-off)")
radau = solve_ivp(kernels.rhs, (0.0, 0.5), x0, method="Radau", jac=kernels.jacobian, rtol=1e-8, atol=1e-10)
print(f"Radau with the compiled Jacobian over 0.5 s: {radau.t.size} steps, {radau.njev} Jacobians, "
      f"end angles within {np.abs(radau.y[:n, -1] - sol.sol(0.5)[:n]).max():.1e} rad of DOP853's")

fig, (ax, ax2) = plt.subplots(1, 2, figsize=(9, 4))
for t, shade in zip((0.0, 0.5, 1.0, 1.5, 2.0), np.linspace(0.25, 1.0, 5)):
    theta = sol.sol(t)[:n]
    xs = np.concatenate([[0.0], np.cumsum(l * np.sin(theta))])
    ys = np.concatenate([[0.0], -np.cumsum(l * np.cos(theta))])
    ax.plot(xs, ys, "o-", ms=2, color=plt.cm.viridis(shade), label=f"t = {t:.1f} s")
ax.set_aspect("equal")
ax.set_xlabel("x (m)")
ax.set_ylabel("y (m)")
ax.legend(fontsize=7)
ax.set_title(f"{n}-link pendulum")
ax2.semilogy(sol.t, np.abs(energy - energy[0]) / abs(energy[0]) + 1e-17)
ax2.set_xlabel("t (s)")
ax2.set_ylabel("|E(t) - E(0)| / |E(0)|")
ax2.set_title("energy error (DOP853, tol 1e-10)")
fig.tight_layout()
plt.show()
