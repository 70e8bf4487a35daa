"""``mechgen bench balloon`` (issue #4): the single-loop branch with stability, mechgen against a hand-written scipy
baseline.

The computation is that of ``scenes/balloon_branches.toml`` (neo-Hookean string, h = 10, beta = 100): the
single-loop branch of steady balloons in lambda0 from -0.5 to 0.27 by pseudo-arclength continuation, about
``POINTS`` = 200 points, with the Galerkin stability verdict (N = 10 sines per component, 3 components: a
60 x 60 eigenproblem) at every point, and the minimum eyelet tension p_e,min along it.

* **baseline** - ``benchmarks/balloon_handwritten.py`` (plain scipy, imported by path):
  ``single_loop_branch(NEO, 10, 200)`` (shooting in (Q0, T) with variational equations, DOP853 at its
  rtol = 1e-12, pseudo-arclength in (Q0, T, l0), ds_max = 0.25) and ``stability(NEO, Q0, T, l0, N=10)``
  at every point; ``pe_minimum`` for p_e,min.
* **mechgen** - the steady BVP from the generated kernels (``steady_bvp``), ``continue_bvp`` with
  s-stage Gauss collocation on M intervals (``DEFAULT``; the scene's Hermite-Simpson on 200 intervals is a
  row of the ladder), ``stability_along`` (M, G, K from the derived linearisation) and
  ``minimize_along_branch``. Its step is set from an untimed pilot branch so that it also has about
  ``POINTS`` points from -0.5 to 0.27 (the baseline's ds_max was chosen by hand for the same purpose).

Steps, in one process, BLAS limited to one thread (threadpoolctl):

1. **References.** p_e,min: the baseline's ``pe_minimum`` with DOP853 at rtol 1e-13, cross-checked against
   mechgen's 5-stage Gauss collocation on 40 intervals (order 10), located to rounding. omega_1 (the lowest
   Galerkin frequency) at lambda0 = ``LAMBDA_F`` with N = 40, from both tools on their converged balloons.
2. **Headline.** Branch + stability, the baseline at every rtol of its ladder and mechgen (``DEFAULT``),
   interleaved, median time per point over ``repeats`` rounds; the ratio baseline (its rtol 1e-12) /
   mechgen, with each side's p_e,min and omega_1 errors; and the ratio at equal accuracy: against the
   baseline at the loosest rtol of its ladder whose p_e,min error is at most mechgen's.
3. **Work against precision.** p_e,min error and omega_1 error (N = 10) vs time per point over mechgen's
   collocation ladder (scheme, stages, mesh) and the baseline's rtol ladder; and omega_1 error vs time
   of one stability evaluation over Galerkin N (both tools).

4. **As a user runs it** (issue #12): ``mechgen run scenes/balloon_branches.toml`` as a whole process, the default
   environment (no BLAS thread variables) against pinned to one BLAS thread, interleaved, median of 3
   (``user_path``; :func:`mechgen.bench.common.user_path`).

``quick=True``: one repeat, short ladders. Writes ``out/balloon_branch.json`` and ``out/balloon_branch.md``.
Timing targets live here, never in unit tests (the load average is recorded: absolute times drift).
"""
from __future__ import annotations

import contextlib
import importlib.util
import os
import statistics
from pathlib import Path

import numpy as np

from mechgen.bench.common import (ROOT, blas_info, blas_threads, environment, suite_report, user_path,
                                  user_path_markdown, write_json, write_text)
from mechgen.bench.common import timed as _timed  # the local name the suite's steps use

SCENE = ROOT / "scenes" / "balloon_branches.toml"
BASELINE = ROOT / "benchmarks" / "balloon_handwritten.py"
H = 10.0
START, STOP = -0.5, 0.27
POINTS = 200
#: the scene timed as a user runs it (a quick run, a smoke test of the structure, times the short frequencies scene)
USER_SCENE, QUICK_USER_SCENE = "balloon_branches.toml", "balloon_frequencies.toml"
N_GALERKIN, N_REFERENCE = 10, 40
LAMBDA_F = 0.2                    # lambda0 of the frequency check (a large single loop: visible truncation error)
TARGET = 3.0                      # issue #4: mechgen at least 3x faster at equal accuracy
DEFAULT = ("gauss", 4, 20)        # (scheme, stages, mesh intervals)
REFERENCE = ("gauss", 5, 40)
MECHGEN_LADDER = (("collocation", None, 50), ("collocation", None, 100), ("collocation", None, 200),
                  ("gauss", 3, 10), ("gauss", 3, 20), ("gauss", 3, 40),
                  ("gauss", 4, 10), ("gauss", 4, 20), ("gauss", 4, 30))
