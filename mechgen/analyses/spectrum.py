"""``spectrum``: the response to a travelling train of impulses, in modal coordinates, and its windowed spectrum.

A contact point moves at ``speed`` v (m/s) from ``start`` x_0 to ``stop`` (m; default the field's
length): x(t) = x_0 + v t. It strikes at every ``spacing`` lambda (m, a corrugation's wavelength),
i.e. at t_k = k lambda / v, with the impulse J(x_k) (N s; ``impulse``: a number or an expression of
the contact position ``x`` and the parameters, e.g. "sin(2*pi*x/wavelength)"). About q = 0 the
linear system M q'' + K q = sum_k (J_k g(x_k) + C_k g'(x_k)) delta(t - t_k) (g(x): the reduced dofs of a
unit point force on ``field`` at x; g'(x), those of a unit point couple, the slope row; C_k the angular
impulse ``couple``, N m s, an expression of x like ``impulse``: a tangential impulse J_t at a distance e
from the neutral axis, an interface off the axis, is the couple e J_t; a lumped model's unit force on the
coordinate ``input``; only M and K are used:
the model's own D and G are replaced by the modal damping, and q = 0 is taken to be a rest state) is projected on its
lowest ``modes`` mass-normalised modes and given the modal damping ratio ``damping`` zeta (0 <= zeta
< 1); each modal coordinate is then a sum of damped sines (mechgen.runtime.linear.impulses), sampled
at ``sample_rate`` (Hz) up to ``t_end`` (s). The response u(t) = sum_n phi_n(observe) q_n(t) (the
field at ``observe``, m, default a tenth of the length; or the coordinate ``output``, default
``input``), or its rate with ``signal = "velocity"``, is windowed (Hann) and Fourier transformed.

Outputs: ``natural_frequencies`` (Hz, of the retained modes), ``spectrum_peaks`` (Hz: the ``peaks``
most prominent maxima of log amplitude below ``f_max``, default 1.1 x the highest natural frequency,
at least ``separation`` bins apart, default 10; ascending),
``frequency_bin`` (Hz, 1 / record length), ``impulses`` (how many blows), ``impulse_rate`` (v / lambda, Hz:
the blows' rate, whose harmonics the train's spectrum also shows while the contact runs), ``frequency`` and
``amplitude`` (the spectrum up to f_max; amplitude in the response's units), ``t`` and ``response``
(the record, at most ``series`` points, evenly thinned, for plots); with ``reference`` (a list of
frequencies in Hz, e.g. published ones) also ``reference_frequencies`` and ``frequency_ratio`` (ours / theirs,
mode by mode).
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import summary
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.response import coordinate
from mechgen.analyses.schema import REQUIRED, Option, count, number, one_of, positive
from mechgen.errors import InputError
from mechgen.runtime.linear.impulses import hann_spectrum, mass_normalised, modal_train, spectral_peaks
from mechgen.runtime.linear.modes import modes as solve_modes
from mechgen.scene.expr import parse_expression
from mechgen.scene.values import expression, fail, show, type_name

#: the most samples one record may hold (the scene's [limits] samples raises it)
SAMPLES_LIMIT = "samples"
#: what the spectrum is taken of: the field (coordinate) at the observation point, or its rate
SIGNALS = ("displacement", "velocity")


def damping_ratio(ctx, key: str, value: object) -> float:
    """0 <= zeta < 1 (light modal damping)."""
    zeta = number(ctx, key, value)
    if not 0.0 <= zeta < 1.0:
        raise fail(ctx.file, key, f"damping ratio {zeta!r} is outside [0, 1)", "a modal damping ratio 0 <= zeta < 1")
    return zeta


def impulse(ctx, key: str, value: object) -> dict:
    """A number (N s) or an expression of the contact position x and the parameters: {"text", "values"}."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a number or an expression of x and parameters")
    text = str(value)
    expr = expression(ctx.file, key, text)
    known = {n for n, v in ctx.params.items() if not isinstance(v, str)}
    for name in expr.names:
        if name != "x" and name not in known:
            raise fail(ctx.file, key, f"unknown name {show(name)} in expression",
                       "the contact position x and numeric parameters")
        if name in ctx.swept:
            raise fail(ctx.file, key, f"expression uses swept parameter '{name}'", "parameters that are not swept")
    return {"text": text, "values": {n: float(ctx.params[n]) for n in expr.names if n != "x"}}


