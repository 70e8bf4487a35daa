"""``continuation`` about a continuation of periodic orbits with ``special_point``: the curve of a cyclic fold
(LPC) in two parameters, e.g. the fold curve of a Duffing frequency-response curve in (frequency, forcing).

The orbit method's residual R(u; a, b) (mechgen.runtime.periodic: harmonic balance or shooting, rebuilt at each
pair of parameter values) gives the minimally augmented fold system of mechgen.runtime.steady.codim2: u and the
first parameter a are unknowns, g = 0 from the bordered [[R_u, w], [v^T, 0]] where R_u is singular, continued in
the second parameter b by pseudo-arclength (so the curve is followed round a cusp, where it turns in b). Output
``curve``: per point both parameters, ``period``, ``frequency``, ``amplitude``, ``start``, ``multipliers`` and
``stability`` (at a cyclic fold one multiplier is 1); with ``type`` (LPC), ``parameters`` ([a, b]), ``status``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses.newton_branch import arclength_steps
from mechgen.analyses.orbit_family import Orbits, record
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.periodic.branch import OrbitBranch, residual_only
from mechgen.runtime.steady import codim2
from mechgen.runtime.steady.continuation import continuation

sps = lazy_module("scipy.sparse")


#: G's difference step for orbits (mechgen.runtime.steady.codim2): a shooting R_u by differences of the compiled
#: flow carries ~1e-10 noise, which a 1e-7 step would amplify to 1e-3 in G's Jacobian
ORBIT_DIFF_STEP = 1e-5


class TwoParameterOrbits:
    """The orbit problems of one method at the parameter pairs (a, b) (a memo of the last few)."""

    def __init__(self, system, first: str, second: str, orbit: dict) -> None:
        self.system, self.first, self.second, self.orbit = system, first, second, orbit
        self.memo: dict = {}

    def at(self, b: float) -> tuple[Orbits, OrbitBranch]:
        """(Orbits, OrbitBranch) of the system at b, moving along a."""
        key = float(b)
        if key not in self.memo:
            if len(self.memo) > 8:
                self.memo.clear()
            orbits = Orbits(self.system.with_params(**{self.second: key}), self.first, self.orbit)
            self.memo[key] = (orbits, OrbitBranch(orbits.make, self.first))
        return self.memo[key]

    def residual(self, u, a, b) -> np.ndarray:
        return residual_only(self.at(b)[1].problem(a), np.asarray(u, float))

    def jacobian(self, u, a, b) -> np.ndarray:
        """dR/du, dense (a collocation of a model with internal variables gives it sparse)."""
        J = self.at(b)[1].residual_jacobian(np.asarray(u, float), a)[1]
        return J.toarray() if sps.issparse(J) else J


def run_orbit_curve(system, options: dict, earlier: dict) -> dict:
    """The LPC curve (module doc) of special point ``special_point`` of an earlier branch of orbits."""
    index = int(options["special_point"])
    specials = earlier.get("special_points") or []
    if not 1 <= index <= len(specials) or specials[index - 1]["type"] != "LPC":
        raise SceneError(f"special_point = {index} is not a cyclic fold of the branch (its special points: "
                         f"{', '.join(s['type'] for s in specials) or 'none'})", key="special_point",
                         expected="the position (from 1) of an LPC in the branch's special_points")
    first, second = earlier["parameter"], options["parameter"]
    if second == first:
        raise SceneError(f"parameter {second!r} is the earlier continuation's own", key="parameter",
                         expected=f"a second parameter, other than {first!r}")
    if "_special_x" not in earlier:
        raise SceneError("the earlier branch of orbits keeps no fold to follow (a hybrid model's branch: not yet)",
                         key="about", expected="a continuation of a smooth model's periodic orbits")
    x = np.asarray(earlier["_special_x"][index - 1], float)
    model = TwoParameterOrbits(system, first, second, earlier["_orbit"])
    b0 = float(system.param_values()[second])
    G, u0 = codim2.fold_system(model.residual, model.jacobian, x[:-1], float(x[-1]), b0)
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    branch = continuation(codim2.equations(G, f"the LPC curve in ({first}, {second})", step=ORBIT_DIFF_STEP), u0, b0,
                          arclength_steps(options, b0, budget, smallest_span=0.1))
    curve = []
    for u, b in zip(branch.u, branch.lam):
        orbits, problems = model.at(b)
        curve.append({second: float(b), **record(orbits, problems, u[:-1], float(u[-1]))})
    return {"type": "LPC", "parameters": [first, second], "curve": curve, "points": len(curve),
            "status": branch.status, "parameter": second}