MECHGEN_LADDER_QUICK = (("collocation", None, 200), ("gauss", 4, 10), ("gauss", 4, 20))
BASELINE_RTOLS = (1e-6, 1e-8, 1e-10, 1e-12)
BASELINE_RTOLS_QUICK = (1e-8, 1e-12)
BASELINE_RTOL = 1e-12             # benchmarks/balloon_handwritten.py's own
GALERKIN = (5, 10, 15, 20)


# -- helpers ------------------------------------------------------------------------------------------------
def _label(config) -> str:
    scheme, stages, mesh = config
    return f"Hermite-Simpson, M = {mesh}" if scheme == "collocation" else f"Gauss s = {stages}, M = {mesh}"


def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


def load_baseline():
    """benchmarks/balloon_handwritten.py as a module (imported by path)."""
    spec = importlib.util.spec_from_file_location("balloon_handwritten", BASELINE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@contextlib.contextmanager
def baseline_rtol(ref, rtol: float):
    """The baseline's integrator tolerances (module globals RTOL, ATOL = rtol / 10) for a block."""
    saved = ref.RTOL, ref.ATOL
    ref.RTOL, ref.ATOL = rtol, rtol / 10
    try:
        yield
    finally:
        ref.RTOL, ref.ATOL = saved


def balloon_system(N: int = N_GALERKIN):
    """The scene's balloon system (as ``mechgen run`` builds it) with N sines per component and the baseline's
    pointwise axial stiffness (the scene's projected one is a different, more accurate discretisation), and
    build info."""
    from mechgen import models
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene
    from mechgen.scene.run import system_for

    scn = load_scene(str(SCENE), overrides=[f"N={N}", "strain=pointwise"], lookup_model=lookup_model, model_names=models.names)
    model = models.get(scn.model)
    free = tuple(n for n in scn.free if model.param(n).is_numeric)
    kernels = ("bvp_outputs", "bvp_residual", "bvp_tangent", "linear")
    seconds, (system, report) = _timed(lambda: system_for(scn.model, tuple(sorted(scn.params.items())), free,
                                                           scn.active, kernels, scn.backend))
    return system, {"N": N, "compile_s": seconds, "backend": report.backend, "params": list(system.metadata.params)}


# -- mechgen --------------------------------------------------------------------------------------------------
class Mechgen:
    """mechgen's side: the steady BVP, its start at lambda0 = -0.5, branches, stability, p_e,min."""

    def __init__(self, system):
        from mechgen.runtime.steady.steady_bvp import solve_steady, steady_bvp

        self.system = system.with_params(lambda0=START)  # the scene's start value
        self.bvp = steady_bvp(self.system)
        self.index = self.bvp.params.index("lambda0")
        self.start = solve_steady(self.bvp, method="collocation", modes={"x": [2.0]})  # the scene's start
        self._steps: dict = {}

    def _continue(self, config, ds, max_points, ds_max=None):
        from mechgen.runtime.steady.continuation import ContinuationOptions, continue_bvp

        scheme, stages, mesh = config
        steps = ContinuationOptions(ds=ds, ds_max=ds if ds_max is None else ds_max, max_points=max_points,
                                    lam_max=STOP)
        return continue_bvp(self.bvp.problem, self.start, self.index, method=scheme, stages=stages, mesh=mesh,
                            options=steps)

    def step(self, config) -> float:
        """The step giving about POINTS points to STOP (from an untimed pilot branch's arclength)."""
        if config not in self._steps:
            pilot = self._continue(config, 0.05, 4 * POINTS, ds_max=1.0)
            if pilot.status != "lam_max":
                raise RuntimeError(f"mechgen pilot branch ({_label(config)}) stopped: {pilot.message}")
            self._steps[config] = float(pilot.arclength[-1]) / (POINTS - 1)
        return self._steps[config]

    def run(self, config, stability: bool = True) -> dict:
        """Branch (timed), then stability at every point (timed): times, points, verdicts and the branch."""
        from mechgen.runtime.steady.branch_stability import stability_along

        ds = self.step(config)
        t_branch, branch = _timed(lambda: self._continue(config, ds, POINTS + 20))
        t_stab, verdicts = _timed(lambda: stability_along(self.system, self.bvp, branch) if stability else [])
        return {"config": config, "branch": branch, "branch_s": t_branch, "stability_s": t_stab,
                "points": len(branch.lam), "lambda0_range": [float(branch.lam[0]), float(branch.lam[-1])],
                "status": branch.status, "verdicts": sorted({v.verdict for v in verdicts})}

    def pe(self, branch, u, lam) -> float:
        return float(self.bvp.outputs(branch.system.to_result(u, lam), np.array([0.0]))["tension"][0])

    def pe_min(self, branch) -> tuple[float, float]:
        """(p_e,min, lambda0 there) located along the branch."""
        from mechgen.runtime.steady.continuation import minimize_along_branch

        best = minimize_along_branch(branch, lambda u, lam: self.pe(branch, u, lam), kind="min")
        return float(best.value), float(best.lam)

    def omega1(self, branch, N: int, lam: float = LAMBDA_F) -> tuple[float, float]:
        """(omega_1 at lambda0 = lam with N sines per component, seconds of one stability evaluation)."""
        from mechgen.runtime.steady.branch_stability import stability_at
        from mechgen.runtime.steady.continuation import point_at

        res = branch.system.to_result(point_at(branch, lam), lam)
        system = self.system if N == int(self.system.choices["N"]) else self.system.refined(N)
        system = system.with_param_vector(res.p)
        stability_at(system, self.bvp, res)                     # tables built: untimed
        seconds, out = _timed(lambda: stability_at(system, self.bvp, res))
        return float(out.frequencies[0]), seconds


# -- baseline -------------------------------------------------------------------------------------------------
def baseline_run(ref, rtol: float = BASELINE_RTOL) -> dict:
    """The baseline's 200-point branch (timed), then its stability at every point (timed)."""
    with baseline_rtol(ref, rtol):
        t_branch, br = _timed(lambda: ref.single_loop_branch(ref.NEO, H, POINTS))
        t_stab, stab = _timed(lambda: [ref.stability(ref.NEO, *X, N=N_GALERKIN) for X in br])
    lam0 = ref.lam0_of(br[:, 2], H)
    return {"rtol": rtol, "branch": br, "branch_s": t_branch, "stability_s": t_stab, "points": len(br),
            "lambda0_range": [float(lam0[0]), float(lam0[-1])], "verdicts": sorted({v for v, _, _ in stab})}


def baseline_pe_min(ref, br, rtol: float) -> tuple[float, float]:
    """(p_e,min, lambda0 there) by the baseline's pe_minimum from its sampled minimum."""
    pe = np.hypot(br[:, 0], br[:, 1])
    with baseline_rtol(ref, rtol):
        X = ref.pe_minimum(ref.NEO, H, br[int(np.argmin(pe))])
    return float(np.hypot(X[0], X[1])), float(ref.lam0_of(X[2], H))


def baseline_omega1(ref, br, rtol: float, N: int, lam: float = LAMBDA_F) -> tuple[float, float]:
    """(omega_1 at lambda0 = lam with N sines, seconds of one stability evaluation (with its integration))."""
    lam0 = ref.lam0_of(br[:, 2], H)
    X0 = br[int(np.argmin(np.abs(lam0 - lam)))]
    with baseline_rtol(ref, rtol):
        X = ref.shoot_fixed(ref.NEO, H, [X0[0], X0[1], ref.l0_of(lam, H)], 2)
        ref.stability(ref.NEO, *X, N=N)
        seconds, out = _timed(lambda: ref.stability(ref.NEO, *X, N=N))
    return float(out[2][0]), seconds


# -- steps ----------------------------------------------------------------------------------------------------
def references(ref, mech: Mechgen, br_base) -> dict:
    """p_e,min and omega_1 (N = 40) references from both tools at tight settings, and their agreement."""
    pe_b, lam_b = baseline_pe_min(ref, br_base, 1e-13)
    fine = mech.run(REFERENCE, stability=False)["branch"]
    pe_m, lam_m = mech.pe_min(fine)
    w_b = baseline_omega1(ref, br_base, 1e-13, N_REFERENCE)[0]
    w_m = mech.omega1(fine, N_REFERENCE)[0]
    return {"p_e_min": pe_b, "lambda0_at_p_e_min": lam_b, "omega_1": w_b, "lambda0_omega": LAMBDA_F,
            "source": f"baseline pe_minimum at DOP853 rtol 1e-13; omega_1: baseline N = {N_REFERENCE}",
            "check": {"method": f"mechgen {_label(REFERENCE)}", "p_e_min": pe_m, "lambda0_at_p_e_min": lam_m,
                      f"omega_1_N{N_REFERENCE}": w_m, "p_e_min_rel_diff": _rel(pe_m, pe_b),
                      "omega_1_rel_diff": _rel(w_m, w_b)}}


def _accuracy_mechgen(mech: Mechgen, run: dict, refs: dict) -> dict:
    (t, (pe, lam)) = _timed(lambda: mech.pe_min(run["branch"]))
    w = mech.omega1(run["branch"], N_GALERKIN)[0]
    return {"p_e_min": pe, "lambda0_at_p_e_min": lam, "p_e_min_error": _rel(pe, refs["p_e_min"]),
            "omega_1": w, "omega_1_error": _rel(w, refs["omega_1"]), "p_e_min_s": t}


def _accuracy_baseline(ref, run: dict, refs: dict) -> dict:
    t, (pe, lam) = _timed(lambda: baseline_pe_min(ref, run["branch"], run["rtol"]))
    w = baseline_omega1(ref, run["branch"], run["rtol"], N_GALERKIN)[0]
    return {"p_e_min": pe, "lambda0_at_p_e_min": lam, "p_e_min_error": _rel(pe, refs["p_e_min"]),
            "omega_1": w, "omega_1_error": _rel(w, refs["omega_1"]), "p_e_min_s": t}


def _public(run: dict) -> dict:
    out = {k: v for k, v in run.items() if k not in ("branch", "config")}
    out["total_s"] = run["branch_s"] + run["stability_s"]
    out["per_point_s"] = out["total_s"] / run["points"]
    return out


def _per_point(runs) -> float:
    return statistics.median((r["branch_s"] + r["stability_s"]) / r["points"] for r in runs)


def headline(ref, mech: Mechgen, repeats: int, rtols) -> dict:
    """Baseline (at every rtol of its ladder) and mechgen (DEFAULT) branch + stability, interleaved, ``repeats``
    rounds; the median time per point of each, the fastest run of each kept for the accuracy checks."""
    base_runs = {rtol: [] for rtol in rtols}
    mech_runs = []
    for _ in range(repeats):
        for rtol in rtols:
            base_runs[rtol].append(baseline_run(ref, rtol))
        mech_runs.append(mech.run(DEFAULT))

    def fastest(runs):
        return min(runs, key=lambda r: r["branch_s"] + r["stability_s"])

    b, m = fastest(base_runs[BASELINE_RTOL]), fastest(mech_runs)
    per_b, per_m = _per_point(base_runs[BASELINE_RTOL]), _per_point(mech_runs)
    return {"repeats": repeats, "baseline": {**_public(b), "per_point_median_s": per_b,
                                             "all_total_s": [r["branch_s"] + r["stability_s"]
                                                             for r in base_runs[BASELINE_RTOL]]},
            "mechgen": {**_public(m), "method": _label(DEFAULT), "per_point_median_s": per_m,
                        "all_total_s": [r["branch_s"] + r["stability_s"] for r in mech_runs]},
            "ratio_per_point": per_b / per_m, "_baseline_runs": {rtol: (fastest(runs), _per_point(runs))
                                                                 for rtol, runs in base_runs.items()},
            "_mechgen_run": m}


def galerkin_ladder(ref, mech: Mechgen, br_base, mech_branch, refs: dict, sizes) -> list[dict]:
    rows = []
    for N in sizes:
        w_m, t_m = mech.omega1(mech_branch, N)
        w_b, t_b = baseline_omega1(ref, br_base, BASELINE_RTOL, N)
        rows.append({"N": N, "mechgen_omega_1_error": _rel(w_m, refs["omega_1"]), "mechgen_s": t_m,
                     "baseline_omega_1_error": _rel(w_b, refs["omega_1"]), "baseline_s": t_b})
    return rows


# -- report -------------------------------------------------------------------------------------------------
def _ms(x: float) -> str:
    return f"{1e3 * x:.2f} ms"


def report_markdown(res: dict) -> str:
    env = res["environment"]
    L = ["# Ballooning string benchmark (issue #4): single-loop branch + stability, mechgen vs hand-written scipy",
         "", f"{'QUICK run (one repeat, short ladders). ' if res['quick'] else ''}Machine: {env['cpu_count']} cores, "
         f"Python {env['python']}, numpy {env['numpy']}, scipy {env['scipy']}; BLAS threads: {res['blas_threads']}; "
         f"load average {env['loadavg_before'][0]:.2f} before, {env['loadavg_after'][0]:.2f} after. "
         "All numbers from one run in one process."]
    r = res["references"]
    c = r["check"]
    L += ["", "## References", "",
          f"* p_e,min = {r['p_e_min']:.13f} at lambda0 = {r['lambda0_at_p_e_min']:.8f} ({r['source'].split(';')[0]}); "
          f"{c['method']}: {c['p_e_min']:.13f} (relative difference {c['p_e_min_rel_diff']:.1e}).",
          f"* omega_1 at lambda0 = {r['lambda0_omega']:g}, N = {N_REFERENCE}: {r['omega_1']:.12f} (baseline); "
          f"{c['method']}: {c[f'omega_1_N{N_REFERENCE}']:.12f} (relative difference {c['omega_1_rel_diff']:.1e})."]
    h = res["headline"]
    b, m = h["baseline"], h["mechgen"]
    L += ["", f"## Branch + stability: {POINTS} points, lambda0 {START} -> {STOP}, N = {N_GALERKIN} x 3 components "
          f"(best of {h['repeats']}, median per point)", "",
          "| | points | lambda0 range | branch | stability | total | per point (median) | p_e,min error | "
          "omega_1 error | verdicts |", "|---|---|---|---|---|---|---|---|---|---|"]
    for name, d in ((f"baseline (DOP853 rtol {BASELINE_RTOL:g})", b), (f"mechgen ({m['method']})", m)):
        L.append(f"| {name} | {d['points']} | {d['lambda0_range'][0]:+.3f} .. {d['lambda0_range'][1]:+.4f} | "
                 f"{d['branch_s']:.3f} s | {d['stability_s']:.3f} s | {d['total_s']:.3f} s | "
                 f"{_ms(d['per_point_median_s'])} | {d['p_e_min_error']:.1e} | {d['omega_1_error']:.1e} | "
                 f"{', '.join(d['verdicts'])} |")
    eq = h["equal_accuracy"]
    L += ["", f"**baseline / mechgen = {h['ratio_per_point']:.2f}** per point at the default settings (target >= "
          f"{TARGET:g}: {'met' if h['ratio_per_point'] >= TARGET else 'NOT met'}).",
          f"At equal accuracy (the baseline at rtol {eq['baseline_rtol']:g}, p_e,min error "
          f"{eq['baseline_p_e_min_error']:.1e} <= mechgen's {eq['mechgen_p_e_min_error']:.1e}): "
          f"**{eq['ratio_per_point']:.2f}** ({'met' if eq['ratio_per_point'] >= TARGET else 'NOT met'}).",
          f"Apart: p_e,min located along the branch in {m['p_e_min_s']:.3f} s (mechgen, minimize_along_branch) and "
          f"{b['p_e_min_s']:.3f} s (baseline, pe_minimum); mechgen compile {res['build']['compile_s']:.2f} s "
          f"(backend {res['build']['backend']}, compile cache as it is)."]
    wp = res["work_precision"]
    L += ["", "## Work against precision: branch + stability", "",
          f"Error of p_e,min and of omega_1 (lambda0 = {LAMBDA_F:g}, N = {N_GALERKIN}) against the references; "
          f"time per point of branch + stability ({POINTS} points; median of the headline's rounds for the "
          "baseline and mechgen's default, one run otherwise).", "",
          "| tool | setting | points | per point | p_e,min error | omega_1 error |", "|---|---|---|---|---|---|"]
    for row in sorted(wp["branch"], key=lambda x: (x["tool"], x["per_point_s"])):
        L.append(f"| {row['tool']} | {row['setting']} | {row['points']} | {_ms(row['per_point_s'])} | "
                 f"{row['p_e_min_error']:.1e} | {row['omega_1_error']:.1e} |")
    L += ["", f"## Work against precision: Galerkin N (omega_1 at lambda0 = {LAMBDA_F:g} against N = {N_REFERENCE})",
          "",
          "| N | mechgen error | mechgen time | baseline error | baseline time (with its integration) |",
          "|---|---|---|---|---|"]
    for row in wp["galerkin"]:
        L.append(f"| {row['N']} | {row['mechgen_omega_1_error']:.1e} | {_ms(row['mechgen_s'])} | "
                 f"{row['baseline_omega_1_error']:.1e} | {_ms(row['baseline_s'])} |")
    if res.get("user_path"):
        L += ["", user_path_markdown(res["user_path"], "The scene as a user runs it")]
    return "\n".join(L)


# -- entry point ----------------------------------------------------------------------------------------------
def run_balloon_benchmarks(out: Path, quick: bool = False) -> dict:
    """Run the balloon benchmark; write ``out/balloon_branch.json`` and ``.md``; return the results."""
    out = Path(out)
    env = environment()
    res: dict = {"quick": quick, "environment": env, "points": POINTS, "default": _label(DEFAULT)}
    ref = load_baseline()
    with blas_threads(1) as nthreads:
        res["blas_threads"] = nthreads if nthreads is not None else "unlimited (threadpoolctl missing)"
        res["blas"] = blas_info()
        system, res["build"] = balloon_system()
        mech = Mechgen(system)
        for config in (DEFAULT, REFERENCE):
            mech.step(config)                                  # pilots (untimed)
        rtols = BASELINE_RTOLS_QUICK if quick else BASELINE_RTOLS
        h = headline(ref, mech, 1 if quick else 3, rtols)
        base_runs, m_run = h.pop("_baseline_runs"), h.pop("_mechgen_run")
        b_run = base_runs[BASELINE_RTOL][0]
        br_base, br_mech = b_run["branch"], m_run["branch"]
        refs = res["references"] = references(ref, mech, br_base)
        h["baseline"].update(_accuracy_baseline(ref, b_run, refs))
        h["mechgen"].update(_accuracy_mechgen(mech, m_run, refs))
        rows = []
        for config in (MECHGEN_LADDER_QUICK if quick else MECHGEN_LADDER):
            run = m_run if config == DEFAULT else mech.run(config)
            row = {"tool": "mechgen", "setting": _label(config), **_public(run), **_accuracy_mechgen(mech, run, refs)}
            if config == DEFAULT:
                row["per_point_s"] = h["mechgen"]["per_point_median_s"]
            rows.append(row)
        for rtol in rtols:
            run, per_point = base_runs[rtol]
            rows.append({"tool": "baseline", "setting": f"DOP853 rtol {rtol:g}", "rtol": rtol, **_public(run),
                         "per_point_s": per_point, **_accuracy_baseline(ref, run, refs)})
        galerkin = galerkin_ladder(ref, mech, br_base, br_mech, refs, GALERKIN if not quick else (5, 10, 20))
        res["work_precision"] = {"branch": rows, "galerkin": galerkin}
        # equal accuracy: the loosest baseline tolerance at least as accurate as mechgen in p_e,min
        target = h["mechgen"]["p_e_min_error"]
        base_rows = sorted((r for r in rows if r["tool"] == "baseline"), key=lambda r: -r["rtol"])
        match = next((r for r in base_rows if r["p_e_min_error"] <= target), base_rows[-1])
        h["equal_accuracy"] = {"baseline_rtol": match["rtol"], "baseline_p_e_min_error": match["p_e_min_error"],
                               "mechgen_p_e_min_error": target, "baseline_per_point_s": match["per_point_s"],
                               "ratio_per_point": match["per_point_s"] / h["mechgen"]["per_point_median_s"]}
        res["headline"] = h
    res["user_path"] = user_path([ROOT / "scenes" / (QUICK_USER_SCENE if quick else USER_SCENE)],
                                 repeats=1 if quick else 3, warm=not quick)
    env["loadavg_after"] = list(os.getloadavg())
    rows, eq = res["work_precision"]["branch"], res["headline"]["equal_accuracy"]
    suite_report(out, "balloon", [{"series": r["tool"], "setting": r["setting"], "seconds": r["per_point_s"],
                                   "error": r["p_e_min_error"]} for r in rows],
                 reference=res["references"]["source"], error="rel. error of p_e,min along the branch",
                 time="seconds per branch point (with stability)", title="Ballooning string: work-precision",
                 ratios=[{"peer": "hand-written scipy baseline (DOP853 shooting)",
                          "ours_s": res["headline"]["mechgen"]["per_point_median_s"],
                          "peer_s": eq["baseline_per_point_s"],
                          "condition": f"equal accuracy in p_e,min (baseline rtol {eq['baseline_rtol']:g}: "
                                       f"{eq['baseline_p_e_min_error']:.1e}, mechgen {eq['mechgen_p_e_min_error']:.1e})"}])
    write_json(out / "balloon_branch.json", res, indent=1)
    table = report_markdown(res)
    write_text(out / "balloon_branch.md", table + "\n")
    print(table)
    print(f"\nwrote {out / 'balloon_branch.json'}, {out / 'balloon_branch.md'}")
    return res
