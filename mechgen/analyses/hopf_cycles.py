"""``continuation`` from a Hopf point in its own parameter: the branch of limit cycles born there.

With ``about`` an earlier continuation of equilibria, ``special_point = k`` naming one of its Hopf points (H)
and ``parameter`` that continuation's own parameter p, the cycles are started from the Hopf normal form
(Kuznetsov, *Elements of Applied Bifurcation Theory*, sec. 3.5): with the critical pair +-i omega, its
eigenvector q (<q, q> = 1), alpha' = d Re(lambda)/dp at the Hopf point p_H (central differences of the spectrum
at the equilibria corrected at p_H +- h) and the first Lyapunov coefficient l1, the cycle at p near p_H is

    x(t) ~ x_H + 2 |z| Re(q exp(i omega t)),   |z|^2 = -alpha' (p - p_H) / (l1 omega),

on the side where |z|^2 > 0 (past a supercritical point, where the equilibrium is unstable; before a
subcritical one). The first cycle is solved by shooting with its period unknown (mechgen.runtime.periodic;
Newton from that guess at the p where |z| is ``HOPF_AMPLITUDE`` of the state's size) and continued as a
branch of orbits (mechgen.analyses.orbit_branch: the outputs of a continuation about a periodic_orbit), with
``hopf`` ({<p>: p_H, frequency, lyapunov, start_parameter}) added. A degenerate Hopf point (l1 zero to working
precision: a linear model) has no cycle amplitude to start from and is refused.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.parametrised import Parametrised
from mechgen.analyses.periodic_orbit import compiled_run, integrator_tolerances, settings
from mechgen.errors import ConvergenceError, SceneError
from mechgen.runtime.periodic.newton import newton
from mechgen.runtime.periodic.shooting import Shooting

#: the first cycle's |z| relative to 1 + |x_H| (small enough for the normal form, large enough to leave x_H)
HOPF_AMPLITUDE = 0.05
#: orbit settings of the cycles (periodic_orbit's defaults)
CYCLE_OPTIONS = {"rtol": 1e-9, "atol": 1e-12, "max_iterations": 50, "loop": "auto", "samples": 201}


def corrected(model, y: np.ndarray, p: float, iterations: int = 8) -> np.ndarray:
    """The equilibrium near y at p (Newton on the static residual, ``model``: parametrised.Parametrised with the
    same parameter as first and second)."""
    for _ in range(iterations):
        r = model.residual(y, p, p)
        y = y - np.linalg.solve(model.jacobian(y, p, p), r)
    return y


def critical(model, y: np.ndarray, p: float) -> complex:
    """The eigenvalue with Im > 0 nearest the imaginary axis of the first-order Jacobian at (y, p)."""
    lam = np.linalg.eigvals(model.state_jacobian(y, p, p))
    upper = lam[lam.imag > 0]
    return complex(upper[np.argmin(np.abs(upper.real))])


def first_cycle(system, name: str, x_h: np.ndarray, l1: float) -> tuple:
    """(the system at the first cycle's p, the shooting problem, its unknowns u, p, (p_H, omega, alpha'))."""
    model = Parametrised(system, name, name)
    y_h, p_h = x_h[:-1], float(x_h[-1])
    h = 1e-5 * (1.0 + abs(p_h))
    slope = (critical(model, corrected(model, y_h, p_h + h), p_h + h).real
             - critical(model, corrected(model, y_h, p_h - h), p_h - h).real) / (2 * h)
    n = system.n
    state = np.concatenate([y_h[:n], np.zeros(n), y_h[n:]])
    lam, vecs = np.linalg.eig(model.state_jacobian(y_h, p_h, p_h))
    k = int(np.argmin(np.where(lam.imag > 0, np.abs(lam.real), np.inf)))
    omega, q = float(lam[k].imag), vecs[:, k] / np.linalg.norm(vecs[:, k])
    size = HOPF_AMPLITUDE * (1.0 + float(np.max(np.abs(state))))
    p = p_h - l1 * omega * size**2 / slope
    q = q * np.exp(-1j * np.angle(q[int(np.argmax(np.abs(q[:n])))]))  # the largest coordinate at its maximum at t = 0
    x0 = state + 2 * size * q.real
    phase = int(np.argmax(np.abs(q[:n])))
    moved = system.with_params(**{name: p})
    options = {**CYCLE_OPTIONS}
    problem = Shooting(moved, None, phase, *integrator_tolerances(options), compiled_run(moved, options))
    x0[n + phase] = 0.0
    try:
        sol = newton(problem.residual_jacobian, problem.unknowns(x0, 2 * np.pi / omega), settings(options, "shooting"))
    except ConvergenceError as exc:
        raise ConvergenceError(f"the first limit cycle near the Hopf point ({name} = {p:.8g}) did not converge: "
                               f"{exc}") from None
    return moved, problem, sol.u, p, (p_h, omega, slope)


def run_hopf_cycles(system, options: dict, earlier: dict, x_h: np.ndarray, record: dict) -> dict:
    """The branch of cycles from the Hopf point x_h = (y, p_H) (module doc)."""
    from mechgen.analyses.orbit_branch import run_orbit_branch

    if record.get("criticality") == "degenerate":
        raise SceneError("the Hopf point is degenerate (l1 = 0 to working precision): no cycle amplitude to start "
                         "a branch of limit cycles from", key="special_point",
                         expected="a Hopf point with a nonzero first Lyapunov coefficient")
    name = options["parameter"]
    moved, problem, u, p, (p_h, omega, slope) = first_cycle(system, name, x_h, float(record["lyapunov"]))
    x0, T = problem.split(u)
    orbit = {"method": "shooting", "phase": problem.phase, "options": dict(CYCLE_OPTIONS),
             "found": {"x0": np.asarray(x0, float), "omega": 2 * np.pi / T}}
    out = run_orbit_branch(moved, {k: v for k, v in options.items() if k != "special_point"}, {"_orbit": orbit})
    out["hopf"] = {name: p_h, "frequency": omega, "lyapunov": float(record["lyapunov"]),
                   "growth_rate_slope": slope, "start_parameter": p}
    return out
