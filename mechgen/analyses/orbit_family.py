"""The orbits of an earlier ``periodic_orbit`` moved along a parameter (:class:`Orbits`: their problems, states,
periods and Floquet multipliers) and one branch point's record: what the continuation of forced orbits
(mechgen.analyses.orbit_branch), of a conservative family (mechgen.analyses.backbone) and the curves of orbit
folds (mechgen.analyses.orbit_curves) share."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from mechgen.analyses.branch_points import branch_point
from mechgen.analyses.periodic_orbit import DEFAULT_HARMONICS, compiled_run, integrator_tolerances
from mechgen.analyses.schema import ParamExpression
from mechgen.analyses.time_series import state_names
from mechgen.runtime.periodic import floquet, fourier
from mechgen.runtime.periodic.branch import OrbitBranch
from mechgen.runtime.periodic.flow import differenced_flow, states_at, variational_flow
from mechgen.runtime.periodic.fourier import peak
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance
from mechgen.runtime.periodic.shooting import Shooting

#: ``parameter`` of a continuation along a conservative family (mechgen.analyses.backbone): the level q_p(0)
FAMILY_PARAMETER = "amplitude"
#: phases at which a branch point's amplitudes are taken
PHASES = 4096


class Orbits:
    """The orbits of one earlier ``periodic_orbit`` moved along ``name``: problems, states and multipliers."""

    def __init__(self, system, name: str, orbit: dict) -> None:
        self.system, self.name = system, name
        self.method, self.phase, self.options = orbit["method"], orbit["phase"], orbit["options"]
        self.frequency = self.options.get("frequency")
        self.autonomous = self.frequency is None
        self.memo: dict = {}
        #: the earlier collocation's mesh (its edges, adapted or uniform), kept along the branch
        self.mesh = orbit["found"].get("problem") if self.method == "collocation" else None

    def omega(self, p: float) -> float | None:
        """The forcing's angular frequency at p (module doc)."""
        if self.frequency is None:
            return None
        if isinstance(self.frequency, ParamExpression):
            return self.frequency.moved(self.name, p, self.system.param_values())
        return float(self.frequency)

    def make(self, p: float):
        """The method's problem at p (the earlier orbit's mesh, harmonics or segments)."""
        moved = self.system.with_params(**{self.name: float(p)})
        if self.method == "harmonic_balance":
            H = int(self.options.get("harmonics", DEFAULT_HARMONICS))
            return HarmonicBalance(moved, fourier.basis(H), self.omega(p), self.phase)
        if self.method == "collocation":  # the earlier mesh and phase condition (its reference orbit)
            return replace(self.mesh, system=moved, omega=self.omega(p))
        return Shooting(moved, self.omega(p), self.phase, *integrator_tolerances(self.options),
                        compiled_run(moved, self.options), int(self.options.get("segments", 1)))

    def start(self, problem, found: dict) -> np.ndarray:
        """The unknowns u of the earlier orbit."""
        if self.method == "harmonic_balance":
            return problem.unknowns(found["U"], found["omega"])
        if self.method == "collocation":
            return np.asarray(found["u"], float)
        T = 2 * np.pi / found["omega"]
        S = getattr(problem, "segments", 1)
        X = self.flow_states(problem, found["x0"], T * np.arange(S) / S) if S > 1 else found["x0"]
        return problem.unknowns(X, T)

    def flow_states(self, problem, x0: np.ndarray, times: np.ndarray) -> np.ndarray:
        """The states from x0 at ``times`` (ascending, from 0) by the problem's flow."""
        if problem.compiled is not None:
            return problem.compiled(np.asarray(x0, float), np.asarray(times, float))
        return states_at(problem.system, x0, 0.0, times, problem.rtol, problem.atol)

    def states(self, problem, u: np.ndarray, times: np.ndarray) -> np.ndarray:
        """The orbit's states at ``times`` in [0, T] (rows (q, v))."""
        if self.method == "harmonic_balance":
            U, w = problem.split(u)
            return np.hstack([fourier.evaluate(U, w * times), w * fourier.evaluate(U, w * times, 1)])
        if self.method == "collocation":
            return problem.states_at(u, times)
        x0, _ = problem.split(u)
        if problem.compiled is not None:
            return problem.compiled(x0, times)
        return states_at(problem.system, x0, 0.0, times, problem.rtol, problem.atol)

    def period(self, problem, u: np.ndarray) -> float:
        """T of the orbit u (harmonic balance's unknowns hold the frequency, the others' the period)."""
        if self.method == "harmonic_balance":
            return float(2 * np.pi / problem.split(u)[1])
        return float(problem.split(u)[1])

    def multipliers(self, problem, u: np.ndarray, p: float) -> np.ndarray:
        """The Floquet multipliers of the orbit u at p: the eigenvalues of its monodromy, by central differences of
        the compiled flow where it runs (4n + 1 runs, about 1e-10 from the exact one:
        mechgen.runtime.periodic.flow.differenced_flow), else from the variational equations; kept per orbit (a
        branch point's are asked twice)."""
        key = (float(p), np.asarray(u, float).tobytes())
        if key not in self.memo:
            if len(self.memo) > 1024:
                self.memo.clear()
            self.memo[key] = self.monodromy_eigenvalues(problem, u)
        return self.memo[key]

    def monodromy_eigenvalues(self, problem, u: np.ndarray) -> np.ndarray:
        """The multipliers: collocation's from its own monodromy (no integration), the others' from the flow."""
        if self.method == "collocation":
            return floquet.multipliers(problem.monodromy(u))
        T = self.period(problem, u)
        x0 = problem.split(u)[0] if self.method == "shooting" else self.states(problem, u, np.array([0.0]))[0]
        run = compiled_run(problem.system, self.options)
        if run is not None:
            _, Phi = differenced_flow(run, x0, T)
        else:
            _, Phi = variational_flow(problem.system, x0, 0.0, T, *integrator_tolerances(self.options))
        return floquet.multipliers(Phi)


def record(orbits: Orbits, branch: OrbitBranch, u: np.ndarray, p: float) -> dict:
    """One branch point's outputs (module doc)."""
    problem = branch.problem(p)
    T = orbits.period(problem, u)
    X = orbits.states(problem, u, T * np.arange(PHASES) / PHASES)
    mu = orbits.multipliers(problem, u, p)
    system = orbits.system
    names = list(system.coordinates)
    internals = state_names(system)[2 * system.n:]
    start = dict(zip(names + [f"{c}_dot" for c in names] + internals, (float(v) for v in X[0])))
    columns = list(range(system.n)) + list(range(2 * system.n, 2 * system.n + system.m))
    return branch_point(orbits.name, p, {
        "period": T, "frequency": float(2 * np.pi / T),
        "amplitude": {c: peak(X[:, i]) for c, i in zip(names + internals, columns)}, "start": start,
        "multipliers": floquet.as_pairs(mu), "stability": floquet.stability(mu, orbits.autonomous)})
