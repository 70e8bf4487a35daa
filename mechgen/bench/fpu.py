"""``mechgen bench fpu``: speed of generated kernels against hand-written and library baselines.

FPU chain (bond force f(r) = gamma r + alpha r^2 + beta r^3, fixed ends): the force
F = -dV/du and its sparse (tridiagonal) stiffness K = dF/du... as CSR data, on the ladder
N = 64, 256, 1024, 4096, 16384, 65536, 262144, 10^6 (quick: 64, 256) and for a batch of 10 000 states
at N = 4096 (quick: 100 at N = 64), computed by

* generated C (mechgen, prepared call),
* a hand-written C loop (benchmarks/hand_fpu.c) built with the same flags and called the same way,
* a hand-written numba loop (the same loop as the hand C, ``@numba.njit``; the ``bench`` extra; skipped
  with a note in the reports when numba is not importable),
* hand-written vectorised numpy,
* ``sympy.lambdify`` of the whole-chain expressions (N <= 1024; expanding bigger chains takes minutes),
* a CasADi SX ``Function`` of the whole chain (vectorised SX operations; N <= 16384: building the SX graph
  of a bigger chain takes longer than the rest of the benchmark).

Memory bandwidth (measured in the same run): the batched force moves 16 N B bytes per call (u read, F
written: 8 bytes per double); its achieved fraction of the bound is (16 N B / t) / bw_all(N B), bw_all(n)
the bandwidth of a numpy copy of n doubles split over every core at once (16 n bytes over its best time of 5,
:func:`mechgen.analyses.symplectic.all_core_copy_bandwidth`: the machine's bound, which a one-thread copy
understates). The leapfrog step of the C time loop (mechgen.runtime.core.symplectic_c,
``scenes/fpu_large.toml``: N = 10^6 FPU-beta, 2000 steps; quick: 10^5, 100 steps) reports its
``bandwidth_share`` the same way, with the bytes its step really streams (80 N:
:func:`mechgen.analyses.symplectic.loop_bytes_per_step`). Target (issue 16): within 2x of the bound, a
fraction >= 0.5.

Also: the Python-level overhead of a prepared call of a small kernel, derivation +
generation + compile time (first run with an empty cache, and cached, each in a
new Python process; quick: N = 8 only), and the time a scene takes to start solving. Every ratio is
measured in one run on one machine; the numbers of the methods are checked
against each other before timing.

The user path (issue #12): ``mechgen run scenes/fpu_chain.toml`` as a whole process in the default
environment (no BLAS thread variables) against the same run pinned to one BLAS thread, interleaved, median
of 3 (``user_path`` in ``fpu_kernels.json``, a table in ``fpu_kernels.md``; :func:`mechgen.bench.common.user_path`).
"""
from __future__ import annotations

import time
from functools import partial
import tomllib
from pathlib import Path

import numpy as np

from mechgen.bench.common import (ROOT, best_time, empty_cache, in_fresh_process, user_path, user_path_markdown,
                                  write_csv, write_json, write_text)

__all__ = ["best_time", "empty_cache", "numpy_force", "numpy_stiffness", "fpu_system", "kernel_rows",
           "numba_kernels", "batch_bandwidth", "leapfrog_bandwidth", "ratio_table", "call_overhead", "build_times",
           "scene_start", "report_markdown", "run_fpu_benchmarks"]

GAMMA, ALPHA, BETA = 1.0, 0.25, 0.1
HAND_C = ROOT / "benchmarks" / "hand_fpu.c"
#: the scene timed as a user runs it
USER_SCENE = "fpu_chain.toml"
#: the N ladder of the force and stiffness timings (full, quick)
LADDER, QUICK_LADDER = (64, 256, 1024, 4096, 16384, 65536, 262144, 1_000_000), (64, 256)
#: the batched force: (N, states), full and quick
BATCH, QUICK_BATCH = (4096, 10_000), (64, 100)
#: the largest N of the whole-chain CasADi SX functions
CASADI_MAX = 16384
#: the leapfrog run: (N, t_end at dt = 0.05), full and quick
LEAPFROG, QUICK_LEAPFROG = (1_000_000, 100.0), (100_000, 5.0)
#: the issue's targets: generated / hand C at most, lambdify / generated at least (N >= 1024), bandwidth share
GEN_HAND_TARGET, LAMBDIFY_TARGET, BANDWIDTH_TARGET = 1.3, 100.0, 0.5


