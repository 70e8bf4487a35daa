"""``continuation`` about a ``periodic_orbit``: the branch of periodic orbits in a parameter, with its cyclic folds,
period doublings and torus points.

The earlier orbit's method (harmonic balance, shooting or collocation, with its mesh and, for a model with internal
variables, its integral phase condition's reference orbit) is continued in ``parameter`` up to ``stop`` by
pseudo-arclength (mechgen.runtime.periodic.branch; mechgen.runtime.steady.continuation), so a frequency-response
curve is followed round its folds: both stable branches and the unstable one between. Collocation and multiple
shooting weigh a node's state by 1 / nodes in the arclength and, for a parameter of size |p0| > 1, the unknowns by
p0^2: the arclength measures the parameter's relative change against the orbit's (a fold at k ~ 5e9 Pa/m is then
within the step control's reach; ``step`` and ``max_step`` are in those units, p0 times the orbit's change where the
branch turns). An autonomous orbit's branch ends where its orbits shrink to an equilibrium (status ``equilibrium``:
a Hopf point, the orbits' size, the largest range of a state component over the period relative to the first
orbit's, at a local minimum below 0.1), at its smallest orbit, rather than return through it; a step that passed
through the equilibrium (the new orbit is the last one half a period on: their deviations from their means are
anti-correlated) ends it at the last orbit before, with no fold recorded for the parameter's turn there. A
forced orbit whose ``frequency`` is an expression of the continued parameter (``frequency = "w"``, continued in
``w``) has its period follow it; otherwise the forcing's frequency stays as it was.

Outputs: ``branch`` (per point: the parameter, ``period``, ``frequency``, ``amplitude`` ({coordinate: max |q| over
the period}, then each internal variable's), ``start`` (the state at t = 0: each coordinate and
``<coordinate>_dot``, then each internal variable), ``multipliers`` ([re, im] by decreasing modulus) and
``stability``), ``points``, ``status``, ``method``, ``folds`` and ``special_points``: ``LPC`` (a cyclic fold: the
branch turns in the parameter), ``PD`` (period doubling: a multiplier through -1) and ``NS`` (Neimark-Sacker: a
complex pair through the unit circle, with ``angle``), each with the parameter, period, amplitude and multipliers
there (mechgen.runtime.steady.cycle_points); with ``switch_branches`` (a forced orbit) ``doubled``, the period-2T
orbit just past every PD point, by the orbit's own method: shooting over 2T from the period-T orbit displaced along
the eigenvector of the multiplier -1; harmonic balance with 2H harmonics of omega / 2 (the period-T orbit's
harmonics are the even ones) and collocation on the mesh repeated over [0, 2T], each from the period-T orbit plus
the perturbation Phi(t) v over [0, 2T] (v that eigenvector: Phi(t + T) v = -Phi(t) v, odd harmonics of omega / 2).
A continued parameter whose name is also an output's (the stick-slip contact's forcing ``amplitude``) keeps its
name; the output is then ``orbit_<name>`` (mechgen.analyses.branch_points).

About an autonomous hybrid orbit (a ``periodic_orbit`` without frequency on a hybrid model, its phase fixed by its
``section``) the branch is that of the return map's fixed points (mechgen.analyses.hybrid_orbit.run_section_branch:
``start`` the state just after the section's event, PD and NS from the return map's multipliers); without
``switch_branches``.

About the free orbit of a conservative model (a ``periodic_orbit`` without frequency on a model that keeps its
energy) the continuation follows its family: mechgen.analyses.backbone (``parameter = "amplitude"``: the backbone).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.branch_points import branch_point
from mechgen.analyses.hybrid_orbit import run_hybrid_branch
from mechgen.analyses.newton_branch import arclength_steps
from mechgen.analyses.orbit_family import FAMILY_PARAMETER, PHASES, Orbits, record
from mechgen.analyses.periodic_orbit import compiled_run, integrator_tolerances
from mechgen.runtime.periodic.fourier import peak
from mechgen.analyses.stability_boundary import own_value
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.periodic import floquet, fourier
from mechgen.runtime.periodic.branch import OrbitBranch, node_weights
from mechgen.runtime.periodic.collocation import Collocation
from mechgen.runtime.periodic.flow import differenced_flow, states_at, variational_flow
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance
from mechgen.runtime.periodic.shooting import Shooting
from mechgen.runtime.steady.continuation import continuation
from mechgen.runtime.steady.cycle_points import cycle_points

#: keys of a continuation that an orbit branch does not take
ORBIT_REFUSES = ("method", "stages", "bounds", "at", "minimize", "switch_branches", "special_point", "eigenvalues",
                 "aliases")  # switch_branches: taken by a forced orbit (and a hybrid model's)
#: an autonomous orbit's branch ends at a local minimum of its orbits' size below COLLAPSE times the first orbit's
COLLAPSE = 0.1
#: phases at which an orbit's size is measured
SIZE_PHASES = 256


class Collapse:
    """``until`` of an autonomous orbit's branch (mechgen.runtime.steady.continuation): the branch ends where its
    orbits shrink onto an equilibrium (a Hopf point), from where it would only return along the same orbits.

    At each accepted point: the orbit's deviation from its mean over SIZE_PHASES phases of the period, d(phase)
    (each state component relative to the first orbit's range), and its size, the largest range. The branch ends

    * when a step passed through the equilibrium: near a Hopf point the orbits are u_eq + A v(phase) + O(A^2), and
      a step across A = 0 lands on the same orbit with A < 0, phase-shifted by half a period, where the parameter
      (even in A) turns back. So the deviations of the two orbits are anti-correlated, sum d_last . d_new < 0,
      where along a branch they agree (+1 in the limit of small steps). The branch ends at the last orbit before
      the passage, and the turn of the parameter (no cyclic fold: both orbits shrink onto one point) is not
      recorded;
    * or at the smallest orbit, when the size, below COLLAPSE, starts to grow again."""

    def __init__(self, orbits: Orbits, branch: OrbitBranch, u0: np.ndarray, p0: float) -> None:
        self.orbits, self.branch = orbits, branch
        deviation = self.deviation(u0, p0)
        self.first = np.ptp(deviation, axis=0) + 1e-300
        self.deviations = [deviation / self.first]
        self.sizes, self.last = [1.0], float(p0)

    def deviation(self, u: np.ndarray, p: float) -> np.ndarray:
        """The states at SIZE_PHASES phases of the period less their mean (their units)."""
        problem = self.branch.problem(p)
        T = self.orbits.period(problem, u)
        states = self.orbits.states(problem, u, T * np.arange(SIZE_PHASES) / SIZE_PHASES)
        return states - states.mean(axis=0)

    def __call__(self, u: np.ndarray, p: float):
        deviation = self.deviation(u, p) / self.first
        size = float(np.max(np.ptp(deviation, axis=0)))
        if float(np.sum(deviation * self.deviations[-1])) < 0.0:
            return ("equilibrium", f"the orbits shrank onto an equilibrium between {self.orbits.name} = "
                    f"{self.last:.10g} and {float(p):.10g} (a Hopf point; the step passed through it): the branch "
                    f"ends at its last orbit before it, {self.sizes[-1]:.3g} of the first orbit's size")
        if len(self.sizes) > 1 and self.sizes[-1] < min(COLLAPSE, self.sizes[-2], size):
            return ("equilibrium", f"the orbits shrank to an equilibrium near {self.orbits.name} = {self.last:.10g} "
                    f"(a Hopf point): the branch ends at its smallest orbit, {self.sizes[-1]:.3g} of the first "
                    "orbit's size")
        self.sizes.append(size)
        self.deviations.append(deviation)
        self.last = float(p)
        return None


def run_orbit_branch(system, options: dict, earlier: dict) -> dict:
    """The branch of orbits through an earlier periodic_orbit (module doc; a hybrid model's:
    mechgen.analyses.hybrid_orbit.run_hybrid_branch, which also takes ``switch_branches``)."""
    if earlier["_orbit"].get("conservative"):  # a free orbit's family (mechgen.analyses.backbone)
        for key in ORBIT_REFUSES:
            if options.get(key):
                raise SceneError(f"{key} does not apply to the family of a conservative model's free orbits",
                                 key=key, expected=f"no {key}")
        from mechgen.analyses.backbone import run_backbone

        return run_backbone(system, options, earlier["_orbit"])
    if options["parameter"] == FAMILY_PARAMETER and FAMILY_PARAMETER not in system.param_values():
        raise SceneError(f"parameter '{FAMILY_PARAMETER}' continues the family of a conservative model's free "
                         "orbits, and the earlier periodic_orbit is not one (it is forced, or its model dissipates "
                         "or is forced)", key="parameter",
                         expected="a model parameter, or about = a periodic_orbit without frequency on a "
                         "conservative model")
    hybrid = bool(earlier["_orbit"].get("hybrid"))
    switchable = earlier["_orbit"]["options"].get("frequency") is not None  # a forced orbit (smooth or hybrid)
    for key in ORBIT_REFUSES:
        if options.get(key) and not (switchable and key == "switch_branches"):
            raise SceneError(f"{key} does not apply to a branch of periodic orbits", key=key,
                             expected=f"no {key} (a continuation about a steady state takes it)")
    if hybrid:
        return run_hybrid_branch(system, options, earlier["_orbit"])
    name = options["parameter"]
    orbits = Orbits(system, name, earlier["_orbit"])
    here = float(own_value(system, name))
    branch = OrbitBranch(orbits.make, name)
    problem = branch.problem(here)
    u0 = orbits.start(problem, earlier["_orbit"]["found"])
    repeats = problem.nodes if orbits.method == "collocation" else getattr(problem, "segments", 1)
    scale = max(1.0, abs(here))
    eqs = branch.equations(node_weights(u0.size, repeats, int(orbits.autonomous), scale) if repeats > 1 else None)
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    until = Collapse(orbits, branch, u0, here) if orbits.autonomous else None
    found = continuation(eqs, u0, here, arclength_steps(options, here, budget, smallest_span=0.1), until=until)
    points = [record(orbits, branch, u, p) for u, p in zip(found.u, found.lam)]
    X = np.hstack([found.u, found.lam[:, None]])

    def multipliers(x):
        return orbits.multipliers(branch.problem(x[-1]), x[:-1], x[-1])

    specials = [("LPC", np.append(f.u, f.lam), f.index, {}) for f in found.folds]
    if options.get("special_points", True):
        specials += [(s.type, s.x, s.index, s.data) for s in cycle_points(eqs, X, multipliers,
                                                                           trivial=orbits.autonomous)]
    records, located = [], []
    for kind, x, index, data in sorted(specials, key=lambda s: s[2]):
        rec = {"type": kind, **record(orbits, branch, x[:-1], x[-1])}
        if kind == "NS":
            rec["angle"] = data["angle"]
        records.append(rec)
        located.append(np.asarray(x, float))
    doubled = {}
    if options.get("switch_branches"):
        doubled["doubled"] = [doubled_record(orbits, branch, X, x, index, k + 1)
                              for k, (kind, x, index, _) in enumerate(sorted(specials, key=lambda s: s[2]))
                              if kind == "PD"]
    return {"parameter": name, "method": orbits.method, "branch": points, "points": len(points),
            "status": found.status, "folds": [r for r in records if r["type"] == "LPC"],
            "special_points": records, "shape_outputs": [], **doubled,
            # a curve of one of these points in two parameters starts here (mechgen.analyses.orbit_curves)
            "_orbit": earlier["_orbit"], "_special_x": located}


def doubled_record(orbits: Orbits, branch: OrbitBranch, X: np.ndarray, x_pd: np.ndarray, index: int,
                   at: int) -> dict:
    """The doubled orbit (period 2T) past the PD point x_pd of a forced orbit: at the parameter half-way to the
    neighbouring branch point whose orbit has a multiplier below -1, from the period-T orbit there displaced along
    the eigenvector of the multiplier nearest -1 (both ways, 1e-3 to 1e-1 of the state's size), the first start
    that converges to an orbit other than the period-T one: by shooting over 2T (:func:`shooting_doubled`), or by
    the earlier orbit's harmonic balance or collocation over 2T (:func:`spectral_doubled`)."""
    from mechgen.analyses.periodic_orbit import settings
    from mechgen.runtime.periodic.newton import newton

    def most_negative(x):
        return float(np.min(orbits.multipliers(branch.problem(x[-1]), x[:-1], x[-1]).real))

    side = min((X[index], X[index + 1]), key=most_negative)
    p = float(x_pd[-1]) + 0.5 * (float(side[-1]) - float(x_pd[-1]))
    single = newton(branch.problem(p).residual_jacobian, np.asarray(x_pd[:-1], float),
                    settings(orbits.options, orbits.method)).u
    if orbits.method == "shooting":
        return shooting_doubled(orbits, branch, p, single, at)
    return spectral_doubled(orbits, branch.problem(p), p, single, at)


def shooting_doubled(orbits: Orbits, branch: OrbitBranch, p: float, single: np.ndarray, at: int) -> dict:
    """Shooting over 2T from the period-T orbit ``single`` at p displaced along the PD eigenvector (the eigenvector
    of Phi = dR/du + I for the multiplier nearest -1)."""
    from mechgen.analyses.periodic_orbit import settings
    from mechgen.errors import ConvergenceError
    from mechgen.runtime.periodic.newton import newton

    values, vectors = np.linalg.eig(branch.residual_jacobian(single, p)[1] + np.eye(single.size))
    v = np.real(vectors[:, int(np.argmin(np.abs(values + 1.0)))])
    v = v / np.linalg.norm(v)
    moved = orbits.system.with_params(**{orbits.name: p})
    double = Shooting(moved, orbits.omega(p) / 2, orbits.phase, *integrator_tolerances(orbits.options),
                      compiled_run(moved, orbits.options))
    scale = 1.0 + float(np.max(np.abs(single)))
    for size in (1e-3, 1e-2, 1e-1):
        for sign in (1.0, -1.0):
            try:
                u = newton(double.residual_jacobian, single + sign * size * scale * v,
                           settings(orbits.options, "shooting")).u
            except ConvergenceError:
                continue
            if np.max(np.abs(u - single)) > 1e-6 * scale:
                mu = floquet.multipliers(double.residual_jacobian(u)[1] + np.eye(u.size))
                T2 = 2 * 2 * np.pi / orbits.omega(p)
                X = orbits.flow_states(double, u, T2 * np.arange(PHASES) / PHASES)
                return doubled_outputs(orbits, p, T2, X, mu, at)
    raise no_doubled(orbits, p, "shooting")


def no_doubled(orbits: Orbits, p: float, method: str):
    """The failure to find the doubled orbit."""
    from mechgen.errors import ConvergenceError

    return ConvergenceError(f"no doubled orbit found at {orbits.name} = {p:.10g} past the PD point ({method} over 2T "
                            "returned the period-T orbit or did not converge); try a smaller max_step near it")


def doubled_outputs(orbits: Orbits, p: float, T2: float, X: np.ndarray, mu: np.ndarray, at: int) -> dict:
    """The record of a doubled orbit: its states X at PHASES phases of [0, 2T], its multipliers mu."""
    names = list(orbits.system.coordinates)
    return branch_point(orbits.name, p, {
        "at": at, "period": T2, "amplitude": {c: peak(X[:, i]) for i, c in enumerate(names)},
        "start": dict(zip(names + [f"{c}_dot" for c in names], (float(c) for c in X[0]))),
        "multipliers": floquet.as_pairs(mu), "stability": floquet.stability(mu, False)})


def flow_of(orbits: Orbits, system, x0: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The states from x0 at ``times`` (ascending, from 0) by the compiled loop where it runs, else scipy's."""
    run = compiled_run(system, orbits.options)
    if run is not None:
        return run(np.asarray(x0, float), np.asarray(times, float))
    return states_at(system, x0, 0.0, times, *integrator_tolerances(orbits.options))


def monodromy(orbits: Orbits, system, x0: np.ndarray, span: float) -> np.ndarray:
    """Phi(span) from x0: central differences of the compiled flow where it runs, else the variational equations."""
    run = compiled_run(system, orbits.options)
    if run is not None:
        return differenced_flow(run, x0, span)[1]
    return variational_flow(system, x0, 0.0, span, *integrator_tolerances(orbits.options))[1]


def pd_perturbation(orbits: Orbits, system, x0: np.ndarray, T: float, times: np.ndarray) -> np.ndarray:
    """dx(t) = Phi(t) v at ``times`` in [0, 2T], v the unit eigenvector of Phi(T) for the multiplier nearest -1 (so
    dx(t + T) = -dx(t): odd harmonics of omega / 2), by central differences of the flow (step 1e-6 (1 + |x0|))."""
    values, vectors = np.linalg.eig(monodromy(orbits, system, x0, T))
    v = np.real(vectors[:, int(np.argmin(np.abs(values + 1.0)))])
    v = v / np.linalg.norm(v)
    h = 1e-6 * (1.0 + float(np.max(np.abs(x0))))
    return (flow_of(orbits, system, x0 + h * v, times) - flow_of(orbits, system, x0 - h * v, times)) / (2 * h)


def doubled_problem(orbits: Orbits, problem, p: float):
    """The earlier method's problem over 2T at p: harmonic balance at omega / 2 with 2H harmonics (the period-T
    orbit's harmonics are the even ones), collocation on the mesh repeated over [0, 2T]."""
    omega = orbits.omega(p) / 2
    if orbits.method == "harmonic_balance":
        return HarmonicBalance(problem.system, fourier.basis(2 * problem.basis.harmonics), omega, orbits.phase)
    edges = problem.edge_array
    twice = np.concatenate([edges / 2, 0.5 + edges[1:] / 2])
    return Collocation(problem.system, 2 * problem.mesh, omega, orbits.phase, tuple(twice))


def doubled_unknowns(double, curve) -> np.ndarray:
    """The doubled problem's unknowns from ``curve``: times in [0, 2T] -> states (rows)."""
    T2 = 2 * np.pi / double.omega
    if isinstance(double, HarmonicBalance):
        N = double.basis.theta.size
        n = double.system.n
        return fourier.coefficients_of_samples(curve(T2 * np.arange(N) / N)[:, :n], double.basis.harmonics).ravel()
    edges = double.edge_array
    from mechgen.runtime.periodic.collocation import DEGREE

    tau = (edges[:-1, None] + (np.arange(DEGREE) / DEGREE)[None, :] * np.diff(edges)[:, None]).ravel()
    return double.unknowns(curve(tau * T2), T2)


def spectral_doubled(orbits: Orbits, problem, p: float, single: np.ndarray, at: int) -> dict:
    """Harmonic balance or collocation over 2T (:func:`doubled_problem`) from the period-T orbit ``single`` at p plus
    s dx(t) (:func:`pd_perturbation`), s = +-(1e-3 .. 1e-1) (1 + max |x|); accepted when x(t + T) differs from x(t)
    by more than 1e-6 of that scale."""
    from mechgen.analyses.periodic_orbit import settings
    from mechgen.errors import ConvergenceError
    from mechgen.runtime.periodic.newton import newton

    T = orbits.period(problem, single)
    grid = 2 * T * np.arange(2 * PHASES) / (2 * PHASES)
    base = orbits.states(problem, single, grid[:PHASES])
    x0 = base[0]
    shift = pd_perturbation(orbits, problem.system, x0, T, grid)
    shift = shift / float(np.max(np.abs(shift)))
    double = doubled_problem(orbits, problem, p)
    scale = 1.0 + float(np.max(np.abs(base)))
    for size in (1e-3, 1e-2, 1e-1):
        for sign in (1.0, -1.0):
            def curve(times, k=sign * size * scale):
                index = np.rint(np.asarray(times) / (2 * T) * 2 * PHASES).astype(int) % (2 * PHASES)
                return np.vstack([base, base])[index] + k * shift[index]
            try:
                u = newton(double.residual_jacobian, doubled_unknowns(double, curve),
                           settings(orbits.options, orbits.method)).u
            except ConvergenceError:
                continue
            X = orbits.states(double, u, grid)
            if np.max(np.abs(X[:PHASES] - X[PHASES:])) > 1e-6 * scale:
                mu = floquet.multipliers(monodromy(orbits, problem.system, X[0], 2 * T))
                return doubled_outputs(orbits, p, 2 * T, X, mu, at)
    raise no_doubled(orbits, p, orbits.method)
