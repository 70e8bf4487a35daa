"""``periodic_orbit`` of a hybrid model: event-aware shooting of a forced or autonomous orbit, its monodromy through
the events.

A forced hybrid model (impacts, stick-slip: mechgen.symbolic.hybrid) has the orbit x(T) = x0 of the forcing's
period T = 2 pi / ``frequency`` found by Newton on x(T; x0) - x0 with the Jacobian Phi - I, Phi the flow map's
Jacobian through the events: the modes' state-transition matrices and the saltation matrices of the events,
generated from the guards and resets (mechgen.runtime.integration.hybrid_monodromy). The orbit starts at t = 0 in
the model's initial mode; an event at the period's boundary (a stick-slip reversal at the drive's extremum) is taken
at T (mechgen.runtime.integration.hybrid_monodromy.closing_run). Outputs as the smooth orbit's
(mechgen.analyses.periodic_orbit): ``period``, ``frequency``, ``t``, ``trajectory`` (with ``mode_series``, the mode
index per sample), ``amplitude`` and ``harmonics`` (the coordinates, then the internal variables), ``multipliers``
(the eigenvalues of Phi), ``stability``, ``method`` (``shooting``), ``residual``, ``iterations``; and ``events``
(those of one period: {t, guard, from, to}) and ``grazing`` (the events of the orbit that touch their guard
tangentially, where the saltation matrix and the multipliers are not to be trusted).

*Autonomous* (no ``frequency``: an orbit of unknown period, such as a stick-slip cycle on a moving belt): the phase
is fixed by a Poincare section at an event, the guard named by ``section`` (left out: the guard of the first event
of the run from the guess); the orbit starts just after that event, in the mode it leads to, and ends just after its
next one (mechgen.runtime.integration.hybrid_autonomous: Newton on the return map, its Jacobian from the saltation
matrices and the return time's gradient). The guess ``q0`` / ``v0`` is run 3 times through the section
(from the model's initial mode; ``period`` the guess of the period, which bounds that run at 9 periods); its state
after the third event starts Newton, and the time between its last two events there is the period's guess from
then on (each run bounded at 3 of them). Outputs as above, with ``section`` (the guard) and ``start_mode``; ``t`` runs
from the section's event (t = 0) over one period. ``multipliers`` hold the trivial 1 (along the orbit; set aside by
``stability``), and a stick phase, which forgets the velocity it started with, gives multipliers 0 (the monodromy
is rank-deficient: a 1-degree-of-freedom stick-slip cycle has multipliers 1 and 0 and is stable).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import time_series
from mechgen.analyses.branch_points import branch_point
from mechgen.errors import SceneError
from mechgen.runtime.integration.events import integrate_hybrid
from mechgen.runtime.integration.hybrid_monodromy import periodic_orbit
from mechgen.runtime.integration.run_options import RunOptions
from mechgen.runtime.periodic import floquet, fourier
from mechgen.runtime.periodic.fourier import peak

#: phases at which amplitudes and harmonics are taken
FINE = 4096


def orbit_states(system, x0: np.ndarray, T: float, times: np.ndarray, rtol: float, atol: float,
                 mode: int | None = None):
    """(states (rows), mode per sample) of the orbit from x0 in ``mode`` (default the initial one) at ``times`` in
    [0, T] (the event-driven flow)."""
    run = integrate_hybrid(system, x0, T, mode=mode, options=RunOptions(method="DOP853", rtol=rtol, atol=atol,
                                                                        t_eval=times, progress=False))
    return np.asarray(run.x, float), np.asarray(run.mode, int)


def run_hybrid_orbit(system, options: dict, guess: np.ndarray) -> dict:
    """The forced orbit of a hybrid model from the starting state ``guess`` (module doc)."""
    if options.get("method", "shooting") != "shooting":
        raise SceneError(f"method {options['method']!r} needs a smooth model; a hybrid model's orbit is found by "
                         "shooting through its events", key="method", expected="shooting (or leave method out)")
    rtol, atol = float(options["rtol"]) * 1e-2, float(options["atol"]) * 1e-2
    if options.get("frequency") is None:
        return run_autonomous(system, options, guess, rtol, atol)
    omega = float(options["frequency"])
    T = 2 * np.pi / omega
    orbit = periodic_orbit(system, guess, T, tol=float(options["rtol"]), max_iter=int(options["max_iterations"]),
                           rtol=rtol, atol=atol)
    out = orbit_outputs(system, options, orbit, rtol, atol, autonomous=False)
    out["frequency"] = omega
    out["_orbit"] = {"method": "shooting", "hybrid": True, "x0": orbit.x0, "mode": orbit.mode,
                     "options": dict(options)}
    return out


def run_autonomous(system, options: dict, guess: np.ndarray, rtol: float, atol: float) -> dict:
    """The autonomous orbit of a hybrid model through the section's event (module doc)."""
    from mechgen.runtime.integration.hybrid_autonomous import autonomous_orbit, settle_on_section

    refuse_forced(system, guess)
    section = options.get("section")
    if section is not None and not any(g.name == section for m in range(len(system.modes))
                                       for g in system.guards(m)):
        names = sorted({g.name for m in range(len(system.modes)) for g in system.guards(m)})
        raise SceneError(f"periodic_orbit: model {system.metadata.model} has no guard {section!r}", key="section",
                         expected="one of its guards: " + ", ".join(names))
    x0, mode, section, period = settle_on_section(system, guess, system.initial_mode, section,
                                                  float(options["period"]), rtol=rtol, atol=atol)
    orbit = autonomous_orbit(system, x0, mode, section, period, tol=float(options["rtol"]),
                             max_iter=int(options["max_iterations"]), rtol=rtol, atol=atol)
    out = orbit_outputs(system, options, orbit, rtol, atol, autonomous=True)
    out.update(section=section, start_mode=system.modes[orbit.mode])
    out["_orbit"] = {"method": "shooting", "hybrid": True, "autonomous": True, "x0": orbit.x0, "mode": orbit.mode,
                     "section": section, "period": orbit.period, "options": dict(options)}
    return out


