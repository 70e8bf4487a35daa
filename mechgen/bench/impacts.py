"""``mechgen bench impacts``: compliant impacts, mechgen's event-driven runs against hand-written solve_ivp.

* **sweep** - the coefficient of restitution e over 200 damping ratios zeta in [0.025, 5] for each of the
  five contact laws of ``viscoelastic_impact`` (``mechgen.restitution``, C kernels, DOP853 at rtol 1e-10,
  with its progress bar), against ``benchmarks/impact_handwritten.py`` (plain numpy right-hand sides and
  ``scipy.integrate.solve_ivp`` with a terminal release event, imported by path) at the same method,
  tolerance and end time (T_END), each side warmed up once and timed as the median of 3 interleaved rounds. Reported per law: wall time, time per impact, the ratio (target >= 5) and each
  side's largest relative error against the closed forms of ``tests/impact_reference.py`` (equal
  accuracy is what the ratio is at).
* **work-precision** - the restitution error at zeta = 0.3 against wall time per impact over a
  tolerance ladder, per law and integrator (DOP853, RK45, Radau, BDF).
* **user path** - ``mechgen run scenes/impact_models.toml --set zeta=0.3`` as a user runs it.

Writes ``out/impacts.{json,md,csv}`` and ``out/impacts_work_precision.png``. ``quick``: 4 damping
ratios, one tolerance and integrator (a smoke run).
"""
from __future__ import annotations

import importlib.util
import math
import time
from pathlib import Path

import numpy as np

from mechgen.bench.common import (ROOT, environment, suite_report, user_path, user_path_markdown,
                                  write_csv, write_json, write_text)

LAWS = ("kelvin_voigt", "modified_kelvin_voigt", "maxwell", "standard_linear", "hunt_crossley")
#: the hand-written baseline's name of each law
BASELINE_NAMES = {"kelvin_voigt": "kv", "modified_kelvin_voigt": "mkv", "maxwell": "maxwell", "standard_linear": "sls",
                  "hunt_crossley": "hunt_crossley"}
RTOL, ATOL = 1e-10, 1e-12
TARGET = 5.0
EPSILON = 0.1


