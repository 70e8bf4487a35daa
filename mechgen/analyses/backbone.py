"""``continuation`` about the free orbit of a conservative model: its family (the backbone curve), or the orbit of
fixed level moved in a model parameter.

The earlier ``periodic_orbit`` found one member of a conservative family (mechgen.analyses.free_orbit): the orbit
with q_p(0) = level, the frequency an unknown and the unfolding eps solved beside it
(mechgen.runtime.periodic.conservative). With ``parameter = "amplitude"`` (a model parameter of that name wins)
the continuation follows the family in the level, q_p(0), from the earlier orbit's to ``stop``, by pseudo-arclength
on the unfolded equations: the backbone curve, frequency against amplitude. With a model parameter it follows the
orbit of the earlier level as the parameter moves. Each branch point reports, beside a branch of orbits' outputs
(mechgen.analyses.orbit_branch: ``period``, ``frequency``, ``amplitude``, ``start``, ``multipliers``,
``stability``), the orbit's ``energy`` (E = T + V, the model's ``energy`` output) and ``unfolding`` (eps, zero to
the corrector's tolerance on each orbit of the family); along the family a point's level, q_p(0), is its
``level`` (also its ``start[<coordinate p>]``; the key ``amplitude`` keeps its meaning, {coordinate: max |q|}). ``stability`` sets aside the two multipliers
nearest 1 (along the orbit and along the family). ``backbone`` gathers the branch as columns: ``frequency``, ``period``,
``amplitude`` ({coordinate: max |q|}), ``energy``, ``unfolding``. Special points: ``LPC`` (the level turns) and
``PD``; NS is not sought (the multipliers of a conservative orbit come in pairs mu, 1/mu, so its test function
vanishes identically).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.free_orbit import orbit_energy
from mechgen.analyses.newton_branch import arclength_steps
from mechgen.analyses.orbit_family import FAMILY_PARAMETER, Orbits, record
from mechgen.analyses.periodic_orbit import DEFAULT_HARMONICS, compiled_run, integrator_tolerances
from mechgen.analyses.stability_boundary import own_value
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.periodic import floquet, fourier
from mechgen.runtime.periodic.branch import OrbitBranch, node_weights
from mechgen.runtime.periodic.collocation import Collocation
from mechgen.runtime.periodic.conservative import Unfolded
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance
from mechgen.runtime.periodic.shooting import Shooting
from mechgen.runtime.steady.continuation import continuation
from mechgen.runtime.steady.cycle_points import cycle_points

class FamilyOrbits(Orbits):
    """The free orbits of the earlier conservative ``periodic_orbit``: problems are :class:`Unfolded`, their
    level the continued one (``family``) or the earlier orbit's."""

    def __init__(self, system, name: str, orbit: dict, family: bool) -> None:
        super().__init__(system, name, orbit)
        self.family = family
        self.level = float(orbit["found"]["level"])

    def make(self, p: float):
        """The unfolded problem at p: level p along the family, else the system at p and the earlier level."""
        moved = self.system if self.family else self.system.with_params(**{self.name: float(p)})
        level = float(p) if self.family else self.level
        if self.method == "harmonic_balance":
            base = HarmonicBalance(moved, fourier.basis(int(self.options.get("harmonics", DEFAULT_HARMONICS))),
                                   None, self.phase)
        elif self.method == "collocation":
            base = Collocation(moved, self.mesh.mesh, None, self.phase, self.mesh.edges)
        else:
            base = Shooting(moved, None, self.phase, *integrator_tolerances(self.options),
                            compiled_run(moved, self.options), int(self.options.get("segments", 1)))
        return Unfolded(base, level)

    def start(self, problem, found: dict) -> np.ndarray:
        """The earlier orbit's unknowns with its eps."""
        if self.method == "harmonic_balance":
            u = problem.problem.unknowns(found["U"], found["omega"])
        elif self.method == "collocation":
            u = np.asarray(found["u"], float)
        else:
            T = 2 * np.pi / found["omega"]
            S = getattr(problem, "segments", 1)
            X = self.flow_states(problem, found["x0"], T * np.arange(S) / S) if S > 1 else found["x0"]
            u = problem.problem.unknowns(X, T)
        return np.append(u, found["unfolding"])


def family_record(orbits: FamilyOrbits, branch: OrbitBranch, u: np.ndarray, p: float) -> dict:
    """One branch point (module doc): a branch of orbits' record with ``energy``, ``unfolding`` and the stability
    of a conservative orbit."""
    out = record(orbits, branch, u, p)
    if orbits.family:  # the family's own level, q_p(0): ``level``; ``amplitude`` stays the orbit's max |q|
        out["level"] = out.pop(orbits.name)
        out["amplitude"] = out.pop(f"orbit_{orbits.name}")
    mu = orbits.multipliers(branch.problem(p), u, p)
    problem = branch.problem(p)
    x0 = problem.split(u)[0] if orbits.method == "shooting" else orbits.states(problem, u, np.array([0.0]))[0]
    out.update(energy=orbit_energy(problem.system, x0), unfolding=float(u[-1]),
               stability=floquet.stability(mu, True, trivial=2))
    return out


def columns(points: list[dict]) -> dict:
    """The branch as columns (``backbone``)."""
    names = list(points[0]["amplitude"]) if points else []
    return {"frequency": [p["frequency"] for p in points], "period": [p["period"] for p in points],
            "amplitude": {c: [p["amplitude"][c] for p in points] for c in names},
            "energy": [p["energy"] for p in points], "unfolding": [p["unfolding"] for p in points]}


def run_backbone(system, options: dict, orbit: dict) -> dict:
    """The family (or the fixed-level orbit in a model parameter) through the earlier free orbit (module doc)."""
    name = options["parameter"]
    family = name == FAMILY_PARAMETER and name not in system.param_values()
    orbits = FamilyOrbits(system, name, orbit, family)
    here = orbits.level if family else float(own_value(system, name))
    branch = OrbitBranch(orbits.make, name)
    problem = branch.problem(here)
    u0 = orbits.start(problem, orbit["found"])
    repeats = problem.nodes if orbits.method == "collocation" else getattr(problem, "segments", 1)
    eqs = branch.equations(node_weights(u0.size, repeats, 2) if repeats > 1 else None)
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    found = continuation(eqs, u0, here, arclength_steps(options, here, budget, smallest_span=0.1))
    points = [family_record(orbits, branch, u, p) for u, p in zip(found.u, found.lam)]
    X = np.hstack([found.u, found.lam[:, None]])
    specials = [("LPC", np.append(f.u, f.lam), f.index) for f in found.folds]
    if options.get("special_points", True):
        specials += [(s.type, s.x, s.index) for s in cycle_points(
            eqs, X, lambda x: orbits.multipliers(branch.problem(x[-1]), x[:-1], x[-1]), kinds=("PD",))]
    records = [{"type": kind, **family_record(orbits, branch, x[:-1], x[-1])}
               for kind, x, _ in sorted(specials, key=lambda s: s[2])]
    return {"parameter": name, "method": orbits.method, "branch": points, "points": len(points),
            "status": found.status, "folds": [r for r in records if r["type"] == "LPC"], "special_points": records,
            "shape_outputs": [], "backbone": columns(points), "_backbone": True}
