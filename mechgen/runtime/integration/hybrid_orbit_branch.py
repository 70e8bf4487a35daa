"""Branches of a forced hybrid model's periodic orbits in a parameter, with their period-doubling and torus points.

The orbit of period T(p) (the drive's: T = 2 pi / w when p is the drive's frequency w) starting at x0 solves

    R(x0, p) = x(T(p); x0, p) - x0 = 0,   R_x0 = Phi - I,

Phi the flow map's Jacobian through the events (mechgen.runtime.integration.hybrid_monodromy), R_p by central
differences (step 1e-6 (1 + |p|): it enters the bordered system's last column only, so it slows the corrector
but never moves a point). The branch is continued by pseudo-arclength (mechgen.runtime.steady.continuation:
cyclic folds LPC are its turning points); PD and NS points are located on it from the Floquet multipliers, the
eigenvalues of Phi (mechgen.runtime.steady.cycle_points). At a PD point the doubled orbit (period 2T) is found
by shooting over 2T just past it, from the PD point displaced along the eigenvector of the multiplier -1
(:func:`doubled_orbit`).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from mechgen.errors import ConvergenceError
from mechgen.runtime.integration.hybrid_monodromy import (FlowJacobian, HybridOrbit, flow_jacobian, flow_map,
                                                          periodic_orbit)
from mechgen.runtime.steady.continuation import ParametricEquations

#: the central-difference step of R_p, relative to 1 + |p|
PARAM_STEP = 1e-6


class OrbitFamily:
    """The orbits of ``system`` in its parameter ``name`` with the period ``period(p)``, started in ``mode``."""

    def __init__(self, system, name: str, period: Callable[[float], float], mode: int | None = None, *,
                 rtol: float = 1e-11, atol: float = 1e-13) -> None:
        self.system, self.name, self.period = system, name, period
        self.mode = system.initial_mode if mode is None else int(mode)
        self.rtol, self.atol = rtol, atol
        self.memo: dict = {}

    def flow(self, x0: np.ndarray, p: float, periods: int = 1) -> FlowJacobian:
        """x(periods T(p); x0, p) and its Jacobian (the last few kept)."""
        key = (tuple(np.asarray(x0, float)), float(p), periods)
        if key not in self.memo:
            if len(self.memo) > 32:
                self.memo.clear()
            moved = self.system.with_params(**{self.name: float(p)})
            self.memo[key] = flow_jacobian(moved, np.asarray(x0, float), periods * self.period(float(p)),
                                           mode=self.mode, rtol=self.rtol, atol=self.atol, close=True)
        return self.memo[key]

    def residual(self, x0, p) -> np.ndarray:
        """R(x0, p) = x(T(p)) - x0 (the flow map only: no Jacobian unless one was already made there)."""
        key = (tuple(np.asarray(x0, float)), float(p), 1)
        if key in self.memo:
            return self.memo[key].x - np.asarray(x0, float)
        moved = self.system.with_params(**{self.name: float(p)})
        x, _ = flow_map(moved, x0, self.period(float(p)), mode=self.mode, rtol=self.rtol, atol=self.atol,
                        close=True)
        return x - np.asarray(x0, float)

    def equations(self) -> ParametricEquations:
        """R, R_x0 and R_p (module doc) for mechgen.runtime.steady.continuation."""
        def R_p(x0, p):
            h = PARAM_STEP * (1.0 + abs(p))
            return (self.residual(x0, p + h) - self.residual(x0, p - h)) / (2 * h)

        return ParametricEquations(self.residual, lambda x0, p: self.flow(x0, p).phi - np.eye(np.size(x0)), R_p,
                                   name=f"the periodic orbits in {self.name}")

    def multipliers(self, x: np.ndarray) -> np.ndarray:
        """The Floquet multipliers of the orbit at the branch point x = (x0, p)."""
        return np.linalg.eigvals(self.flow(x[:-1], x[-1]).phi)

    def orbit(self, x0, p: float, periods: int = 1, **newton) -> HybridOrbit:
        """The orbit of ``periods`` T(p) by shooting from x0 at p."""
        moved = self.system.with_params(**{self.name: float(p)})
        return periodic_orbit(moved, x0, periods * self.period(float(p)), mode=self.mode, rtol=self.rtol,
                              atol=self.atol, **newton)


def doubled_orbit(family: OrbitFamily, x_pd: np.ndarray, beyond: float, *, shift: float = 1e-3) -> HybridOrbit:
    """The period-2T orbit at p = p_PD + ``beyond`` (the side where the period-T orbit has a multiplier below -1),
    by shooting over 2T from the PD point's x0 displaced by ``shift`` along the eigenvector of the multiplier
    nearest -1 (either way: the first that converges to an orbit other than the period-T one)."""
    x0, p = np.asarray(x_pd[:-1], float), float(x_pd[-1]) + beyond
    values, vectors = np.linalg.eig(family.flow(x0, float(x_pd[-1])).phi)
    v = np.real(vectors[:, int(np.argmin(np.abs(values + 1.0)))])
    v = v / np.linalg.norm(v)
    single = family.orbit(x0, p)
    errors = []
    for start in _doubling_guesses(family, single.x0, v, p, shift):
        try:
            orbit = family.orbit(start, p, periods=2)
        except ConvergenceError as exc:
            errors.append(str(exc))
            continue
        if np.linalg.norm(orbit.x0 - single.x0) > 1e-6 * (1 + np.linalg.norm(single.x0)):
            return orbit
    raise ConvergenceError(f"no doubled orbit found at {family.name} = {p:.10g} from the PD point "
                           f"({'; '.join(errors) or 'shooting returned the period-T orbit'}); try a larger shift "
                           "or a parameter further past the PD point")


def _doubling_guesses(family: OrbitFamily, x0: np.ndarray, v: np.ndarray, p: float, shift: float):
    """Starts of the 2T shooting: the period-T orbit displaced by +-shift along v, at 10 and 100 times the shift,
    and where 200 periods of the flow from the displaced start settle (a supercritical PD's doubled orbit is
    stable, the period-T orbit past it is not)."""
    for scale in (1.0, 10.0, 100.0):
        for sign in (1.0, -1.0):
            yield x0 + sign * scale * shift * v
    moved = family.system.with_params(**{family.name: float(p)})
    settled, _ = flow_map(moved, x0 + shift * v, 200 * family.period(p), mode=family.mode, rtol=1e-10, atol=1e-12)
    yield settled