def _by_path(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def references():
    """tests/impact_reference.py (closed forms) and benchmarks/impact_handwritten.py (the baseline), by path."""
    return (_by_path("impact_reference", ROOT / "tests" / "impact_reference.py"),
            _by_path("impact_handwritten", ROOT / "benchmarks" / "impact_handwritten.py"))


def exact(ref, law: str, zeta: float) -> float:
    """The reference restitution of a law (Hunt-Crossley at a = alpha v_in = 3 pi zeta / 2, as the model)."""
    return {"kelvin_voigt": ref.kv_restitution, "modified_kelvin_voigt": ref.mkv_restitution,
            "maxwell": ref.maxwell_restitution,
            "standard_linear": lambda z: ref.sls_restitution(z, EPSILON),
            "hunt_crossley": lambda z: ref.hc_restitution(1.5 * math.pi * z)}[law](zeta)


def _error(values, expected) -> float:
    """The largest error, relative where e > 1e-8 and absolute below (e = 0: no release, zeta >= 1)."""
    values, expected = np.asarray(values, float), np.asarray(expected, float)
    return float(np.max(np.abs(values - expected) / np.maximum(np.abs(expected), 1e-8)))


def _abs_error(values, expected) -> float:
    """The largest absolute error |e - e_exact| (e is per unit v_in: the release speed over the impact speed)."""
    return float(np.max(np.abs(np.asarray(values, float) - np.asarray(expected, float))))


def _worst(values, expected, zetas) -> float:
    """The damping ratio of the largest error of :func:`_error` (near zeta = 1 e is exponentially small for the
    half-period laws, so a relative error there is an absolute one of atol's size)."""
    values, expected = np.asarray(values, float), np.asarray(expected, float)
    return float(np.asarray(zetas)[int(np.argmax(np.abs(values - expected) / np.maximum(np.abs(expected), 1e-8)))])


#: both sides integrate each impact to this end time (the model's time unit: omega_n = 1, and one Hunt-Crossley time
#: scale, at the model's defaults m = k = v_in = 1), so that a contact that never releases costs both the same
T_END = 60.0


def sweep_row(law: str, zetas, ref, hand, *, method: str = "DOP853", rtol: float = RTOL, atol: float = ATOL,
              repeats: int = 3) -> dict:
    """One law's sweep timed both ways: each side warmed up once, then ``repeats`` interleaved rounds, the median
    of each side's; both integrate to T_END at the same method and tolerances; with their errors."""
    import mechgen

    system = mechgen.compile("viscoelastic_impact", {"law": law, "epsilon": EPSILON}, free=["zeta"])
    grid = [1.5 * math.pi * z for z in zetas] if law == "hunt_crossley" else list(zetas)
    got = {}

    def ours():
        got["ours"] = mechgen.restitution(system, over={"zeta": [float(z) for z in zetas]}, t_end=T_END,
                                          method=method, rtol=rtol, atol=atol, hysteresis=0, progress=False).outputs

    def theirs():
        got["theirs"] = hand.restitution_sweep(BASELINE_NAMES[law], grid, rtol=rtol, atol=atol, method=method,
                                               t_max=T_END, **({"epsilon": EPSILON} if law == "standard_linear"
                                                               else {}))

    times = {"ours": [], "theirs": []}
    ours(), theirs()  # warm-ups, excluded
    for _ in range(repeats):
        for name, fn in (("ours", ours), ("theirs", theirs)):
            start = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - start)
    out, base = got["ours"], got["theirs"]
    ours_s, theirs_s = float(np.median(times["ours"])), float(np.median(times["theirs"]))
    expected = [exact(ref, law, float(z)) for z in zetas]
    return {"law": law, "impacts": len(zetas), "method": method, "rtol": rtol, "t_end": T_END, "repeats": repeats,
            "mechgen_s": ours_s, "handwritten_s": theirs_s, "mechgen_per_impact_s": ours_s / len(zetas),
            "handwritten_per_impact_s": theirs_s / len(zetas), "ratio": theirs_s / ours_s,
            "handwritten_nfev": int(np.sum(base.nfev)),
            "mechgen_error": _error(out["restitution"], expected), "handwritten_error": _error(base.e, expected),
            "mechgen_abs_error": _abs_error(out["restitution"], expected),
            "handwritten_abs_error": _abs_error(base.e, expected),
            "mechgen_worst_zeta": _worst(out["restitution"], expected, zetas),
            "handwritten_worst_zeta": _worst(base.e, expected, zetas), "target": TARGET}


def work_precision(ref, laws, methods, rtols, zeta: float = 0.3) -> list[dict]:
    """Restitution error against wall time per impact, per law, integrator and tolerance."""
    import mechgen

    rows = []
    for law in laws:
        system = mechgen.compile("viscoelastic_impact", {"law": law, "epsilon": EPSILON, "zeta": zeta})
        expected = exact(ref, law, zeta)
        for method in methods:
            for rtol in rtols:
                def once():
                    return mechgen.impact(system, t_end=60.0, method=method, rtol=rtol, atol=rtol * 1e-2,
                                          max_steps=10**6).outputs["restitution"]
                once()
                count, start = 0, time.perf_counter()
                while True:
                    e = once()
                    count += 1
                    if time.perf_counter() - start > 0.2 or count >= 20:
                        break
                seconds = (time.perf_counter() - start) / count
                rows.append({"law": law, "method": method, "rtol": rtol, "seconds_per_impact": seconds,
                             "error": abs(e - expected) / expected})
    return rows