def amplitudes(system, states: np.ndarray, period: float, events) -> dict:
    """{name: max |value|} over one period (the coordinates, then the internal variables), from the states (rows) at
    the equally spaced phases period * k / rows and the states on both sides of the ``events``: the largest sample
    refined by the parabola through it and its neighbours (mechgen.runtime.periodic.fourier.peak) unless an event
    falls between those neighbours (a kink, where the parabola would overshoot: a flat slip phase meets a stick
    phase), then the larger of that sample and the event states."""
    n, names = system.n, time_series.state_names(system)
    columns = list(range(n)) + list(range(2 * n, 2 * n + system.m))
    times = np.array([e.t for e in events], float)
    sides = np.array([s for e in events for s in (e.x_before, e.x_after)], float).reshape(-1, states.shape[1])
    return {names[j]: kinked_peak(states[:, j], period, times, sides[:, j]) for j in columns}


def kinked_peak(values: np.ndarray, period: float, event_times: np.ndarray, event_values: np.ndarray) -> float:
    """max |value| of a piecewise-smooth periodic signal sampled at period * k / values.size (amplitudes' doc)."""

    y = np.abs(np.asarray(values, float))
    k, h = int(np.argmax(y)), period / y.size
    gap = np.abs(np.mod(event_times - k * h + period / 2, period) - period / 2)
    best = peak(values) if not np.any(gap < h) else float(y[k])
    return float(max(best, np.max(np.abs(event_values), initial=0.0)))


def start_state(system, x0: np.ndarray) -> dict:
    """{state name: value} of the orbit's start: the coordinates, their velocities, the internal variables."""
    return dict(zip(time_series.state_names(system), (float(v) for v in x0)))


def refuse_forced(system, x: np.ndarray) -> None:
    """An autonomous orbit needs equations and guards without t: each mode's dx/dt and guards compared at t = 0 and
    t = 1.2345 at the guess x (a SceneError at ``frequency`` when they differ)."""
    for k in range(len(system.modes)):
        f0, f1 = system.mode(k).rhs(0.0, x), system.mode(k).rhs(1.2345, x)
        g0, g1 = system.guard_values(k, 0.0, x)[0], system.guard_values(k, 1.2345, x)[0]
        if not (np.allclose(f0, f1, rtol=1e-12, atol=1e-14) and np.allclose(g0, g1, rtol=1e-12, atol=1e-14)):
            raise SceneError(f"periodic_orbit: model {system.metadata.model}'s equations or guards depend on t (in "
                             f"mode {system.modes[k]}: a forcing) and no frequency is given", key="frequency",
                             expected="the forcing's angular frequency (rad/s), a number or a parameter expression")