def numpy_force(u: np.ndarray) -> np.ndarray:
    """Vectorised numpy FPU force for (..., N) arrays."""
    pad = np.zeros(u.shape[:-1] + (1,))
    r = np.diff(np.concatenate([pad, u, pad], axis=-1), axis=-1)
    f = r * (GAMMA + r * (ALPHA + r * BETA))
    return f[..., 1:] - f[..., :-1]


def numpy_stiffness(u: np.ndarray) -> np.ndarray:
    """CSR data of the tridiagonal K (rows ascending) in numpy."""
    n = u.shape[-1]
    r = np.diff(np.concatenate([[0.0], u, [0.0]]))
    k = GAMMA + r * (2 * ALPHA + 3 * BETA * r)
    data = np.empty(3 * n - 2)
    data[0::3] = k[:-1] + k[1:]
    data[1::3] = -k[1:-1]
    data[2::3] = -k[1:-1]
    return data


def fpu_system(n: int):
    """The FPU chain of n sites compiled to C with its force and stiffness kernels: (system, build report)."""
    from mechgen import models
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.specialize import specialize

    model = models.get("fpu_chain")
    spec = specialize(model, {"N": n, "gamma": GAMMA, "alpha": ALPHA, "beta": BETA})
    return compile_model(model, spec, kernels={"force", "stiffness"}, backend="c")


def _bind_force(system, u: np.ndarray, out: np.ndarray):
    nb = u.shape[0] if u.ndim == 2 else 1
    inputs = {"q": u, "v": np.zeros_like(u), "z": np.zeros(0), "t": np.zeros((nb, 1)), "p": system.params}
    return system.kernels["force"].bind(inputs, {"f": out}, system.sizes("force"))


def _bind_stiffness(system, u: np.ndarray, outs: dict):
    pat = system.pattern("stiffness")
    inputs = {"q": u, "v": np.zeros_like(u), "p": system.params, **pat.slots}
    return system.kernels["stiffness"].bind(inputs, outs, system.sizes("stiffness"))


def _hand(lib, name: str, u: np.ndarray, out: np.ndarray, n: int, nbatch: int):
    from mechgen.codegen.build import function_address, get_caller

    params = np.array([GAMMA, ALPHA, BETA])
    return get_caller().bind(function_address(lib, name), [u.ctypes.data, params.ctypes.data], [out.ctypes.data],
                             [n], nbatch, (u, out, params, lib))


def _lambdified(n: int):
    import sympy as sp

    u = sp.symbols(f"u1:{n + 1}", real=True)
    ext = (0,) + u + (0,)
    f = [GAMMA * r + ALPHA * r**2 + BETA * r**3 for r in (ext[i + 1] - ext[i] for i in range(n + 1))]
    start = time.perf_counter()
    force = sp.lambdify([u], [f[i + 1] - f[i] for i in range(n)], "numpy")
    return force, time.perf_counter() - start


def _casadi_force(n: int):
    import casadi as ca

    u = ca.SX.sym("u", n)
    ext = ca.vertcat(0, u, 0)
    r = ext[1:] - ext[:-1]
    f = r * (GAMMA + r * (ALPHA + r * BETA))
    F = ca.Function("F", [u], [f[1:] - f[:-1]])
    K = ca.Function("K", [u], [ca.jacobian(-(f[1:] - f[:-1]), u)])
    return F, K


def numba_kernels():
    """(force, stiffness, None) as hand-written numba loops - the loops of benchmarks/hand_fpu.c, u of shape
    (states, N), outputs written in place - or (None, None, why) when numba is not importable."""
    try:
        import numba
    except ImportError as exc:
        return None, None, f"numba is not importable ({exc}): pip install 'mechgen[bench]'"

    @numba.njit(cache=False)
    def force(u, g, a, b, F):  # F_i = f(u_{i+1} - u_i) - f(u_i - u_{i-1}), u_0 = u_{N+1} = 0
        nb, n = u.shape
        for s in range(nb):
            left = u[s, 0] * (g + u[s, 0] * (a + u[s, 0] * b))
            for i in range(n):
                r = (u[s, i + 1] if i + 1 < n else 0.0) - u[s, i]
                right = r * (g + r * (a + r * b))
                F[s, i] = right - left
                left = right

    @numba.njit(cache=False)
    def stiffness(u, g, a, b, K):  # CSR data of K = -dF/du, rows ascending, k(r) = f'(r)
        n = u.shape[0]
        left = g + u[0] * (2.0 * a + 3.0 * b * u[0])
        p = 0
        for i in range(n):
            r = (u[i + 1] if i + 1 < n else 0.0) - u[i]
            right = g + r * (2.0 * a + 3.0 * b * r)
            if i > 0:
                K[p] = -left
                p += 1
            K[p] = left + right
            p += 1
            if i + 1 < n:
                K[p] = -right
                p += 1
            left = right

    return force, stiffness, None


