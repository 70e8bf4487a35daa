"""``mechgen bench beam`` (continua): work against precision on the clamped-free beam, and assembly speed against
scikit-fem.

1. **Work-precision.** Euler-Bernoulli beam, EI = rhoA = L = 1, clamped at s = 0
   and free at s = L. Exact frequencies omega_n = (beta_n L)^2 with beta_n L the
   roots of cos(x) cosh(x) = -1 (Blevins, *Formulas for Natural Frequency and Mode
   Shape*, 1979, Table 8-1), recomputed here by brentq to 1e-15, independently of
   mechgen. For every discretisation that can represent the beam (C1 elements
   ``hermite`` and ``quintic``, global ``legendre`` and ``beam`` bases) and a ladder of
   sizes: the largest relative error of the first five frequencies, and the wall
   time of a full solve = compile from a warm cache + ``linear()`` + ``modes(count=5)``
   (best and median of several repeats after one untimed warm-up). Sizes that leave
   fewer than five unknowns after the boundary conditions are skipped.

2. **Assembly against scikit-fem.** A Hermite beam of 2 000 elements, *unconstrained*
   (free-free, no boundary conditions, so both libraries return the same
   4 002 x 4 002 matrices with the same dof order: value and slope per node). The
   matrices are first checked against the closed-form Hermite element matrices
   (Przemieniecki, *Theory of Matrix Structural Analysis*, 1968) and against each
   other, and the first five clamped-free frequencies of both against the exact ones;
   then timed, best of several repeats, in one run:

   * mechgen ``linear()`` on a system whose discretisation is built (M, D, G, K: the
     pointwise kernel at all Gauss points, element matrices, CSR scatter; D and G are
     zero for this model but are still assembled) versus scikit-fem ``asm`` of the
     ``u*v`` and ``dd(u)[0,0]*dd(v)[0,0]`` forms on a built ``Basis``;
   * from scratch: ``system.refined(N).linear()`` (jet tables, dof maps and CSR
     pattern rebuilt) versus ``MeshLine`` + ``Basis`` + the two ``asm`` calls;
   * the assembly step alone (element matrices + scatter of M and K from pointwise
     coefficients already evaluated).

Every ratio is mechgen / scikit-fem measured in the same process on the same
machine.

3. **As a user runs it** (issue #12): the continua scenes (``USER_SCENES``: ``beam_modes``,
   ``timoshenko_modes``, ``beck_column``) as whole ``mechgen run`` processes, the default environment (no BLAS
   thread variables) against pinned to one BLAS thread, interleaved, median of 3 (quick: the first, once):
   ``beam_user_path.{json,md}`` (:func:`mechgen.bench.common.user_path`).

Entry point: :func:`run_field_benchmarks`.
"""
from __future__ import annotations

import platform
import statistics
import warnings
from pathlib import Path

import numpy as np

from mechgen.bench.common import (ROOT, repeat_times, suite_report, user_path, user_path_markdown,
                                  write_json, write_text)

MODEL = "euler_bernoulli_beam"
COUNT = 5
LADDERS = {
    "hermite": [4, 8, 16, 32, 64, 128, 256, 512],
    "quintic": [2, 4, 8, 16, 32, 64, 128],
    "legendre": [8, 10, 12, 14, 16, 20, 24, 28, 32, 40],
    "beam": [5, 6, 8, 10, 12, 16, 20],
}
QUICK_LADDERS = {"hermite": [4, 16, 64], "quintic": [2, 8], "legendre": [8, 16], "beam": [5, 10]}
ASSEMBLY_ELEMENTS = 2000
#: the continua scenes timed as a user runs them
USER_SCENES = ("beam_modes.toml", "timoshenko_modes.toml", "beck_column.toml")
PLOT_FLOOR = 1e-16  # errors below this (exact to round-off) are drawn at the floor of the log plot


# -- reference -------------------------------------------------------------------
def clamped_free_roots(count: int = COUNT) -> np.ndarray:
    """beta_n L, n = 1..count: roots of cos(x) cosh(x) + 1 = 0 (scaled by exp(-x) to stay finite)."""
    from scipy.optimize import brentq

    g = lambda x: (np.cos(x) * np.cosh(x) + 1.0) * np.exp(-x)  # noqa: E731
    return np.array([brentq(g, (n - 0.5) * np.pi - 0.5, (n - 0.5) * np.pi + 0.4, xtol=1e-15)
                     for n in range(1, count + 1)])