def orbit_outputs(system, options: dict, orbit, rtol: float, atol: float, *, autonomous: bool) -> dict:
    """The outputs (module doc) of a converged orbit (a HybridOrbit or an AutonomousOrbit) of period orbit.period,
    sampled from its start x0 in orbit.mode."""
    T, n = float(orbit.period), system.n
    # the coordinates, then the internal variables (as a smooth orbit's: mechgen.analyses.periodic_orbit.report)
    columns = list(range(n)) + list(range(2 * n, 2 * n + system.m))
    names = list(system.coordinates) + time_series.state_names(system)[2 * n:]
    fine, _ = orbit_states(system, orbit.x0, T, T * np.arange(FINE) / FINE, rtol, atol, orbit.mode)
    amplitude = amplitudes(system, fine, T, orbit.events)
    fine = fine[:, columns]
    t = np.linspace(0.0, T, int(options["samples"]))
    X, modes = orbit_states(system, orbit.x0, T, t, rtol, atol, orbit.mode)
    series = time_series.sampled_outputs_by_mode(system.mode, t, X, modes)
    history = time_series.time_history(system, t, X, series, None)
    history["trajectory"]["mode_series"] = modes.tolist()
    U = fourier.coefficients_of_samples(fine, int(options.get("harmonics", 7)))
    mu = orbit.multipliers
    return {"period": T, "frequency": 2 * np.pi / T, "t": history["t"], "trajectory": history["trajectory"],
            "amplitude": amplitude,
            "harmonics": fourier.harmonics_table(U, names), "multipliers": floquet.as_pairs(mu),
            "stability": floquet.stability(mu, autonomous), "method": "shooting", "residual": orbit.residual,
            "iterations": orbit.iterations, "loop": "c" if getattr(system, "backend", None) == "c" else "python",
            "events": [{"t": float(e.t), "guard": e.guard, "from": system.modes[e.source],
                        "to": None if e.target is None else system.modes[e.target]} for e in orbit.events],
            "grazing": [orbit.events[i].guard for i in orbit.grazing]}


def run_hybrid_branch(system, options: dict, orbit: dict) -> dict:
    """``continuation`` about a hybrid model's ``periodic_orbit``: the branch of forced orbits in ``parameter``
    (mechgen.runtime.integration.hybrid_orbit_branch), its cyclic folds (LPC), period doublings (PD) and torus
    points (NS); with ``switch_branches``, the doubled orbit just past every PD (``doubled``: {at, <parameter>,
    period, start, multipliers, stability})."""
    from mechgen.analyses.newton_branch import arclength_steps
    from mechgen.analyses.schema import ParamExpression
    from mechgen.analyses.stability_boundary import own_value
    from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
    from mechgen.runtime.integration.hybrid_orbit_branch import OrbitFamily
    from mechgen.runtime.steady.continuation import continuation
    from mechgen.runtime.steady.cycle_points import cycle_points

    if orbit.get("autonomous"):
        return run_section_branch(system, options, orbit)
    name, frequency = options["parameter"], orbit["options"]["frequency"]
    rtol, atol = float(orbit["options"]["rtol"]) * 1e-2, float(orbit["options"]["atol"]) * 1e-2

    def period(p: float) -> float:
        w = frequency.moved(name, p, system.param_values()) if isinstance(frequency, ParamExpression) else frequency
        return 2 * np.pi / float(w)

    family = OrbitFamily(system, name, period, orbit["mode"], rtol=rtol, atol=atol)
    here = float(own_value(system, name))
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    eqs = family.equations()
    found = continuation(eqs, np.asarray(orbit["x0"], float), here, arclength_steps(options, here, budget,
                                                                                    smallest_span=0.1))
    X = np.hstack([found.u, found.lam[:, None]])
    points = [hybrid_record(family, x) for x in X]
    specials = [("LPC", np.append(f.u, f.lam), f.index) for f in found.folds]
    if options.get("special_points", True):
        specials += [(s.type, s.x, s.index) for s in cycle_points(eqs, X, family.multipliers)]
    specials.sort(key=lambda s: s[2])
    out = {"parameter": name, "method": "shooting", "branch": points, "points": len(points), "status": found.status,
           "special_points": [{"type": kind, **hybrid_record(family, x)} for kind, x, _ in specials],
           "shape_outputs": []}
    out["folds"] = [s for s in out["special_points"] if s["type"] == "LPC"]
    if options.get("switch_branches"):
        out["doubled"] = [doubled_record(family, X, x, index, k + 1)
                          for k, (kind, x, index) in enumerate(specials) if kind == "PD"]
    return out