def _row(rows: list, method: str, quantity: str, n: int, batch: int, seconds: float) -> None:
    rows.append({"method": method, "quantity": quantity, "N": n, "batch": batch, "seconds": seconds})


def kernel_rows(sizes, batch_n: int, batch: int, lambdify_max: int, casadi_max: int = CASADI_MAX,
                numba: bool = True, min_time: float = 0.1, repeats: int = 5) -> list[dict]:
    """Time every method for the force and the stiffness; checks agreement first. ``numba``: time the numba
    loops too (when importable). ``min_time``, ``repeats``: those of :func:`best_time` (the quick run's
    are shorter: it checks that the suite runs, its times are not reported as measurements)."""
    timer = partial(best_time, min_time=min_time, repeats=repeats)

    from mechgen.codegen.build import load_shared

    lib = load_shared(HAND_C.read_text(), stem="hand_fpu")
    nb_force, nb_stiff, _ = numba_kernels() if numba else (None, None, None)
    rows: list = []
    rng = np.random.default_rng(0)
    for n, nb in [(n, 1) for n in sizes] + [(batch_n, batch)]:
        system, _ = fpu_system(n)
        u = np.ascontiguousarray(rng.normal(scale=0.1, size=(nb, n)))
        u1 = u[0].copy()
        f_gen, f_hand = np.zeros((nb, n)), np.zeros((nb, n))
        gen, hand = _bind_force(system, u if nb > 1 else u1, f_gen if nb > 1 else f_gen[0]), \
            _hand(lib, "hand_force", u, f_hand, n, nb)
        gen(), hand()
        ref = numpy_force(u)
        assert np.allclose(f_gen, ref, rtol=1e-12, atol=1e-15) and np.allclose(f_hand, ref, rtol=1e-12, atol=1e-15)
        _row(rows, "generated C", "force", n, nb, timer(gen))
        _row(rows, "hand C -O3", "force", n, nb, timer(hand))
        _row(rows, "numpy", "force", n, nb, timer(lambda: numpy_force(u)))
        if nb_force is not None:
            f_nb = np.zeros((nb, n))
            nb_force(u, GAMMA, ALPHA, BETA, f_nb)
            assert np.allclose(f_nb, ref, rtol=1e-12, atol=1e-15)
            _row(rows, "numba", "force", n, nb, timer(lambda: nb_force(u, GAMMA, ALPHA, BETA, f_nb)))
        F, Kc = _casadi_force(n) if n <= casadi_max and n * nb <= 1_000_000 else (None, None)
        if F is not None and nb == 1:
            assert np.allclose(np.asarray(F(u1)).ravel(), ref[0], rtol=1e-12, atol=1e-15)
            _row(rows, "casadi SX", "force", n, nb, timer(lambda: F(u1)))
        elif F is not None:
            Fm = F.map(nb)
            _row(rows, "casadi SX map", "force", n, nb, timer(lambda: Fm(u.T)))
        if n <= lambdify_max and nb == 1:
            lam, _ = _lambdified(n)
            assert np.allclose(lam(u1), ref[0], rtol=1e-12, atol=1e-15)
            _row(rows, "sympy.lambdify", "force", n, nb, timer(lambda: lam(u1)))
        if nb == 1:
            pat = system.pattern("stiffness")
            outs = {"K": np.zeros(pat.nnz)}
            k_gen = _bind_stiffness(system, u1, outs)
            k_hand_out = np.zeros(3 * n - 2)
            k_hand = _hand(lib, "hand_stiffness", u1, k_hand_out, n, 1)
            k_gen(), k_hand()
            ref_k = numpy_stiffness(u1)
            assert np.allclose(outs["K"], ref_k, rtol=1e-12) and np.allclose(k_hand_out, ref_k, rtol=1e-12)
            _row(rows, "generated C", "stiffness", n, 1, timer(k_gen))
            _row(rows, "hand C -O3", "stiffness", n, 1, timer(k_hand))
            _row(rows, "numpy", "stiffness", n, 1, timer(lambda: numpy_stiffness(u1)))
            if nb_stiff is not None:
                k_nb = np.zeros(3 * n - 2)
                nb_stiff(u1, GAMMA, ALPHA, BETA, k_nb)
                assert np.allclose(k_nb, ref_k, rtol=1e-12)
                _row(rows, "numba", "stiffness", n, 1, timer(lambda: nb_stiff(u1, GAMMA, ALPHA, BETA, k_nb)))
            if Kc is not None:
                _row(rows, "casadi SX", "stiffness", n, 1, timer(lambda: Kc(u1)))
    return rows


