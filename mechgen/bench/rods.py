"""``mechgen bench rods``: the geometrically exact (Cosserat) rod, mechgen against PyElastica (issue 15).

Peer: PyElastica (``pyelastica==1.0.0``, the pin in pyproject's ``bench`` extra; :data:`PYELASTICA_PIN`),
its ``CosseratRod.straight_rod`` with ``OneEndFixedBC`` (node 0 and element 0's directors held),
``EndpointForces`` (a dead tip force, ramp time 1e-300 s: a step load) and, for the static limit,
``AnalyticalLinearDamper(uniform_damping_constant=c)`` (v and omega multiplied by exp(-c dt) after each
step), stepped by its ``PositionVerlet``. Without pyelastica the PyElastica parts are skipped with a message
(``"pyelastica": "skipped: ..."`` in the results) and mechgen's parts still run.

Mapping (PyElastica 1.0.0, ``elastica/rod/factory_function.py``; a solid disc of radius r, density rho,
Young's modulus E, shear modulus G): A = pi r^2, I = A^2/(4 pi) = pi r^4/4 about each bending axis,
J = 2 I (polar);

    EA = E A,  GA = alpha_c G A,  GJ = G J,  EI = E I  (N, N, N m^2, N m^2),
    rhoA = rho A (kg/m),  rhoI = rho I,  rhoJ = rho J (kg m: PyElastica's mass second moment of inertia of an
    element is diag(I, I, 2I) rho dl),

with PyElastica's shear coefficient alpha_c = 27/28 (1.0.0: "best correlation for Poisson ratio 0.5,
Kaneko 1975"; the 0.2 releases used 4/3). The suite does not trust this note: it builds a PyElastica rod
and reads alpha_c = S_11/(G A) and the mass second moment back from it (``pyelastica.alpha_c`` and
``pyelastica.mass_second_moment_over_rho_dl`` in the results).

Parts:

* **static** - the cantilever under a dead tip load P perpendicular to it, P L^2/EI = 10, rod along +x:
  tip displacement error against wall time over each discretisation ladder: mechgen's ``rod_statics`` by
  Lie-group midpoint collocation (elements 10 .. 640, order 2) and by RKMK4 shooting (steps 5 .. 160, order
  4), and PyElastica's static limit (a damped run until max |v| < REST_TOL m/s) over n_elem 10 .. 160 at
  its stable dt. All three solve the same extensible, shearable rod (PyElastica's section:
  EA/EI = 4/r^2 = 4e4, GA/EI = 1.29e4 at r = 0.01). Reference: mechgen RKMK4 shooting of that rod at
  REFERENCE_STEPS steps (its own distance to half the steps is reported). The reference solver is
  validated independently: Bisshopp & Drucker's elliptic-integral solution of the inextensible
  cantilever (Q. Appl. Math. 3 (1945) 272; :func:`elastica`, scipy's ellipk/ellipkinc/ellipe/ellipeinc and
  a root solve) reproduces Mattiasson's table (Int. J. Numer. Meth. Eng. 17 (1981) 145, PL^2/EI = 10:
  (L - x)/L = 0.55500, y/L = -0.81061), and mechgen's shooting of a nearly inextensible rod (EA/EI = GA/EI
  = 1e8) matches it. Error: max(|x - x_ref|, |y - y_ref|)/L of the tip.
* **dynamic** (``mechgen.rod_dynamics``; skipped with a message where it is missing): the same cantilever
  released from straight under a step tip load (P L^2/EI = DYN_LOAD), undamped, to DYN_T_END. Error of a
  run: max over the run of |tip(t) - tip_ref(t)| / max |tip deflection of the reference|, the reference
  being mechgen's finest run (DYN_REF_ELEMENTS elements, half its smallest dt; its distance to half the
  elements is reported). mechgen runs over N x dt ladders (implicit midpoint, dt from t_end/25), PyElastica
  over an N ladder, each N at its largest dt on DT_FACTORS x Section.stable_dt that neither blows up nor
  loses accuracy (error <= 1.1 x that at the smallest factor; generous to the peer). Reported: the two
  codes' agreement at the same N (the same measure); the ratio at the same resolution (mechgen's fastest
  dt at N = ``elements`` whose error is at most PyElastica's there) and at matched accuracy across
  resolutions (each side's least time for an error at most PyElastica's finest).
* **gravity**: the same comparison for scenes/rod_dynamics.toml's soft rod (L = 1 m, r = 2.5 cm, rho = 1000
  kg/m^3, E = 10 MPa, G = E/3) released under gravity (9.81 m/s^2 along -y) to GRAVITY_T_END, N = 40 as in
  the scene, with PyElastica's GravityForces; GA = alpha_c G A with PyElastica's alpha_c on both sides (the
  scene's comment says 4/3, PyElastica 1.0.0 has 27/28).
* **stiff** (needs ``mechgen.rod_dynamics``): E (and G) 100 times larger: PyElastica's explicit step must
  stay below dl sqrt(rho/max(E, G)) (and the section's shear-rotation mode, 2/omega_rot, omega_rot =
  sqrt(alpha_c G A/(rho I))); it is run at 0.5 and at STIFF_OVER times that limit (the second blows up:
  non-finite or |tip| > 1.5 L), while mechgen's implicit step runs at dt far above it (70 .. 1100 x the
  limit). The same step load P L^2/EI = DYN_LOAD, to 0.2 s (about one period of the first mode). Two
  comparisons: (a) ``times`` (not at equal accuracy): mechgen's fastest dt at N = 20 with a time error <=
  STIFF_ACCURACY against its own run at dt/4, same N, against PyElastica at 0.5 x its limit; (b)
  ``matched`` (equal accuracy, as for the dynamic case): every run's max tip error over the run /
  max deflection against a common reference, mechgen at STIFF_REF_ELEMENTS = 160 elements and dt =
  t_end/STIFF_REF_STEPS (1.95e-5 s; its distances to 80 elements and to twice the dt are reported as
  ``common_reference.self_convergence_*``), mechgen over an N x dt grid (N = 5 .. 40, ``grid``) and
  PyElastica over an N ladder (20 .. 160, ``pyelastica_ladder``, one run each at 0.5 x its limit at that N,
  first order in N); the target error is PyElastica's finest, each side's least time meeting it.

Every mechgen row of the dynamic, gravity and stiff ladders carries its Newton counts (``newton_iterations``,
``jacobians``, ``splits``: rod_dynamics' outputs), the work behind its time.

Newton's Jacobians (mechgen only): the AD ones (the default) against finite differences on the same
states, collocation, shooting and the dynamics step over an N ladder: seconds per Jacobian and their
difference (the FD error), in ``rods.json`` ("jacobians") and ``rods.md``.

Timing: one BLAS thread for both (common.blas_threads); PyElastica's numba functions compiled by an untimed
warm-up run first (its seconds reported); a PyElastica time is its stepping loop, a mechgen time the whole
public call (``mechgen.rod_statics`` / ``mechgen.rod_dynamics``: set-up and solve) on a compiled system. The
ladders (the work-precision points): mechgen the median of 3 runs after an untimed one, PyElastica one run each
(its runs are the long ones). Every ratio: the two runs it compares timed again, the median of 3 rounds in which
the two alternate, after an untimed call of each (:func:`interleaved_medians`; one round in quick mode). Writes
``rods_work_precision.{csv,png}`` (the static work-precision), ``rods_ratios.json`` (every ratio, = PyElastica
seconds / mechgen seconds at the condition stated), ``rods_dynamic_work_precision.{csv,png}`` (the dynamic,
gravity and stiff points, each with its reference), ``rods.json`` and ``rods.md``; ``quick``: tiny ladders
(about 15 s once numba's cache is warm; numba's first compilation of PyElastica adds about 10 s once).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechgen.bench.common import (blas_threads, environment, loglog_plot, suite_report, write_csv,
                                  write_json, write_text)

#: the PyElastica release the suite was written and measured against (pyproject's bench extra)
PYELASTICA_PIN = "1.0.0"
#: PyElastica 1.0.0's shear coefficient (elastica/rod/factory_function.py); the suite measures it too
ALPHA_C_PIN = 27.0 / 28.0
#: Mattiasson (1981), table 1, at P L^2/EI = 10: (L - x)/L, y/L (tip load along -y)
MATTIASSON_10 = (0.55500, -0.81061)
#: the static load P L^2/EI
STATIC_LOAD = 10.0
#: PyElastica's static limit: run (damped) until max |v| < REST_TOL (m/s), at most REST_T_MAX (s). 1e-6 m/s, not
#: 1e-9: the tip then differs from the 1e-9 one by at most 1.1e-7 L (measured at n_elem 10, 40, 160), against
#: PyElastica's own static errors of 5.5e-2 .. 3.2e-3 L there, and the run stops 1.3-1.6 s (of 4.3 s) earlier
REST_TOL = 1e-6
REST_T_MAX = 60.0
#: PyElastica's damping for the static limit (1/s; about twice the loaded rod's first frequency)
REST_DAMPING = 10.0
#: the dynamic step load P L^2/EI, the run's length (s; the first period of the unloaded rod is 1.79 s)
DYN_LOAD = 2.0
DYN_T_END = 1.0
DYN_REF_ELEMENTS = 160
#: the gravity case (scenes/rod_dynamics.toml): g (m/s^2) along -y, run length (s)
GRAVITY = 9.81
GRAVITY_T_END = 2.0
#: the stiff case: E and G times STIFF_FACTOR; PyElastica also run at STIFF_OVER times its stable limit
STIFF_FACTOR = 100.0
STIFF_OVER = 2.0
#: the stiff case's time comparison: mechgen's fastest run within this error of its own same-N reference
STIFF_ACCURACY = 1e-2
#: the stiff case's common reference: mechgen at STIFF_REF_ELEMENTS elements, dt = t_end/STIFF_REF_STEPS
STIFF_REF_ELEMENTS = 160
STIFF_REF_STEPS = 10240
#: the speed target at matched accuracy (issue 15)
TARGET = 5.0


@dataclass(frozen=True)
class Section:
    """A solid circular rod of length L (m), radius r (m), density rho (kg/m^3), moduli E, G (Pa)."""

    L: float
    r: float
    rho: float
    E: float
    G: float

    @property
    def A(self) -> float:
        return math.pi * self.r ** 2

    @property
    def I(self) -> float:  # noqa: E743 (the second moment of area, m^4)
        return self.A ** 2 / (4 * math.pi)

    def params(self, alpha_c: float = ALPHA_C_PIN) -> dict:
        """mechgen's ``cosserat_rod`` parameters of this section (the mapping in the module doc)."""
        A, I = self.A, self.I
        return {"L": self.L, "EA": self.E * A, "GA": alpha_c * self.G * A, "GJ": self.G * 2 * I, "EI": self.E * I,
                "rhoA": self.rho * A, "rhoI": self.rho * I, "rhoJ": self.rho * 2 * I}

    def stable_dt(self, n: int, alpha_c: float = ALPHA_C_PIN) -> float:
        """PyElastica's explicit limit (s): min(dl sqrt(rho/max(E, G)), 2/omega_rot), omega_rot = sqrt(alpha_c G
        A/(rho I)) the element's shear-rotation frequency (independent of dl: it binds when dl > ~r)."""
        wave = self.L / n * math.sqrt(self.rho / max(self.E, self.G))
        rot = 2.0 / math.sqrt(alpha_c * self.G * self.A / (self.rho * self.I))
        return min(wave, rot)