def run_section_branch(system, options: dict, orbit: dict) -> dict:
    """``continuation`` about an autonomous hybrid orbit: the branch of orbits through the section's event in
    ``parameter`` (mechgen.runtime.integration.hybrid_autonomous.SectionFamily), its cyclic folds (LPC) and its PD
    and NS points from the return map's multipliers. The doubled orbit past a PD point is not sought
    (mechgen.analyses.orbit_branch refuses ``switch_branches`` about an autonomous orbit)."""
    from mechgen.analyses.newton_branch import arclength_steps
    from mechgen.analyses.stability_boundary import own_value
    from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
    from mechgen.runtime.integration.hybrid_autonomous import SectionFamily
    from mechgen.runtime.steady.continuation import continuation
    from mechgen.runtime.steady.cycle_points import cycle_points

    name = options["parameter"]
    rtol, atol = float(orbit["options"]["rtol"]) * 1e-2, float(orbit["options"]["atol"]) * 1e-2
    family = SectionFamily(system, name, orbit["mode"], orbit["section"], orbit["period"], rtol=rtol, atol=atol)
    here = float(own_value(system, name))
    budget = Budget("continuation", unit="points", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    eqs = family.equations()
    found = continuation(eqs, np.asarray(orbit["x0"], float), here, arclength_steps(options, here, budget,
                                                                                    smallest_span=0.1))
    X = np.hstack([found.u, found.lam[:, None]])
    specials = [("LPC", np.append(f.u, f.lam), f.index) for f in found.folds]
    if options.get("special_points", True):
        specials += [(s.type, s.x, s.index) for s in cycle_points(eqs, X, family.multipliers)]
    specials.sort(key=lambda s: s[2])
    out = {"parameter": name, "method": "shooting", "branch": [section_record(family, x) for x in X],
           "points": len(X), "status": found.status, "shape_outputs": [],
           "special_points": [{"type": kind, **section_record(family, x)} for kind, x, _ in specials]}
    out["folds"] = [s for s in out["special_points"] if s["type"] == "LPC"]
    return out


def section_record(family, x: np.ndarray) -> dict:
    """One autonomous orbit of a branch: the parameter, period, frequency, amplitude, start (just after the
    section's event), multipliers (the monodromy's), stability and the events per period."""
    x0, p = x[:-1], float(x[-1])
    rm = family.map(x0, p)
    T = rm.period
    fine, _ = orbit_states(family.moved(p), x0, T, T * np.arange(1024) / 1024, family.rtol, family.atol,
                           family.mode)
    mu = floquet.multipliers(rm.monodromy)
    return branch_point(family.name, p, {
        "period": T, "frequency": 2 * np.pi / T, "amplitude": amplitudes(family.system, fine, T, rm.events),
        "start": start_state(family.system, x0), "multipliers": floquet.as_pairs(mu),
        "stability": floquet.stability(mu, True), "events_per_period": len(rm.events)})


def hybrid_record(family, x: np.ndarray) -> dict:
    """One orbit of a hybrid branch: the parameter, period, frequency, amplitude, start, multipliers, stability and
    the events per period."""
    x0, p = x[:-1], float(x[-1])
    T = family.period(p)
    moved = family.system.with_params(**{family.name: p})
    fine, _ = orbit_states(moved, x0, T, T * np.arange(1024) / 1024, family.rtol, family.atol)
    mu = floquet.multipliers(family.flow(x0, p).phi)
    return branch_point(family.name, p, {
        "period": T, "frequency": 2 * np.pi / T, "amplitude": amplitudes(family.system, fine, T, family.flow(x0, p).events),
        "start": start_state(family.system, x0), "multipliers": floquet.as_pairs(mu),
        "stability": floquet.stability(mu, False), "events_per_period": len(family.flow(x0, p).events)})


def doubled_record(family, X: np.ndarray, x_pd: np.ndarray, index: int, at: int) -> dict:
    """The doubled orbit past the PD point x_pd (between branch points index and index + 1): on the side whose
    orbit has a multiplier below -1, half-way to that branch point."""
    from mechgen.runtime.integration.hybrid_orbit_branch import doubled_orbit

    side = max((X[index], X[index + 1]), key=lambda x: -float(np.min(family.multipliers(x).real)))
    p = float(x_pd[-1]) + 0.5 * (float(side[-1]) - float(x_pd[-1]))
    orbit = doubled_orbit(family, x_pd, p - float(x_pd[-1]))
    fine, _ = orbit_states(family.system.with_params(**{family.name: p}), orbit.x0, orbit.period,
                           orbit.period * np.arange(1024) / 1024, family.rtol, family.atol)
    mu = orbit.multipliers
    return branch_point(family.name, p, {
        "at": at, "amplitude": amplitudes(family.system, fine, orbit.period, orbit.events), "period": orbit.period,
        "start": start_state(family.system, orbit.x0), "multipliers": floquet.as_pairs(mu),
        "stability": floquet.stability(mu, False), "events_per_period": len(orbit.events)})