def batch_bandwidth(rows: list, batch_n: int, batch: int) -> dict:
    """The batched force's achieved share of the memory-bandwidth bound, per method timed on it (generated C,
    hand C, numba, numpy): (16 N B bytes / its seconds) / bw_all(N B) (module docstring), bw_all measured now."""
    from mechgen.analyses.symplectic import all_core_copy_bandwidth

    moved = 16.0 * batch_n * batch
    bw = all_core_copy_bandwidth(batch_n * batch)
    shares = {r["method"]: moved / r["seconds"] / bw for r in rows
              if (r["quantity"], r["N"], r["batch"]) == ("force", batch_n, batch) and r["method"] in
              ("generated C", "hand C -O3", "numba", "numpy")}
    return {"N": batch_n, "states": batch, "bytes_per_call": moved, "copy_bandwidth_GBps": bw / 1e9,
            "fraction": shares, "target": BANDWIDTH_TARGET}


def leapfrog_bandwidth(n: int, t_end: float) -> dict:
    """The leapfrog's steps per second and share of the bandwidth bound in the C time loop: scenes/fpu_large.toml
    (FPU-beta, fixed ends, dt = 0.05) at N = ``n`` to ``t_end``, as the symplectic analysis reports them."""
    import mechgen

    scene = tomllib.loads((ROOT / "scenes" / "fpu_large.toml").read_text())
    scene["params"]["N"] = int(n)
    (analysis,) = scene["analysis"]
    analysis["t_end"] = float(t_end)
    analysis["stride"] = min(int(analysis.get("stride", 500)), int(round(t_end / analysis["dt"])))
    out = mechgen.run(scene)["analyses"][0]["outputs"]
    return {"N": int(n), "steps": out["steps"], "loop": out["loop"], "steps_per_second": out["steps_per_second"],
            "energy_error": out["energy_error"], "fraction": out["bandwidth_share"],
            "bytes_per_step": out["bytes_per_step"], "target": BANDWIDTH_TARGET}


def ratio_table(rows: list) -> list[dict]:
    """Per quantity, N and batch: generated C / hand C (target <= GEN_HAND_TARGET), and lambdify, numba, numpy,
    CasADi over generated C (> 1: generated C is faster); None where a method was not timed."""
    out = []
    for q, n, b in sorted({(r["quantity"], r["N"], r["batch"]) for r in rows}, key=lambda k: (k[0], k[2], k[1])):
        hand = _ratio(rows, "hand C -O3", q, n, b, "generated C")
        cas = _ratio(rows, "casadi SX", q, n, b, "generated C") or _ratio(rows, "casadi SX map", q, n, b,
                                                                          "generated C")
        gen_hand = None if hand is None else 1.0 / hand
        out.append({"quantity": q, "N": n, "batch": b, "gen_over_hand_c": gen_hand,
                    "within_gen_hand_target": None if gen_hand is None else gen_hand <= GEN_HAND_TARGET,
                    "lambdify_over_gen": _ratio(rows, "sympy.lambdify", q, n, b, "generated C"),
                    "numba_over_gen": _ratio(rows, "numba", q, n, b, "generated C"),
                    "numpy_over_gen": _ratio(rows, "numpy", q, n, b, "generated C"), "casadi_over_gen": cas})
    return out


def call_overhead(states: int = 1_000_000, min_time: float = 0.3) -> dict:
    """Prepared-call overhead of a small kernel: one call (timed for at least ``min_time`` s) vs its share of a
    batch of ``states`` states (10^6; the quick run: 10^5 and 0.01 s)."""
    from mechgen import models
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.specialize import specialize

    model = models.get("laval_rotor")
    system, _ = compile_model(model, specialize(model, {"Omega": 100.0}), kernels={"force"}, backend="c")
    one = {"q": np.full(4, 0.01), "v": np.zeros(4), "z": np.zeros(0), "t": np.zeros(1), "p": system.params}
    out = {"f": np.zeros(4)}
    single = best_time(system.kernels["force"].bind(one, out), min_time=min_time)
    nb = states
    many = {"q": np.full((nb, 4), 0.01), "v": np.zeros((nb, 4)), "z": np.zeros(0), "t": np.zeros((nb, 1)),
            "p": system.params}
    per_state = best_time(system.kernels["force"].bind(many, {"f": np.zeros((nb, 4))}), repeats=3) / nb
    return {"single_call_ns": single * 1e9, "kernel_per_state_ns": per_state * 1e9,
            "overhead_ns": (single - per_state) * 1e9}


