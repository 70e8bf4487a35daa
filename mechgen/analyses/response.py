"""``response``: the steady harmonic response of the linearised system (a frequency or unbalance response).

About an operating point the linearised system M q'' + (D + G) q' + K q = Re(f exp(i omega t)) responds in
steady state with q(t) = Re(X exp(i omega t)),

    X = H(omega) f,   H(omega) = (K - omega^2 M + i omega (D + G))^-1

(mechgen.runtime.linear.harmonic). H is the receptance (coordinate per unit generalized force: m/N for a
translation driven by a force). The forcing is one of (mechgen.analyses.forcing):

* ``input``: a unit force on one coordinate, f = e_j; ``amplitude`` and ``phase`` are |H_kj| and arg H_kj;
* ``force``: a harmonic force pattern on several coordinates, ``{x = 1.0, y = {amplitude = 1.0, phase = 90}}``
  (generalized force units, phases in degrees): f_k = A_k exp(i phi_k);
* ``unbalance``: a mass ``mass`` (kg) at an eccentricity ``eccentricity`` (m) on a disk whose translations
  ``coordinates = [x, y]`` are named, phase ``phase`` (degrees): the force m e Omega^2 rotating with the
  shaft, F_x = m e Omega^2 cos(Omega t + phi), F_y = m e Omega^2 sin(Omega t + phi), over the speeds
  ``over = {<speed parameter> = ...}`` (as campbell names them); at each speed the model is linearised with
  the speed parameter set to it (its gyroscopic G(Omega), and K(Omega) where it depends on it), and the
  driving frequency is the speed.

Scene keys: one of ``input``, ``force``, ``unbalance``; ``omega`` (driving frequencies: a list or {start,
stop, num}; required with input or force, refused with unbalance) or ``over`` (with unbalance); ``speed_unit``
(rad/s, the default, Hz or rpm: the unit of the numbers in ``omega``, ``over`` and ``orbit_at`` and of the
plots' axis); ``outputs`` (the coordinates to report; default all), ``orbits`` (coordinate pairs whose orbits
are reported; default the unbalances' pairs, or the model's whirl pairs that a force pattern drives on both
coordinates), ``orbit_at`` (the speeds or
frequencies whose orbits the orbit figure draws), ``about`` / ``at`` (the operating point, as for ``modes``),
``max_seconds`` (the wall-time budget, default 600 s: the time of all the frequencies is estimated from the
first ones and a response that would take longer is refused, naming the frequencies done). Outputs: ``omega``
(rad/s), ``amplitude`` and ``phase`` (per output coordinate, |X_k| and arg X_k in rad relative to cos(omega t),
one value per frequency), ``input`` (with input), ``forcing``, ``speed_unit`` and ``omega_in_unit`` (the
frequencies in speed_unit), with unbalance ``speeds`` (rad/s) and ``parameter``, and ``orbit`` per pair
(``major``, ``minor``, ``angle``, ``whirl``, ``whirl_ratio``) with ``orbit_at``. A frequency at which the
undamped system is singular (a resonance without damping) raises a ConvergenceError naming it.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import forcing, response_figures, summary
from mechgen.analyses.operating_point import linear_about, operating_point
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option, about, coordinate_table, one_of, positive, value_range
from mechgen.errors import SceneError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
from mechgen.runtime.linear.campbell import fit_speed_polynomial
from mechgen.runtime.linear.harmonic import harmonic_responses, orbits
from mechgen.scene.values import fail, listing, show, type_name


def coordinate(ctx, key: str, value: object) -> str:
    """One of the (active) coordinate names."""
    if not isinstance(value, str) or value not in ctx.coordinates:
        raise fail(ctx.file, key, f"unknown coordinate {show(value)}", "one of: " + listing(ctx.coordinates))
    return value


def coordinates(ctx, key: str, value: object) -> list[str]:
    """A list of coordinate names."""
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a non-empty list of coordinate names")
    return [coordinate(ctx, f"{key}[{i + 1}]", v) for i, v in enumerate(value)]


def frequencies(ctx, key: str, value: object) -> list[float]:
    """Driving frequencies >= 0 (in speed_unit, rad/s by default): a list of numbers, or {start, stop, num}."""
    if isinstance(value, dict):
        values = value_range(ctx, key, value)
    elif isinstance(value, list) and value:
        values = [float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else
                  _bad(ctx, f"{key}[{i + 1}]", v) for i, v in enumerate(value)]
    else:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a list of frequencies or {start, stop, num}")
    if not all(np.isfinite(values)) or min(values) < 0:
        raise fail(ctx.file, key, "a frequency is negative or not finite", "frequencies >= 0 (in speed_unit)")
    return values


def _bad(ctx, key: str, value: object):
    raise fail(ctx.file, key, f"value is {type_name(value)}", "a number (in speed_unit, rad/s by default)")


def check(ctx, base: str, options: dict) -> None:
    """A continuum's unknowns are not named coordinates: the response needs a lumped model or a chain; one
    forcing with its frequencies or speeds (mechgen.analyses.forcing.check_forcing)."""
    if ctx.model.continuum:
        raise fail(ctx.file, f"{base}.kind", "a response drives a named coordinate; a continuum's unknowns are "
                   "not named", "a lumped model or a chain")
    forcing.check_forcing(ctx, base, options)


SCHEMA = {"input": Option(coordinate, doc="the coordinate driven by a unit harmonic generalized force (one of "
                          "input, force, unbalance)"),
          "force": Option(forcing.force_pattern, doc="a harmonic force pattern: a table coordinate = amplitude or "
                          "coordinate = {amplitude, phase}, the generalized force A cos(omega t + phase) (N or "
                          "N m; phase in degrees, default 0)"),
          "unbalance": Option(forcing.unbalances, doc="a mass eccentricity at a disk: {coordinates = [x, y] (the "
                              "disk's translations), mass (kg), eccentricity (m, >= 0), phase (degrees, default "
                              "0)}, or an array of them; the force m e Omega^2 rotating with the shaft, driven over "
                              "the speeds of 'over'"),
          "omega": Option(frequencies, doc="the driving frequencies (in speed_unit, rad/s by default): a list or "
                          "{start, stop, num}; with input or force"),
          "over": Option(forcing.speed_range, doc="with unbalance: the spin speed, one numeric model parameter, "
                         "and its values (in speed_unit): {Omega = {start, stop, num}} or an array, as campbell "
                         "names it; the driving frequency is the speed"),
          "speed_unit": Option(one_of("speed unit", tuple(forcing.SPEED_UNITS)), "rad/s",
                               doc="the unit of the numbers in omega, over and orbit_at and of the plots' axis: "
                               "rad/s, Hz (2 pi rad/s) or rpm (2 pi / 60 rad/s); outputs stay in rad/s and add "
                               "omega_in_unit"),
          "outputs": Option(coordinates, doc="the coordinates whose response is reported (default all)"),
          "orbits": Option(forcing.pairs, doc="the coordinate pairs [[x, y], ...] whose orbits are reported "
                           "(default: the unbalances' pairs, or the model's whirl pairs (Model.whirl_pair) that a force pattern "
                           "drives on both coordinates; none for input)"),
          "orbit_at": Option(forcing.speed_values, doc="the speeds or frequencies (in speed_unit) whose orbits "
                             "the orbit figure draws, the nearest computed ones (default: up to five, the "
                             "largest response among them)"),
          "about": Option(about, doc="the name of an earlier steady analysis whose state is the operating point"),
          "at": Option(coordinate_table, doc="the operating point's coordinates (a table coordinate = value; "
                       "left out: zero)"),
          "max_seconds": Option(positive, doc="the wall-time budget (s, default 600), estimated from the first "
                                "frequencies")}


def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel."""
    return {"linear"}