def markdown(sweeps: list[dict], wp: list[dict], users: list[dict], env: dict) -> str:
    lines = ["# Compliant impacts: mechgen against hand-written solve_ivp", "",
             f"Restitution over {sweeps[0]['impacts']} damping ratios per law, {sweeps[0]['method']} at rtol "
             f"{sweeps[0]['rtol']:g}, both sides integrating every impact to t = {sweeps[0]['t_end']:g} (a contact "
             "that never releases costs both the same), each side warmed up once and timed as the median of "
             f"{sweeps[0]['repeats']} interleaved rounds, in one run (target: ratio >= {TARGET:g} at equal accuracy).",
             "",
             "Errors against the closed forms of tests/impact_reference.py: the largest relative one (absolute "
             "where e < 1e-8), at the damping ratio named, and the largest absolute one. From zeta = 1 the "
             "half-period laws (Kelvin-Voigt, Maxwell) have e = 0 (x creeps back to 0 without crossing); there "
             "both sides may cross at the end of the run by round-off, at |e| ~ atol, which the relative "
             "column shows as (abs. error) / 1e-8.", "",
             "| law | mechgen per impact | hand-written per impact | ratio | mechgen max rel. error (at zeta) | "
             "hand-written max rel. error (at zeta) | mechgen max abs. error | hand-written max abs. error |",
             "|---|---|---|---|---|---|---|---|"]
    for r in sweeps:
        lines.append(f"| {r['law']} | {r['mechgen_per_impact_s'] * 1e3:.3f} ms | "
                     f"{r['handwritten_per_impact_s'] * 1e3:.3f} ms | **{r['ratio']:.2f}** | "
                     f"{r['mechgen_error']:.2e} ({r['mechgen_worst_zeta']:.3g}) | "
                     f"{r['handwritten_error']:.2e} ({r['handwritten_worst_zeta']:.3g}) | "
                     f"{r['mechgen_abs_error']:.2e} | {r['handwritten_abs_error']:.2e} |")
    total_ours = sum(r["mechgen_s"] for r in sweeps)
    total_theirs = sum(r["handwritten_s"] for r in sweeps)
    lines += ["", f"All laws: mechgen {total_ours:.2f} s, hand-written {total_theirs:.2f} s, ratio "
              f"**{total_theirs / total_ours:.2f}**.", "", "## Work-precision (zeta = 0.3)", "",
              "| law | method | rtol | s per impact | rel. error |", "|---|---|---|---|---|"]
    lines += [f"| {r['law']} | {r['method']} | {r['rtol']:g} | {r['seconds_per_impact']:.3g} | {r['error']:.2e} |"
              for r in wp]
    lines += ["", user_path_markdown(users), "", f"Environment: {env}"]
    return "\n".join(lines) + "\n"


def run_impact_benchmarks(out: Path, quick: bool = False) -> dict:
    """Run the suite (see the module doc) and write its reports into ``out``."""
    out = Path(out)
    env = environment()
    ref, hand = references()
    zetas = np.linspace(0.025, 5.0, 4 if quick else 200)
    sweeps = [sweep_row(law, zetas, ref, hand, repeats=1 if quick else 3) for law in LAWS]
    methods = ("DOP853",) if quick else ("DOP853", "RK45", "Radau", "BDF")
    rtols = (1e-8,) if quick else (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    wp = work_precision(ref, LAWS, methods, rtols)
    users = user_path([ROOT / "scenes" / "impact_models.toml"], repeats=1 if quick else 3,
                      overrides=("zeta=0.3",))
    env["loadavg_after"] = list(__import__("os").getloadavg())
    results = {"sweep": sweeps, "work_precision": wp, "user_path": users, "environment": env}
    write_json(out / "impacts.json", results)
    write_csv(out / "impacts.csv", wp)
    write_text(out / "impacts.md", markdown(sweeps, wp, users, env))
    suite_report(out, "impacts", [{"series": f"{r['law']} {r['method']}", "setting": f"rtol {r['rtol']:g}",
                                   "seconds": r["seconds_per_impact"], "error": r["error"]} for r in wp],
                 reference="closed-form restitution of each law (tests/impact_reference.py)",
                 error="relative error of e (zeta = 0.3)", time="seconds per impact",
                 title="Compliant impacts: work-precision",
                 ratios=[{"peer": f"hand-written solve_ivp with events ({r['law']})", "ours_s": r["mechgen_s"],
                          "peer_s": r["handwritten_s"],
                          "condition": f"{r['impacts']} zeta values, {r['method']} at rtol {r['rtol']:g}, both to t = "
                                       f"{r['t_end']:g}, median of {r['repeats']} interleaved rounds, same "
                                       f"tolerances (abs. error of e: ours {r['mechgen_abs_error']:.2g}, theirs "
                                       f"{r['handwritten_abs_error']:.2g})"} for r in sweeps])
    return results