_FRESH_BUILD = """
import json, sys, time
start = time.perf_counter()
import mechgen.pipeline, mechgen.models, mechgen.symbolic.specialize  # noqa: E401 (imports timed apart)
from mechgen.bench.fpu import fpu_system
from mechgen.codegen.build import STATS
imported = time.perf_counter()
_, report = fpu_system(int(sys.argv[1]))
print(json.dumps({"seconds": time.perf_counter() - imported, "import_s": imported - start,
                  "compiled": STATS["miss"] > 0, "cached": report.cached,
                  **{f"{k}_s": v for k, v in report.seconds.items()}}))
"""

_FRESH_SCENE = """
import json, sys, time
start = time.perf_counter()
import mechgen.pipeline, mechgen.models  # noqa: E401 (imports timed apart)
from mechgen.codegen.build import STATS
from mechgen.scene.run import run_scene
imported = time.perf_counter()
seconds = run_scene(sys.argv[1])["build"]["seconds_total"]
print(json.dumps({"seconds": seconds, "import_s": imported - start, "compiled": STATS["miss"] > 0}))
"""


def build_times(sizes) -> list[dict]:
    """Derivation + generation + compile of the FPU kernels, first run (empty cache) and cached, for each N.

    Each run is a new Python process, as a user's first and second call would be:
    no sympy cache, no loaded library, no mgcall extension carried over from the
    kernel timings. ``seconds`` is the compile_model call; imports are reported
    apart (``import_s``); ``compiled`` says whether the C compiler ran.
    """
    rows = []
    for n in sizes:
        with empty_cache():
            for label in ("first", "cached"):
                rows.append({"N": n, "run": label, **in_fresh_process(_FRESH_BUILD, str(n))})
    return rows


def scene_start(scene: Path) -> dict:
    """Seconds from run_scene() to its first analysis, first (empty cache) and cached, each in a new process."""
    out = {}
    with empty_cache():
        for label in ("first", "cached"):
            out[label] = in_fresh_process(_FRESH_SCENE, str(scene))["seconds"]
    return out


def _ratio(rows, method, quantity, n, batch, base) -> float | None:
    def pick(m):
        for r in rows:
            if (r["method"], r["quantity"], r["N"], r["batch"]) == (m, quantity, n, batch):
                return r["seconds"]
        return None

    a, b = pick(method), pick(base)
    return None if a is None or b is None else a / b


def bandwidth_markdown(batched: dict, leapfrog: dict, numba_note: str | None) -> list[str]:
    """The bandwidth lines (and why numba is missing, if it is)."""
    shares = ", ".join(f"{m} {f:.2f}" for m, f in batched["fraction"].items())
    lines = ["", f"batched force, {batched['states']:,} states at N = {batched['N']:,} "
             f"({batched['bytes_per_call'] / 1e6:.0f} MB moved per call; numpy copy of the same size on every core "
             f"{batched['copy_bandwidth_GBps']:.2f} GB/s): share of the bandwidth bound {shares} "
             f"(target >= {BANDWIDTH_TARGET:g})",
             f"leapfrog step, C time loop ({leapfrog['loop']}), N = {leapfrog['N']:,}, {leapfrog['steps']:,} steps: "
             f"{leapfrog['steps_per_second']:.1f} steps/s, {leapfrog['bytes_per_step'] / leapfrog['N']:.0f} N bytes "
             f"per step, share of the all-core bandwidth bound {leapfrog['fraction']:.2f} "
             f"(target >= {BANDWIDTH_TARGET:g}), energy error {leapfrog['energy_error']:.1e}"]
    if numba_note:
        lines.append(f"numba: not timed - {numba_note}")
    return lines