def frequencies_hz(ctx, key: str, value: object) -> list[float]:
    """A non-empty list of frequencies > 0 (Hz), e.g. published natural frequencies to print beside ours."""
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}", "a non-empty list of frequencies in Hz")
    return [positive(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]


def field_name(ctx, key: str, value: object) -> str:
    """A string (checked against the system's fields when it runs)."""
    if not isinstance(value, str):
        raise fail(ctx.file, key, f"value is {type_name(value)}", "the name of a field")
    return value


SCHEMA = {
    "speed": Option(positive, REQUIRED, "the sliding velocity in m/s (a number or expression)",
                    doc="the contact point's speed v (m/s)"),
    "spacing": Option(positive, REQUIRED, "the distance between impulses in m (a corrugation's wavelength)",
                      doc="the distance lambda between blows (m, a corrugation's wavelength)"),
    "t_end": Option(positive, REQUIRED, "the record length in s", doc="the record length (s)"),
    "sample_rate": Option(positive, REQUIRED, "samples per second (Hz), above twice the highest mode's",
                          doc="samples per second of the record (Hz), above twice the highest mode's frequency"),
    "impulse": Option(impulse, {"text": "1", "values": {}}, doc="each blow's force impulse J (N s): a number or an "
                      "expression of the contact position x and the parameters"),
    "couple": Option(impulse, doc="each blow's angular impulse on the field's slope (N m s), an expression of x "
                     "like impulse"),
    "start": Option(number, 0.0, doc="where the contact starts, x_0 (m)"),
    "stop": Option(number, doc="where the contact stops (m; default the field's length)"),
    "field": Option(field_name, doc="the field the blows strike (default the model's only field)"),
    "observe": Option(number, doc="where the field's response is observed (m; default a tenth of the length)"),
    "input": Option(coordinate, doc="a lumped model's coordinate the unit force drives"),
    "output": Option(coordinate, doc="a lumped model's coordinate whose response is analysed (default input)"),
    "modes": Option(count, 8, doc="how many of the lowest mass-normalised modes the response is projected on"),
    "damping": Option(damping_ratio, 0.01, doc="the modal damping ratio zeta (0 <= zeta < 1, dimensionless)"),
    "peaks": Option(count, 4, doc="how many of the most prominent spectrum maxima to report"),
    "f_max": Option(positive, doc="the highest frequency of the spectrum and its peaks (Hz; default 1.1 x the "
                    "highest natural frequency)"),
    "series": Option(count, 2000, doc="the most points of the record t, response reported for plots"),
    "signal": Option(one_of("signal", SIGNALS), "displacement", doc="the analysed signal: displacement or "
                     "velocity"),
    "separation": Option(count, 10, doc="the fewest frequency bins between two reported peaks"),
    "reference": Option(frequencies_hz, doc="reference frequencies (Hz, e.g. published ones) compared mode by "
                        "mode"),
}


def check(ctx, base: str, options: dict) -> None:
    """A lumped model needs ``input``; a continuum takes ``field`` / ``observe`` instead; the record's size."""
    from mechgen.scene.bounds import LIMITS

    if ctx.model.continuum:
        for key in ("input", "output"):
            if key in options:
                raise fail(ctx.file, f"{base}.{key}", f"'{key}' names a coordinate; a continuum's unknowns are not "
                           "named", "field and observe (a position in m) for a continuum")
    else:
        if "input" not in options:
            raise fail(ctx.file, f"{base}.input", "missing required key 'input' for a spectrum of a lumped model",
                       "the coordinate the impulses drive")
        for key in ("field", "observe"):
            if key in options:
                raise fail(ctx.file, f"{base}.{key}", f"'{key}' is for a continuum", "input and output coordinates")
        if "couple" in options:
            raise fail(ctx.file, f"{base}.couple", "'couple' (an angular impulse on the field's slope) is for a "
                       "continuum", "impulse alone for a lumped model")
    samples = options["t_end"] * options["sample_rate"]
    top = ctx.limits.get(SAMPLES_LIMIT, LIMITS[SAMPLES_LIMIT])
    if samples > top:
        raise fail(ctx.file, f"{base}.t_end", f"t_end x sample_rate = {samples:.4g} samples is above the safety "
                   f"limit {top}", f"a shorter record or a lower rate (or [limits] {SAMPLES_LIMIT} = ...)")
    if samples < 16:
        raise fail(ctx.file, f"{base}.t_end", f"t_end x sample_rate = {samples:.4g} samples", "at least 16 samples")


def needs(options: dict, *, internal: bool) -> set[str]:
    """M and K: the linear kernel."""
    return {"linear"}


def _blows(system, options: dict) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and positions (m) of the impulses: x_k = start + k spacing while within [start, stop] and t_k < t_end."""
    v, lam, x0 = options["speed"], options["spacing"], options["start"]
    stop = options.get("stop")
    if stop is None:
        stop = system.disc.length if system.is_field else x0 + v * options["t_end"]
    n = int(np.floor((stop - x0) / lam * (1 + 1e-12))) + 1 if stop >= x0 else 0
    x = x0 + lam * np.arange(max(n, 0))
    t = (x - x0) / v
    keep = t < options["t_end"]
    return t[keep], x[keep]


def _loads(system, options: dict, x: np.ndarray, order: int = 0):
    """Columns g(x_k) (reduced generalized force of a unit point force; with ``order`` 1, of a unit point
    couple: the slope row) and the observation row c (u = c q)."""
    if not system.is_field:
        names = list(system.coordinates)
        g = np.zeros((system.n, len(x)))
        g[names.index(options["input"])] = 1.0
        c = np.zeros(system.n)
        c[names.index(options.get("output") or options["input"])] = 1.0
        return g, c
    disc = system.disc
    field = options.get("field") or disc.fields[0]
    if field not in disc.fields:
        raise InputError(f"unknown field {show(field)}", key="field", expected="one of: " + ", ".join(disc.fields))
    length = disc.length
    for key, where in (("start", options["start"]), ("observe", options.get("observe", 0.1 * length))):
        if not 0.0 <= where <= length:
            raise InputError(f"{key} = {where:g} m is outside the field [0, {length:g}]", key=key,
                             expected="a position along the field in m")
    red = system.reduction
    g = (np.column_stack([red.vector(disc.row(field, order, float(p))) for p in x]) if len(x)
         else np.zeros((system.n, 0)))
    c = red.vector(disc.row(field, 0, float(options.get("observe", 0.1 * length))))
    return g, c


def run_spectrum(system, options: dict, context: dict) -> dict:
    """Natural frequencies, the modal impulse-train response and the peaks of its Hann spectrum (module doc)."""
    mats = system.linear(np.zeros(system.n))
    res = solve_modes(mats["M"], mats["K"], count=options["modes"],
                      allow_singular_mass=getattr(system, "has_multipliers", False))
    omega, phi = res.frequencies[res.rigid:], res.shapes[:, res.rigid:]
    if not len(omega):
        raise InputError("the system has no elastic mode", key="modes", expected="a model with stiffness")
    phi = mass_normalised(mats["M"], phi)
    rate, t_end = options["sample_rate"], options["t_end"]
    f_n = omega / (2 * np.pi)
    if rate <= 2 * f_n[-1]:
        raise InputError(f"sample_rate = {rate:g} Hz is not above twice the highest retained mode's frequency, "
                         f"{f_n[-1]:.6g} Hz (mode {len(f_n)}): its response would alias", key="sample_rate",
                         expected=f"a rate above {2 * f_n[-1]:.6g} Hz, or fewer modes")
    t_k, x_k = _blows(system, options)
    magnitude = parse_expression(options["impulse"]["text"], key="impulse")
    J = np.array([magnitude.evaluate({**options["impulse"]["values"], "x": float(x)}) for x in x_k])
    g, c = _loads(system, options, x_k)
    P = phi.T @ (g * J)                     # generalized modal impulses, N s per unit modal coordinate
    if options.get("couple") is not None:   # angular impulses on the slope row
        turning = parse_expression(options["couple"]["text"], key="couple")
        C = np.array([turning.evaluate({**options["couple"]["values"], "x": float(x)}) for x in x_k])
        P = P + phi.T @ (_loads(system, options, x_k, order=1)[0] * C)
    samples = int(round(t_end * rate))
    dt = 1.0 / rate
    u = np.zeros(samples)
    for n, w in enumerate(omega):
        u += (c @ phi[:, n]) * modal_train(float(w), options["damping"], dt, samples, t_k, P[n],
                                                 SIGNALS.index(options["signal"]))
    freq, amp = hann_spectrum(u, rate)
    f_max = options.get("f_max") or 1.1 * float(f_n[-1])
    peaks = spectral_peaks(freq, amp, options["peaks"], f_max, options["separation"])
    shown = freq <= f_max
    step = max(1, samples // options["series"])
    out = {"natural_frequencies": [float(f) for f in f_n]}
    if options.get("reference"):
        ref = options["reference"][:len(f_n)]
        out.update({"reference_frequencies": list(ref),
                    "frequency_ratio": [float(f / r) for f, r in zip(f_n, ref)]})
    return {**out, "spectrum_peaks": peaks,
            "frequency_bin": float(freq[1] - freq[0]), "impulses": int(len(t_k)),
            "impulse_rate": options["speed"] / options["spacing"],
            "frequency": [float(f) for f in freq[shown]], "amplitude": [float(a) for a in amp[shown]],
            "t": [float(v) for v in (np.arange(samples) * dt)[::step]], "response": [float(v) for v in u[::step]]}


def summary_lines(outputs: dict) -> list[str]:
    """Every output but the spectrum and the record."""
    return summary.output_lines(outputs, skip=("frequency", "amplitude", "response"))


def plot(plt, entry: dict, path) -> list:
    """The spectrum (log amplitude) with the natural frequencies (dashed) and the peaks (dots) marked."""
    out = entry["outputs"]
    fig, ax = plt.subplots(figsize=(7, 4))
    amp = np.maximum(out["amplitude"], 1e-300)
    ax.semilogy(out["frequency"], amp, lw=0.8)
    shown = [f for f in out["natural_frequencies"] if f <= out["frequency"][-1]]
    for i, f in enumerate(shown):
        ax.axvline(f, color="tab:red", ls="--", lw=0.7, label="natural frequencies" if i == 0 else None)
    f = np.asarray(out["frequency"])
    for i, p in enumerate(out["spectrum_peaks"]):
        ax.plot(p, amp[int(np.argmin(np.abs(f - p)))], "o", color="k", ms=4, label="peaks" if i == 0 else None)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("amplitude (Hann window)")
    ax.set_title(entry["name"])
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("spectrum", SCHEMA, run_spectrum, needs, summary_lines, check=check, plot=plot))