def base_section(stiff: float = 1.0) -> Section:
    """L = 1 m, r = 0.01 m, EI = stiff N m^2, rhoA = 1 kg/m, G = E/3 (PyElastica's default, nu = 0.5)."""
    r = 0.01
    A, I = math.pi * r ** 2, math.pi * r ** 4 / 4
    E = stiff / I
    return Section(L=1.0, r=r, rho=1.0 / A, E=E, G=E / 3)


# -- the elliptic-integral reference ----------------------------------------------------------------------------
def elastica(alpha: float) -> tuple[float, float, float]:
    """Bisshopp & Drucker's inextensible cantilever under a dead tip load P (alpha = P L^2/EI):
    ((L - x)/L, y/L (along the load), tip angle phi) with sqrt(alpha) = K(k) - F(psi0, k), k^2 = (1 + sin phi)/2,
    sin psi0 = 1/(k sqrt 2), x/L = sqrt(2 sin phi/alpha), y/L = 1 - 2 (E(k) - E(psi0, k))/sqrt(alpha)."""
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

    def gap(phi):
        m = (1 + math.sin(phi)) / 2
        return ellipk(m) - ellipkinc(math.asin(1 / math.sqrt(2 * m)), m) - math.sqrt(alpha)

    phi = brentq(gap, 1e-12, math.pi / 2 - 1e-13, xtol=1e-15)
    m = (1 + math.sin(phi)) / 2
    psi0 = math.asin(1 / math.sqrt(2 * m))
    x = math.sqrt(2 * math.sin(phi) / alpha)
    y = 1 - 2 / math.sqrt(alpha) * (ellipe(m) - ellipeinc(psi0, m))
    return 1 - x, y, phi


# -- PyElastica ---------------------------------------------------------------------------------------------------
def pyelastica_version() -> str | None:
    """The installed pyelastica's version, or None."""
    try:
        from importlib.metadata import PackageNotFoundError, version
        return version("pyelastica")
    except PackageNotFoundError:
        return None


def _elastica():
    import elastica as ea
    from elastica.timestepper.symplectic_steppers import PositionVerlet

    class Simulator(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    return ea, Simulator, PositionVerlet


def pyelastica_rod(sec: Section, n: int):
    """A straight PyElastica rod from the origin along +x (normal +z), n elements."""
    ea, _, _ = _elastica()
    return ea.CosseratRod.straight_rod(n, np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]),
                                       sec.L, sec.r, sec.rho, youngs_modulus=sec.E, shear_modulus=sec.G)


def pyelastica_section_check(sec: Section) -> dict:
    """alpha_c = S_11/(G A) and the mass second moment / (rho dl) (expected diag(I, I, 2I)) read back from a
    PyElastica rod, with PyElastica's EA, EI, GJ against the mapping's."""
    rod = pyelastica_rod(sec, 4)
    dl = sec.L / 4
    S, B, Jm = rod.shear_matrix[:, :, 0], rod.bend_matrix[:, :, 0], rod.mass_second_moment_of_inertia[:, :, 0]
    p = sec.params(S[0, 0] / (sec.G * sec.A))
    return {"alpha_c": float(S[0, 0] / (sec.G * sec.A)), "EA_rel_diff": float(S[2, 2] / p["EA"] - 1),
            "EI_rel_diff": float(B[0, 0] / p["EI"] - 1), "GJ_rel_diff": float(B[2, 2] / p["GJ"] - 1),
            "mass_second_moment_over_rho_dl": [float(Jm[i, i] / (sec.rho * dl)) for i in range(3)],
            "I": sec.I, "J": 2 * sec.I}


