"""``mechgen bench simulate``: a smooth model's time response, compiled loop against scipy's stepper, and a sweep.

The problem (issue 25's targets): the forced, damped Duffing oscillator

    m x'' + c x' + k x + k3 x^3 = F cos(w t),   m = k = 1, c = 0.05, k3 = 0.5, F = 0.3, w = 1.2,

from x(0) = 0.5 at rest over 200 forcing periods (t_end = 400 pi / w), 201 equally spaced samples, at
rtol = 1e-10, atol = 1e-12. The model is a user's file (written into the output folder), compiled on the C
backend. Timed, each the median of ``repeats`` interleaved rounds after one warm-up of each side:

* ``mechgen compiled``: ``mechgen.simulate`` with ``method = "DOP853"``, ``loop = "c"`` (what ``auto`` runs);
* ``mechgen scipy stepper``: the same call with ``loop = "python"`` (scipy's DOP853 stepped in Python on the
  same C kernels: the path every smooth model took before the compiled loop);
* ``hand-written scipy``: ``scipy.integrate.solve_ivp(method="DOP853")`` on a numpy right-hand side written by
  hand, ``t_eval`` at the same samples (what a user writes without mechgen).

All three produce the same samples of x and x'; the error column is the largest sample error of x against a
reference run of the hand-written right-hand side at rtol = 1e-13. Both mechgen sides integrate the energy
balance's work and dissipation with the state (three more components, the same on both: like for like); the
hand-written solve_ivp does not, and its ratio says so.
The ratios (peer seconds / compiled seconds) go to ``simulate_ratios.json``; the issue's target is >= 50 against
mechgen's scipy stepper.

Against a hand-written C DOP853 loop (``benchmarks/hand_dop853.c``: scipy's method written out in C around a
hand-written Duffing right-hand side, the tableau passed in from scipy's arrays, built with mechgen's compiler
flags), like for like: both integrate the same 200 periods at the same tolerances and return the end state only
(mechgen with ``samples = 2`` on a system compiled without the energy balance's kernel), taking the same steps;
the issue's target is mechgen within 1.5x of it (``ratio_hand_c`` = mechgen seconds / hand C seconds; the
mechgen call's own setup - validation, the loop's buffers, the result - is part of its time).

The sweep: 10^3 forcing frequencies w in [0.5, 2] (``mechgen.sweep``, serial and on 2 processes, each point 20 forcing periods of
the lowest frequency, t_end = 40 pi / 0.5, rtol 1e-8, no time history kept), its wall time against the target
of 1 s. ``quick``: 50 periods, 100 sweep points, one round.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from mechgen.bench.common import blas_threads, environment, suite_report, write_json, write_text

M, C, K, K3, F, W = 1.0, 0.05, 1.0, 0.5, 0.3, 1.2
RTOL, ATOL = 1e-10, 1e-12
#: the issue's targets: compiled / scipy-stepper ratio, and the 10^3-point sweep's seconds
TARGET_RATIO, TARGET_SWEEP_S = 50.0, 1.0

DUFFING = '''\
"""Forced, damped Duffing oscillator: m x'' + c x' + k x + k3 x^3 = F cos(w t) (mechgen bench simulate)."""
import sympy as sp
from mechgen import Model, Param

model = Model("bench_duffing", doc=__doc__)
model.params(Param("m", 1.0, "kg", positive=True), Param("c", 0.05, "N s/m", minimum=0.0),
             Param("k", 1.0, "N/m"), Param("k3", 0.5, "N/m^3"), Param("F", 0.3, "N"), Param("w", 1.2, "rad/s"))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2 + p.k3 * q.x**4 / 4


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def forces(p, t):
    return {"x": p.F * sp.cos(p.w * t)}


