"""``mechgen bench orbits``: a frequency-response curve by harmonic balance and shooting against a hand-written
scipy shooting-plus-continuation baseline, at equal accuracy.

The problem (issue 27, item 9): the forced Duffing oscillator x'' + c x' + x + k3 x^3 = F cos(w t), c = 0.1,
k3 = 1, F = 0.3, its curve of periodic orbits from w = 0.5 to 2.5 rad/s through both cyclic folds. Accuracy is
the error of the two folds' frequencies against a converged reference (mechgen's shooting at Newton rtol 1e-12,
the integrator at 1e-14: at its folds the largest multiplier is 1 to 1e-9); cost is the wall time of the whole
curve and per branch point. Sides (each the median of ``repeats`` interleaved rounds after one warm-up):

* ``harmonic balance H``: mechgen.periodic_orbit + mechgen.continuation with H = 3, 5, 7, 9 harmonics;
* ``shooting rtol``: the same by shooting (Newton rtol 1e-6, 1e-8, 1e-10; the compiled DOP853 loop at 1/100);
* ``hand-written scipy``: benchmarks/duffing_frc_handwritten.py (solve_ivp DOP853 at rtol 1e-6, 1e-8, 1e-10,
  fsolve, forward-difference tangents, folds by the secant on t_w), ds = 0.05 as mechgen's largest step.

The headline ratio compares the baseline at rtol 1e-10 with mechgen's fastest series whose fold error is no
larger than the baseline's (the condition says which); the issue's target is >= 10x. Symbolic work is independent
of H (the model is derived once; the harmonics are numeric: DESIGN.md).
"""
from __future__ import annotations

import importlib.util
import time
from pathlib import Path

import numpy as np

from mechgen.bench.common import blas_threads, environment, suite_report, write_json, write_text

ROOT = Path(__file__).resolve().parents[2]
BASELINE = ROOT / "benchmarks" / "duffing_frc_handwritten.py"
PARAMS = {"m": 1.0, "c": 0.1, "k": 1.0, "k3": 1.0, "F": 0.3, "w": 0.5}
W_STOP = 2.5
TARGET_RATIO = 10.0


def baseline_module():
    """benchmarks/duffing_frc_handwritten.py, imported by path."""
    spec = importlib.util.spec_from_file_location("duffing_frc_handwritten", BASELINE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def mechgen_curve(mechgen, system, method: str, setting) -> tuple[list[float], int]:
    """(the folds' w, branch points) of mechgen's curve by ``method`` (H harmonics, or shooting's Newton rtol)."""
    options = {"harmonics": int(setting)} if method == "harmonic_balance" else {"rtol": float(setting),
                                                                                "atol": float(setting) * 1e-3}
    orbit = mechgen.periodic_orbit(system, method=method, frequency="w", **options)
    curve = mechgen.continuation(system, about=orbit, parameter="w", stop=W_STOP, max_step=0.05, max_points=600,
                                 progress=False)
    return sorted(s["w"] for s in curve["special_points"] if s["type"] == "LPC"), int(curve["points"])


def run_orbit_benchmarks(out: Path, quick: bool = False) -> dict:
    """Run the suite, write its reports into ``out`` and return the results."""
    import mechgen

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    system = mechgen.compile("duffing", PARAMS)
    reference, _ = mechgen_curve(mechgen, system, "shooting", 1e-12)
    base = baseline_module()
    sides = {f"harmonic balance H={H}": ("harmonic_balance", H) for H in ((5, 9) if quick else (3, 5, 7, 9))}
    sides.update({f"shooting rtol={r:g}": ("shooting", r) for r in ((1e-8,) if quick else (1e-6, 1e-8, 1e-10))})
    hand = {f"hand-written scipy rtol={r:g}": r for r in ((1e-8,) if quick else (1e-6, 1e-8, 1e-10))}
    results, times = {}, {name: [] for name in list(sides) + list(hand)}

    def call(name):
        if name in sides:
            return mechgen_curve(mechgen, system, *sides[name])
        points, folds = base.frequency_response(PARAMS["w"], W_STOP, hand[name])
        return sorted(folds), len(points)

    with blas_threads(1):
        for name in times:  # warm-up
            results[name] = call(name)
        for _ in range(1 if quick else 3):
            for name in times:
                start = time.perf_counter()
                results[name] = call(name)
                times[name].append(time.perf_counter() - start)
    seconds = {name: float(np.median(ts)) for name, ts in times.items()}
    errors = {name: _fold_error(folds, reference) for name, (folds, _) in results.items()}
    points = [{"series": name.rsplit(" ", 1)[0], "setting": name.rsplit(" ", 1)[1], "seconds": seconds[name],
               "error": errors[name], "branch_points": results[name][1],
               "seconds_per_point": seconds[name] / max(results[name][1], 1)} for name in times]
    peer = list(hand)[-1]
    ours = _fastest_as_accurate(seconds, errors, sides, errors[peer])
    ratios = [{"peer": "hand-written scipy shooting + continuation (benchmarks/)", "ours_s": seconds[ours],
               "peer_s": seconds[peer], "condition": f"same curve (w 0.5 to 2.5, both folds); ours: {ours} (fold error "
               f"{errors[ours]:.1e}), peer: {peer} (fold error {errors[peer]:.1e}); mechgen also gives every "
               "orbit's multipliers, stability and amplitude, the baseline the branch and its folds only"}]
    suite_report(out, "orbits", points, reference="mechgen shooting at Newton rtol 1e-12 (folds' multiplier 1)",
                 error="max |w_fold - w_fold,ref| (rad/s)", time="seconds per curve (median of interleaved rounds)",
                 title="Duffing frequency-response curve", ratios=ratios)
    data = {"reference_folds": reference, "seconds": seconds, "errors": errors, "points": points,
            "ratio": seconds[peer] / seconds[ours], "ours": ours, "peer": peer, "target_ratio": TARGET_RATIO,
            "environment": environment()}
    write_json(out / "orbits.json", data)
    write_text(out / "orbits.md", _markdown(data))
    return data


def _fold_error(folds: list[float], reference: list[float]) -> float:
    if len(folds) != len(reference):
        return float("inf")
    return float(np.max(np.abs(np.asarray(folds) - np.asarray(reference))))


def _fastest_as_accurate(seconds: dict, errors: dict, sides: dict, bound: float) -> str:
    """mechgen's fastest series whose fold error is at most ``bound`` (else its most accurate one)."""
    good = [name for name in sides if errors[name] <= bound]
    return min(good, key=seconds.get) if good else min(sides, key=errors.get)


def _markdown(data: dict) -> str:
    rows = "\n".join(f"| {p['series']} | {p['setting']} | {p['seconds']:.3f} | {p['branch_points']} | "
                     f"{1e3 * p['seconds_per_point']:.2f} | {p['error']:.1e} |" for p in data["points"])
    return ("# orbits: Duffing frequency-response curve (w 0.5 to 2.5 rad/s, both folds)\n\n"
            "| series | setting | seconds | branch points | ms per point | fold error (rad/s) |\n"
            "|---|---|---|---|---|---|\n" + rows + "\n\n"
            f"reference folds: {', '.join(f'{w:.10f}' for w in data['reference_folds'])} rad/s\n\n"
            f"{data['peer']} / {data['ours']} (at least as accurate): **{data['ratio']:.1f}x** "
            f"(target >= {data['target_ratio']:g}).\n")
