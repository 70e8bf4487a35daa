"""``mechgen bench rotor`` (issue #5): Campbell diagrams of ROSS's example rotor, mechgen against ROSS.

The rotor is ROSS's documented example (``ross.rotor_example()``: 1.5 m solid steel shaft, D = 0.05 m,
two disks from geometry at s = 0.5 and 1.0 m, bearings kxx = 1e6, kyy = 0.8e6 N/m at both ends, no
damping) with each of its six shaft elements split in eight:

* mechgen: ``scenes/ross_example_rotor.toml`` with ``N = 48``, ``discretisation = "timoshenko2"`` (ROSS's
  two-node Timoshenko element; the disks are mesh vertices), 196 lateral unknowns;
* ROSS 2.3.0: 48 ``ShaftElement(0.03125, 0, 0.05, steel)``, disks at nodes 16 and 32, the same bearings
  (as ``benchmarks/ross_reference.py`` builds it), 294 dofs (ROSS's nodes also carry the axial and
  torsional dofs, exactly decoupled from the lateral ones).

Steps 1-5 in one process, BLAS limited to one thread for both tools (threadpoolctl); step 6 as a user runs it:

1. **Accuracy first.** The first eight damped natural frequencies of mechgen's ``modes`` analysis and of
   ROSS's ``run_modal`` (its lateral modes; ROSS's lists also hold a torsional mode at 774 rad/s) agree
   to ``TOL`` = 1e-6 relative at 0 and 1000 rad/s, and every lateral curve of ROSS's Campbell diagram
   is matched at every speed by one of mechgen's eight curves to ``TOL``. Otherwise the benchmark raises:
   it must compare equal computations.
2. **Campbell timing.** mechgen's campbell analysis (``mechgen.analyses.campbell.run_campbell``: 50 speeds over
   0..1000 rad/s, 8 curves) against ``rotor.run_campbell(np.linspace(0, 1000, 50), frequencies=8)``,
   median of 3, interleaved (ROSS, mechgen, ROSS, mechgen ...), ROSS's ``run_modal`` lru_cache cleared
   before every run. ROSS's Campbell tracks its modes and computes no critical speeds, so the matched
   comparison is mechgen's analysis with ``multiples = []`` (tracking only); the full analysis with
   ``multiples = [1.0]`` (critical speeds refined by secant steps on the reduced model, each confirmed by
   one exact solve) is timed too. The analysis is the library path: the matrices are detected to be
   polynomial in Omega (``fit_speed_polynomial``: three assemblies, then sparse adds), the modes are
   solved at full size (sparse shift-invert) at the first and last speed and on a reduced basis at the
   others, with a residual safeguard that solves at full size where the basis falls short
   (``mechgen.runtime.linear.campbell``). Compilation (a
   ``compile_model`` call with the compile cache as it is) and mechgen's first Campbell call (mesh and
   discretisation tables built) are reported apart, as is ROSS's first ``run_modal`` (numba JIT).
3. **Profile** of mechgen's campbell analysis (cProfile): where the time goes, and the library's two
   paths timed apart (``candidate_fixes``): ``method = "exact"`` (a full-size sparse solve at every speed,
   matrices from the speed polynomial) and the default reduced basis; their frequencies are compared
   with the analysis's.
4. **A 2 000-dof rotor**: the same rotor with ``N = 498`` (1 996 unknowns; ROSS's elements split 83 times);
   ``modes`` with ``count = 8`` (ARPACK shift-invert), and the Campbell diagram over 100 speeds with mode
   tracking (issue 30: >= 100x ROSS, frequencies equal to 1e-6). ROSS's ``run_modal`` of the equal rotor
   (2 994 dofs) is timed once and compared; ROSS's ``run_campbell`` takes tens of seconds per speed at this size,
   so it is timed at three of the speeds, one per round interleaved with mechgen's whole diagram, and its time
   for the diagram is extrapolated (median per speed x 100; the report says so beside the ratio). Full run only;
   quick: N = 150 and 10 speeds, no ROSS.
5. **Work against precision**: quintic (N = 12, 24) and two-node (N = 48, 96, 192) meshes: the largest
   relative error of the first eight frequencies at 0 and 1000 rad/s against a Richardson-extrapolated
   reference (two-node element, N = 384 and 768, second order; cross-checked against quintic N = 48),
   and the time per Campbell speed.

6. **As a user runs it** (issue #12): the Campbell comparison of step 2 again in two child processes, one
   per configuration: *unpinned* (the default environment: no OPENBLAS/OMP/MKL_NUM_THREADS, so ROSS runs
   with OpenBLAS's default threads and mechgen with its own thread control) and *pinned* (all three = 1);
   mechgen through its public ``mechgen.campbell`` (``multiples = []``), ROSS's ``run_campbell`` as above,
   interleaved, median of 3, Campbell diagrams checked to agree (``configurations``: both times and
   ROSS / mechgen per configuration; the headline and the target >= 20 are the pinned, like-for-like figure; the
   unpinned one is reported beside it with its condition; ROSS also builds mode shapes at every speed). And the whole scene,
   ``mechgen run scenes/ross_example_rotor.toml`` as a process, unpinned against pinned (``user_path``).

``quick=True`` (< 60 s): 10 Campbell speeds, one repeat, no critical-speed run, a 604-unknown "large"
rotor, reference from N = 192 and 384, no ROSS run on the large rotor nor in step 6. Writes ``out/rotor_campbell.json`` and
``out/rotor_campbell.md``. When ROSS is not installed, mechgen's parts run and the report says so.
Timing targets live here, never in unit tests; absolute times drift with the machine's load
(the load average is recorded).
"""
from __future__ import annotations

import contextlib
import cProfile
import io
import os
import pstats
import statistics
import sys
import warnings
from pathlib import Path

import numpy as np