def frees(options: dict) -> list[str]:
    """With an unbalance, the speed parameter: free in the kernels (set at every speed)."""
    return list(options.get("over") or {})


def _constant(system, options: dict, context: dict):
    """matrices_at for a fixed system: M, C = D + G, K about the operating point, whatever omega."""
    q = operating_point(system, options, context)
    mats = linear_about(system, q, options, context)
    fixed = {"M": mats["M"], "C": mats["D"] + mats["G"], "K": mats["K"]}
    return lambda w: fixed


def _speed_dependent(system, options: dict, context: dict, speeds: list[float]):
    """matrices_at(Omega) with the speed parameter set to Omega (rad/s): the matrices assembled at the
    operating point, through a polynomial in the speed when they are one (fit_speed_polynomial, as campbell)."""
    (name, _), = options["over"].items()
    if name not in system.metadata.params:
        raise SceneError(f"an unbalance response over {name!r}, which the compiled kernels fold as a constant",
                         key="over", expected="a numeric model parameter kept free (the spin speed)")
    q = operating_point(system, options, context)

    def assembled(speed: float) -> dict:
        mats = system.with_params(**{name: speed}).linear(q)
        return {"M": mats["M"], "D": mats["D"], "G": mats["G"], "K": mats["K"]}

    poly = fit_speed_polynomial(assembled, min(speeds), max(speeds)) if len(speeds) > 4 else None
    if poly is not None:
        return poly.combined({"M": ("M",), "C": ("D", "G"), "K": ("K",)})

    def matrices_at(speed: float) -> dict:
        mats = assembled(speed)
        return {"M": mats["M"], "C": mats["D"] + mats["G"], "K": mats["K"]}

    return matrices_at


