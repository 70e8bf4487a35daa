"""``special_points`` of a continuation: folds (LP), branch points (BP) and Hopf points (H) of an equilibrium
branch, as records, and the branches switched onto at each BP.

The numerics (test functions, location, the first Lyapunov coefficient, the other branch's direction) are
mechgen.runtime.steady.special_points. Each record is ``{type, <parameter>: value, coordinates, the model's
outputs}`` in branch order; an H record adds ``frequency`` (omega of the critical pair +-i omega, rad per unit of
the model's time), ``lyapunov`` (the first Lyapunov coefficient l1) and ``criticality`` ("supercritical" when
l1 < 0: a stable limit cycle is born; "subcritical" when l1 > 0; "degenerate" when |l1| is below what the
differences resolve, e.g. a linear model); a BP record adds ``direction`` (the other
branch's unit direction: per coordinate and the parameter). With ``switch_branches = true`` the continuation
also follows the other branch from every BP, both ways (``switched_branches``: one entry per half,
``{at: the BP's position in special_points (from 1), half: "+" or "-", branch: [points], status}``).
"""
from __future__ import annotations

import numpy as np

from mechgen.runtime.steady import special_points as sp
from mechgen.runtime.steady.continuation import continuation


def eigenvalues_at(system, name: str):
    """x = (y, p) -> the first-order spectrum of the linearisation about the equilibrium y at p."""
    from mechgen.analyses.stability_boundary import spectrum

    return lambda x: spectrum(system.with_params(**{name: float(x[-1])}), x[:-1]).eigenvalues


def jacobian_at(system, name: str):
    """x = (y, p) -> (J(state) of the first-order field at p, the equilibrium's state (q, 0, z))."""
    n = system.n

    def at(x):
        moved = system.with_params(**{name: float(x[-1])})
        y = x[:-1]
        state = np.concatenate([y[:n], np.zeros(n), y[n:]])
        return (lambda s: np.asarray(moved.jacobian(0.0, s), float)), state

    return at


def located(system, eqs, X: np.ndarray, branch, name: str, hopf: bool) -> list[sp.SpecialPoint]:
    """LP (the continuation's folds, but for a turn on a segment holding a BP), BP and (``hopf``: with the
    spectrum) H of a branch, in branch order."""
    bps = sp.branch_points(eqs, X)
    # the parameter also turns at a BP along a pitchfork's side branch: that turn is the BP, not a fold
    found = [sp.SpecialPoint("LP", np.append(f.u, f.lam), f.index) for f in branch.folds
             if f.index not in {b.index for b in bps}] + bps
    if hopf:
        found += sp.hopf_points(eqs, X, eigenvalues_at(system, name), jacobian_at(system, name))
    return sorted(found, key=lambda s: (s.index, s.type))


def record(system, name: str, special: sp.SpecialPoint, point) -> dict:
    """The output record of one special point (module doc); ``point(y, p)``: the branch point's record."""
    out = {"type": special.type, **point(special.x[:-1], special.x[-1])}
    if special.type == "H":
        l1 = special.data["lyapunov"]
        resolved = abs(l1) > special.data["resolution"]
        out.update(frequency=special.data["frequency"], lyapunov=l1,
                   criticality="degenerate" if not resolved else "supercritical" if l1 < 0 else "subcritical")
    elif special.type == "BP":
        d = special.data["direction"]
        out["direction"] = {**{c: float(v) for c, v in zip(system.coordinates, d[:system.n])}, name: float(d[-1])}
    return out


def switched(eqs, specials: list[sp.SpecialPoint], steps, point) -> list[dict]:
    """The other branch from every BP, both halves (module doc); ``steps``: the continuation's options."""
    out = []
    for k, special in enumerate(specials):
        if special.type != "BP":
            continue
        for half, sign in (("+", 1.0), ("-", -1.0)):
            d = sign * special.data["direction"]
            branch = continuation(eqs, special.x[:-1], special.x[-1], steps, start_tangent=d)
            out.append({"at": k + 1, "half": half, "status": branch.status,
                        "branch": [point(u, lam) for u, lam in zip(branch.u[1:], branch.lam[1:])]})
    return out