def report_markdown(rows, overhead, builds, start) -> str:
    """The summary table with the issue's targets."""
    lines = ["| quantity | N | batch | generated C | hand C | gen/hand (target <= 1.3) | numba/gen | numpy/gen | "
             "lambdify/gen (target >= 100 at N >= 1024) | casadi/gen |", "|---|---|---|---|---|---|---|---|---|---|"]
    keys = sorted({(r["quantity"], r["N"], r["batch"]) for r in rows}, key=lambda k: (k[0], k[2], k[1]))
    for q, n, b in keys:
        gen = next(r["seconds"] for r in rows if (r["method"], r["quantity"], r["N"], r["batch"]) ==
                   ("generated C", q, n, b))
        hand = _ratio(rows, "hand C -O3", q, n, b, "generated C")
        fmt = lambda x: "-" if x is None else f"{x:.2f}"  # noqa: E731
        gh = None if hand is None else 1 / hand
        lam = _ratio(rows, "sympy.lambdify", q, n, b, "generated C")
        cas = _ratio(rows, "casadi SX", q, n, b, "generated C") or _ratio(rows, "casadi SX map", q, n, b,
                                                                          "generated C")
        hand_s = next((r["seconds"] for r in rows if (r["method"], r["quantity"], r["N"], r["batch"]) ==
                       ("hand C -O3", q, n, b)), None)
        lines.append(f"| {q} | {n} | {b} | {gen * 1e6:.2f} us | "
                     f"{'-' if hand_s is None else f'{hand_s * 1e6:.2f} us'} | {fmt(gh)} | "
                     f"{fmt(_ratio(rows, 'numba', q, n, b, 'generated C'))} | "
                     f"{fmt(_ratio(rows, 'numpy', q, n, b, 'generated C'))} | {fmt(lam)} | {fmt(cas)} |")
    lines.append("")
    lines.append(f"prepared call of a 4-DOF kernel: {overhead['single_call_ns']:.0f} ns per call, kernel "
                 f"{overhead['kernel_per_state_ns']:.0f} ns per state -> overhead {overhead['overhead_ns']:.0f} ns "
                 "(target about 250 ns)")
    for b in builds:
        lines.append(f"build N={b['N']} {b['run']}: {b['seconds']:.3f} s in a new process "
                     f"({'C compiler ran' if b['compiled'] else 'no compile'}; imports {b['import_s']:.2f} s apart) "
                     "(target < 2 s)")
    lines.append(f"scene start (run_scene to first analysis, new process): first {start['first']:.3f} s, "
                 f"cached {start['cached']:.3f} s (target < 0.5 s cached)")
    return "\n".join(lines)


def run_fpu_benchmarks(*, out: Path, quick: bool = False) -> dict:
    """Run the FPU benchmark and write ``out/fpu_kernels.{csv,json,md}``."""
    sizes = QUICK_LADDER if quick else LADDER
    batch = QUICK_BATCH if quick else BATCH
    numba_note = numba_kernels()[2]
    rows = kernel_rows(sizes, batch[0], batch[1], lambdify_max=256 if quick else 1024,
                       **({"min_time": 0.01, "repeats": 2} if quick else {}))
    batched = batch_bandwidth(rows, *batch)
    leapfrog = leapfrog_bandwidth(*(QUICK_LEAPFROG if quick else LEAPFROG))
    ratios = ratio_table(rows)
    overhead = call_overhead(**({"states": 100_000, "min_time": 0.01} if quick else {}))
    builds = build_times((8, 100_000) if not quick else (8,))
    start = scene_start(ROOT / "scenes" / "spring_pendulum.toml")
    users = user_path([ROOT / "scenes" / USER_SCENE], repeats=1 if quick else 3, warm=not quick)
    out = Path(out)
    write_csv(out / "fpu_kernels.csv", rows)
    result = {"kernels": rows, "ratios": ratios, "batched_force_bandwidth": batched, "leapfrog_bandwidth": leapfrog,
              "numba": numba_note or "timed", "call_overhead": overhead, "builds": builds, "scene_start": start,
              "user_path": users}
    write_json(out / "fpu_kernels.json", result)
    table = (report_markdown(rows, overhead, builds, start) + "\n".join([""] + bandwidth_markdown(batched, leapfrog,
                                                                                                 numba_note))
             + "\n\n" + user_path_markdown(users, "The scene as a user runs it"))
    write_text(out / "fpu_kernels.md", table + "\n")
    print(table)
    print(f"\nwrote {out / 'fpu_kernels.csv'}, {out / 'fpu_kernels.json'}, {out / 'fpu_kernels.md'}")
    return result