def hermite_closed_form(elements: int, length: float = 1.0):
    """Unconstrained M and K (CSR) of a uniform cubic Hermite beam, EI = rhoA = 1, dofs (w, w_s) per node."""
    import scipy.sparse as sps

    h = length / elements
    ke = np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                   [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]) / h**3
    me = h / 420 * np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                             [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    dofs = 2 * np.arange(elements)[:, None] + np.arange(4)[None, :]
    rows = np.repeat(dofs, 4, axis=1).ravel()
    cols = np.tile(dofs, (1, 4)).ravel()
    n = 2 * elements + 2
    mat = lambda e: sps.csr_matrix((np.tile(e.ravel(), elements), (rows, cols)), shape=(n, n))  # noqa: E731
    return mat(me), mat(ke)


def _relative(A, B) -> float:
    """max |A - B| / max |B| (sparse or dense)."""
    diff = abs(A - B)
    return float(diff.max() / abs(B).max())


def _lowest_frequencies(M, K, fixed=(0, 1), count: int = COUNT) -> np.ndarray:
    """First frequencies with the dofs ``fixed`` removed: shift-invert Lanczos about 0 (scipy), independent of mechgen."""
    import scipy.sparse as sps
    import scipy.sparse.linalg as spla

    keep = np.setdiff1d(np.arange(M.shape[0]), fixed)
    M, K = sps.csc_matrix(M)[keep][:, keep], sps.csc_matrix(K)[keep][:, keep]
    start = np.random.default_rng(0).standard_normal(K.shape[0])  # fixed: the same figures every run
    lam = spla.eigsh(K, k=count, M=M, sigma=0.0, which="LM", return_eigenvectors=False, v0=start)
    return np.sqrt(np.sort(lam))


# -- work-precision --------------------------------------------------------------
def _beam(bc: str, disc: str, size: int, backend: str):
    from mechgen import models
    from mechgen.pipeline import compile_model
    from mechgen.symbolic.specialize import specialize

    model = models.get(MODEL)
    spec = specialize(model, {"bc": bc, "discretisation": disc, "N": int(size), "EI": 1.0, "rhoA": 1.0, "L": 1.0})
    return compile_model(model, spec, kernels={"linear"}, backend=backend)


def work_precision(ladders: dict, *, repeats: int = 5, backend: str = "c") -> list[dict]:
    """One row per (discretisation, size): unknowns, max relative error of the first five frequencies, seconds."""
    from mechgen.runtime.linear.modes import modes

    exact = clamped_free_roots(COUNT) ** 2
    rows = []
    for disc, sizes in ladders.items():
        for size in sizes:
            system, report = _beam("clamped-free", disc, size, backend)  # also fills the compile cache
            if system.n < COUNT:
                continue

            def solve(disc=disc, size=size):
                system, _ = _beam("clamped-free", disc, size, backend)
                mats = system.linear()
                return modes(mats["M"], mats["K"], count=COUNT).frequencies

            freqs = solve()
            err = float(np.max(np.abs(freqs / exact - 1.0)))
            times = repeat_times(solve, repeats)
            rows.append({"discretisation": disc, "size": int(size), "unknowns": int(system.n),
                         "max_rel_error": err, "seconds": min(times), "median_seconds": statistics.median(times),
                         "backend": report.backend})
    return rows


def _write_work_precision(rows: list[dict], out: Path, exact: np.ndarray, ratios: list[dict]) -> list[Path]:
    """The harness's standard reports (beam_work_precision.csv with the beam's own columns too, .png,
    beam_ratios.json) and the markdown table."""
    points = [{"series": r["discretisation"], "setting": f"N {r['size']}", "seconds": r["seconds"],
               "error": r["max_rel_error"], **{k: r[k] for k in ("discretisation", "size", "unknowns", "max_rel_error",
                                                                  "median_seconds", "backend")}} for r in rows]
    files = suite_report(out, "beam", points,
                         reference=f"exact clamped-free roots of cos(bL) cosh(bL) = -1 (first {COUNT} frequencies)",
                         error="max relative error, first five frequencies",
                         time="full solve wall time [s] (warm compile + linear() + modes(5))",
                         title="Clamped-free Euler-Bernoulli beam: work-precision", ratios=ratios, floor=PLOT_FLOOR)
    files.append(write_text(out / "beam_work_precision.md", work_precision_markdown(rows, exact)))
    return files


def work_precision_markdown(rows: list[dict], exact: np.ndarray) -> str:
    """The work-precision table as markdown."""
    lines = ["# Clamped-free Euler-Bernoulli beam: work against precision", "",
             "EI = rhoA = L = 1. Error: max over the first five frequencies of |omega / omega_exact - 1|, "
             "omega_exact = (beta_n L)^2 with cos(beta L) cosh(beta L) = -1 "
             f"(beta_n L = {', '.join(f'{b:.10f}' for b in np.sqrt(exact))}). "
             "Time: compile from a warm cache + linear() + modes(count=5), best (and median) of the repeats, "
             "one process, one machine.", "",
             "| discretisation | size | unknowns | max rel. error | best s | median s |",
             "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        lines.append(f"| {r['discretisation']} | {r['size']} | {r['unknowns']} | {r['max_rel_error']:.2e} | "
                     f"{r['seconds']:.2e} | {r['median_seconds']:.2e} |")
    return "\n".join(lines) + "\n"


# -- assembly against scikit-fem ----------------------------------------------------
def _skfem():
    """(skfem module, its version) or (None, reason)."""
    try:
        import skfem
    except ImportError as exc:
        return None, f"scikit-fem is not installed ({exc}); pip install 'mechgen[bench]'"
    return skfem, getattr(skfem, "__version__", "unknown")


def _skfem_assembler(skfem, elements: int):
    """(build + assemble from scratch, assemble on a built basis) for the Hermite beam's M and K."""
    from skfem.helpers import dd

    mass = skfem.BilinearForm(lambda u, v, w: u * v)
    stiffness = skfem.BilinearForm(lambda u, v, w: dd(u)[0, 0] * dd(v)[0, 0])

    def basis():
        return skfem.Basis(skfem.MeshLine(np.linspace(0.0, 1.0, elements + 1)), skfem.ElementLineHermite())

    def scratch():
        b = basis()
        return skfem.asm(mass, b), skfem.asm(stiffness, b)

    built = basis()
    return scratch, lambda: (skfem.asm(mass, built), skfem.asm(stiffness, built))


def _assembly_only(system):
    """A callable assembling M and K from pointwise coefficients evaluated once (None if not reachable)."""
    from mechgen.runtime.fields.assemble import element_matrices

    try:
        disc = system.disc
        na = len(disc.jets)
        local = system.pointwise("linear", np.zeros(disc.points.shape + (na,)))
        coeff = {k: np.asarray(local[k]).reshape(disc.points.shape + (na, na)) for k in ("M", "K")}
    except Exception:  # noqa: BLE001 - a system without pointwise kernels: the row is simply left out
        return None
    pairs = {k: [tuple(ab) for ab in np.argwhere(np.any(c != 0, axis=(0, 1)))] for k, c in coeff.items()}
    asm = system.assembler

    def run():
        return {k: asm.matrix(element_matrices(disc.tables, disc.weights, coeff[k], pairs[k])) for k in coeff}

    return run


def assembly_comparison(elements: int = ASSEMBLY_ELEMENTS, *, repeats: int = 7, min_time: float = 0.05,
                        backend: str = "c") -> dict:
    """Check, then time, mechgen's and scikit-fem's Hermite beam M and K (unconstrained)."""
    import scipy.sparse as sps

    system, report = _beam("free-free", "hermite", elements, backend)
    mats = system.linear()
    M, K = sps.csr_matrix(mats["M"]), sps.csr_matrix(mats["K"])
    Mx, Kx = hermite_closed_form(elements)
    exact = clamped_free_roots(COUNT) ** 2
    result = {"elements": elements, "dofs": int(M.shape[0]), "backend": report.backend, "constraints": "none (free-free)",
              "checks": {"mechgen_vs_closed_form": max(_relative(M, Mx), _relative(K, Kx)),
                         "mechgen_clamped_free_freq_error": float(np.max(np.abs(_lowest_frequencies(M, K) / exact - 1)))},
              "seconds": {}, "ratios": {}}
    if result["checks"]["mechgen_vs_closed_form"] > 1e-12:
        raise AssertionError(f"mechgen's Hermite matrices deviate from the closed form: {result['checks']}")
    t = result["seconds"]
    t["mechgen linear()"] = min(repeat_times(system.linear, repeats, min_time))
    t["mechgen refined(N).linear()"] = min(repeat_times(lambda: system.refined(elements).linear(), repeats, min_time))
    only = _assembly_only(system)
    if only is not None:
        check = only()
        if max(_relative(check["M"], Mx), _relative(check["K"], Kx)) > 1e-12:
            raise AssertionError("assembly-only M/K differ from linear()'s")
        t["mechgen assembly only (M, K)"] = min(repeat_times(only, repeats, min_time))
    skfem, version = _skfem()
    result["skfem_version"] = version if skfem is not None else None
    if skfem is None:
        result["skipped"] = version
        return result
    scratch, built = _skfem_assembler(skfem, elements)
    Ms, Ks = built()
    if Ms.shape != M.shape or (abs(Ms) > 0).nnz != (abs(M) > 0).nnz:
        raise AssertionError(f"scikit-fem's matrices have another shape or pattern: {Ms.shape} vs {M.shape}")
    freq_sk = _lowest_frequencies(Ms, Ks)
    result["checks"].update({
        "skfem_vs_closed_form": max(_relative(Ms, Mx), _relative(Ks, Kx)),
        "mechgen_vs_skfem": max(_relative(M, Ms), _relative(K, Ks)),
        "skfem_clamped_free_freq_error": float(np.max(np.abs(freq_sk / exact - 1))),
    })
    # scikit-fem's ElementLineHermite inverts a Vandermonde matrix in global coordinates per element, so its
    # entries drift from the closed form as h shrinks (about 1e-5 relative at 2 000 elements); the same operator
    # is still recognisable well inside 1e-3.
    if result["checks"]["mechgen_vs_skfem"] > 1e-3:
        raise AssertionError(f"mechgen and scikit-fem assemble different operators: {result['checks']}")
    t["skfem asm(M)+asm(K)"] = min(repeat_times(built, repeats, min_time))
    t["skfem MeshLine+Basis+asm"] = min(repeat_times(scratch, repeats, min_time))
    r = result["ratios"]
    r["linear() / asm"] = t["mechgen linear()"] / t["skfem asm(M)+asm(K)"]
    r["refined(N).linear() / MeshLine+Basis+asm"] = t["mechgen refined(N).linear()"] / t["skfem MeshLine+Basis+asm"]
    if "mechgen assembly only (M, K)" in t:
        r["assembly only / asm"] = t["mechgen assembly only (M, K)"] / t["skfem asm(M)+asm(K)"]
    return result


def assembly_markdown(res: dict) -> str:
    """The assembly comparison as markdown."""
    lines = [f"# Hermite beam assembly: mechgen against scikit-fem {res.get('skfem_version') or '(not installed)'}", "",
             f"{res['elements']} elements, {res['dofs']} dofs, unconstrained M and K (free-free), EI = rhoA = L = 1, "
             f"mechgen backend {res['backend']}. Best of the repeats, one process, one machine "
             f"({platform.processor() or platform.machine()}).", "",
             "| what | seconds |", "| --- | ---: |"]
    lines += [f"| {k} | {v:.3e} |" for k, v in res["seconds"].items()]
    if res["ratios"]:
        lines += ["", "| ratio mechgen / scikit-fem | value |", "| --- | ---: |"]
        lines += [f"| {k} | {v:.2f} |" for k, v in res["ratios"].items()]
    if res.get("skipped"):
        lines += ["", f"scikit-fem part skipped: {res['skipped']}"]
    lines += ["", "Checks (max |A - B| / max |B|; frequency errors against cos cosh = -1, first five, "
              "clamped-free by removing the two dofs at s = 0):", ""]
    lines += [f"- {k}: {v:.2e}" for k, v in res["checks"].items()]
    return "\n".join(lines) + "\n"


# -- entry point -----------------------------------------------------------------
def run_field_benchmarks(out: Path, quick: bool = False) -> dict:
    """Write ``out/beam_work_precision.{csv,png,md}`` and ``out/beam_assembly.{json,md}``; print; return numbers."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    exact = clamped_free_roots(COUNT) ** 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a missing compiler falls back to numpy: recorded per row
        rows = work_precision(QUICK_LADDERS if quick else LADDERS, repeats=2 if quick else 5)
        assembly = assembly_comparison(ASSEMBLY_ELEMENTS, repeats=3 if quick else 7, min_time=0.0 if quick else 0.05)
    users = user_path([ROOT / "scenes" / name for name in (USER_SCENES[:1] if quick else USER_SCENES)],
                      repeats=1 if quick else 3, warm=not quick)
    write_json(out / "beam_assembly.json", assembly)
    write_text(out / "beam_assembly.md", assembly_markdown(assembly))
    users_md = user_path_markdown(users, "The continua scenes as a user runs them")
    write_json(out / "beam_user_path.json", users)
    write_text(out / "beam_user_path.md", users_md + "\n")
    files = [out / "beam_assembly.json", out / "beam_assembly.md", out / "beam_user_path.json",
             out / "beam_user_path.md"]
    t = assembly["seconds"]
    ratios = [{"peer": "scikit-fem asm(M)+asm(K)", "ours_s": t[ours], "peer_s": t["skfem asm(M)+asm(K)"],
               "condition": f"{ours}: the same Hermite M and K, {assembly['elements']} elements (checked equal)"}
              for ours in ("mechgen linear()", "mechgen assembly only (M, K)")
              if ours in t and "skfem asm(M)+asm(K)" in t]
    if "skfem MeshLine+Basis+asm" in t:
        ratios.append({"peer": "scikit-fem MeshLine+Basis+asm", "ours_s": t["mechgen refined(N).linear()"],
                       "peer_s": t["skfem MeshLine+Basis+asm"],
                       "condition": f"from scratch at {assembly['elements']} elements"})
    files = _write_work_precision(rows, out, exact, ratios) + files
    print(work_precision_markdown(rows, exact))
    print(assembly_markdown(assembly))
    print(users_md)
    return {"work_precision": rows, "assembly": assembly, "user_path": users, "files": [str(f) for f in files]}