def pyelastica_cantilever(sec: Section, n: int, *, tip_force, dt: float, t_end: float, damping: float = 0.0,
                          save_every: int = 1, rest_tol: float | None = None, check_every: int = 500,
                          gravity=(0.0, 0.0, 0.0)) -> dict:
    """PyElastica's clamped cantilever (``OneEndFixedBC`` at node 0, tip force on the last node, ``GravityForces``
    with ``gravity`` (m/s^2) where it is not zero) stepped by
    PositionVerlet at dt (s) to t_end (s), or, with ``rest_tol``, until max |v| < rest_tol (m/s; checked every
    ``check_every`` steps). Returns t (s), tip_trajectory ([x, y, z] every ``save_every`` steps, m),
    tip_position, wall_s (the stepping loop), steps, blew_up (non-finite or |tip| > BLOWN L) and t_blew_up."""
    ea, Simulator, PositionVerlet = _elastica()
    sim = Simulator()
    rod = pyelastica_rod(sec, n)
    sim.append(rod)
    sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))
    sim.add_forcing_to(rod).using(ea.EndpointForces, np.zeros(3), np.array(tip_force, dtype=float),
                                  ramp_up_time=1e-300)
    if any(gravity):
        sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array(gravity, dtype=float))
    if damping > 0:
        sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=damping, time_step=dt)
    sim.finalize()
    stepper = PositionVerlet()
    steps = int(round(t_end / dt))
    t, dt64 = np.float64(0.0), np.float64(dt)
    ts, traj = [0.0], [rod.position_collection[:, -1].copy()]
    blew = None
    start = time.perf_counter()
    k = 0
    while k < steps:
        t = stepper.step(sim, t, dt64)
        k += 1
        if k % save_every == 0:
            ts.append(float(t))
            traj.append(rod.position_collection[:, -1].copy())
        if k % check_every == 0:
            tip = rod.position_collection[:, -1]
            if not np.all(np.isfinite(tip)) or np.linalg.norm(tip) > BLOWN * sec.L:
                blew = float(t)
                break
            if rest_tol is not None and np.max(np.abs(rod.velocity_collection)) < rest_tol:
                break
    wall = time.perf_counter() - start
    tip = rod.position_collection[:, -1].copy()
    if blew is None and (not np.all(np.isfinite(tip)) or np.linalg.norm(tip) > BLOWN * sec.L):
        blew = float(t)
    return {"t": ts, "tip_trajectory": np.array(traj), "tip_position": tip, "wall_s": wall, "steps": k, "dt": dt,
            "blew_up": blew is not None, "t_blew_up": blew,
            "max_speed": float(np.max(np.abs(rod.velocity_collection)))}


#: a run has blown up when its tip is farther than BLOWN x L from the clamp (an intact rod's is within ~L)
BLOWN = 1.5
#: the factors of Section.stable_dt tried by :func:`stable_runs`
DT_FACTORS = (0.5, 0.7, 1.0, 1.4, 2.0, 2.8, 4.0)


def stable_runs(sec: Section, n: int, force, t_end: float, save_dt: float, gravity=(0.0, 0.0, 0.0)) -> list[dict]:
    """PyElastica's runs to t_end at dt = DT_FACTORS x Section.stable_dt(n), up to and including the first that
    blows up (each a :func:`pyelastica_cantilever` result with its ``factor``)."""
    limit = sec.stable_dt(n)
    runs = []
    for factor in DT_FACTORS:
        dt = factor * limit
        run = pyelastica_cantilever(sec, n, tip_force=force, dt=dt, t_end=t_end,
                                    save_every=max(1, int(round(save_dt / dt))), check_every=20, gravity=gravity)
        runs.append({**run, "factor": factor})
        if run["blew_up"]:
            break
    return runs


def pyelastica_warmup() -> float:
    """Seconds of a tiny untimed PyElastica run (numba compiles or loads its cache)."""
    start = time.perf_counter()
    pyelastica_cantilever(base_section(), 4, tip_force=[0.0, -1.0, 0.0], dt=1e-5, t_end=1e-4, damping=1.0,
                          check_every=5)
    return time.perf_counter() - start


# -- mechgen ------------------------------------------------------------------------------------------------------
def _system(params: dict):
    """The compiled ``cosserat_rod`` (C backend) at ``params``; rhoI, rhoJ left out where the model has none
    (before rod dynamics: statics need no inertia)."""
    import mechgen

    known = {p.name for p in mechgen.load_model("cosserat_rod").param_list}
    return mechgen.compile("cosserat_rod", params={k: v for k, v in params.items() if k in known}, backend="c")


def _timed_median(fn, repeats: int):
    """(median seconds of ``repeats`` timed calls of ``fn`` after one untimed call, its result)."""
    result = fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), result


def interleaved_medians(ours, theirs, repeats: int) -> tuple[float, float]:
    """(median seconds of ``ours``, median of ``theirs``'s own seconds) over ``repeats`` rounds after one untimed
    call of each, the two alternating in every round: ``ours`` is timed here (mechgen's whole public call),
    ``theirs`` returns its seconds (PyElastica's stepping loop, its set-up left out)."""
    ours()
    theirs()
    mine, peer = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        ours()
        mine.append(time.perf_counter() - start)
        peer.append(float(theirs()))
    return float(np.median(mine)), float(np.median(peer))


def retimed(entry: dict, ours, theirs, repeats: int) -> dict:
    """``entry`` (a comparison with mechgen_s, pyelastica_s) with both sides timed again by
    :func:`interleaved_medians` and its ratio from those times."""
    mine, peer = interleaved_medians(ours, theirs, repeats)
    return {**entry, "mechgen_s": mine, "pyelastica_s": peer, "ratio": peer / mine,
            "statistic": f"median of {repeats} interleaved rounds, each side's first call untimed"}


def _tip_error(tip, ref, L: float) -> float:
    return float(max(abs(tip[0] - ref[0]), abs(tip[1] - ref[1]))) / L


