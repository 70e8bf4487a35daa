"""``response``: the steady harmonic response to a unit force at one coordinate (a frequency response).

About an operating point the linearised system M q'' + (D + G) q' + K q = e_j cos(omega t), e_j
a unit generalized force on the coordinate ``input``, responds in steady state with
q(t) = Re(H(omega) e_j exp(i omega t)), where

    H(omega) = (K - omega^2 M + i omega (D + G))^-1

is the receptance (units of coordinate per unit of generalized force: m/N for a translation
driven by a force). Scene keys: ``input`` (a coordinate name, required), ``omega`` (driving
frequencies in rad/s: a list, or {start, stop, num}; required), ``outputs`` (the coordinates to
report; default all), ``about`` / ``at`` (the operating point, as for ``modes``), ``max_seconds``
(the wall-time budget, default 600 s: the time of all the frequencies is estimated from the first
ones and a response that would take longer is refused, naming the frequencies done). Outputs:
``omega`` (the frequencies), ``amplitude`` and ``phase`` (per output coordinate, |H_kj| and
arg H_kj in rad, one value per frequency). A frequency at which the undamped system is singular
(a resonance without damping) raises a ConvergenceError naming it.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.operating_point import linear_about, operating_point
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import REQUIRED, Option, about, coordinate_table, positive, value_range
from mechgen.errors import ConvergenceError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, Budget
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
    """Driving frequencies >= 0 (rad/s): a list of numbers, or {start, stop, num}."""
    if isinstance(value, dict):
        values = value_range(ctx, key, value)
    elif isinstance(value, list) and value:
        values = [float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else
                  _bad(ctx, f"{key}[{i + 1}]", v) for i, v in enumerate(value)]
    else:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a list of frequencies or {start, stop, num}")
    if not all(np.isfinite(values)) or min(values) < 0:
        raise fail(ctx.file, key, "a frequency is negative or not finite", "frequencies >= 0 in rad/s")
    return values


def _bad(ctx, key: str, value: object):
    raise fail(ctx.file, key, f"value is {type_name(value)}", "a number (rad/s)")


def check(ctx, base: str, options: dict) -> None:
    """A continuum's unknowns are not named coordinates: the response needs a lumped model or a chain."""
    if ctx.model.continuum:
        raise fail(ctx.file, f"{base}.kind", "a response drives a named coordinate; a continuum's unknowns are "
                   "not named", "a lumped model or a chain")


SCHEMA = {"input": Option(coordinate, REQUIRED, "a coordinate name",
                          doc="the coordinate driven by the unit harmonic generalized force"),
          "omega": Option(frequencies, REQUIRED, "driving frequencies in rad/s",
                          doc="the driving frequencies (rad/s): a list or {start, stop, num}"),
          "outputs": Option(coordinates, doc="the coordinates whose response is reported (default all)"),
          "about": Option(about, doc="the name of an earlier steady analysis whose state is the operating point"),
          "at": Option(coordinate_table, doc="the operating point's coordinates (a table coordinate = value; "
                       "left out: zero)"),
          "max_seconds": Option(positive, doc="the wall-time budget (s, default 600), estimated from the first "
                                "frequencies")}


def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel."""
    return {"linear"}


def run_response(system, options: dict, context: dict) -> dict:
    """|H_kj(omega)| and arg H_kj(omega) for the input j and every output k (see the module doc)."""
    import scipy.linalg as sla
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    q = operating_point(system, options, context)
    mats = linear_about(system, q, options, context)
    names = list(system.coordinates)
    j = names.index(options["input"])
    rows = [names.index(k) for k in options.get("outputs") or names]
    force = np.zeros(system.n, dtype=complex)
    force[j] = 1.0
    K, M, C = mats["K"], mats["M"], mats["D"] + mats["G"]
    columns = []
    omegas = options["omega"]
    budget = Budget("response", unit="frequencies", seconds=float(options.get("max_seconds", DEFAULT_SECONDS)))
    for i, w in enumerate(omegas):
        budget.project(i, len(omegas), lambda: f"{i:,} of {len(omegas):,} frequencies (omega = {w:g} rad/s)")
        A = K - w**2 * M + 1j * w * C
        if sps.issparse(A):
            h = spla.spsolve(sps.csc_matrix(A, dtype=complex), force)
        else:
            lu, piv = sla.lu_factor(np.asarray(A, dtype=complex), check_finite=False)
            if np.min(np.abs(np.diag(lu))) <= 1e3 * np.finfo(float).eps * np.max(np.abs(np.diag(lu))):
                raise ConvergenceError(f"response: the system is singular at omega = {w:g} rad/s (a resonance "
                                       "without damping); drive off it or add damping")
            h = sla.lu_solve((lu, piv), force, check_finite=False)
        if not np.all(np.isfinite(h)):
            raise ConvergenceError(f"response: no finite response at omega = {w:g} rad/s (a resonance without "
                                   "damping); drive off it or add damping")
        columns.append(h[rows])
    H = np.array(columns).T
    out_names = [names[k] for k in rows]
    return {"omega": [float(w) for w in options["omega"]], "input": options["input"],
            "amplitude": {n: [float(v) for v in np.abs(H[i])] for i, n in enumerate(out_names)},
            "phase": {n: [float(v) for v in np.angle(H[i])] for i, n in enumerate(out_names)}}


def plot(plt, entry: dict, path):
    """Amplitude against driving frequency, one curve per output coordinate (log amplitude)."""
    out = entry["outputs"]
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, amp in out["amplitude"].items():
        ax.semilogy(out["omega"], np.maximum(amp, 1e-300), label=name)
    ax.set_xlabel("omega (rad/s)")
    ax.set_ylabel(f"|H| per unit force at {out['input']}")
    ax.set_title(entry["name"])
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("response", SCHEMA, run_response, needs, summary.lines, check=check, plot=plot))