model.output("position", lambda q: q.x, unit="m")
'''


def duffing_rhs(t: float, y: np.ndarray) -> list:
    """The hand-written right-hand side: (x, x') -> (x', (F cos(w t) - c x' - k x - k3 x^3) / m)."""
    x, v = y
    return [v, (F * math.cos(W * t) - C * v - K * x - K3 * x**3) / M]


def hand_written(t_eval: np.ndarray, rtol: float = RTOL, atol: float = ATOL) -> np.ndarray:
    """x at t_eval from scipy's solve_ivp DOP853 on :func:`duffing_rhs`."""
    from scipy.integrate import solve_ivp

    sol = solve_ivp(duffing_rhs, (0.0, float(t_eval[-1])), [0.5, 0.0], method="DOP853", rtol=rtol, atol=atol,
                    t_eval=t_eval)
    return sol.y[0]


HAND_C = Path(__file__).resolve().parents[2] / "benchmarks" / "hand_dop853.c"


def hand_c_loop():
    """``run(t_end) -> (x, x', steps)``: the hand-written C DOP853 loop (benchmarks/hand_dop853.c), built once."""
    import ctypes

    from scipy.integrate._ivp import dop853_coefficients as tableau

    from mechgen.codegen.build import load_shared

    lib = load_shared(HAND_C.read_text(), stem="hand_dop853", ldflags=("-lm",), symbols=("hand_dop853",))
    ptr, dbl = ctypes.POINTER(ctypes.c_double), ctypes.c_double
    lib.hand_dop853.argtypes = [dbl, ptr, ptr, dbl, dbl, ptr, ptr, ptr, ptr, ptr, ctypes.c_long]
    lib.hand_dop853.restype = ctypes.c_long
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (tableau.A, tableau.B, tableau.C, tableau.E3, tableau.E5)]
    params = np.array([M, C, K, K3, F, W])

    def run(t_end: float) -> tuple[float, float, int]:
        y = np.array([0.5, 0.0])
        steps = lib.hand_dop853(t_end, y.ctypes.data_as(ptr), params.ctypes.data_as(ptr), RTOL, ATOL,
                                *(a.ctypes.data_as(ptr) for a in arrays), 10**8)
        return float(y[0]), float(y[1]), int(steps)

    return run


def _against_hand_c(mechgen, model_file: Path, t_end: float, repeats: int) -> dict:
    """Like for like with the hand-written C loop: end state only, no energy balance (module doc)."""
    plain = mechgen.compile(str(model_file), kernels=["residual", "tangent", "flow", "outputs"])
    run_c = hand_c_loop()
    got = {}

    def ours():
        got["mechgen"] = mechgen.simulate(plain, t_end=t_end, q0={"x": 0.5}, method="DOP853", rtol=RTOL, atol=ATOL,
                                         samples=2, progress=False, series=False)

    def theirs():
        got["hand"] = run_c(t_end)

    seconds = _median_rounds({"mechgen compiled (end state)": ours, "hand-written C DOP853": theirs}, repeats)
    x_hand, _, steps = got["hand"]
    return {"seconds": seconds, "hand_steps": steps, "end_x_difference": abs(float(got["mechgen"]["position"]) - x_hand),
            "ratio_hand_c": seconds["mechgen compiled (end state)"] / seconds["hand-written C DOP853"]}


def _median_rounds(sides: dict, repeats: int) -> dict:
    """Median seconds of each side over ``repeats`` rounds, the sides interleaved in each round (one warm-up
    call of each first)."""
    for fn in sides.values():
        fn()
    times = {name: [] for name in sides}
    for _ in range(repeats):
        for name, fn in sides.items():
            start = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - start)
    return {name: float(np.median(ts)) for name, ts in times.items()}


def run_simulate_benchmarks(out: Path, quick: bool = False) -> dict:
    """Run the suite, write its reports into ``out`` and return the results."""
    import mechgen

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    model_file = write_text(out / "bench_duffing.py", DUFFING)
    system = mechgen.compile(str(model_file))
    periods = 50 if quick else 200
    t_end = periods * 2 * math.pi / W
    options = dict(t_end=t_end, q0={"x": 0.5}, method="DOP853", rtol=RTOL, atol=ATOL, samples=201, progress=False)
    t_eval = np.linspace(0.0, t_end, 201)
    reference = hand_written(t_eval, 1e-13, 1e-14)
    results = {}

    def run(loop):
        def call():
            results[loop] = mechgen.simulate(system, loop=loop, **options)
        return call

    def hand():
        results["hand"] = hand_written(t_eval)

    with blas_threads(1):
        seconds = _median_rounds({"mechgen compiled": run("c"), "mechgen scipy stepper": run("python"),
                                  "hand-written scipy": hand}, 1 if quick else 5)
        hand_c = _against_hand_c(mechgen, model_file, t_end, 3 if quick else 21)
        sweep_points = 100 if quick else 1000
        sweep_s, sweep_ok = _sweep(mechgen, system, sweep_points)
    errors = {"mechgen compiled": _error(results["c"]["trajectory"]["x"], reference),
              "mechgen scipy stepper": _error(results["python"]["trajectory"]["x"], reference),
              "hand-written scipy": _error(results["hand"], reference)}
    assert results["c"]["loop"] == "c", "the compiled loop did not run (no C compiler?)"
    points = [{"series": name, "setting": f"rtol={RTOL:g}", "seconds": s, "error": errors[name]}
              for name, s in seconds.items()]
    ours = seconds["mechgen compiled"]
    same = f"same problem, {periods} periods, 201 samples, rtol {RTOL:g}"
    conditions = {"mechgen scipy stepper": same + "; both integrate the energy balance with the state",
                  "hand-written scipy": same + "; mechgen also integrates the energy balance (3 more state "
                                               "components), the hand-written side does not"}
    ratios = [{"peer": name, "ours_s": ours, "peer_s": s, "condition": conditions[name]}
              for name, s in seconds.items() if name != "mechgen compiled"]
    suite_report(out, "simulate", points, reference="scipy DOP853 at rtol 1e-13 on the hand-written equation",
                 error="max |x - x_ref| over the samples", time="seconds (median of interleaved rounds)",
                 title="Duffing oscillator: time response", ratios=ratios)
    data = {"periods": periods, "seconds": seconds, "errors": errors,
            "ratio_scipy_stepper": seconds["mechgen scipy stepper"] / ours,
            "ratio_hand_scipy": seconds["hand-written scipy"] / ours, "target_ratio": TARGET_RATIO,
            "hand_c": hand_c, "sweep_points": sweep_points, "sweep_seconds": sweep_s, "sweep_ok": sweep_ok,
            "target_sweep_s": TARGET_SWEEP_S, "environment": environment()}
    write_json(out / "simulate.json", data)
    write_text(out / "simulate.md", _markdown(data))
    return data


def _sweep(mechgen, system, points: int) -> tuple[dict, bool]:
    """({executor: wall seconds} of a sweep of simulate over ``points`` forcing frequencies, serial and on 2
    local processes (forked, as the executor's documentation recommends for a machine's cores), every point ok
    and both giving the same numbers)."""
    seconds, results = {}, {}
    for label, workers in (("serial", 0), ("2 processes", 2)):
        start = time.perf_counter()
        results[label] = mechgen.sweep(system, "simulate", grid={"w": {"start": 0.5, "stop": 2.0, "num": points}},
                                       t_end=40 * math.pi / 0.5, q0={"x": 0.5}, rtol=1e-8, atol=1e-10, samples=2,
                                       workers=workers)
        seconds[label] = time.perf_counter() - start
    same = bool(np.array_equal(results["serial"]["energy"], results["2 processes"]["energy"]))
    return seconds, bool(same and all(r["failed"] == 0 for r in results.values()))


def _error(x, reference) -> float:
    return float(np.max(np.abs(np.asarray(x) - reference)))


def _markdown(data: dict) -> str:
    rows = "\n".join(f"| {name} | {s:.4f} | {data['errors'][name]:.2e} |" for name, s in data["seconds"].items())
    return (f"# simulate: forced Duffing oscillator, {data['periods']} periods, rtol 1e-10\n\n"
            "| side | seconds (median) | max error of x |\n|---|---|---|\n" + rows + "\n\n"
            "compiled / scipy stepper, both with the energy balance: "
            f"**{data['ratio_scipy_stepper']:.0f}x** (target >= {TARGET_RATIO:g}); "
            f"compiled / hand-written scipy: {data['ratio_hand_scipy']:.0f}x (the compiled side also integrates "
            "the energy balance).\n\n"
            f"mechgen (end state only, no energy balance) / hand-written C DOP853: "
            f"**{data['hand_c']['ratio_hand_c']:.2f}x** (target <= 1.5; {data['hand_c']['hand_steps']} steps, end x "
            f"differs by {data['hand_c']['end_x_difference']:.1e}).\n\n"
            f"sweep of {data['sweep_points']} points (each 80 pi / 0.5 s of the response at rtol 1e-8): "
            + ", ".join(f"{k} {v:.2f} s" for k, v in data["sweep_seconds"].items())
            + f" (target for 10^3: {TARGET_SWEEP_S:g} s); all points ok and the executors equal: {data['sweep_ok']}.\n")
