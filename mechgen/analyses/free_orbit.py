"""The free periodic orbit of a conservative model: ``periodic_orbit`` without ``frequency`` on a model that keeps its
energy, solved as one member of its family (mechgen.runtime.periodic.conservative).

A model is taken as conservative when its residual passes the power balance v . r(q, v, a, t) = dE/dt (E its
``energy`` output, T + V) at a few states about the guess, to POWER_TOLERANCE relative
(mechgen.runtime.periodic.conservative.power_gap): no dissipation, no forcing, no non-conservative force. Such an
orbit is not isolated: periodic_orbit finds the member whose coordinate p (the one with the largest |q0|) has the
guess's displacement at t = 0, q_p(0) = q0_p (an extremum of q_p there), with the frequency an unknown and the
unfolding eps (Munoz-Almaraz et al. 2003) solved beside it, zero on the orbit; ``unfolding`` reports it and
``energy`` the orbit's E. ``continuation`` about it follows the family (mechgen.analyses.backbone).
"""
from __future__ import annotations

import numpy as np

from mechgen.runtime.periodic import fourier
from mechgen.runtime.periodic.collocation import Collocation
from mechgen.runtime.periodic.conservative import POWER_TOLERANCE, Unfolded, power_gap
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance
from mechgen.runtime.periodic.newton import newton
from mechgen.runtime.periodic.shooting import Shooting

#: the states of the power-balance test: this many, about the guess
PROBES = 4


def is_conservative(system, x0: np.ndarray) -> bool:
    """Whether the model passes the power balance (module doc) at PROBES states about x0 (seeded, so the verdict is
    reproducible): q, v about the guess's scale, any a, t in [0, 2)."""
    if system.m or not system.n:
        return False
    n = system.n
    scale = max(float(np.max(np.abs(x0), initial=0.0)), 1e-3)
    rng = np.random.default_rng(20031)
    states = np.asarray(x0, float)[None, :2 * n] + scale * rng.uniform(-1.0, 1.0, (PROBES, 2 * n))
    accelerations = scale * rng.uniform(-1.0, 1.0, (PROBES, n))
    try:
        return power_gap(system, states, accelerations, 2.0 * rng.uniform(size=PROBES)) <= POWER_TOLERANCE
    except (KeyError, ValueError):  # no energy output among the outputs
        return False


def base_problem(system, options: dict, start, method: str, defaults: dict):
    """The method's autonomous problem and its unknowns from the guess (as periodic_orbit's solvers build them)."""
    n, p = system.n, start.phase
    if method == "harmonic_balance":
        H = int(options.get("harmonics", defaults["harmonics"]))
        problem = HarmonicBalance(system, fourier.basis(H), None, p)
        N = problem.basis.theta.size
        U = fourier.coefficients_of_samples(start.curve(start.period * np.arange(N) / N)[:, :n], H)
        U[H + 1, p] = 0.0
        return problem, problem.unknowns(U, 2 * np.pi / start.period)
    if method == "collocation":
        problem = Collocation(system, int(options.get("mesh", defaults["mesh"])), None, p)
        X = start.curve(start.period * np.arange(problem.nodes) / problem.nodes)
        X[0, n + p] = 0.0
        return problem, problem.unknowns(X, start.period)
    S = int(options.get("segments", 1))
    problem = Shooting(system, None, p, *defaults["tolerances"], defaults["run"], S)
    X = start.curve(start.period * np.arange(S) / S)
    X[0] = start.x0
    X[0, n + p] = 0.0
    return problem, problem.unknowns(X, start.period)


def solve_free(system, options: dict, start, method: str, defaults: dict, settings) -> dict:
    """The free orbit of level q_p(0) = the guess's (module doc): the solver's dict as periodic_orbit's methods
    return it (the method's problem and unknowns, without eps), with ``unfolding`` (eps) and ``level``."""
    problem, u0 = base_problem(system, options, start, method, defaults)
    family = Unfolded(problem, float(start.x0[start.phase]))
    sol = newton(family.residual_jacobian, np.append(u0, 0.0), settings)
    for _ in range(int(options.get("adapt", 0)) if method == "collocation" else 0):
        problem, u = problem.adapted(sol.u[:-1])
        family = Unfolded(problem, family.level)
        sol = newton(family.residual_jacobian, np.append(u, sol.u[-1]), settings)
    u = sol.u[:-1]
    found = {"problem": problem, "u": u, "residual": sol.residual, "iterations": sol.iterations,
             "unfolding": float(sol.u[-1]), "level": family.level}
    if method == "harmonic_balance":
        U, w = problem.split(u)
        found.update(U=U, omega=w, x0=problem.start_state(u)[0])
    elif method == "collocation":
        X, T = problem.split(u)
        found.update(x0=X[0].copy(), omega=2 * np.pi / T)
    else:
        x0, T = problem.split(u)
        found.update(x0=np.asarray(x0, float), omega=2 * np.pi / T, run=defaults["run"])
    return found


def orbit_energy(system, x0: np.ndarray) -> float:
    """E = T + V (the model's ``energy`` output) at the orbit's state x0 (constant along it)."""
    return float(system.outputs_series(np.zeros(1), np.asarray(x0, float)[None, :])["energy"][0])
