"""``periodic_orbit``: a periodic orbit of a smooth lumped model, forced or autonomous, by harmonic balance,
shooting or orthogonal collocation, with its Floquet multipliers and stability.

*Forced* (``frequency`` given: the forcing's angular frequency omega, rad/s, a number or an expression of the
parameters such as ``"omega"`` or ``"2*omega"``): the orbit of period T = 2 pi / omega, t = 0 the forcing's time
origin. *Autonomous* (``frequency`` left out): a limit cycle, whose period is an unknown found beside the orbit,
from the starting guess ``period``; a phase condition fixes where t = 0 lies on it (below). Either way the
starting guess is ``q0`` / ``v0`` (tables of coordinates, the state at t = 0; left out: zero, or the model's
declared initial state; each method starts from the first harmonic through them), or ``from`` an earlier
``simulate`` that kept its trajectory: its motion over one period (a cubic spline through its samples) starts each
method (harmonic balance its projection, collocation its values at the nodes, shooting its states at the segments'
starts): forced, its last whole period [m T, (m + 1) T]; autonomous, from the second-to-last to the last maximum of
the coordinate that varies most over the run's second half, their distance the period's guess (unless ``period`` is
given).

*Free orbits of a conservative model* (no ``frequency``, and a model that keeps its energy: its residual passes the
power balance v . r = dE/dt of its ``energy`` output at a few states about the guess, so no damping and no forcing;
mechgen.analyses.free_orbit): such orbits are not isolated but form a one-parameter family (the backbone curve), so
the orbit found is the member whose coordinate p (the largest |q0|) has the guess's displacement at t = 0,
q_p(0) = q0_p, where the phase condition puts an extremum of q_p; its frequency is an unknown. The family is
regularised by the unfolding parameter eps of Munoz-Almaraz, Freire, Galan, Doedel & Vanderbauwhede (Physica D 181,
2003), an unknown beside the orbit that vanishes on it: harmonic balance and collocation solve
r(q, v, a, t) + eps v = 0 (the energy balance over a period, eps int |v|^2 dt = 0, forces eps = 0), shooting
x(T) - x(0) + eps grad E(x(0)) = 0 (the flow keeps E) (mechgen.runtime.periodic.conservative). The outputs add
``unfolding`` (eps, zero to Newton's tolerance) and ``energy`` (E = T + V of the orbit); ``stability`` sets aside the
two multipliers nearest 1 (along the orbit and along the family). ``continuation`` with ``parameter = "amplitude"``
follows the family (mechgen.analyses.backbone).

*The linear start* (``start = "linear"``, a forced orbit without q0 / v0 / from): the first guess is the linear
forced response at the forcing's frequency, X_k = (K - (k omega)^2 M + i k omega C)^-1 F_k for each harmonic k of
the forcing f(t) = -r(0, 0, 0, t), the model linearised at q = 0 (mechgen.analyses.linear_start): a guess within a
few Newton steps of the orbit far from resonance, where the nonlinear forces are small beside the linear ones (at
resonance the linear amplitude F / (c omega) may be far above the nonlinear one: there a continuation from a
frequency away from it serves better). Where K - (k omega)^2 M + i k omega C is singular (an undamped resonance) the
linear response does not exist and the start is refused (exit 2 at ``start``).

Methods (``method``; left out: ``harmonic_balance`` when ``harmonics`` is given, ``collocation`` when ``mesh`` is,
``shooting`` otherwise; the output ``method`` says which ran):

* ``harmonic_balance``: each coordinate a Fourier series of H = ``harmonics`` harmonics (default 7); the residual
  r(q, v, a, t) of the model's generated kernel is evaluated in one batched call at N = 8 (H + 1) phases
  (alternating frequency-time) and projected onto the harmonics; Newton on the coefficients with the exact
  Jacobian from the generated ``tangent`` kernel (mechgen.runtime.periodic.harmonic_balance). Autonomous: the
  frequency is an unknown and the phase condition is b_1(q_p) = 0 (no sine part in the first harmonic of the
  coordinate p with the largest |q0|). Its error is the truncation of the series (it falls fast with H for a smooth
  orbit).
* ``shooting``: Newton on x(T) - x(0) = 0 (mechgen.runtime.periodic.shooting, .flow: DOP853 at 1/100 of ``rtol``
  and ``atol``); with ``segments`` S > 1, multiple shooting: the period split into S segments, each from its own
  unknown start state (on the guess's curve to begin with), for unstable or stiff orbits. With ``loop = "auto"``
  (the default) on the C backend, x(T) comes from the compiled DOP853 loop
  (mechgen.runtime.integration.smooth_c) and Newton's Jacobian, the monodromy matrix, from central differences of
  it (4n + 1 compiled runs, about 1e-10 from the exact one); with ``loop = "python"`` (or where the compiled loop
  cannot run) both come from the variational equations (the Jacobian from the generated ``tangent`` kernel) by
  scipy's DOP853. Autonomous: the period is an unknown and the phase condition is v_p(0) = 0 (the
  orbit starts at an extremum of q_p). Its error is the integrator's.
* ``collocation``: orthogonal collocation (mechgen.runtime.periodic.collocation): ``mesh`` equal intervals
  (default 40) of t / T, on each a polynomial of degree 4 in q and v collocated at the 4 Gauss points in the model's
  implicit form dq/dtau = T v, r(q, v, (dv/dtau) / T, t) = 0 (the residual kernel at all points in one batched
  call, the exact Jacobian from the tangent kernel; no mass matrix inverted). Autonomous: the period is an unknown
  and the phase condition v_p(0) = 0, as shooting's. Its error falls as mesh^-8 at the mesh points (the order 2m
  of Gauss collocation). With ``adapt`` = k > 0 the mesh is adapted k times after the uniform solve: its intervals
  moved so that each holds an equal share of the monitor |x^(5)|^(1/5) (AUTO's rule: small intervals where the orbit
  turns fast), the orbit interpolated onto them and solved again. A model with internal variables z (with or
  without coordinates) is collocated in its first-order form: beside the rows above, dz/dtau = T g(q, v, z, t) with
  g the generated ``rates`` kernel (its Jacobian from ``rates_tangent``), each point's rows weighted by its
  interval's width, the Jacobian sparse (SuperLU); autonomous, the phase condition is AUTO's integral one,
  int_0^1 x(tau) . x_ref'(tau) dtau = 0 against the starting guess x_ref (then the previous solution at each
  adaptation). Its guess is one period re-integrated (Radau IIA with the exact Jacobian, in the compiled loop where
  it runs) from the guess's state at t = 0 (``z0`` / ``q0`` / ``v0``, or the ``from`` simulate's state at its
  second-to-last maximum), cut at its slowest point and closed by a Poincare section there
  (mechgen.runtime.periodic.cycle_guess: a stiff cycle's fast phase,
  such as a stick-slip cycle's slip, falls between a simulate's samples, and the maxima's distance guesses the
  period to a sample's width), and the first mesh already equidistributes the guess's monitor (from 4 x ``mesh``
  uniform intervals). A stiff cycle wants ``mesh`` of 50 to 100 and ``adapt`` = 2 (the stick-slip cycle of
  scenes/rate_state_stick_slip.toml: period error 4e-8 at 50 intervals, 1.5e-10 at 100); on a mesh too coarse for it
  Newton may converge to a spurious orbit, which the trivial multiplier shows (far from 1: 2.4 at 25 intervals).

Newton stops after a step ||du||_inf <= ``atol`` + ``rtol`` ||u||_inf (u the unknowns), and raises a
ConvergenceError after ``max_iterations`` steps, naming the residual. Stability comes from the monodromy matrix
Phi(T) of the converged orbit: the Floquet multipliers are its eigenvalues. For shooting and harmonic balance Phi(T)
comes from the variational equations (for harmonic balance integrated over one period from the orbit's state at
t = 0); for collocation from the collocation equations themselves (AUTO's way: each interval's linearised equations
condensed to its end state's dependence on its start state, their product Phi(T), of the method's order and with no
integration, so that a stiff cycle's multipliers cost nothing more). With
``floquet = "hill"`` (harmonic balance only) they come from Hill's method instead
(mechgen.runtime.periodic.harmonic_balance.hill_exponents: the quadratic eigenproblem of the linearisation on the
harmonics, the 2n exponents whose eigenvectors weigh most on the low harmonics kept; no integration). The orbit is
``stable`` when each |mu| <= 1 + 1e-6 (an autonomous orbit's trivial multiplier, the one nearest 1, set aside)
(mechgen.runtime.periodic.floquet).

Outputs: ``period`` (T), ``frequency`` (2 pi / T), ``t`` and ``trajectory`` (one period, ``samples`` times from 0
to T, named as simulate's: each coordinate, ``<coordinate>_dot`` and the model's outputs), ``amplitude``
({coordinate: max |q| over the period}: the largest of 4096 phases, refined by the parabola through it and its
neighbours), ``harmonics`` (per coordinate: ``mean``, ``cos`` a_k and
``sin`` b_k, ``amplitude`` sqrt(a_k^2 + b_k^2) and ``phase`` atan2(-b_k, a_k), k = 1..H, so that
q = mean + sum_k a_k cos(k omega t) + b_k sin(k omega t) = mean + sum_k amplitude_k cos(k omega t + phase_k); for
shooting and collocation H = ``harmonics`` or 7, projected from 4096 samples of the orbit), ``multipliers``
([re, im] pairs, by decreasing modulus), ``stability``, ``method``, ``residual`` (||R||_inf at the solution:
force units for harmonic balance, the state's for shooting, both for collocation), ``iterations`` and ``loop``
(``c``: shooting's integrations ran in the compiled loop; ``python``: in scipy's).

Smooth lumped models, with or without internal variables, and forced hybrid models: a hybrid model's orbit (impacts,
stick-slip) is found by single shooting through its events, the monodromy built from the modes'
state-transition matrices and the saltation matrices of the events (generated from the guards and resets;
mechgen.analyses.hybrid_orbit), with ``events`` (one period's) and ``grazing`` besides the outputs above; harmonic
balance, collocation and multiple shooting are refused for it (exit 2 at the key). A forced hybrid orbit starts at
t = 0 in the model's initial mode; an event at the period's boundary is accepted (the stick-slip contact under
u = U cos(omega t) reverses at t = 0 = T, so its run ends a round-off short of the slip -> stick event): a run that
ends in another mode is continued 1e-8 T past T and the events there are taken at T, their saltation matrices in the
monodromy. An autonomous hybrid orbit (no
``frequency``; ``period`` its guess) has its phase fixed by a Poincare section at an event, the guard ``section``
(left out: the first event's guard of the run from the guess): the orbit starts just after that event and Newton
solves the return map to it, whose Jacobian holds the saltation matrices and the return time's gradient
(mechgen.runtime.integration.hybrid_autonomous); ``t`` starts at the event, and the outputs add ``section`` and
``start_mode``. Its ``multipliers`` hold the trivial 1, and a stick phase (a velocity held at the belt's) makes the
monodromy rank-deficient: multipliers 0, one per held state component (scenes/belt_stick_slip.toml: 1 and 0). A
model with internal variables z is solved by collocation (above) or shooting, whose flow carries them (``z0`` their
guess; shooting's phase condition of a model of internal variables only is dz_p/dt = 0 at t = 0; ``amplitude`` and
``harmonics`` list them after the coordinates); harmonic balance, whose residual holds the coordinates only, is
refused for it (exit 2 at ``method``). A continuum or a chain is refused (key ``method``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mechgen.analyses import schema, summary, time_series
from mechgen.analyses.free_orbit import is_conservative, orbit_energy, solve_free
from mechgen.analyses.linear_start import linear_coefficients
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import ABSENT, Option
from mechgen.analyses.simulate_start import declared_start, initial_state
from mechgen.errors import ConvergenceError, SceneError
from mechgen.runtime.core.memory import dense_bytes, require
from mechgen.runtime.periodic import floquet, fourier
from mechgen.runtime.periodic.fourier import peak
from mechgen.runtime.periodic.collocation import Collocation
from mechgen.runtime.periodic.cycle_guess import closed_cycle
from mechgen.runtime.periodic.flow import compiled_flow, states_at, variational_flow
from mechgen.runtime.periodic.harmonic_balance import HarmonicBalance, hill_multipliers
from mechgen.runtime.periodic.newton import NewtonSettings, newton
from mechgen.runtime.periodic.shooting import Shooting
from mechgen.scene.values import fail, listing, show

METHODS = ("harmonic_balance", "shooting", "collocation")
LOOPS = ("auto", "python", "c")
FLOQUET = ("monodromy", "hill")
STARTS = ("guess", "linear")
#: the harmonics of harmonic balance, and those reported by shooting, when ``harmonics`` is left out
DEFAULT_HARMONICS = 7
#: collocation's intervals when ``mesh`` is left out
DEFAULT_MESH = 40
#: phases at which amplitudes and a shooting orbit's harmonics are taken
FINE = 4096
#: shooting's Newton steps are at most this times (1 + ||u||_inf) (mechgen.runtime.periodic.newton: a full step from a
#: poor guess leaves for states whose flow is far from periodic); harmonic balance's are not limited
SHOOTING_TRUST = 0.5
#: the shooting integrator's tolerances are these fractions of Newton's rtol / atol
INTEGRATOR_SHARE = 1e-2

#: the most harmonics (a guard against typos: harmonic balance's Jacobian has ((2H + 1) n)^2 entries)
MAX_HARMONICS = 1000


def harmonics_count(ctx, key: str, value: object) -> int:
    """An integer from 1 to 1000 (a guard against typos)."""
    H = schema.int_at_least(ctx, key, value, 1)
    if H > MAX_HARMONICS:
        raise fail(ctx.file, key, f"harmonics {H} is above {MAX_HARMONICS}", f"an integer from 1 to {MAX_HARMONICS}")
    return H


def internal_table(ctx, key: str, value: object) -> dict[str, float]:
    """A table internal variable -> number (the names are checked against the compiled model's at run time)."""
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {show(value)}", "a table of internal variable = value")
    out = {}
    for name, item in value.items():
        if not isinstance(name, str) or not name.isidentifier():
            raise fail(ctx.file, f"{key}.{name}", f"{show(name)} is not a name", "an internal variable's name")
        out[name] = schema.number(ctx, f"{key}.{name}", item)
    return out


def earlier_simulate(ctx, key: str, value: object) -> str:
    """The name of an earlier simulate analysis."""
    runs = [n for n, k in ctx.earlier.items() if k == "simulate"]
    expected = "the name of an earlier simulate analysis: " + (listing(runs) if runs else "none in this scene")
    if ctx.swept:
        raise fail(ctx.file, key, "'from' is not available inside a sweep", "no 'from' key")
    if not isinstance(value, str) or value not in ctx.earlier:
        later = isinstance(value, str) and value in ctx.all_names
        what = f"analysis {show(value)} comes later in the scene" if later else f"no earlier analysis {show(value)}"
        raise fail(ctx.file, key, what, expected)
    if ctx.earlier[value] != "simulate":
        raise fail(ctx.file, key, f"analysis '{value}' is a {ctx.earlier[value]} analysis, not simulate", expected)
    return value


#: the most collocation intervals (a guard against typos: the dense Jacobian has (8 mesh n)^2 entries)
MAX_MESH = 2000


def mesh_count(ctx, key: str, value: object) -> int:
    """An integer from 2 to 2000 (a guard against typos)."""
    count = schema.int_at_least(ctx, key, value, 2)
    if count > MAX_MESH:
        raise fail(ctx.file, key, f"mesh {count} is above {MAX_MESH}", f"an integer from 2 to {MAX_MESH}")
    return count


def adapt_count(ctx, key: str, value: object) -> int:
    """An integer from 0 to 10."""
    count = schema.int_at_least(ctx, key, value, 0)
    if count > 10:
        raise fail(ctx.file, key, f"adapt {count} is above 10", "an integer from 0 to 10")
    return count


SCHEMA = {
    "method": Option(schema.one_of("method", METHODS), ABSENT, doc="harmonic_balance, shooting or collocation "
                     "(left out: harmonic_balance when harmonics is given, collocation when mesh is, else shooting)"),
    "frequency": Option(schema.positive_expression, ABSENT, doc="the forcing's angular frequency omega (rad/s): a number or an "
                        "expression of parameters such as \"omega\"; the period is 2 pi / omega (left out: an "
                        "autonomous orbit, its period found)"),
    "period": Option(schema.positive, ABSENT, doc="the starting guess of an autonomous orbit's period (s, or the "
                     "model's time unit; required without frequency)"),
    "section": Option(schema.name, ABSENT, doc="an autonomous hybrid orbit's Poincare section: the name of the guard "
                      "whose event starts and ends the period (left out: the guard of the first event of the run "
                      "from the guess); a smooth model's orbit takes none"),
    "harmonics": Option(harmonics_count, ABSENT, doc="harmonic balance's number of harmonics H "
                        "(default 7); with shooting, how many harmonics are reported"),
    "mesh": Option(mesh_count, ABSENT, doc="collocation's number of mesh intervals (default 40), each with a "
                   "polynomial of degree 4 collocated at 4 Gauss points"),
    "adapt": Option(adapt_count, 0,
                    doc="collocation's mesh adaptations: after each solve the intervals are moved so that each holds "
                    "an equal share of |x^(5)|^(1/5) (AUTO's monitor) and the orbit is solved again (0: the uniform "
                    "mesh)"),
    "q0": Option(schema.coordinate_table, {}, doc="the starting guess of the coordinates at t = 0, a table "
                 "coordinate = value (left out: zero, or the model's declared initial state)"),
    "z0": Option(internal_table, {}, doc="the starting guess of the internal variables at t = 0, a table "
                 "name = value (left out: the model's declared initial values, else zero); for collocation the "
                 "state one period is re-integrated from"),
    "v0": Option(schema.coordinate_table, {}, doc="the starting guess of the velocities at t = 0, a table "
                 "coordinate = value"),
    "from": Option(earlier_simulate, ABSENT, doc="an earlier simulate analysis (with its trajectory) whose "
                   "motion near its end is the starting guess instead of q0 / v0 (and, for an autonomous orbit, the "
                   "period between its last two maxima the period's; an autonomous collocation of a model with "
                   "internal variables re-integrates one period from its state at the second-to-last maximum)"),
    "segments": Option(schema.count, 1, doc="shooting's number of segments S of the period (1: single shooting; more: "
                       "multiple shooting, for unstable or stiff orbits)"),
    "rtol": Option(schema.positive, 1e-9, doc="Newton's relative tolerance on the unknowns (shooting integrates "
                   "at 1/100 of it)"),
    "atol": Option(schema.positive, 1e-12, doc="Newton's absolute tolerance on the unknowns (the coordinates' "
                   "units; shooting integrates at 1/100 of it)"),
    "max_iterations": Option(schema.count, 50, doc="the most Newton steps before a convergence error"),
    "floquet": Option(schema.one_of("floquet", FLOQUET), "monodromy", doc="how the multipliers are found: monodromy "
                      "(the eigenvalues of the monodromy matrix of the converged orbit) or hill (harmonic balance "
                      "only: Hill's method on the harmonics, no integration)"),
    "loop": Option(schema.one_of("loop", LOOPS), "auto", doc="shooting's integrations: auto (the compiled DOP853 "
                   "loop where it can run: the C backend), python (scipy's DOP853 and the variational equations "
                   "throughout) or c (compiled, else an input error)"),
    "start": Option(schema.one_of("start", STARTS), "guess", doc="the forced orbit's first guess: guess (q0 / v0, "
                    "or from) or linear (the linear forced response at the frequency, (K - omega^2 M + i omega C)^-1 "
                    "F per harmonic of the forcing, the model linearised at q = 0: mechgen.analyses.linear_start; "
                    "refused where K - omega^2 M + i omega C is singular)"),
    "samples": Option(schema.count_within("samples"), 201, doc="how many equally spaced times from 0 to T the "
                      "reported orbit (t, trajectory) has"),
}


def check(ctx, base: str, options: dict) -> None:
    """A smooth lumped model; not both harmonics and mesh without a method; an autonomous orbit needs a period guess,
    a forced one none."""
    model = ctx.model
    if getattr(model, "modes", ()):
        check_hybrid(ctx, base, options)
        return
    if "section" in options:
        raise fail(ctx.file, f"{base}.section", f"model {model.name} has no modes: section is an autonomous hybrid "
                   "orbit's Poincare section (a guard)", "no section (a smooth orbit's phase is fixed by v_p(0) = 0)")
    why = ("is a continuum" if getattr(model, "continuum", False) else "is a chain" if getattr(model, "chain", None)
           else None)
    if getattr(model, "internals", False) and chosen_method(options) == "harmonic_balance":
        raise fail(ctx.file, f"{base}.method", f"model {model.name} has internal variables, which "
                   "harmonic_balance does not carry (its residual is the coordinates')",
                   "method = \"collocation\" or \"shooting\" (both carry the internal variables)")
    if why:
        raise fail(ctx.file, f"{base}.method", f"model {model.name} {why}: periodic_orbit's methods need a smooth "
                   "lumped model", "a smooth lumped model (a hybrid model's periodic response: kind periodic)")
    if "harmonics" in options and "mesh" in options and "method" not in options:
        raise fail(ctx.file, f"{base}.method", "both harmonics (harmonic balance) and mesh (collocation) are given",
                   "method = \"harmonic_balance\" or \"collocation\" beside them, or one of the two keys")
    if options.get("floquet") == "hill" and chosen_method(options) != "harmonic_balance":
        raise fail(ctx.file, f"{base}.floquet", f"Hill's method needs harmonic balance, and the method is "
                   f"{chosen_method(options)}", "floquet = \"monodromy\", or method = \"harmonic_balance\"")
    if "frequency" in options and "period" in options:
        raise fail(ctx.file, f"{base}.period", "a forced orbit's period is 2 pi / frequency; period is the guess of "
                   "an autonomous one", "period or frequency, not both")
    if "from" in options and ({"q0", "v0"} & {k for k, v in options.items() if v}):
        raise fail(ctx.file, f"{base}.from", "a starting guess both from a simulate and from q0 / v0",
                   "from, or q0 / v0")
    if options.get("start") == "linear":
        check_linear_start(ctx, base, options)
    if "frequency" not in options and "period" not in options and "from" not in options:
        raise fail(ctx.file, f"{base}.period", "an autonomous orbit (no frequency) needs a starting guess of its "
                   "period", "period = a number > 0 (or frequency = the forcing's, for a forced orbit)")


def check_linear_start(ctx, base: str, options: dict) -> None:
    """start = "linear": a forced orbit of a model without internal variables, and no other guess."""
    if "frequency" not in options:
        raise fail(ctx.file, f"{base}.start", "start = \"linear\" is the linear forced response, and the orbit has "
                   "no frequency (autonomous)", "frequency = the forcing's, or start = \"guess\"")
    given = [k for k in ("q0", "v0", "z0", "from") if options.get(k)]
    if given:
        raise fail(ctx.file, f"{base}.start", f"start = \"linear\" and a guess ({', '.join(given)}) are both given",
                   f"start = \"linear\" or {given[0]}, not both")
    if getattr(ctx.model, "internals", False):
        raise fail(ctx.file, f"{base}.start", f"model {ctx.model.name} has internal variables, which the linear "
                   "response of the coordinates does not give", "start = \"guess\" (q0, v0, z0)")


def check_hybrid(ctx, base: str, options: dict) -> None:
    """A hybrid model's orbit: forced, by single shooting through its events (mechgen.analyses.hybrid_orbit)."""
    model = ctx.model
    if options.get("method", "shooting") != "shooting" or "harmonics" in options and "method" not in options or \
            "mesh" in options and "method" not in options:
        raise fail(ctx.file, f"{base}.method", f"model {model.name} has modes (a hybrid model): its orbit is found by "
                   "shooting through its events", "method = \"shooting\" (or no method, harmonics or mesh)")
    if int(options.get("segments", 1)) != 1:
        raise fail(ctx.file, f"{base}.segments", "a hybrid model's orbit is found by single shooting",
                   "segments = 1 (or no segments)")
    if "frequency" not in options and "period" not in options:
        raise fail(ctx.file, f"{base}.period", f"an autonomous orbit of a hybrid model ({model.name}) needs a "
                   "guess of its period", "period = a number > 0 (or frequency = the forcing's, for a forced orbit)")
    if "frequency" in options and ("period" in options or "section" in options):
        key = "period" if "period" in options else "section"
        raise fail(ctx.file, f"{base}.{key}", f"a forced orbit's period is 2 pi / frequency and starts at t = 0; "
                   f"{key} belongs to an autonomous one", f"{key} or frequency, not both")
    if options.get("floquet") == "hill" or "from" in options or options.get("start") == "linear":
        key = "floquet" if options.get("floquet") == "hill" else "from" if "from" in options else "start"
        raise fail(ctx.file, f"{base}.{key}", f"{key} does not apply to a hybrid model's orbit",
                   f"no {key} (q0 / v0 as the starting guess)")


def needs(options: dict, *, internal: bool) -> set[str]:
    """The residual and its tangent (the flow's dx/dt and Jacobian), the outputs for the trajectory; for a hybrid
    model the event derivatives of its saltation matrices (ignored by a smooth model); the internal variables'
    rates and their Jacobians."""
    return {"residual", "tangent", "flow", "outputs", "saltation"} | ({"rates", "rates_tangent"} if internal else set())


def chosen_method(options: dict) -> str:
    """The method that runs (module doc)."""
    if options.get("method"):
        return options["method"]
    return "harmonic_balance" if "harmonics" in options else "collocation" if "mesh" in options else "shooting"


def refuse_unsupported(system) -> None:
    """A system the methods cannot run: hybrid, continuum, chain, internal variables (key method)."""
    why = ("is a continuum" if getattr(system, "is_field", False) else "is a chain"
           if getattr(system, "is_lattice", False) else None)
    if why:
        raise SceneError(f"periodic_orbit: model {system.metadata.model} {why}", key="method",
                         expected="a smooth lumped model (a hybrid model's periodic response: kind periodic)")


def refuse_time_dependent(system, x: np.ndarray) -> None:
    """An autonomous orbit needs a residual without t: compared at t = 0 and t = 1.2345 at the guess."""
    r0 = system.rhs(0.0, x)
    r1 = system.rhs(1.2345, x)
    if not np.allclose(r0, r1, rtol=1e-12, atol=1e-14):
        raise SceneError(f"periodic_orbit: model {system.metadata.model}'s equations depend on t (a forcing) and no "
                         "frequency is given", key="frequency",
                         expected="the forcing's angular frequency (rad/s), a number or a parameter expression")


@dataclass(frozen=True)
class Guess:
    """A starting guess: the state ``x0`` at t = 0, the ``period``, the ``phase`` coordinate p of an autonomous
    orbit's phase condition, and ``curve``: times in [0, period] -> the guessed states there (rows)."""

    x0: np.ndarray
    period: float
    phase: int
    curve: Callable[[np.ndarray], np.ndarray]


def first_harmonic_states(x0: np.ndarray, omega: float, times: np.ndarray, n: int) -> np.ndarray:
    """The states (rows) at ``times`` of q = q0 cos(omega t) + (v0 / omega) sin(omega t): the first harmonic through
    the guess x0 = (q0, v0)."""
    c, s = np.cos(omega * times)[:, None], np.sin(omega * times)[:, None]
    q0, b = x0[None, :n], x0[None, n:2 * n] / omega
    z = np.repeat(x0[None, 2 * n:], np.size(times), axis=0)  # internal variables held at their guess
    return np.hstack([q0 * c + b * s, omega * (b * c - q0 * s), z])


def guess(system, options: dict, omega) -> Guess:
    """The guess of ``q0`` / ``v0`` (tables over the declared initial state, zero when none): the first harmonic
    through them, of the forcing's period or the guessed one; p the coordinate with the largest |q0|."""

    q0, v0 = initial_state(system, options)
    x0 = np.concatenate([q0, v0, internal_start(system, options.get("z0"))])
    period = 2 * np.pi / omega if omega is not None else float(options["period"])
    w, n = 2 * np.pi / period, system.n
    phase = int(np.argmax(np.abs(q0))) if n else int(np.argmax(np.abs(x0)))
    return Guess(x0, period, phase, lambda times: first_harmonic_states(x0, w, times, n))


def linear_guess(system, options: dict, omega: float) -> Guess:
    """The linear forced response at omega (mechgen.analyses.linear_start) as the guess: its series over one period
    (harmonics: ``harmonics`` or 7)."""
    U = linear_coefficients(system, float(omega), int(options.get("harmonics", DEFAULT_HARMONICS)))

    def curve(times):
        theta = omega * np.asarray(times, float)
        return np.hstack([fourier.evaluate(U, theta), omega * fourier.evaluate(U, theta, 1)])

    return Guess(curve(np.zeros(1))[0], 2 * np.pi / omega, 0, curve)


def internal_start(system, table: dict | None = None) -> np.ndarray:
    """The internal variables' guess: ``table`` (``z0``) over their declared initial values (zero when none are
    declared); an unknown name is a SceneError at ``z0``."""

    start = declared_start(system)
    z = np.zeros(system.m) if start is None or not system.m else np.asarray(start[2 * system.n:], float).copy()
    names = time_series.state_names(system)[2 * system.n:]
    for name, value in (table or {}).items():
        if name not in names:
            raise SceneError(f"periodic_orbit: z0 names {name!r}, not an internal variable of "
                             f"{system.metadata.model}", key=f"z0.{name}",
                             expected="one of: " + (", ".join(names) or "(the model has none)"))
        z[names.index(name)] = float(value)
    return z


def simulated_states(system, options: dict, context: dict) -> tuple[np.ndarray, np.ndarray]:
    """(t, states as rows) of the ``from`` simulate's trajectory; a SceneError when it kept none."""
    name = options["from"]
    earlier = context.get(name, {})
    trajectory = earlier.get("trajectory")
    names = time_series.state_names(system)
    if not trajectory or any(k not in trajectory for k in names) or len(earlier.get("t", ())) < 4:
        raise SceneError(f"periodic_orbit: simulate analysis '{name}' kept no trajectory to start from", key="from",
                         expected="a simulate analysis with series = true (and at least 4 samples)")
    return np.asarray(earlier["t"], float), np.column_stack([trajectory[k] for k in names]).astype(float)


def too_short(options: dict, what: str) -> SceneError:
    """The ``from`` simulate does not hold what its guess needs."""
    return SceneError(f"periodic_orbit: simulate analysis '{options['from']}' {what}", key="from",
                      expected="a simulate run over at least two periods of the orbit (a longer t_end)")


def guess_from_simulate(system, options: dict, context: dict, omega) -> Guess:
    """The guess of the ``from`` simulate: its motion over one period, by a cubic spline through its samples.
    Forced: the last whole period [m T, (m + 1) T] within the run (T = 2 pi / omega). Autonomous: from its
    second-to-last maximum of the coordinate p that varies most over the run's second half to its last, whose
    distance is the period's guess (unless ``period`` is given)."""
    from scipy.interpolate import CubicSpline

    t, X = simulated_states(system, options, context)
    spline = CubicSpline(t, X, axis=0)
    if omega is not None:
        T = 2 * np.pi / omega
        start = (np.floor((t[-1] + 1e-9 * T) / T) - 1) * T
        if start < t[0]:
            raise too_short(options, f"ends at t = {t[-1]:.6g}, before a whole period T = {T:.6g} of the forcing")
        return Guess(spline(start), T, 0, lambda times: spline(start + np.asarray(times)))
    half = t >= (t[0] + t[-1]) / 2
    first = X[:, :system.n] if system.n else X[:, 2 * system.n:]  # the coordinates, or the internal variables
    p = int(np.argmax(np.ptp(first[half], axis=0)))
    q = first[:, p]
    peaks = np.flatnonzero((q[1:-1] >= q[:-2]) & (q[1:-1] > q[2:])) + 1
    if peaks.size < 2:
        raise too_short(options, f"shows fewer than two maxima of '{time_series.state_names(system)[p + 2 * system.n if not system.n else p]}'")
    start = t[peaks[-2]]
    period = float(options.get("period", t[peaks[-1]] - start))
    return Guess(spline(start), period, p, lambda times: spline(start + np.asarray(times)))


def closed_guess(system, start: Guess) -> Guess:
    """An autonomous collocation of a model with internal variables starts from one period re-integrated from the
    guess's state at t = 0, cut at its slowest point and closed by a Poincare section there
    (mechgen.runtime.periodic.cycle_guess): a stiff cycle's fast phase lies between a simulate's samples."""
    x0, period, curve = closed_cycle(system, start.x0, start.period)
    return Guess(x0, period, start.phase, curve)


def settings(options: dict, method: str) -> NewtonSettings:
    """Newton's tolerances and its failure's advice."""
    advice = ("a better starting guess (q0, v0" + (", period" if "frequency" not in options else "") + ")"
              + (", more harmonics" if method == "harmonic_balance" else "") + " or the other method")
    return NewtonSettings(rtol=float(options["rtol"]), atol=float(options["atol"]),
                          max_iterations=int(options["max_iterations"]), what=f"periodic_orbit ({method})",
                          advice=advice, trust=SHOOTING_TRUST if method == "shooting" else np.inf)


def solve_harmonic_balance(system, options: dict, start: Guess, omega) -> dict:
    """Harmonic balance from the guess (its curve projected onto the harmonics): {U, omega, x0 (the state at
    t = 0), residual, iterations}."""
    H = int(options.get("harmonics", DEFAULT_HARMONICS))
    size = (2 * H + 1) * system.n
    require(dense_bytes(size, size) + dense_bytes(fourier.sample_count(H), size, system.n), f"harmonic balance's "
            f"dense {size} x {size} Jacobian (H = {H}, {system.n} coordinates)", key="harmonics")
    problem = HarmonicBalance(system, fourier.basis(H), omega, start.phase)
    w = 2 * np.pi / start.period
    n, N = system.n, problem.basis.theta.size
    U = fourier.coefficients_of_samples(start.curve(start.period * np.arange(N) / N)[:, :n], H)
    if problem.autonomous:
        U[H + 1, start.phase] = 0.0
    sol = newton(problem.residual_jacobian, problem.unknowns(U, w), settings(options, "harmonic_balance"))
    u = sol.u.copy()
    if problem.autonomous and u[-1] < 0:  # the same orbit with omega -> -omega and b_k -> -b_k (no t in r)
        u[(H + 1) * n:-1] *= -1
        u[-1] = -u[-1]
    U, w = problem.split(u)
    if not w > 0:
        raise ConvergenceError("periodic_orbit (harmonic_balance): Newton converged to frequency 0 (an "
                               "equilibrium); try a starting guess nearer the limit cycle (q0, v0, period)")
    x0, _ = problem.start_state(u)
    return {"U": U, "omega": w, "x0": x0, "residual": sol.residual, "iterations": sol.iterations,
            "problem": problem, "u": u}


def solve_collocation(system, options: dict, start: Guess, omega) -> dict:
    """Collocation from the guess (its curve at the nodes; with internal variables on the mesh adapted to the guess):
    {problem, u, x0, omega, residual, iterations}."""
    mesh = int(options.get("mesh", DEFAULT_MESH))
    if system.m:
        problem, u = first_order_start(system, mesh, start, omega)
    else:
        problem = Collocation(system, mesh, omega, start.phase)
        size = problem.nodes * 2 * system.n + 1
        require(dense_bytes(size, size), f"collocation's dense {size} x {size} Jacobian", key="mesh")
        X = start.curve(start.period * np.arange(problem.nodes) / problem.nodes)
        if problem.autonomous:
            X[0, system.n + start.phase] = 0.0
        u = problem.unknowns(X, start.period)
    sol = newton(problem.residual_jacobian, u, settings(options, "collocation"))
    for _ in range(int(options.get("adapt", 0))):
        problem, u = problem.adapted(sol.u)
        sol = newton(problem.residual_jacobian, u, settings(options, "collocation"))
    X, T = problem.split(sol.u)
    if not T > 0:
        raise ConvergenceError(f"periodic_orbit (collocation): Newton converged to the period {T:.6g}; try a better "
                               "starting guess (period, q0, v0, or from a simulate)")
    return {"problem": problem, "u": sol.u, "x0": X[0].copy(), "omega": 2 * np.pi / T, "residual": sol.residual,
            "iterations": sol.iterations}


#: a model with internal variables: the guess is first laid on GUESS_REFINEMENT x ``mesh`` uniform intervals, whose
#: monitor places the ``mesh`` intervals of the first solve
GUESS_REFINEMENT = 4


def first_order_start(system, mesh: int, start: Guess, omega) -> tuple[Collocation, np.ndarray]:
    """(problem, u) of a model with internal variables: the first-order collocation (sparse Jacobian; autonomous:
    the integral phase condition against the guess) on ``mesh`` intervals that equidistribute the guess's monitor
    (AUTO's, as ``adapt``: a stiff cycle's fast phase gets its intervals before the first solve)."""
    fine = Collocation(system, GUESS_REFINEMENT * mesh, omega, start.phase)
    X = np.asarray(start.curve(start.period * fine.node_tau()), float)
    if fine.autonomous:
        fine = Collocation(system, fine.mesh, omega, start.phase, None, X)
    return fine.adapted(fine.unknowns(X, start.period), mesh)


def compiled_run(system, options: dict):
    """The compiled flow (mechgen.runtime.periodic.flow.compiled_flow) that ``loop`` asks for, or None."""
    if options.get("loop", "auto") == "python":
        return None
    run = compiled_flow(system, *integrator_tolerances(options))
    if run is None and options.get("loop") == "c":
        from mechgen.runtime.integration.smooth_c import smooth_loop_problem

        raise SceneError(f"periodic_orbit: loop 'c' cannot run here: "
                         f"{smooth_loop_problem(system, *integrator_tolerances(options))}", key="loop",
                         expected="auto or python, or a system on the C backend with a C compiler")
    return run


def solve_shooting(system, options: dict, start: Guess, omega) -> dict:
    """Shooting from the guess (``segments`` S > 1: the segments' starts on its curve): {x0, omega, residual,
    iterations, run}."""
    rtol, atol = integrator_tolerances(options)
    run = compiled_run(system, options)
    S = int(options.get("segments", 1))
    problem = Shooting(system, omega, start.phase, rtol, atol, run, S)
    X = start.curve(start.period * np.arange(S) / S)
    X[0] = start.x0
    if problem.autonomous and system.n:
        X[0, system.n + start.phase] = 0.0
    sol = newton(problem.residual_jacobian, problem.unknowns(X, start.period), settings(options, "shooting"))
    x0, T = problem.split(sol.u)
    return {"x0": np.asarray(x0, float), "omega": 2 * np.pi / T, "residual": sol.residual,
            "iterations": sol.iterations, "run": run}


def integrator_tolerances(options: dict) -> tuple[float, float]:
    """DOP853's rtol, atol: INTEGRATOR_SHARE of Newton's."""
    return float(options["rtol"]) * INTEGRATOR_SHARE, float(options["atol"]) * INTEGRATOR_SHARE


def orbit_samples(system, options: dict, found: dict, method: str, times: np.ndarray) -> np.ndarray:
    """The states (rows) at ``times`` within [0, T]: the series of harmonic balance, the flow of shooting."""
    if method == "collocation":
        return found["problem"].states_at(found["u"], times)
    if method == "harmonic_balance":
        theta = found["omega"] * times
        q = fourier.evaluate(found["U"], theta)
        v = found["omega"] * fourier.evaluate(found["U"], theta, 1)
        return np.hstack([q, v])
    if found.get("run") is not None:
        return found["run"](found["x0"], times)
    return states_at(system, found["x0"], 0.0, times, *integrator_tolerances(options))


def run_periodic_orbit(system, options: dict, context: dict) -> dict:
    """See the module doc."""
    refuse_unsupported(system)
    if hasattr(system, "modes"):  # a hybrid model: event-aware shooting (mechgen.analyses.hybrid_orbit)
        from mechgen.analyses.hybrid_orbit import run_hybrid_orbit

        return run_hybrid_orbit(system, options, guess(system, options, options.get("frequency")).x0)
    method = chosen_method(options)
    omega = options.get("frequency")
    start = guess_from_simulate(system, options, context, omega) if "from" in options else \
        linear_guess(system, options, omega) if options.get("start") == "linear" else guess(system, options, omega)
    if omega is None:
        refuse_time_dependent(system, start.x0)
        if not np.any(start.x0):
            key = "q0" if system.n else "z0"
            raise SceneError("periodic_orbit: an autonomous orbit from a zero starting guess would find the "
                             "equilibrium", key=key, expected="a starting guess on or near the orbit ("
                             + ("q0, v0" if system.n else "z0") + ", or from a simulate)")
    if method == "collocation" and system.m and omega is None:
        start = closed_guess(system, start)
    free = omega is None and is_conservative(system, start.x0)
    if free and not np.any(start.x0[:system.n]):
        raise SceneError("periodic_orbit: the free orbit of a conservative model is the member through the guess's "
                         "displacement q_p(0) = q0_p, and q0 is zero", key="q0",
                         expected="q0 = the displacement at an extremum of the orbit (its amplitude), e.g. "
                         "q0 = { x = 0.5 }")
    if free:  # a member of a conservative family (mechgen.analyses.free_orbit)
        found = solve_free(system, options, start, method, free_defaults(system, options, method),
                           settings(options, method))
    else:
        solve = {"harmonic_balance": solve_harmonic_balance, "collocation": solve_collocation}.get(method,
                                                                                                  solve_shooting)
        found = solve(system, options, start, omega)
    out = report(system, options, found, method, autonomous=omega is None, conservative=free)
    if free:
        out.update(unfolding=found["unfolding"], energy=orbit_energy(system, found["x0"]))
    # what a continuation of the orbit starts from (mechgen.analyses.orbit_branch)
    out["_orbit"] = {"method": method, "phase": start.phase, "found": found, "options": dict(options),
                     "conservative": free}
    return out


def free_defaults(system, options: dict, method: str) -> dict:
    """The defaults the free orbit's problems take (mechgen.analyses.free_orbit.base_problem)."""
    return {"harmonics": DEFAULT_HARMONICS, "mesh": DEFAULT_MESH, "tolerances": integrator_tolerances(options),
            "run": compiled_run(system, options) if method == "shooting" else None}


def report(system, options: dict, found: dict, method: str, *, autonomous: bool, conservative: bool = False) -> dict:
    """The outputs (module doc) of a converged orbit (``conservative``: a free orbit of a conservative family, whose
    two multipliers nearest 1 are trivial)."""
    w = found["omega"]
    T = 2 * np.pi / w
    n = system.n
    # the coordinates, then the internal variables (a model's state x = (q, v, z))
    columns = list(range(n)) + list(range(2 * n, 2 * n + system.m))
    names = list(system.coordinates) + time_series.state_names(system)[2 * n:]
    fine_t = T * np.arange(FINE) / FINE
    fine = orbit_samples(system, options, found, method, fine_t)[:, columns]
    if autonomous and np.max(np.ptp(fine, axis=0)) <= 1e3 * float(options["atol"]):
        raise ConvergenceError(f"periodic_orbit ({method}): Newton converged to an equilibrium (the orbit's "
                               "coordinates do not vary); try a starting guess nearer the limit cycle (q0, v0, period)")
    U = found["U"] if method == "harmonic_balance" else fourier.coefficients_of_samples(  # shooting, collocation
        fine, int(options.get("harmonics", DEFAULT_HARMONICS)))
    if options.get("floquet") == "hill":
        mu = hill_multipliers(found["problem"], found["u"])
    elif method == "collocation":  # the discretisation's own monodromy (mechgen.runtime.periodic.collocation)
        mu = floquet.multipliers(found["problem"].monodromy(found["u"]))
    else:
        _, Phi = variational_flow(system, found["x0"], 0.0, T, *integrator_tolerances(options))
        mu = floquet.multipliers(Phi)
    t = np.linspace(0.0, T, int(options["samples"]))
    X = orbit_samples(system, options, found, method, t)
    series = time_series.sampled_outputs(system, t, X)
    trajectory = time_series.time_history(system, t, X, series, None)
    return {"period": float(T), "frequency": float(w), "t": trajectory["t"], "trajectory": trajectory["trajectory"],
            "amplitude": {c: peak(fine[:, i]) for i, c in enumerate(names)},
            "harmonics": fourier.harmonics_table(U, names), "multipliers": floquet.as_pairs(mu),
            "stability": floquet.stability(mu, autonomous, trivial=2 if conservative else None), "method": method, "residual": float(found["residual"]),
            "iterations": int(found["iterations"]), "loop": "c" if found.get("run") is not None else "python"}


def plot(plt, a: dict, path) -> list:
    """The orbit: each coordinate against t over one period, and the phase portrait of each (up to 4); a model of
    internal variables only: each internal variable against t, and the second against the first (one panel when it
    has one)."""
    out = a["outputs"]
    traj = out["trajectory"]
    names = [c for c in traj if f"{c}_dot" in traj][:4]
    pairs = [(c, f"{c}_dot") for c in names]
    internals = [] if names else list(out["amplitude"])[:4]
    if len(internals) > 1:
        pairs = [(internals[0], internals[1])]
    fig, axes = plt.subplots(1, 2 if pairs else 1, figsize=(9 if pairs else 5.5, 3.6), squeeze=False)
    axes = axes[0]
    for c in names or internals:
        axes[0].plot(out["t"], traj[c], label=c)
    for x, y in pairs:
        axes[1].plot(traj[x], traj[y], label=x if names else None)
    axes[0].set_xlabel("t (s, or the model's time unit)")
    axes[0].set_ylabel("coordinates" if names else "internal variables" if len(internals) != 1 else internals[0])
    if pairs:  # a single internal variable has no phase portrait
        axes[1].set_xlabel("q" if names else pairs[0][0])
        axes[1].set_ylabel("dq/dt" if names else pairs[0][1])
    for ax in axes if len(names or internals) > 1 else ():
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="small")
    fig.suptitle(f"{a['name']}: T = {out['period']:.6g}, {out['stability']} ({out['method']})")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


def summary_lines(outputs: dict) -> list[str]:
    """Every output but the series and the harmonic tables, then the first harmonic's amplitude per coordinate."""
    lines = summary.output_lines(outputs, skip=("harmonics", "trajectory", "t"))
    first = {c: round(h["amplitude"][0], 6) if h["amplitude"] else 0.0 for c, h in outputs["harmonics"].items()}
    return lines + [f"    first harmonic amplitude: {first}"] + time_series.summary_lines(outputs)


register(AnalysisKind("periodic_orbit", SCHEMA, run_periodic_orbit, needs, summary_lines, check=check, plot=plot))