from mechgen.bench.common import (ROOT, blas_info, blas_threads, environment, suite_report, user_path,
                                  user_path_markdown, write_json, write_text)
from mechgen.bench.common import timed as _timed  # the local name the suite's steps use

SCENE = ROOT / "scenes" / "ross_example_rotor.toml"
COUNT = 8
SPLIT = 8                 # every ROSS element split in 8: N = 48
TOL = 1e-6                # agreement required of mechgen and ROSS (relative)
TARGET = 20.0             # issue #5: mechgen at least 20x faster than ROSS's run_campbell
MAX_SPEED = 1000.0
BIG_SPLIT, BIG_SPLIT_QUICK = 83, 25   # 2 000-dof rotor: N = 498 (1 996 unknowns); quick: N = 150 (604)
LARGE_SPEEDS, LARGE_SPEEDS_QUICK = 100, 10   # the large rotor's Campbell diagram (issue 30: 100 speeds)
LARGE_TARGET = 100.0      # issue 30: ROSS / mechgen >= 100 on the 2 000-dof rotor's 100-speed Campbell diagram
WP_LADDER = (("quintic", 12), ("quintic", 24), ("timoshenko2", 48), ("timoshenko2", 96), ("timoshenko2", 192))


# -- helpers ------------------------------------------------------------------------------------------------
@contextlib.contextmanager
def _fd_stdout_to_stderr():
    """Send fd-level stdout to stderr while ROSS imports (ccp -> CoolProp prints REFPROP noise)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        yield
        return
    sys.stdout.flush()
    saved = os.dup(fd)
    try:
        os.dup2(2, fd)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, fd)
        os.close(saved)


def import_ross():
    """(ross module, None) or (None, why it was skipped)."""
    try:
        with _fd_stdout_to_stderr(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import ross
        return ross, None
    except Exception as exc:  # noqa: BLE001 (any failure to import means: skip ROSS)
        return None, f"{type(exc).__name__}: {exc}"


def _summary(times: list[float]) -> dict:
    return {"median_s": statistics.median(times), "all_s": list(times)}


def speeds_of(count: int) -> list[float]:
    return [float(w) for w in np.linspace(0.0, MAX_SPEED, count)]


def rotor_system(N: int, discretisation: str = "timoshenko2", *, fresh: bool = False):
    """mechgen's example rotor with N elements: (system laid out with the scene's parts, build info).

    Built as ``mechgen run`` builds it (load_scene, compile_model of the 'linear' kernel with Omega free,
    the scene's layout). ``fresh`` bypasses run_scene's in-process cache so that the compile time
    (with the on-disk compile cache as it is) is measured.
    """
    from mechgen import models
    from mechgen.runtime.fields.mesh import Layout
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene
    from mechgen.scene.run import laid_out, system_for

    scn = load_scene(str(SCENE), overrides=[f"N={N}", f"discretisation={discretisation}"],
                     lookup_model=lookup_model, model_names=models.names)
    model = models.get(scn.model)
    free = tuple(n for n in scn.free if model.param(n).is_numeric)
    seconds, (system, report) = _timed(lambda: system_for(scn.model, tuple(sorted(scn.params.items())), free,
                                                          scn.active, ("linear",), scn.backend, fresh=fresh))
    info = {"N": N, "discretisation": discretisation, "unknowns": None, "compile_s": seconds,
            "compile_cache_hit": bool(report.cached), "backend": report.backend}
    system = laid_out(system, Layout(scn.segments, scn.parts))
    return system, info


def mechgen_modes(system, speed: float, count: int = COUNT) -> dict:
    """mechgen's ``modes`` analysis at spin speed ``speed``: its outputs (frequencies, log_dec, whirl)."""
    from mechgen.analyses.modes import run_modes

    return run_modes(system.with_params(Omega=speed), {"count": count}, {})


def mechgen_damped_solve(system, speed: float, count: int = COUNT) -> dict:
    """The ``modes`` analysis without its mode-shape sampling: linear() + run_damped_modes (the eigen-solve)."""
    from mechgen.analyses.whirl import run_damped_modes

    at_speed = system.with_params(Omega=speed)
    return run_damped_modes(at_speed, at_speed.linear(np.zeros(system.n)), {"count": count})


def mechgen_campbell(system, speeds, multiples=(), method: str = "auto") -> dict:
    """mechgen's ``campbell`` analysis (the scene runner) over ``speeds``, 8 curves (``method``: see
    mechgen.runtime.linear.campbell.campbell; 'auto' is the scene's)."""
    from mechgen.analyses.campbell import run_campbell

    return run_campbell(system, {"over": {"Omega": list(speeds)}, "count": COUNT, "multiples": list(multiples),
                                 "method": method}, {})


def ross_rotor(rs, nsub: int):
    """rotor_example() with each of its six shaft elements split into ``nsub`` (benchmarks/ross_reference.py)."""
    steel = rs.materials.steel
    shaft = [rs.ShaftElement(0.25 / nsub, 0.0, 0.05, material=steel, shear_effects=True, rotary_inertia=True,
                             gyroscopic=True) for _ in range(6 * nsub)]
    disks = [rs.DiskElement.from_geometry(n=2 * nsub, material=steel, width=0.07, i_d=0.05, o_d=0.28),
             rs.DiskElement.from_geometry(n=4 * nsub, material=steel, width=0.07, i_d=0.05, o_d=0.28)]
    bearings = [rs.BearingElement(0, kxx=1e6, kyy=0.8e6, cxx=0), rs.BearingElement(6 * nsub, kxx=1e6, kyy=0.8e6, cxx=0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rs.Rotor(shaft, disks, bearings)


def _lateral_columns(rotor, evectors) -> np.ndarray:
    """True for eigenvectors whose displacement part lies mostly in the lateral dofs (x, y, alpha, beta).

    ROSS's own ``mode_type`` is not used: on fine meshes it divides by round-off-level axial/torsional
    amplitudes (NaN, with RuntimeWarnings) and mislabels lateral modes.
    """
    nd, ndof = rotor.number_dof, rotor.ndof
    X = np.abs(np.asarray(evectors)[:ndof]) ** 2
    local = np.arange(ndof) % nd
    lat = X[np.isin(local, (0, 1, 3, 4))].sum(axis=0)
    return lat > 0.5 * X.sum(axis=0)


def ross_lateral(rotor, speed: float, count: int = COUNT) -> np.ndarray:
    """The first ``count`` lateral damped frequencies of ROSS's run_modal (ARPACK, its default)."""
    rotor.run_modal.cache_clear()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = rotor.run_modal(speed, num_modes=2 * (count + 4))
    lateral = _lateral_columns(rotor, m.evectors)[:len(m.wd)]
    wd = np.asarray(m.wd, dtype=float)[lateral][:count]
    rotor.run_modal.cache_clear()
    if len(wd) < count:
        raise RuntimeError(f"ROSS returned only {len(wd)} lateral modes at {speed} rad/s")
    return wd


def ross_campbell(rotor, speeds):
    rotor.run_modal.cache_clear()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        camp = rotor.run_campbell(speed_range=np.asarray(speeds, dtype=float), frequencies=COUNT)
    rotor.run_modal.cache_clear()  # run_campbell reorders cached ModalResults in place
    return camp


def _rel(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b) / np.abs(b)))


def campbell_agreement(mech_freqs, ross_camp) -> float:
    """Largest relative distance from a lateral ROSS Campbell value to the nearest mechgen curve, same speed."""
    wd = np.asarray(ross_camp.wd, dtype=float)
    lateral = ~np.isnan(np.asarray(ross_camp.whirl_values, dtype=float))
    mech = np.asarray(mech_freqs, dtype=float)
    worst = 0.0
    for i in range(wd.shape[0]):
        for v in wd[i, lateral[i]]:
            worst = max(worst, float(np.min(np.abs(mech[i] - v)) / abs(v)))
    return worst


# -- as a user runs it: both tools unpinned, and both pinned --------------------------------------------------
_CONFIGURATION = """
import json, sys
from mechgen.bench.rotor import configuration_timing
print(json.dumps(configuration_timing(int(sys.argv[1]), int(sys.argv[2]), with_ross=sys.argv[3] == "1")))
"""


def configuration_timing(n_speeds: int, repeats: int, with_ross: bool = True) -> dict:
    """ROSS's run_campbell against mechgen's campbell analysis as the scene runner and ``mechgen.campbell`` run it
    (``run_analysis``, with mechgen's thread control; tracking only, ``multiples = []``, as ROSS; and the public
    ``mechgen.campbell`` with its default critical speeds, timed after the pairs) on the rotor of :func:`rotor_system` (N = 48), in this process's BLAS configuration as it is (no
    threadpoolctl limit from the benchmark: mechgen's own thread control decides for mechgen, the
    environment for ROSS). Warm-ups first (mechgen's first call, ROSS's first run_modal and a 2-speed
    run_campbell), then ``repeats`` interleaved runs of each; the Campbell diagrams are checked to agree to
    TOL. ``with_ross=False``: mechgen only. Run it in a child process whose environment is the configuration
    (:func:`user_configurations`)."""
    import mechgen
    from mechgen.analyses.result import run_analysis
    from mechgen.bench.common import THREAD_VARS

    rs, skipped = import_ross() if with_ross else (None, "not run (quick)")
    speeds = speeds_of(n_speeds)
    system, _info = rotor_system(6 * SPLIT)

    def mech():  # the scene runner's path (run_analysis: its thread control), tracking only as ROSS
        return run_analysis("campbell", "campbell", system, {"over": {"Omega": speeds}, "count": COUNT,
                                                             "multiples": []}, {})

    def public():  # the public function, its defaults: critical speeds (multiples = [1]) as well
        return mechgen.campbell(system, over={"Omega": speeds}, count=COUNT)

    out: dict = {"environment": {k: os.environ.get(k) for k in THREAD_VARS}, "blas": blas_info(),
                 "speeds": len(speeds), "repeats": repeats, "ross_skipped": skipped}
    out["mechgen_first_call_s"], res = _timed(mech)
    rotor = None
    if rs is not None:
        rotor = ross_rotor(rs, SPLIT)
        out["ross_first_run_modal_s"], _ = _timed(lambda: ross_lateral(rotor, 0.0))
        out["ross_first_run_campbell_2_speeds_s"], _ = _timed(lambda: ross_campbell(rotor, [0.0, MAX_SPEED]))
    mech_t, ross_t, camp = [], [], None
    for _ in range(repeats):
        if rotor is not None:
            t, camp = _timed(lambda: ross_campbell(rotor, speeds))
            ross_t.append(t)
        t, res = _timed(mech)
        mech_t.append(t)
    out["mechgen"] = _summary(mech_t)
    public()
    out["mechgen_public_with_critical_speeds"] = _summary([_timed(public)[0] for _ in range(repeats)])
    if rotor is not None:
        out["ross"] = _summary(ross_t)
        agree = campbell_agreement(res.outputs["frequencies"], camp)
        if not agree <= TOL:
            raise AssertionError(f"Campbell diagrams of mechgen and ROSS differ by {agree:.3e} relative (> {TOL:g})")
        out["campbell_max_rel_diff"] = agree
        out["ratio_ross_over_mechgen"] = out["ross"]["median_s"] / out["mechgen"]["median_s"]
        out["ratio_ross_over_mechgen_public_with_critical_speeds"] = (
            out["ross"]["median_s"] / out["mechgen_public_with_critical_speeds"]["median_s"])
    return out


def user_configurations(n_speeds: int, repeats: int, with_ross: bool = True) -> dict:
    """:func:`configuration_timing` in two child processes: ``unpinned`` (the default environment, no BLAS
    thread variables, as a user runs both tools) and ``pinned`` (OPENBLAS/OMP/MKL_NUM_THREADS = 1)."""
    from mechgen.bench.common import in_fresh_process, user_env

    return {name: in_fresh_process(_CONFIGURATION, str(n_speeds), str(repeats), "1" if with_ross else "0",
                                   env=user_env(pinned))
            for name, pinned in (("unpinned", False), ("pinned", True))}


# -- profile and candidate fixes ------------------------------------------------------------------------------
_PROFILE_KEYS = {
    "run_campbell (whole analysis)": ("whirl.py", "run_campbell"),
    "campbell (tracking, incl. solves)": ("campbell.py", "campbell"),
    "critical_speeds (secant refinement)": ("campbell.py", "critical_speeds"),
    "damped_modes (all calls)": ("damped.py", "damped_modes"),
    "  dense scipy.linalg.eig": ("_decomp.py", "eig"),
    "  sparse ARPACK path": ("damped.py", "_sparse_eig"),
    "fit_speed_polynomial (assemblies)": ("campbell.py", "fit_speed_polynomial"),
    "system.linear (all assemblies)": ("whirl.py", "assembled"),
    "full-size solves (tracking)": ("campbell.py", "_modes_at"),
    "reduced-basis solves": ("campbell.py", "modes"),
    "basis enrichment / projection": ("campbell.py", "enrich"),
    "_align (degenerate clusters)": ("campbell.py", "_align"),
    "linear_sum_assignment": ("_lsap.py", "linear_sum_assignment"),
}


def profile_campbell(system, speeds, multiples) -> dict:
    """cProfile of mechgen's campbell analysis: cumulative seconds of the parts that matter, and the top list."""
    prof = cProfile.Profile()
    prof.enable()
    mechgen_campbell(system, speeds, multiples)
    prof.disable()
    stats = pstats.Stats(prof)
    parts = {}
    for label, (fname, func) in _PROFILE_KEYS.items():
        hits = [(v[1], v[3]) for (f, _, fn), v in stats.stats.items() if fn == func and f.endswith(fname)]
        if hits:
            parts[label] = {"calls": int(sum(h[0] for h in hits)), "cumulative_s": float(sum(h[1] for h in hits))}
    top = sorted(((v[3], v[2], v[1], f"{Path(f).name}:{ln}({fn})") for (f, ln, fn), v in stats.stats.items()),
                 reverse=True)
    buf = io.StringIO()
    pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(12)
    return {"speeds": len(speeds), "multiples": list(multiples), "parts": parts,
            "top_cumulative": [{"function": t[3], "cumulative_s": t[0], "own_s": t[1], "calls": t[2]}
                               for t in top[:25]],
            "text_tottime": buf.getvalue()}


def candidate_fixes(system, speeds, reference_freqs, repeats: int, reference_whirl=None) -> list[dict]:
    """Time the library's two Campbell paths (run_campbell, tracking only) against the analysis's frequencies."""
    ref = np.asarray(reference_freqs)
    rows = []
    for label, method in (("library, method = 'exact': speed polynomial, full-size sparse solve at every speed",
                           "exact"),
                          ("library, reduced basis (the default): full-size solves at the end speeds + safeguard",
                           "auto")):
        times, res = [], None
        for _ in range(repeats):
            t, res = _timed(lambda: mechgen_campbell(system, speeds, (), method))
            times.append(t)
        rows.append({"variant": label, **_summary(times), "max_rel_diff_vs_run_campbell": _rel(res["frequencies"], ref),
                     "whirl_equal": None if reference_whirl is None else res["whirl"] == reference_whirl})
    return rows


# -- the parts ------------------------------------------------------------------------------------------------
def accuracy_check(system, rotor, speeds_check=(0.0, MAX_SPEED)) -> dict:
    """mechgen's modes vs ROSS's run_modal (lateral) at the check speeds; raises beyond TOL."""
    rows = []
    for w in speeds_check:
        mech = np.asarray(mechgen_modes(system, w)["frequencies"], dtype=float)
        ross = ross_lateral(rotor, w)
        rows.append({"speed": w, "mechgen": mech.tolist(), "ross": ross.tolist(), "max_rel_diff": _rel(mech, ross)})
    worst = max(r["max_rel_diff"] for r in rows)
    if not worst <= TOL:
        raise AssertionError(f"mechgen and ROSS disagree: first {COUNT} frequencies differ by {worst:.3e} relative "
                             f"(> {TOL:g}); the benchmark would compare different computations")
    return {"speeds": list(speeds_check), "rows": rows, "max_rel_diff": worst, "tolerance": TOL, "passed": True}


def campbell_timing(system, rotor, speeds, repeats: int, critical: bool = True) -> dict:
    """Interleaved median-of-``repeats`` timings of ROSS's run_campbell and mechgen's campbell analysis.

    ``critical``: also time mechgen's full analysis with critical speeds (``multiples = [1.0]``) once.
    """
    out: dict = {"speeds": len(speeds), "repeats": repeats}
    first, res = _timed(lambda: mechgen_campbell(system, speeds))
    out["mechgen_first_call_s"] = first
    mech_t, ross_t, camp = [], [], None
    for _ in range(repeats):
        if rotor is not None:
            t, camp = _timed(lambda: ross_campbell(rotor, speeds))
            ross_t.append(t)
        t, res = _timed(lambda: mechgen_campbell(system, speeds))
        mech_t.append(t)
    out["mechgen_tracking"] = _summary(mech_t)
    out["mechgen_frequencies"] = res["frequencies"]
    out["mechgen_whirl"] = res["whirl"]
    if critical:
        t, full = _timed(lambda: mechgen_campbell(system, speeds, [1.0]))
        out["mechgen_with_critical_speeds"] = {"median_s": t, "all_s": [t], "critical_speeds": full["critical_speeds"]}
    if rotor is not None:
        out["ross"] = _summary(ross_t)
        agree = campbell_agreement(res["frequencies"], camp)
        if not agree <= TOL:
            raise AssertionError(f"Campbell diagrams of mechgen and ROSS differ by {agree:.3e} relative (> {TOL:g})")
        out["campbell_max_rel_diff"] = agree
        out["ratio_ross_over_mechgen"] = out["ross"]["median_s"] / out["mechgen_tracking"]["median_s"]
        if critical:
            out["ratio_ross_over_mechgen_with_critical_speeds"] = out["ross"]["median_s"] / t
    return out


def large_rotor(rs, split: int, repeats: int, with_ross: bool, n_speeds: int = LARGE_SPEEDS) -> dict:
    """The rotor with every element split ``split`` times: mechgen modes (count 8) and a Campbell diagram over
    ``n_speeds`` speeds with mode tracking, against ROSS's ``run_campbell`` on the equal rotor.

    ROSS takes tens of seconds per speed at this size (a sparse eigen-solve with mode shapes and whirl per
    mode), so its Campbell diagram is timed at ``repeats`` of the speeds, one speed per round (``run_campbell``
    over that one speed), interleaved with mechgen's whole diagram; ROSS's time for the diagram is the median per
    speed times ``n_speeds`` (its cost per speed does not depend on the speed: one ``run_modal`` and the MAC
    tracking against the previous speed, which a one-speed call leaves out). At each of those speeds every
    lateral ROSS frequency must equal one of mechgen's curves to ``TOL``."""
    N = 6 * split
    system, info = rotor_system(N)
    info["unknowns"] = system.n
    first, _ = _timed(lambda: mechgen_modes(system, 500.0))
    times, res = [], None
    for _ in range(repeats):
        t, res = _timed(lambda: mechgen_modes(system, 500.0))
        times.append(t)
    solve = [_timed(lambda: mechgen_damped_solve(system, 500.0))[0] for _ in range(repeats)]
    out = {**info, "modes_speed": 500.0, "modes_first_call_s": first, "modes": _summary(times),
           "frequencies_500": res["frequencies"], "modes_solve_only": _summary(solve)}
    rotor = None
    if with_ross and rs is not None:
        build_t, rotor = _timed(lambda: ross_rotor(rs, split))
        t, wd = _timed(lambda: ross_lateral(rotor, 500.0))
        diff = _rel(res["frequencies"], wd)
        if not diff <= TOL:
            raise AssertionError(f"large rotor: mechgen and ROSS differ by {diff:.3e} relative (> {TOL:g})")
        out["ross"] = {"dofs": int(rotor.ndof), "build_s": build_t, "run_modal_s": t,
                       "call": f"rotor.run_modal(500.0, num_modes={2 * (COUNT + 4)})", "max_rel_diff": diff,
                       "ratio_ross_over_mechgen_modes": t / out["modes"]["median_s"]}
    out.update(large_campbell(system, rotor, n_speeds, repeats))
    return out


def large_campbell(system, rotor, n_speeds: int, repeats: int) -> dict:
    """mechgen's Campbell diagram of the large rotor over ``n_speeds`` speeds (tracking only), median of
    ``repeats``; with a ROSS rotor, interleaved with ROSS's ``run_campbell`` at one of the speeds per round
    (:func:`large_rotor`)."""
    speeds = speeds_of(n_speeds)
    mechgen_campbell(system, speeds[:2])          # first call (discretisation tables) untimed
    probes = [speeds[round(k * (n_speeds - 1) / max(repeats - 1, 1))] for k in range(repeats)]
    mech_t, ross_t, camp, worst = [], [], None, 0.0
    for probe in probes:
        t, camp = _timed(lambda: mechgen_campbell(system, speeds))
        mech_t.append(t)
        if rotor is not None:
            t, ross_camp = _timed(lambda: ross_campbell(rotor, [probe]))
            ross_t.append(t)
            row = camp["frequencies"][speeds.index(probe)]
            worst = max(worst, lateral_agreement(row, rotor, ross_camp.modal_results[probe]))
    out = {"campbell_speeds": n_speeds, "campbell": _summary(mech_t)}
    if rotor is not None:
        if not worst <= TOL:
            raise AssertionError(f"large rotor Campbell: ROSS's lateral frequencies and mechgen's curves differ by "
                                 f"{worst:.3e} relative (> {TOL:g})")
        per_speed = statistics.median(ross_t)
        out["ross_campbell"] = {"speeds_timed": probes, "seconds_per_speed": _summary(ross_t),
                                "extrapolated_s": per_speed * n_speeds, "max_rel_diff": worst,
                                "call": f"rotor.run_campbell([speed], frequencies={COUNT})",
                                "ratio_ross_over_mechgen": per_speed * n_speeds / out["campbell"]["median_s"]}
    return out


def lateral_agreement(mech_row, rotor, modal) -> float:
    """Largest relative distance from a lateral frequency of ROSS's modal result (its first ``COUNT`` modes,
    lateral by their eigenvectors, :func:`_lateral_columns`) to the nearest of mechgen's frequencies ``mech_row``
    at the same speed."""
    wd = np.asarray(modal.wd, dtype=float)[:COUNT]
    lateral = _lateral_columns(rotor, modal.evectors)[:COUNT]
    mech = np.asarray(mech_row, dtype=float)
    return max((float(np.min(np.abs(mech - v)) / abs(v)) for v in wd[lateral]), default=0.0)


def work_precision(repeats: int, quick: bool, ross_row: dict | None) -> dict:
    """First-8-frequency error against a Richardson reference vs time per Campbell speed."""
    check = (0.0, MAX_SPEED)

    found: dict = {}

    def freqs(n: int, disc: str = "timoshenko2"):
        """The check frequencies of one mesh, solved once (the quick reference's coarse mesh, N = 192, and its
        quintic cross-check, N = 24, are also rungs of the ladder)."""
        if (n, disc) not in found:
            system = rotor_system(n, disc)[0]
            found[n, disc] = np.array([mechgen_modes(system, w)["frequencies"] for w in check], dtype=float)
        return found[n, disc]

    coarse, fine = (192, 384) if quick else (384, 768)
    f_c, f_f = freqs(coarse), freqs(fine)
    ref = f_f + (f_f - f_c) / 3.0                      # second order: error ~ h^2
    cross_n = 24 if quick else 48
    cross = freqs(cross_n, "quintic")
    speeds = speeds_of(10 if quick else 50)
    rows = []
    for disc, n in WP_LADDER:
        system, info = rotor_system(n, disc)
        err = _rel(freqs(n, disc), ref)
        mechgen_campbell(system, speeds)           # first call (tables) untimed
        times = [_timed(lambda: mechgen_campbell(system, speeds))[0] for _ in range(repeats)]
        rows.append({"method": f"mechgen {disc}", "N": n, "unknowns": system.n, "max_rel_error": err,
                     "seconds_per_speed": statistics.median(times) / len(speeds), "speeds": len(speeds)})
    if ross_row is not None:
        rows.append({"method": "ROSS two-node (elements split 8)", "N": 6 * SPLIT, "unknowns": ross_row["dofs"],
                     "max_rel_error": _rel(ross_row["frequencies"], ref),
                     "seconds_per_speed": ross_row["seconds_per_speed"], "speeds": ross_row["speeds"]})
    return {"reference": {"method": f"Richardson (order 2) of timoshenko2 N = {coarse}, {fine}",
                          "speeds": list(check), "frequencies": ref.tolist(),
                          f"max_rel_diff_vs_quintic_N{cross_n}": _rel(cross, ref)},
            "rows": rows}


# -- report -------------------------------------------------------------------------------------------------
def _fmt_s(x: float | None) -> str:
    if x is None:
        return "-"
    return f"{x * 1e3:.1f} ms" if x < 1 else f"{x:.2f} s"


def report_markdown(res: dict) -> str:
    L = ["# Rotor Campbell benchmark (issue #5): mechgen vs ROSS", ""]
    env = res["environment"]
    L.append(f"{'QUICK run (fewer speeds, one repeat): ratios are indicative only. ' if res['quick'] else ''}"
             f"Machine: {env['cpu_count']} cores, {env['machine']}, Python {env['python']}, numpy {env['numpy']}, "
             f"scipy {env['scipy']}, ROSS {env.get('ross') or 'not installed'}; BLAS threads: {res['blas_threads']}; "
             f"load average {env['loadavg_before'][0]:.2f} before, {env['loadavg_after'][0]:.2f} after. "
             "All numbers from one run in one process.")
    if res.get("ross_skipped"):
        L += ["", f"**ROSS skipped** ({res['ross_skipped']}): only mechgen's parts ran."]
    acc = res.get("accuracy")
    if acc:
        L += ["", "## Accuracy (checked before timing)", "",
              f"First {COUNT} damped frequencies (rad/s), mechgen `modes` (timoshenko2, N = {6 * SPLIT}) vs ROSS "
              f"`run_modal` lateral modes (elements split {SPLIT}); tolerance {TOL:g} relative.", "",
              "| speed (rad/s) | mechgen | ROSS | max rel. diff |", "|---|---|---|---|"]
        for r in acc["rows"]:
            L.append(f"| {r['speed']:g} | {', '.join(f'{v:.6f}' for v in r['mechgen'])} | "
                     f"{', '.join(f'{v:.6f}' for v in r['ross'])} | {r['max_rel_diff']:.2e} |")
        ct = res["campbell"]
        if "campbell_max_rel_diff" in ct:
            L.append(f"\nCampbell diagrams: every lateral ROSS curve value is matched by a mechgen curve at the same "
                     f"speed to {ct['campbell_max_rel_diff']:.2e} relative.")
    ct = res["campbell"]
    L += ["", f"## Campbell diagram: {ct['speeds']} speeds over 0..{MAX_SPEED:g} rad/s, {COUNT} modes, "
              f"median of {ct['repeats']}", "",
          "| run | median | all | per speed | ROSS / this (target >= 20) |", "|---|---|---|---|---|"]
    ross_med = ct.get("ross", {}).get("median_s")

    def row(label, d):
        ratio = "-" if ross_med is None else f"{ross_med / d['median_s']:.2f}"
        L.append(f"| {label} | {_fmt_s(d['median_s'])} | {', '.join(_fmt_s(x) for x in d['all_s'])} | "
                 f"{_fmt_s(d['median_s'] / ct['speeds'])} | {ratio} |")

    if ross_med is not None:
        row(f"ROSS `run_campbell(np.linspace(0, {MAX_SPEED:g}, {ct['speeds']}), frequencies={COUNT})`", ct["ross"])
    row("mechgen campbell analysis, `multiples = []` (tracking only: the matched comparison)", ct["mechgen_tracking"])
    if "mechgen_with_critical_speeds" in ct:
        row("mechgen campbell analysis, `multiples = [1.0]` (plus critical speeds, secant on the reduced model)",
            ct["mechgen_with_critical_speeds"])
    b = res["build"]
    L.append("")
    L.append(f"Apart: mechgen compile_model {_fmt_s(b['compile_s'])} (compile cache "
             f"{'hit' if b['compile_cache_hit'] else 'miss'}, backend {b['backend']}), mechgen first Campbell call "
             f"{_fmt_s(ct['mechgen_first_call_s'])}; ROSS first run_modal (numba JIT) "
             f"{_fmt_s(res.get('ross_first_run_modal_s'))}, then an untimed warm-up run_campbell of 2 speeds "
             f"{_fmt_s(res.get('ross_first_run_campbell_2_speeds_s'))}.")
    if ross_med is not None:
        ratio = ct["ratio_ross_over_mechgen"]
        crit = ct.get("ratio_ross_over_mechgen_with_critical_speeds")
        crit = "" if crit is None else f"; {crit:.2f} with critical speeds"
        L.append(f"\n**ROSS / mechgen = {ratio:.2f}** (tracking only{crit}): target >= {TARGET:g} "
                 f"{'met' if ratio >= TARGET else 'NOT met'}.")
    conf = res.get("configurations")
    if conf:
        un = conf["unpinned"]
        L += ["", f"## As a user runs both: unpinned and pinned ({un['speeds']} speeds, median of {un['repeats']})", "",
              "Each configuration in its own process: ROSS `run_campbell` against mechgen's campbell analysis "
              "as `mechgen run` runs it (`run_analysis`, tracking only: `multiples = []`), interleaved; then the "
              "public `mechgen.campbell(system, over=..., count=8)` (with its default critical speeds). *Unpinned*: the default "
              "environment (no OPENBLAS/OMP/MKL_NUM_THREADS; mechgen's own thread control decides for mechgen); "
              "*pinned*: all three = 1.", "",
              "| configuration | ROSS | mechgen | ROSS / mechgen (target >= 20 unpinned) | `mechgen.campbell` with "
              "critical speeds | ROSS / that | BLAS threads at start |",
              "|---|---|---|---|---|---|---|"]
        for name in ("unpinned", "pinned"):
            c = conf[name]
            threads = ", ".join(f"{b['api']} {b['num_threads']}" for b in c["blas"]) or "-"
            ross = c.get("ross")
            L.append(f"| {name} | {'-' if ross is None else _fmt_s(ross['median_s'])} "
                     f"({'-' if ross is None else ', '.join(_fmt_s(x) for x in ross['all_s'])}) | "
                     f"{_fmt_s(c['mechgen']['median_s'])} ({', '.join(_fmt_s(x) for x in c['mechgen']['all_s'])}) | "
                     f"{'-' if ross is None else format(c['ratio_ross_over_mechgen'], '.1f')} | "
                     f"{_fmt_s(c['mechgen_public_with_critical_speeds']['median_s'])} | "
                     f"{'-' if ross is None else format(c['ratio_ross_over_mechgen_public_with_critical_speeds'], '.1f')}"
                     f" | {threads} |")
        if "ratio_ross_over_mechgen" in un:
            pinned = conf["pinned"]["ratio_ross_over_mechgen"]
            # the like-for-like figure is the pinned one: unpinned, ROSS's OpenBLAS threads contend for the cores
            # while mechgen pins itself; and ROSS builds every mode's shape at every speed, which mechgen's
            # Campbell analysis does not
            L.append(f"\n**Pinned (like for like) ROSS / mechgen = {pinned:.1f}**: target >= {TARGET:g} "
                     f"{'met' if pinned >= TARGET else 'NOT met'}. Unpinned, as a user runs both: "
                     f"{un['ratio_ross_over_mechgen']:.1f} (ROSS's OpenBLAS on its default threads contends for the "
                     "cores while mechgen pins itself to one). Both figures carry one more difference: ROSS builds "
                     "every mode's shape at every speed, mechgen's Campbell analysis does not.")
    if res.get("user_path"):
        L += ["", user_path_markdown(res["user_path"], "The scene as a user runs it")]
    prof = res.get("profile")
    if prof:
        L += ["", f"## Where mechgen's time goes (cProfile, {prof['speeds']} speeds, multiples = {prof['multiples']})",
              "", "| part | calls | cumulative |", "|---|---|---|"]
        for k, v in prof["parts"].items():
            L.append(f"| {k} | {v['calls']} | {_fmt_s(v['cumulative_s'])} |")
    fixes = res.get("candidate_fixes")
    if fixes:
        L += ["", "## The library's Campbell paths (tracking only, `run_campbell`)", "",
              "| variant | median | per speed | ROSS / this | max rel. diff vs analysis |", "|---|---|---|---|---|"]
        for f in fixes:
            ratio = "-" if ross_med is None else f"{ross_med / f['median_s']:.1f}"
            same = {True: ", whirl equal", False: ", whirl DIFFERS", None: ""}[f.get("whirl_equal")]
            L.append(f"| {f['variant']} | {_fmt_s(f['median_s'])} | {_fmt_s(f['median_s'] / ct['speeds'])} | {ratio} | "
                     f"{f['max_rel_diff_vs_run_campbell']:.1e}{same} |")
    big = res["large"]
    L += ["", f"## Large rotor: N = {big['N']} two-node elements, {big['unknowns']} unknowns", "",
          f"* `modes`, count = {COUNT}, at {big['modes_speed']:g} rad/s (sparse shift-invert): median "
          f"{_fmt_s(big['modes']['median_s'])} (first call {_fmt_s(big['modes_first_call_s'])}, compile "
          f"{_fmt_s(big['compile_s'])}); of which the eigen-solve (linear() + run_damped_modes, no mode-shape "
          f"sampling) {_fmt_s(big['modes_solve_only']['median_s'])}",
          f"* Campbell, {big['campbell_speeds']} speeds, {COUNT} modes: median {_fmt_s(big['campbell']['median_s'])} "
          f"({_fmt_s(big['campbell']['median_s'] / big['campbell_speeds'])} per speed)"]
    if "ross" in big:
        r = big["ross"]
        L.append(f"* ROSS `{r['call']}` on the equal rotor ({r['dofs']} dofs): {_fmt_s(r['run_modal_s'])} "
                 f"(Rotor built in {_fmt_s(r['build_s'])}); frequencies agree to {r['max_rel_diff']:.1e}; "
                 f"ROSS / mechgen modes = {r['ratio_ross_over_mechgen_modes']:.0f}")
    if "ross_campbell" in big:
        rc = big["ross_campbell"]
        ratio = rc["ratio_ross_over_mechgen"]
        L.append(f"* ROSS `{rc['call']}` at {len(rc['speeds_timed'])} of the speeds "
                 f"({', '.join(f'{w:g}' for w in rc['speeds_timed'])} rad/s, one per round, interleaved with "
                 f"mechgen's whole diagram): median {_fmt_s(rc['seconds_per_speed']['median_s'])} per speed, so "
                 f"{_fmt_s(rc['extrapolated_s'])} for {big['campbell_speeds']} speeds (extrapolated: ROSS's cost per "
                 f"speed does not depend on the speed); lateral frequencies equal to mechgen's curves to "
                 f"{rc['max_rel_diff']:.1e}. **ROSS (extrapolated) / mechgen = {ratio:.0f}** on the "
                 f"{big['campbell_speeds']}-speed diagram, BLAS pinned to one thread: target >= {LARGE_TARGET:g} "
                 f"{'met' if ratio >= LARGE_TARGET else 'NOT met'}. ROSS also builds every mode's shape.")
    wp = res["work_precision"]
    ref = wp["reference"]
    cross = next(v for k, v in ref.items() if k.startswith("max_rel_diff_vs_quintic"))
    L += ["", "## Work against precision", "",
          f"Error: largest relative error of the first {COUNT} frequencies at 0 and {MAX_SPEED:g} rad/s against "
          f"{ref['method']} (which agrees with quintic to {cross:.1e}). Time: Campbell analysis (tracking only) "
          "per speed, median.", "", "| method | N | unknowns | max rel. error | time per speed |",
          "|---|---|---|---|---|"]
    for r in sorted(wp["rows"], key=lambda r: r["seconds_per_speed"]):
        L.append(f"| {r['method']} | {r['N']} | {r['unknowns']} | {r['max_rel_error']:.1e} | "
                 f"{_fmt_s(r['seconds_per_speed'])} |")
    return "\n".join(L)


# -- entry point ----------------------------------------------------------------------------------------------
def run_rotor_benchmarks(out: Path, quick: bool = False) -> dict:
    """Run the rotor benchmark; write ``out/rotor_campbell.json`` and ``out/rotor_campbell.md``; return the results."""
    out = Path(out)
    repeats = 1 if quick else 3
    speeds = speeds_of(10 if quick else 50)
    rs, skipped = import_ross()
    env = environment(ross=getattr(rs, "__version__", None))
    res: dict = {"quick": quick, "environment": env, "ross_skipped": skipped}
    with blas_threads(1) as nthreads:
        res["blas_threads"] = nthreads if nthreads is not None else "unlimited (threadpoolctl missing)"
        res["blas"] = blas_info()
        system, info = rotor_system(6 * SPLIT, fresh=True)
        info["unknowns"] = system.n
        res["build"] = info
        rotor = None
        if rs is not None:
            rotor = ross_rotor(rs, SPLIT)
            rotor.run_modal.cache_clear()
            res["ross_first_run_modal_s"], _ = _timed(lambda: ross_lateral(rotor, 0.0))
            res["ross_first_run_campbell_2_speeds_s"], _ = _timed(lambda: ross_campbell(rotor, [0.0, MAX_SPEED]))
            res["accuracy"] = accuracy_check(system, rotor)
        res["campbell"] = ct = campbell_timing(system, rotor, speeds, repeats, critical=not quick)
        res["profile"] = profile_campbell(system, speeds, [] if quick else [1.0])
        res["candidate_fixes"] = candidate_fixes(system, speeds, ct["mechgen_frequencies"], repeats,
                                                 ct["mechgen_whirl"])
        split = BIG_SPLIT_QUICK if quick else BIG_SPLIT
        res["large"] = large_rotor(rs, split, repeats, with_ross=not quick,
                                   n_speeds=LARGE_SPEEDS_QUICK if quick else LARGE_SPEEDS)
        ross_row = None
        if rotor is not None:
            ross_row = {"dofs": int(rotor.ndof), "speeds": ct["speeds"],
                        "seconds_per_speed": ct["ross"]["median_s"] / ct["speeds"],
                        "frequencies": [res["accuracy"]["rows"][k]["ross"] for k in range(2)]}
        res["work_precision"] = work_precision(repeats, quick, ross_row)
    # as a user runs it: both tools unpinned and both pinned (child processes), and the whole scene
    res["configurations"] = user_configurations(len(speeds), repeats, with_ross=not quick)
    res["user_path"] = user_path([SCENE], repeats=repeats, warm=not quick)
    env["loadavg_after"] = list(os.getloadavg())
    wp = res["work_precision"]
    ratios = []
    if "ross" in ct:
        ratios.append({"peer": f"ROSS {env.get('ross')} run_campbell", "ours_s": ct["mechgen_tracking"]["median_s"],
                       "peer_s": ct["ross"]["median_s"],
                       "condition": f"the same rotor and {ct['speeds']} speeds, BLAS pinned to 1 thread, Campbell "
                                    f"diagrams equal to {ct['campbell_max_rel_diff']:.1e} relative; ROSS also builds "
                                    "every mode's shape at every speed, mechgen does not"})
    suite_report(out, "rotor", [{"series": r["method"], "setting": f"N {r['N']}", "seconds": r["seconds_per_speed"],
                                 "error": r["max_rel_error"]} for r in wp["rows"]],
                 reference=wp["reference"]["method"], error="max rel. error of the frequencies",
                 time="seconds per speed", title="ROSS example rotor: work-precision", ratios=ratios)
    write_json(out / "rotor_campbell.json", res, indent=1)
    table = report_markdown(res)
    write_text(out / "rotor_campbell.md", table + "\n")
    print(table)
    print(f"\nwrote {out / 'rotor_campbell.json'}, {out / 'rotor_campbell.md'}")
    return res