def run_response(system, options: dict, context: dict) -> dict:
    """The response X(omega) = H(omega) f to the scene's forcing at every frequency or speed (module doc)."""
    names = list(system.coordinates)
    unit = options.get("speed_unit", "rad/s")
    n = system.n
    if "unbalance" in options:
        (param, values), = options["over"].items()
        omegas = forcing.to_rad_per_s(values, unit)
        matrices_at = _speed_dependent(system, options, context, omegas)
        force_at = lambda w: forcing.unbalance_force(n, names, options["unbalance"], w)  # noqa: E731
    else:
        omegas = forcing.to_rad_per_s(options["omega"], unit)
        matrices_at = _constant(system, options, context)
        if "input" in options:
            fixed = np.zeros(n, dtype=complex)
            fixed[names.index(options["input"])] = 1.0
        else:
            fixed = forcing.pattern_force(n, names, options["force"])
        force_at = lambda w: fixed  # noqa: E731
    budget = Budget("response", unit="frequencies", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    X = harmonic_responses(matrices_at, omegas, force_at, budget)
    out = _outputs(names, X, options, omegas)
    out["forcing"] = next(k for k in ("input", "force", "unbalance") if k in options)
    if "unbalance" in options:
        out["speeds"], out["parameter"] = list(out["omega"]), param
    out.update(_orbit_outputs(system, options, X, omegas))
    return out


def _outputs(names: list[str], X: np.ndarray, options: dict, omegas: list[float]) -> dict:
    """omega (rad/s), amplitude |X_k| and phase arg X_k (rad) per output coordinate, the frequencies in unit."""
    rows = [names.index(k) for k in options.get("outputs") or names]
    unit = options.get("speed_unit", "rad/s")
    out = {"omega": [float(w) for w in omegas]}
    if "input" in options:
        out["input"] = options["input"]
    out["amplitude"] = {names[k]: [float(v) for v in np.abs(X[k])] for k in rows}
    out["phase"] = {names[k]: [float(v) for v in np.angle(X[k])] for k in rows}
    out["speed_unit"] = unit
    out["omega_in_unit"] = forcing.in_unit(omegas, unit)
    return out


def _orbit_outputs(system, options: dict, X: np.ndarray, omegas: list[float]) -> dict:
    """``orbit``: {"x,y": orbits(X_x, X_y)} per pair, and ``orbit_at``: the frequencies (rad/s) the orbit figure
    draws (the computed ones nearest ``orbit_at``, else up to five spread over the range and the largest)."""
    pairs = forcing.orbit_pairs(system, options)
    if not pairs:
        return {}
    names = list(system.coordinates)
    table = {f"{x},{y}": orbits(X[names.index(x)], X[names.index(y)]) for x, y in pairs}
    w = np.asarray(omegas)
    if "orbit_at" in options:
        wanted = forcing.to_rad_per_s(options["orbit_at"], options.get("speed_unit", "rad/s"))
        picks = sorted({int(np.argmin(np.abs(w - v))) for v in wanted})
    else:
        size = np.asarray(table[f"{pairs[0][0]},{pairs[0][1]}"]["major"])
        picks = sorted(set(np.linspace(0, len(w) - 1, min(4, len(w))).round().astype(int).tolist())
                       | {int(np.argmax(size))})
    return {"orbit": table, "orbit_at": [float(w[i]) for i in picks]}


register(AnalysisKind("response", SCHEMA, run_response, needs, summary.lines, check=check, frees=frees,
                      plot=response_figures.plot))