def static_study(quick: bool, repeats: int, have_elastica: bool) -> dict:
    """The static part (module doc): rows of mechgen and PyElastica tip errors against wall time."""
    import mechgen

    sec = base_section()
    P = STATIC_LOAD * sec.params()["EI"] / sec.L ** 2
    force = [0.0, -P, 0.0]
    system = _system(sec.params())

    def statics(method, n, sys_=system):
        return mechgen.rod_statics(sys_, tip_force=force, elements=n, method=method, steps=5)["tip_position"]

    ref_steps = 40 if quick else 320
    ref = statics("shooting", ref_steps)
    half = statics("shooting", ref_steps // 2)
    # validation of the reference solver: the elliptic solution against Mattiasson, and mechgen's shooting of
    # a nearly inextensible rod against the elliptic solution
    u, v, phi = elastica(STATIC_LOAD)
    stiff_sys = _system({"L": 1.0, "EI": 1.0, "GJ": 1.0, "EA": 1e8, "GA": 1e8})
    inext = mechgen.rod_statics(stiff_sys, tip_force=[0.0, -STATIC_LOAD, 0.0], elements=20 if quick else 80,
                                method="shooting", steps=5)["tip_position"]
    validation = {"elliptic_(L-x)/L": u, "elliptic_y/L": -v, "elliptic_tip_angle": phi,
                  "mattiasson_10": list(MATTIASSON_10),
                  "elliptic_minus_mattiasson": [u - MATTIASSON_10[0], -v - MATTIASSON_10[1]],
                  "mechgen_shooting_EA_GA_1e8_minus_elliptic": [1 - inext[0] - u, inext[1] + v],
                  "reference_minus_elliptic": [1 - ref[0] - u, ref[1] + v],
                  "reference_self_convergence": _tip_error(ref, half, sec.L)}
    rows = []
    ladders = {"collocation": (10, 20, 40) if quick else (10, 20, 40, 80, 160, 320, 640),
               "shooting": (5, 10) if quick else (5, 10, 20, 40, 80, 160)}
    for method, ns in ladders.items():
        for n in ns:
            seconds, tip = _timed_median(lambda: statics(method, n), repeats)
            rows.append({"side": f"mechgen {method}", "n": n, "seconds": seconds,
                         "error": _tip_error(tip, ref, sec.L), "tip": list(tip)})
    pyel = []
    if have_elastica:
        for n in ((10, 20) if quick else (10, 20, 40, 80, 160)):
            dt = 0.5 * sec.stable_dt(n)
            run = pyelastica_cantilever(sec, n, tip_force=force, dt=dt, t_end=REST_T_MAX, damping=REST_DAMPING,
                                        rest_tol=REST_TOL)
            pyel.append({"side": "PyElastica static limit", "n": n, "seconds": run["wall_s"],
                         "error": _tip_error(run["tip_position"], ref, sec.L), "tip": list(run["tip_position"]),
                         "dt": dt, "steps": run["steps"], "t_rest": run["steps"] * dt,
                         "max_speed_end": run["max_speed"], "blew_up": run["blew_up"]})
    headline = None
    ours = [r for r in rows if r["side"] == "mechgen collocation" and pyel and r["error"] <= pyel[-1]["error"]]
    if ours:  # the like-for-like ratio: both chosen runs timed again, interleaved
        finest = pyel[-1]
        headline = retimed({"mechgen_n": ours[0]["n"], "pyelastica_n": finest["n"]},
                           lambda: statics("collocation", ours[0]["n"]),
                           lambda: pyelastica_cantilever(sec, finest["n"], tip_force=force, dt=finest["dt"],
                                                         t_end=REST_T_MAX, damping=REST_DAMPING,
                                                         rest_tol=REST_TOL)["wall_s"], repeats)
    return {"section": sec.__dict__, "params": sec.params(), "tip_force": force, "reference_steps": ref_steps,
            "reference_tip": list(ref), "validation": validation, "rows": rows + pyel, "headline": headline,
            "orders": {side: _orders([r for r in rows + pyel if r["side"] == side])
                       for side in dict.fromkeys(r["side"] for r in rows + pyel)}}


def _orders(rows: list[dict]) -> list[float]:
    """Observed orders log2(e(n)/e(2n)) along a doubling ladder."""
    return [math.log(a["error"] / b["error"]) / math.log(b["n"] / a["n"])
            for a, b in zip(rows, rows[1:]) if a["error"] > 0 and b["error"] > 0]


# -- dynamics -----------------------------------------------------------------------------------------------------
def _dynamics_available() -> bool:
    import mechgen

    return hasattr(mechgen, "rod_dynamics")


#: the Newton counts of a mechgen run that the dynamic ladders report beside its time (rod_dynamics outputs)
NEWTON_COUNTS = ("newton_iterations", "jacobians", "splits")


def _mechgen_dynamic(system, n: int, dt: float, t_end: float, force, save_every: int = 1) -> dict:
    import mechgen

    res = mechgen.rod_dynamics(system, elements=n, dt=dt, t_end=t_end, tip_force=force, damping=0.0,
                               save_every=save_every)
    return {"t": np.asarray(res.outputs["t"], dtype=float),
            "tip_trajectory": np.asarray(res.outputs["tip_trajectory"], dtype=float),
            "energy_error": float(np.max(np.abs(np.asarray(res.outputs["energy_error"], dtype=float)))),
            "orthonormality_error": float(np.max(res.outputs["orthonormality_error"])),
            "newton": {key: int(res.outputs[key]) for key in NEWTON_COUNTS}}


def _traj_error(t, tip, t_ref, tip_ref, scale: float) -> float:
    """max over the run of |tip(t) - tip_ref(t)| / scale, the reference interpolated linearly onto t."""
    ref = np.stack([np.interp(t, t_ref, tip_ref[:, i]) for i in range(3)], axis=1)
    return float(np.max(np.linalg.norm(tip - ref, axis=1))) / scale


def _fastest(rows: list[dict], bound: float) -> dict | None:
    """The least-time row whose error is at most ``bound`` (None if none)."""
    ok = [r for r in rows if r.get("error") is not None and r["error"] <= bound]
    return min(ok, key=lambda r: r["seconds"]) if ok else None


def scene_section() -> Section:
    """scenes/rod_dynamics.toml's soft rod: L = 1 m, r = 2.5 cm, rho = 1000 kg/m^3, E = 10 MPa, G = E/3."""
    return Section(L=1.0, r=0.025, rho=1000.0, E=1.0e7, G=1.0e7 / 3)


def dynamic_study(quick: bool, repeats: int, have_elastica: bool, case: str = "tip_load") -> dict:
    """The dynamic part (module doc): mechgen over N x dt ladders, PyElastica over an N ladder at its largest
    unspoiled stable dt; the same-resolution comparison at N = ``elements`` and the matched-accuracy one
    across resolutions (target: PyElastica's finest error). ``case``: "tip_load" (base_section, a step tip
    load P L^2/EI = DYN_LOAD, DYN_T_END, N = 20) or "gravity" (scenes/rod_dynamics.toml's rod released under
    g = 9.81 m/s^2 along -y, to 2 s, N = 40 as in the scene)."""
    if case == "gravity":
        sec = scene_section()
        params = {**sec.params(), "g_y": -GRAVITY}
        force, gravity = [0.0, 0.0, 0.0], (0.0, -GRAVITY, 0.0)
        t_end = 0.5 if quick else GRAVITY_T_END
        n = 10 if quick else 40
        ours_n = (10,) if quick else (10, 20, 40)
    else:
        sec = base_section()
        params = sec.params()
        force, gravity = [0.0, -DYN_LOAD * params["EI"] / sec.L ** 2, 0.0], (0.0, 0.0, 0.0)
        t_end = 0.25 if quick else DYN_T_END
        n = 10 if quick else 20
        ours_n = (10,) if quick else (10, 20, 40)
    system = _system(params)
    peer_n = (10, 20) if quick else (20, 40, 80, 160)
    ref_n = 40 if quick else DYN_REF_ELEMENTS
    dts = (t_end / 20, t_end / 40) if quick else tuple(t_end / k for k in (25, 50, 100, 200, 400, 800))
    ref_dt = dts[-1] / 2
    ref = _mechgen_dynamic(system, ref_n, ref_dt, t_end, force)
    half = _mechgen_dynamic(system, ref_n // 2, ref_dt, t_end, force)
    t_ref, tip_ref = ref["t"], ref["tip_trajectory"]
    scale = float(np.max(np.linalg.norm(tip_ref - tip_ref[0], axis=1)))
    rows, runs_at_n = [], {}
    for m in ours_n:
        for dt in dts:
            seconds, run = _timed_median(lambda: _mechgen_dynamic(system, m, dt, t_end, force), repeats)
            steps = int(round(t_end / dt))
            rows.append({"side": f"mechgen N={m}", "n": m, "dt": dt, "seconds": seconds, "steps": steps,
                         "seconds_per_step": seconds / steps,
                         "error": _traj_error(run["t"], run["tip_trajectory"], t_ref, tip_ref, scale),
                         "energy_error": run["energy_error"], "orthonormality_error": run["orthonormality_error"],
                         **run["newton"]})
            if m == n:
                runs_at_n[dt] = run
    out = {"case": case, "section": sec.__dict__, "params": params, "tip_force": force, "gravity": list(gravity),
           "t_end": t_end, "elements": n,
           "reference": {"elements": ref_n, "dt": ref_dt, "max_tip_deflection": scale,
                         "self_convergence_half_elements": _traj_error(half["t"], half["tip_trajectory"], t_ref,
                                                                       tip_ref, scale)}}
    def pair(mine: dict, peer: dict) -> tuple:
        """(mechgen's run, PyElastica's run) of two chosen rows, to be timed again."""
        return (lambda: _mechgen_dynamic(system, mine["n"], mine["dt"], t_end, force),
                lambda: pyelastica_cantilever(sec, peer["n"], tip_force=force, dt=peer["dt"], t_end=t_end,
                                              save_every=max(1, int(round(dts[-1] / peer["dt"]))), check_every=20,
                                              gravity=gravity)["wall_s"])

    if have_elastica:
        peers, searches, same_run = [], {}, None
        for m in peer_n:
            # the peer's dt, generous to it: the largest on the ladder that neither blows up nor has an error
            # over 1.1 x that of the smallest dt tried (an accuracy not yet spoiled by the step)
            runs = stable_runs(sec, m, force, t_end, dts[-1], gravity)
            for run in runs:
                run["error"] = None if run["blew_up"] else _traj_error(np.asarray(run["t"]), run["tip_trajectory"],
                                                                         t_ref, tip_ref, scale)
            ok = [run for run in runs if run["error"] is not None and run["error"] <= 1.1 * runs[0]["error"]]
            if not ok:
                raise RuntimeError(f"PyElastica blew up at every dt tried down to {runs[0]['dt']:.3g} s (N = {m})")
            peer = max(ok, key=lambda run: run["dt"])
            searches[m] = [{"dt": run["dt"], "factor": run["factor"], "blew_up": run["blew_up"],
                            "error": run["error"], "seconds": run["wall_s"]} for run in runs]
            peers.append({"side": "PyElastica", "n": m, "dt": peer["dt"], "seconds": peer["wall_s"],
                          "error": peer["error"], "steps": peer["steps"],
                          "seconds_per_step": peer["wall_s"] / peer["steps"], "blew_up": False})
            if m == n:
                same_run = peer
        out["pyelastica_dt_search"] = searches
        out["pyelastica"] = peers
        out["pyelastica_orders"] = _orders(peers)
        if same_run is not None:
            for r in rows:
                if r["n"] == n:
                    run = runs_at_n[r["dt"]]
                    r["agreement_with_pyelastica"] = _traj_error(np.asarray(same_run["t"]), same_run["tip_trajectory"],
                                                                 run["t"], run["tip_trajectory"], scale)
            theirs = next(p for p in peers if p["n"] == n)
            best = _fastest([r for r in rows if r["n"] == n], theirs["error"])
            out["same_resolution"] = None if best is None else retimed({
                "elements": n, "mechgen_dt": best["dt"], "mechgen_error": best["error"],
                "pyelastica_dt": theirs["dt"], "pyelastica_error": theirs["error"],
                "dt_ratio": best["dt"] / theirs["dt"]}, *pair(best, theirs), repeats)
        target = peers[-1]["error"]
        ours, theirs = _fastest(rows, target), _fastest(peers, target)
        out["matched"] = None if ours is None or theirs is None else retimed({
            "target_error": target, "mechgen_n": ours["n"], "mechgen_dt": ours["dt"], "mechgen_error": ours["error"],
            "pyelastica_n": theirs["n"], "pyelastica_dt": theirs["dt"], "pyelastica_error": theirs["error"],
            "dt_ratio": ours["dt"] / theirs["dt"],
            "mechgen_is_coarsest": ours["n"] == min(ours_n) and ours["dt"] == max(dts)}, *pair(ours, theirs), repeats)
    out["rows"] = rows
    return out


def stiff_study(quick: bool, repeats: int, have_elastica: bool) -> dict:
    """The stiff part (module doc): E, G x STIFF_FACTOR, a step tip load P L^2/EI = DYN_LOAD to t_end.

    Two comparisons. ``rows``/``pyelastica``/``times``: mechgen at N = ``elements`` against its own run at
    dt/4 (time error only) and PyElastica at 0.5, STIFF_OVER (and the wave limit's) times its limit at that N.
    ``grid``/``pyelastica_ladder``/``matched``: every run's max tip error over the run against a common
    reference, mechgen at STIFF_REF_ELEMENTS elements and dt = t_end/STIFF_REF_STEPS (its distance to half the
    elements and to twice the dt reported: ``common_reference``), over mechgen's N x dt grid and PyElastica's N
    ladder at 0.5 x Section.stable_dt(N); ``matched``: each side's least time for an error at most
    PyElastica's finest."""
    sec = base_section(STIFF_FACTOR)
    params = sec.params()
    system = _system(params)
    P = DYN_LOAD * params["EI"] / sec.L ** 2
    force = [0.0, -P, 0.0]
    n = 10 if quick else 20
    t_end = 0.05 if quick else 0.2
    limit = sec.stable_dt(n)
    out = {"section": sec.__dict__, "params": params, "elements": n, "t_end": t_end, "pyelastica_limit_dt": limit,
           "wave_limit_dt": sec.L / n * math.sqrt(sec.rho / max(sec.E, sec.G))}
    dts = (t_end / 10, t_end / 20) if quick else tuple(t_end / k for k in (20, 40, 80, 160, 320))
    ours_n = (10, 20) if quick else (5, 10, 20, 40)
    peer_n = (10, 20) if quick else (20, 40, 80, 160)
    # the common reference and its self-convergence (half the elements; twice the dt)
    ref_n = 40 if quick else STIFF_REF_ELEMENTS
    ref_dt = t_end / (320 if quick else STIFF_REF_STEPS)
    common = _mechgen_dynamic(system, ref_n, ref_dt, t_end, force)
    t_c, tip_c = common["t"], common["tip_trajectory"]
    c_scale = float(np.max(np.linalg.norm(tip_c - tip_c[0], axis=1)))
    half_n = _mechgen_dynamic(system, ref_n // 2, ref_dt, t_end, force)
    double_dt = _mechgen_dynamic(system, ref_n, 2 * ref_dt, t_end, force)
    out["common_reference"] = {
        "elements": ref_n, "dt": ref_dt, "steps": int(round(t_end / ref_dt)), "max_tip_deflection": c_scale,
        "dt_over_pyelastica_limit": ref_dt / sec.stable_dt(ref_n),
        "self_convergence_half_elements": _traj_error(half_n["t"], half_n["tip_trajectory"], t_c, tip_c, c_scale),
        "self_convergence_double_dt": _traj_error(double_dt["t"], double_dt["tip_trajectory"], t_c, tip_c, c_scale),
        "energy_error": common["energy_error"], "orthonormality_error": common["orthonormality_error"]}
    # the same-N comparison's reference (time error only)
    ref = _mechgen_dynamic(system, n, dts[-1] / 4, t_end, force)
    scale = float(np.max(np.linalg.norm(ref["tip_trajectory"] - ref["tip_trajectory"][0], axis=1)))
    rows, grid = [], []
    for m in ours_n:
        for dt in dts:
            seconds, run = _timed_median(lambda: _mechgen_dynamic(system, m, dt, t_end, force), repeats)
            steps = int(round(t_end / dt))
            grid.append({"side": f"mechgen N={m}", "n": m, "dt": dt, "dt_over_pyelastica_limit": dt / sec.stable_dt(m),
                         "seconds": seconds, "steps": steps, "seconds_per_step": seconds / steps,
                         "energy_error": run["energy_error"], "orthonormality_error": run["orthonormality_error"],
                         "error": _traj_error(run["t"], run["tip_trajectory"], t_c, tip_c, c_scale), **run["newton"]})
            if m == n:
                rows.append({"side": f"stiff mechgen N={n}", "n": n, "dt": dt, "dt_over_pyelastica_limit": dt / limit,
                             "seconds": seconds, "energy_error": run["energy_error"],
                             "error": _traj_error(run["t"], run["tip_trajectory"], ref["t"], ref["tip_trajectory"],
                                                  scale)})
    out["reference"] = {"elements": n, "dt": dts[-1] / 4, "max_tip_deflection": scale,
                        "note": "the same N (time error only)"}
    out["grid"] = grid
    c_dt = dts[-1]

    def pair(mine: dict, peer: dict, save_dt: float = c_dt) -> tuple:
        """(mechgen's run, PyElastica's run) of two chosen rows, to be timed again (PyElastica at its dt to
        t_end: a stable run)."""
        return (lambda: _mechgen_dynamic(system, mine["n"], mine["dt"], t_end, force),
                lambda: pyelastica_cantilever(sec, peer["n"], tip_force=force, dt=peer["dt"], t_end=t_end,
                                              save_every=max(1, int(round(save_dt / peer["dt"]))),
                                              check_every=20)["wall_s"])

    if have_elastica:
        peer, stable_at_n = [], None
        wave = out["wave_limit_dt"]
        for factor in (0.5, STIFF_OVER) + ((wave / limit,) if wave > STIFF_OVER * limit else ()):
            dt = factor * limit
            t_run = t_end if factor < 1 else min(t_end, 2000 * dt)
            run = pyelastica_cantilever(sec, n, tip_force=force, dt=dt, t_end=t_run,
                                        save_every=max(1, int(round(dts[-1] / dt))), check_every=20)
            err = None if run["blew_up"] else _traj_error(np.asarray(run["t"]), run["tip_trajectory"], ref["t"],
                                                          ref["tip_trajectory"], scale)
            peer.append({"side": f"stiff PyElastica N={n}", "n": n, "dt": dt, "dt_over_limit": factor,
                         "dt_over_wave_limit": dt / wave,
                         "seconds": run["wall_s"], "steps": run["steps"], "blew_up": run["blew_up"],
                         "t_blew_up": run["t_blew_up"], "t_run": t_run, "error": err})
            if factor == 0.5:
                stable_at_n = run
        out["pyelastica"] = peer
        ours = _fastest(rows, STIFF_ACCURACY)
        if ours is not None and not peer[0]["blew_up"]:
            out["times"] = retimed({"mechgen_dt": ours["dt"], "mechgen_error": ours["error"],
                                    "pyelastica_dt": peer[0]["dt"], "pyelastica_error": peer[0]["error"],
                                    "dt_ratio": ours["dt"] / peer[0]["dt"]}, *pair(ours, peer[0]), repeats)
        # PyElastica's N ladder at 0.5 x its limit (the run at N = elements above is reused), one run each
        ladder = []
        for m in peer_n:
            dt = 0.5 * sec.stable_dt(m)
            run = stable_at_n if m == n else pyelastica_cantilever(
                sec, m, tip_force=force, dt=dt, t_end=t_end, save_every=max(1, int(round(dts[-1] / dt))),
                check_every=20)
            err = None if run["blew_up"] else _traj_error(np.asarray(run["t"]), run["tip_trajectory"], t_c, tip_c,
                                                          c_scale)
            ladder.append({"side": "PyElastica", "n": m, "dt": dt, "dt_over_limit": 0.5, "seconds": run["wall_s"],
                           "steps": run["steps"], "seconds_per_step": run["wall_s"] / max(run["steps"], 1),
                           "blew_up": run["blew_up"], "error": err})
        out["pyelastica_ladder"] = ladder
        fine = [r for r in ladder if r["error"] is not None]
        out["pyelastica_orders"] = _orders(fine)
        if fine:
            target = fine[-1]["error"]
            mine, theirs = _fastest(grid, target), _fastest(fine, target)
            out["matched"] = None if mine is None or theirs is None else retimed({
                "target_error": target, "mechgen_n": mine["n"], "mechgen_dt": mine["dt"],
                "mechgen_error": mine["error"], "pyelastica_n": theirs["n"],
                "pyelastica_dt": theirs["dt"], "pyelastica_error": theirs["error"],
                "dt_ratio": mine["dt"] / theirs["dt"],
                "mechgen_dt_over_pyelastica_limit": mine["dt_over_pyelastica_limit"],
                "mechgen_is_coarsest": mine["n"] == min(ours_n) and mine["dt"] == max(dts),
                "mechgen_at_coarsest_n": mine["n"] == min(ours_n),
                "mechgen_coarsest_meets_target": any(r["n"] == min(ours_n) and r["dt"] == max(dts)
                                                     and r["error"] <= target for r in grid)},
                *pair(mine, theirs, c_dt), repeats)
    out["rows"] = rows
    return out


def jacobian_study(quick: bool, repeats: int) -> dict:
    """Newton's Jacobians by AD (the default) against finite differences, on the same states: the time of
    one Jacobian (best of ``repeats``) and their largest difference relative to the AD one (the FD error).
    Collocation and shooting at the static tip load's converged state (PL^2/EI = 10), the dynamics step
    of the gravity case's rod at its reference state with a nonzero increment."""
    from mechgen.analyses.rod_statics import rod_of
    from mechgen.runtime.rods import dynamics as dyn
    from mechgen.runtime.rods import statics as rs

    sec = base_section()
    system = _system(sec.params())
    EI = sec.params()["EI"]
    options = {"tip_force": [0.0, -STATIC_LOAD * EI / sec.L**2, 0.0], "tip_torque": [0.0, 0.0, 0.0],
               "base": "clamped", "tip": "free"}
    rod = rod_of(system, options)
    rows = []

    def timed(kind: str, n: int, ad_fn, fd_fn, dense):
        ad_fn(), fd_fn()                                      # builds, compiles, caches
        t_ad, a = _timed_median(ad_fn, repeats)
        t_fd, f = _timed_median(fd_fn, repeats)
        a, f = dense(a), dense(f)
        rows.append({"piece": kind, "n": n, "ad_s": t_ad, "fd_s": t_fd, "ratio": t_fd / t_ad,
                     "fd_minus_ad": float(np.max(np.abs(f - a)) / np.max(np.abs(a)))})

    for n in ((10, 40) if quick else (40, 160, 640)):
        state = rs.solve_statics(rod, method="collocation", elements=n).final
        r0 = rs.collocation_residual(rod, state.H, state.sigma, 1.0)
        timed("collocation", n, lambda: rs.collocation_jacobian(rod, state.H, state.sigma, 1.0),
              lambda: rs.collocation_jacobian(rod, state.H, state.sigma, 1.0, r0, method="fd"),
              lambda J: J.toarray())
    for n in ((10,) if quick else (40, 160)):
        z = rs.shoot(rod, n, 1.0, np.zeros(12))
        z = np.zeros(12) if z is None else z[0]
        timed("shooting", n, lambda: rs.shooting_jacobian(rod, z, n, 1.0)[1],
              lambda: rs.shooting_jacobian_fd(rod, z, n, 1.0)[1], lambda J: J)
    if _dynamics_available():
        body_sys = _system(scene_section().params())
        drod = rod_of(body_sys, {**options, "tip_force": [0.0, 0.0, 0.0]})
        M = np.asarray(body_sys.call("rod", f=np.array([drod.f0]), r=np.zeros((1, 3)))["M"], dtype=float).reshape(6, 6)
        for n in ((10,) if quick else (20, 80, 320)):
            disc = dyn.Discrete(dyn.RodBody(drod, M), n)
            st0 = dyn.reference_state(disc.body, n)
            z = 1e-3 * np.random.default_rng(0).normal(size=(n + 1, 6))
            r0 = disc.residual(st0, z, 0.005)[0]
            timed("dynamics step", n, lambda: disc.jacobian_band(st0, z, 0.005),
                  lambda: disc.jacobian_band(st0, z, 0.005, r0, method="fd"), lambda J: J)
    return {"rows": rows}


# -- the suite ------------------------------------------------------------------------------------------------------
def markdown(results: dict) -> str:
    """The suite's report as Markdown tables."""
    st = results["static"]
    pe = results["pyelastica"]
    lines = ["# Cosserat rod: mechgen against PyElastica", "",
             f"PyElastica: {pe if isinstance(pe, str) else 'pyelastica ' + pe['version'] + ', alpha_c = ' + format(pe['alpha_c'], '.6g')}",
             "", "## Static tip load, P L^2/EI = 10", "",
             f"Reference: mechgen RKMK4 shooting, {st['reference_steps']} steps, of the same extensible rod "
             f"(EA = {st['params']['EA']:.4g} N, GA = {st['params']['GA']:.4g} N, EI = {st['params']['EI']:.4g} N m^2); "
             f"self-convergence {st['validation']['reference_self_convergence']:.1e}; elliptic minus Mattiasson "
             f"{max(map(abs, st['validation']['elliptic_minus_mattiasson'])):.1e}; mechgen (EA = GA = 1e8 EI) minus "
             f"elliptic {max(map(abs, st['validation']['mechgen_shooting_EA_GA_1e8_minus_elliptic'])):.1e}.", "",
             "| side | n | seconds | error / L |", "|---|---|---|---|"]
    lines += [f"| {r['side']} | {r['n']} | {r['seconds']:.3g} | {r['error']:.2e} |" for r in st["rows"]]
    lines += ["", "Observed orders: " + "; ".join(f"{k}: {', '.join(f'{o:.2f}' for o in v)}"
                                                 for k, v in st["orders"].items())]
    for key, title in (("dynamic", "Dynamic step tip load"), ("gravity", "Released under gravity (scenes/rod_dynamics.toml's rod)"),
                       ("stiff", "Stiff rod (E x 100)")):
        part = results[key]
        lines += ["", f"## {title}", ""]
        if isinstance(part, str):
            lines.append(part)
            continue
        lines += ["| side | N | dt (s) | seconds | error | agreement with PyElastica |", "|---|---|---|---|---|---|"]
        for r in part["rows"] + (part.get("pyelastica") if isinstance(part.get("pyelastica"), list) else []):
            err = "blew up" if r.get("blew_up") else f"{r['error']:.2e}"
            agree = r.get("agreement_with_pyelastica")
            lines.append(f"| {r['side']} | {r['n']} | {r['dt']:.3g} | {r['seconds']:.3g} | {err} | "
                         f"{'' if agree is None else format(agree, '.2e')} |")
        if part.get("grid"):
            c = part["common_reference"]
            lines += ["", "The rows above: errors against mechgen's own run at dt/4, same N (time error only). "
                          f"Against a common reference, mechgen at N = {c['elements']}, dt {c['dt']:.3g} s "
                          f"(max tip deflection {c['max_tip_deflection']:.4g} m; its distance to N = "
                          f"{c['elements'] // 2}: {c['self_convergence_half_elements']:.1e}, to dt x 2: "
                          f"{c['self_convergence_double_dt']:.1e}):", "",
                      "| side | N | dt (s) | dt / PyElastica's limit at N | seconds | error |", "|---|---|---|---|---|---|"]
            for r in part["grid"] + part.get("pyelastica_ladder", []):
                err = "blew up" if r.get("blew_up") else f"{r['error']:.2e}"
                over = r.get("dt_over_pyelastica_limit", r.get("dt_over_limit"))
                lines.append(f"| {r['side']} | {r['n']} | {r['dt']:.3g} | {over:.3g} | {r['seconds']:.3g} | {err} |")
        if part.get("pyelastica_orders"):
            lines += ["", "PyElastica's observed orders in N: " + ", ".join(f"{o:.2f}" for o in part["pyelastica_orders"])]
        if part.get("times"):
            m = part["times"]
            lines += ["", f"mechgen's fastest dt with a time error <= {STIFF_ACCURACY:g}: {m['mechgen_dt']:.3g} s "
                          f"({m['dt_ratio']:.0f} x PyElastica's dt {m['pyelastica_dt']:.3g} s), {m['mechgen_s']:.3g} s "
                          f"against PyElastica's {m['pyelastica_s']:.3g} s (ratio {m['ratio']:.2f}, not at equal accuracy)."]
        if part.get("same_resolution"):
            m = part["same_resolution"]
            lines += ["", f"Same resolution N = {m['elements']}: mechgen's fastest run with an error <= PyElastica's, "
                          f"dt {m['mechgen_dt']:.3g} s (error {m['mechgen_error']:.2e}, {m['mechgen_s']:.3g} s) "
                          f"against PyElastica dt {m['pyelastica_dt']:.3g} s (error {m['pyelastica_error']:.2e}, "
                          f"{m['pyelastica_s']:.3g} s): ratio {m['ratio']:.2f} (target {TARGET:g})."]
        if part.get("matched"):
            m = part["matched"]
            lines += ["", f"Matched accuracy (error <= {m['target_error']:.2e}, PyElastica's finest"
                          + (", common reference" if key == "stiff" else "") + "): mechgen "
                          f"N = {m['mechgen_n']}, dt {m['mechgen_dt']:.3g} s ({m['mechgen_s']:.3g} s) against "
                          f"PyElastica N = {m['pyelastica_n']}, dt {m['pyelastica_dt']:.3g} s "
                          f"({m['pyelastica_s']:.3g} s): ratio {m['ratio']:.2f} (target {TARGET:g})"
                          + (f" - mechgen's dt {m['mechgen_dt_over_pyelastica_limit']:.0f} x PyElastica's limit at its N"
                             if "mechgen_dt_over_pyelastica_limit" in m else "")
                          + (" - mechgen's coarsest point: a lower bound" if m["mechgen_is_coarsest"] else
                             " - at mechgen's coarsest N (a coarser one might be faster)" if m.get("mechgen_at_coarsest_n")
                             else "") + "."]
    jac = results.get("jacobians")
    if isinstance(jac, dict):
        lines += ["", "## Newton's Jacobians: AD against finite differences (same states)", "",
                  "| piece | N | AD (s) | FD (s) | FD / AD | max abs(FD - AD) / max abs(AD) |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['piece']} | {r['n']} | {r['ad_s']:.3g} | {r['fd_s']:.3g} | {r['ratio']:.2f} | "
                  f"{r['fd_minus_ad']:.1e} |" for r in jac["rows"]]
    return "\n".join(lines) + "\n"


def run_rods_benchmarks(out: Path, quick: bool = False) -> dict:
    """Run the suite (see the module doc) and write its reports into ``out``."""
    out = Path(out)
    version = pyelastica_version()
    have = version is not None
    env = environment(pyelastica=version)
    repeats = 1 if quick else 3
    results: dict = {"quick": quick, "environment": env, "target": TARGET}
    with blas_threads(1):
        if have:
            warm = pyelastica_warmup()
            results["pyelastica"] = {"version": version, "pin": PYELASTICA_PIN, "jit_warmup_s": warm,
                                     **pyelastica_section_check(base_section())}
        else:
            results["pyelastica"] = "skipped: pyelastica is not installed (pip install pyelastica==" \
                                    f"{PYELASTICA_PIN}, or the bench extra)"
        results["static"] = static_study(quick, repeats, have)
        if _dynamics_available():
            results["dynamic"] = dynamic_study(quick, repeats, have)
            results["gravity"] = dynamic_study(quick, repeats, have, case="gravity")
            results["stiff"] = stiff_study(quick, repeats, have)
        else:
            results["dynamic"] = results["gravity"] = results["stiff"] = \
                "skipped: mechgen.rod_dynamics is not available"
        results["jacobians"] = jacobian_study(quick, repeats)
    env["loadavg_after"] = list(__import__("os").getloadavg())
    write_reports(out, results)
    return results


def write_reports(out: Path, results: dict) -> None:
    """The suite's reports from its results (also from a saved rods.json): the standard three for the static
    work-precision (``rods_work_precision.{csv,png}``, ``rods_ratios.json`` with every ratio),
    ``rods_dynamic_work_precision.{csv,png}`` (the dynamic, gravity and stiff points; "stiff" errors against
    mechgen's own same-N run, "stiff (common reference)" ones against the stiff case's common reference),
    ``rods.json`` and ``rods.md``."""
    out = Path(out)
    points = [{"series": f"static: {r['side']}", "setting": f"n={r['n']}", "seconds": r["seconds"],
               "error": r["error"]} for r in results["static"]["rows"]]
    ratios = []
    st_rows = results["static"]["rows"]
    peer_rows = [r for r in st_rows if r["side"].startswith("PyElastica")]
    if peer_rows:
        finest = peer_rows[-1]
        ours = [r for r in st_rows if r["side"] == "mechgen collocation" and r["error"] <= finest["error"]]
        if ours:
            coarsest = ours[0] is next(r for r in st_rows if r["side"] == "mechgen collocation")
            head = results["static"].get("headline") or {"mechgen_s": ours[0]["seconds"],
                                                         "pyelastica_s": finest["seconds"]}
            ratios.append({"peer": "PyElastica (static limit)", "ours_s": head["mechgen_s"],
                           "peer_s": head["pyelastica_s"],
                           "condition": f"static tip error <= {finest['error']:.2e} L: PyElastica n_elem "
                                        f"{finest['n']} (damped run to rest: it has no static solver), mechgen "
                                        f"collocation {ours[0]['n']} elements (error {ours[0]['error']:.2e})"
                                        + ("; mechgen's coarsest point already meets it: a lower bound" if coarsest
                                           else "")})
    dynamic_points = []
    for key in ("dynamic", "gravity", "stiff"):
        part = results[key]
        if isinstance(part, str):
            continue
        own = "its own run at dt/4, same N" if key == "stiff" else "mechgen's finest run"
        for r in part["rows"] + (part["pyelastica"] if isinstance(part.get("pyelastica"), list) else
                                 [part["pyelastica"]] if "pyelastica" in part else []):
            if r.get("error") is not None:
                dynamic_points.append({"series": f"{key}: {r['side']}", "setting": f"N={r['n']} dt={r['dt']:.3g}",
                                       "seconds": r["seconds"], "error": r["error"], "reference": own})
        if part.get("grid"):
            c = part["common_reference"]
            for r in part["grid"] + part.get("pyelastica_ladder", []):
                if r.get("error") is not None:
                    dynamic_points.append({"series": f"{key} (common reference): {r['side']}",
                                           "setting": f"N={r['n']} dt={r['dt']:.3g}", "seconds": r["seconds"],
                                           "error": r["error"],
                                           "reference": f"mechgen N={c['elements']} dt={c['dt']:.3g}"})
        if part.get("same_resolution"):
            m = part["same_resolution"]
            ratios.append({"peer": f"PyElastica ({key}, same N)", "ours_s": m["mechgen_s"], "peer_s": m["pyelastica_s"],
                           "condition": f"same resolution N = {m['elements']}, mechgen's fastest dt with a max tip error "
                                        f"over the run {m['mechgen_error']:.2e} (dt {m['mechgen_dt']:.3g} s) <= "
                                        f"PyElastica's {m['pyelastica_error']:.2e} (dt {m['pyelastica_dt']:.3g} s)"})
        if part.get("times"):
            m = part["times"]
            ratios.append({"peer": "PyElastica (stiff)", "ours_s": m["mechgen_s"], "peer_s": m["pyelastica_s"],
                           "condition": f"stiff rod (E x {STIFF_FACTOR:g}), N = {part['elements']}: mechgen's fastest "
                                        f"dt ({m['mechgen_dt']:.3g} s, {m['dt_ratio']:.0f} x PyElastica's) with a time "
                                        f"error <= {STIFF_ACCURACY:g} against its own dt/4 run; PyElastica at 0.5 x its "
                                        f"limit (dt {m['pyelastica_dt']:.3g} s; its difference from that run "
                                        f"{m['pyelastica_error']:.2e}, spatial discretisation included): not an "
                                        "equal-accuracy ratio"})
        if part.get("matched"):
            m = part["matched"]
            ratios.append({"peer": f"PyElastica ({key}, matched accuracy)", "ours_s": m["mechgen_s"],
                           "peer_s": m["pyelastica_s"],
                           "condition": (f"stiff rod (E x {STIFF_FACTOR:g}), errors against mechgen N = "
                                         f"{part['common_reference']['elements']}, dt "
                                         f"{part['common_reference']['dt']:.3g} s; mechgen's dt "
                                         f"{m['mechgen_dt_over_pyelastica_limit']:.0f} x PyElastica's limit at its N: "
                                         if key == "stiff" else "")
                                        + f"each side's least time for a max tip error <= {m['target_error']:.2e} "
                                        f"(PyElastica's finest): mechgen N = {m['mechgen_n']}, dt {m['mechgen_dt']:.3g} s; "
                                        f"PyElastica N = {m['pyelastica_n']}, dt {m['pyelastica_dt']:.3g} s"
                                        + ("; mechgen's coarsest point: a lower bound" if m["mechgen_is_coarsest"]
                                           else "")})
    results["ratios"] = [{**r, "ratio": r["peer_s"] / r["ours_s"]} for r in ratios]
    steps = results["static"].get("reference_steps")
    suite_report(out, "rods", points,
                 reference=f"mechgen RKMK4 shooting ({steps} steps), same rod",
                 error="tip error / L", time="wall time (s)",
                 title="Cantilever, tip load P L^2/EI = 10: statics", ratios=ratios)
    if dynamic_points:
        reference = ("mechgen's finest run (stiff: its own run at dt/4, same N; stiff (common reference): mechgen's "
                     "finest stiff run)")
        write_csv(out / "rods_dynamic_work_precision.csv", dynamic_points,
                  header=["series", "setting", "seconds", "error", "reference"])
        series: dict = {}
        for p in dynamic_points:
            series.setdefault(p["series"], []).append((p["seconds"], p["error"], p["setting"].split()[0]
                                                       if "PyElastica" in p["series"] else ""))
        loglog_plot(out / "rods_dynamic_work_precision.png", series, xlabel="wall time (s)",
                    ylabel="max |tip - tip_ref| over the run / max deflection",
                    title=f"Cantilever dynamics: mechgen (N x dt) against PyElastica (N)\nreference: {reference}")
    write_json(out / "rods.json", results)
    write_text(out / "rods.md", markdown(results))
