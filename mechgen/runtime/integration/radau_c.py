"""The compiled Radau IIA loop for a smooth lumped model: scipy's Radau, step for step, in one C function.

For x = (q, v, z) (and the energy balance's integrals after z, mechgen.runtime.integration.augmented), in C

    dq/dt = v,   dv/dt = -M^-1 r(q, v, 0, z, t),   dz/dt = rates(q, v, z, t),
    J = [[0, I, 0], [-M^-1 r_q, -M^-1 r_v, -M^-1 r_z], [g_q, g_v, g_z]]   (the integrals' rows and columns: 0),

from the model's ``flow`` (or ``residual`` and ``tangent``), ``tangent`` (at the current acceleration), ``rates``
(``energy_rates`` with the integrals) and ``rates_tangent`` kernels called by address, stepped by the implicit
Radau IIA method of order 5 exactly as scipy.integrate.Radau steps it (``runtime/csrc/radau_loop.c``'s
doc), the samples at ``t_eval`` from its collocation polynomial. No Python runs between the steps: the C function
returns every :data:`SLICE` steps (budget clock, progress bar) and at the end. Dense LU (real and complex, partial
pivoting) of the nx x nx Newton matrices: states up to :data:`MAX_STATES` entries.
"""
from __future__ import annotations

import ctypes
import logging
from functools import lru_cache

import numpy as np

from mechgen.errors import BuildError, CompilerUnavailable, ConvergenceError, KernelError
from mechgen.runtime import csrc
from mechgen.runtime.core.budget import BudgetExceeded, Progress
from mechgen.runtime.core.integrate import CHECK_EVERY, project_steps, reached_at
from mechgen.runtime.core.pattern import extent
from mechgen.runtime.integration.events_c import INPUTS, kernel_call_problem

log = logging.getLogger("mechgen")

SOURCE = csrc.path("radau_loop.c")
STEM = "mgradau"
#: the C loop hands back to Python (budget clock and projection, progress bar) after this many steps: the Python
#: path's CHECK_EVERY, so that the step-size projection (integrate.project_steps) refuses at the same step
SLICE = CHECK_EVERY
#: the largest first-order state (2n + m + integrals) the loop's dense O(nx^3) LUs take
MAX_STATES = 200
PORTS, PICKS = 8, 4
#: the kernels by the loop's slot (MGR_K_*), with the outputs it reads from each
KERNELS = (("flow", ("r", "M")), ("residual", ("r",)), ("tangent", ("r_a", "r_q", "r_v", "r_z")),
           ("rates", ("g",)), ("rates_tangent", ("g_q", "g_v", "g_z")))
DONE, SLICED = 0, 5
E_KERNEL, E_RHS, E_JAC, E_SINGULAR, E_SMALL, E_BUDGET, E_MEMORY, E_INPUT = -1, -2, -3, -5, -6, -9, -11, -12

c_long, c_double, c_void_p = ctypes.c_long, ctypes.c_double, ctypes.c_void_p


class CKernel(ctypes.Structure):
    """mgr_kernel: a kernel's address, what its inputs are, its output lengths and the outputs used."""

    _fields_ = [("fn", c_void_p), ("nin", c_long), ("nout", c_long), ("ports", c_long * PORTS),
                ("out_len", c_long * PORTS), ("pick", c_long * PICKS)]


class CProblem(ctypes.Structure):
    """mgr_problem: sizes, kernels, parameters, tolerances, samples and bounds."""

    _fields_ = [("n", c_long), ("m", c_long), ("extra", c_long), ("kernels", CKernel * len(KERNELS)),
                ("p", c_void_p), ("rtol", c_double), ("atol", c_double), ("t_end", c_double),
                ("n_eval", c_long), ("t_eval", c_void_p), ("s_x", c_void_p), ("budget_left", c_long),
                ("slice", c_long), ("atol_v", c_void_p)]


class CState(ctypes.Structure):
    """mgr_state: where the run is, its counters, the last error's place and the loop's workspace."""

    _fields_ = [("t", c_double), ("x", c_void_p), ("steps", c_long), ("nfev", c_long), ("njev", c_long),
                ("nlu", c_long), ("i_eval", c_long), ("counted", c_long), ("err_kind", c_long),
                ("err_rc", c_long), ("err_t", c_double), ("err_x", c_void_p), ("work", c_void_p),
                ("h_last", c_double)]


LAYOUT = (CKernel, CProblem, CState)


@lru_cache(maxsize=None)
def library():
    """(the loaded Radau loop library, None) or (None, why it is unavailable); built once per machine (the compile
    cache), loaded once per process, its structs checked against their Python mirrors."""
    from mechgen.buildlock import load_shared_once as load_shared  # compiled once across processes

    try:
        lib = load_shared(csrc.source(SOURCE), stem=STEM, ldflags=("-lm",),
                          symbols=("mgr_run", "mgr_free", "mgr_layout"))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("C Radau loop unavailable (%s)", exc)
        return None, f"the C Radau loop cannot be built ({exc})"
    lib.mgr_layout.argtypes, lib.mgr_layout.restype = [c_long], c_long
    for i, struct in enumerate(LAYOUT):
        if lib.mgr_layout(i) != ctypes.sizeof(struct):
            return None, f"the C Radau loop's {struct.__name__} layout differs from its Python mirror"
    lib.mgr_run.argtypes = [ctypes.POINTER(CProblem), ctypes.POINTER(CState)]
    lib.mgr_run.restype = ctypes.c_int
    lib.mgr_free.argtypes, lib.mgr_free.restype = [ctypes.POINTER(CState)], None
    return lib, None


def forget_library() -> None:
    """Forget the loaded (or refused) library: the next run builds or finds it again (tests change CC)."""
    library.cache_clear()


def loop_kernels(system, extra: int) -> dict:
    """The kernels the loop calls, by its names (module doc): ``rates`` is ``energy_rates`` when the state carries
    ``extra`` integrals; ``flow`` when the system has it, else ``residual``; neither, nor ``tangent``, for a model
    of internal variables only (n = 0: dx/dt is the rates)."""
    first = "flow" if "flow" in system.kernels else "residual"
    names = {first: first, "tangent": "tangent"} if system.n else {}
    if system.m or extra:
        names["rates"] = "energy_rates" if extra else "rates"
    if system.m:
        names["rates_tangent"] = "rates_tangent"
    return names


def kernel_problem(system, names: dict) -> str | None:
    """Why the loop cannot call these kernels of ``system`` (None when it can)."""
    picks = dict(KERNELS)
    for slot, name in names.items():
        kernel = system.kernels.get(name)
        if kernel is None:
            return f"the system has no {name} kernel"
        why = kernel_call_problem(name, kernel, [p for p in picks[slot] if not (p == "r_z" and not system.m)])
        if why is not None:
            return why
    return None


def radau_loop_problem(system, rtol=1e-8, atol=1e-10, extra: int = 0) -> str | None:
    """Why the compiled Radau loop cannot integrate ``system`` (None when it can): a smooth lumped system of the
    C backend with at least one and at most MAX_STATES first-order states (a model of internal variables only, n = 0,
    included), a scalar rtol, an atol that is a scalar or one per state (scipy's), a C compiler."""
    if hasattr(system, "modes"):
        return "the system has modes (the compiled Radau loop integrates smooth models)"
    if system.is_lattice or system.is_field:
        return "the compiled Radau loop integrates lumped systems only"
    if getattr(system, "backend", None) != "c":
        return f"the system's kernels are {getattr(system, 'backend', 'unknown')} ones, not compiled C"
    size = 2 * system.n + system.m + extra
    if np.ndim(rtol) or np.ndim(atol) > 1 or (np.ndim(atol) == 1 and np.size(atol) != size):
        return f"the compiled Radau loop takes a scalar rtol and a scalar atol or {size} of them (one per state)"
    if 2 * system.n + system.m < 1 or size > MAX_STATES:
        return f"the compiled Radau loop takes 1 to {MAX_STATES} states"
    why = kernel_problem(system, loop_kernels(system, extra))
    return why if why is not None else library()[1]


def kernel_struct(kernel, picks: tuple) -> CKernel:
    """The mgr_kernel of a compiled kernel, reading the outputs ``picks`` (absent ones: -1)."""
    spec = kernel.spec
    out = CKernel(fn=kernel.address, nin=len(spec["inputs"]), nout=len(spec["outputs"]))
    for i, port in enumerate(spec["inputs"]):
        out.ports[i] = INPUTS[port["name"]]
    names = [p["name"] for p in spec["outputs"]]
    for j, port in enumerate(spec["outputs"]):
        out.out_len[j] = extent(port["extent"], {})
    for i in range(PICKS):
        out.pick[i] = names.index(picks[i]) if i < len(picks) and picks[i] in names else -1
    return out


def problem_of(system, x0: np.ndarray, t_end: float, options, extra: int) -> tuple[CProblem, dict]:
    """The C problem of a run and the arrays it points into (kept alive by the caller)."""
    names = loop_kernels(system, extra)
    atol = np.array(options.atol, dtype=float)  # 0-d (one for every state) or one per state (a contiguous copy)
    problem = CProblem(n=system.n, m=system.m, extra=extra, rtol=float(options.rtol),
                       atol=float(atol) if atol.ndim == 0 else 0.0, t_end=float(t_end), budget_left=-1, slice=SLICE)
    for slot, (kind, picks) in enumerate(KERNELS):
        if kind in names:
            problem.kernels[slot] = kernel_struct(system.kernels[names[kind]], picks)
    t_eval = np.ascontiguousarray([] if options.t_eval is None else options.t_eval, dtype=float).reshape(-1)
    keep = {"p": np.ascontiguousarray(system.params, dtype=float), "t_eval": t_eval,
            "s_x": np.zeros((len(t_eval), x0.size)), "x": x0.copy(), "err_x": np.zeros(x0.size), "atol": atol}
    problem.atol_v = atol.ctypes.data if atol.ndim else None
    problem.p = keep["p"].ctypes.data if keep["p"].size else None
    problem.n_eval, problem.t_eval = len(t_eval), t_eval.ctypes.data if len(t_eval) else None
    problem.s_x = keep["s_x"].ctypes.data if len(t_eval) else None
    return problem, keep


def integrate_radau_c(system, x0, t_end: float, options, *, extra: int = 0) -> tuple[np.ndarray, np.ndarray, dict]:
    """(t, x rows at the options' ``t_eval``, counts {steps, nfev, njev, nlu}) of a smooth lumped system
    integrated by the compiled Radau loop (module doc; ``options``: RunOptions, ``method`` and ``loop`` not read;
    ``extra``: integrals after z, their rates from ``energy_rates``). CompilerUnavailable when it cannot run
    (:func:`radau_loop_problem` says why); failures raise KernelError, ConvergenceError or BudgetExceeded."""
    why = radau_loop_problem(system, options.rtol, options.atol, extra)
    if why is not None:
        raise CompilerUnavailable(why)
    if options.t_eval is None:
        raise ValueError("the compiled Radau loop samples at t_eval only (give the sample times)")
    lib = library()[0]
    x0 = np.array(x0, dtype=float).reshape(-1)
    if x0.size != 2 * system.n + system.m + extra:
        raise ValueError(f"x0 has {x0.size} entries for a state of {2 * system.n + system.m + extra}")
    t_end = float(t_end)
    problem, keep = problem_of(system, x0, t_end, options, extra)
    state = CState(t=0.0, x=keep["x"].ctypes.data, err_x=keep["err_x"].ctypes.data)
    try:
        drive(lib, system, problem, state, keep, options)
    finally:
        lib.mgr_free(ctypes.byref(state))
    t_eval = keep["t_eval"][:state.i_eval]
    counts = {"steps": int(state.steps), "nfev": int(state.nfev), "njev": int(state.njev), "nlu": int(state.nlu)}
    return t_eval.copy(), keep["s_x"][:state.i_eval].copy(), counts


def drive(lib, system, problem: CProblem, state: CState, keep: dict, options) -> None:
    """Call the C loop until t_end, between calls counting the budget's steps and clock, projecting the steps
    still needed at the latest step size (as the Python path every CHECK_EVERY steps) and moving the progress bar;
    an error code raises its exception (:func:`failure`)."""
    budget, t_end = options.budget, problem.t_end
    with Progress(t_end, desc=options.desc, unit="t", enabled=options.progress) as bar:
        while True:
            if budget is not None and budget.limit is not None:
                problem.budget_left = max(0, budget.limit - budget.used)
            rc = lib.mgr_run(ctypes.byref(problem), ctypes.byref(state))
            if state.counted and budget is not None:
                budget.spend(state.counted, lambda: reached_at(state.t, t_end, int(state.steps)))
            if rc < 0:
                raise failure(rc, system, state, keep, t_end, options)
            if rc == SLICED and budget is not None:
                project_steps(budget, "Radau", int(state.steps), state.t, state.h_last, t_end)
            bar.to(state.t)
            if rc == DONE:
                return


def explanation(rc: int, system, state: CState, keep: dict, options) -> str:
    """``options.explain`` at the failing state, or at the last accepted one when that is not finite or the step
    size collapsed there (as the Python path explains), for the failures a state can explain; "" otherwise."""
    if options.explain is None or rc not in (E_RHS, E_JAC, E_SINGULAR, E_SMALL):
        return ""
    size = 2 * system.n + system.m
    if rc == E_SMALL:
        return options.explain(float(state.t), keep["x"][:size].copy())
    x = keep["err_x"][:size].copy()
    if np.all(np.isfinite(x)):
        return options.explain(float(state.err_t), x)
    return options.explain(float(state.t), keep["x"][:size].copy())


def failure(rc: int, system, state: CState, keep: dict, t_end: float, options) -> Exception:
    """The exception for the C loop's error code ``rc``, worded as the Python path's (scipy's Radau stepped by
    mechgen.runtime.core.integrate)."""
    t, model = float(state.err_t), system.metadata.model
    x = keep["err_x"][:2 * system.n + system.m]
    where = reached_at(t, t_end, int(state.steps))
    why = explanation(rc, system, state, keep, options)
    if rc == E_KERNEL:
        return KernelError(f"kernel {KERNELS[state.err_kind][0]} of {model} returned error code {state.err_rc} at "
                           f"{where}")
    if rc == E_RHS:
        if why:
            return KernelError(f"Radau at t = {t:.6g} of t_end = {t_end:.6g}: {why}")
        return KernelError(f"kernel residual/tangent of {model} gave NaN/Inf at t = {t}, x = {x[:6]} (Radau at "
                           f"{where})")
    tail = f"; {why}" if why else ""
    if rc == E_JAC:
        return ConvergenceError(f"Radau failed at {where}: the Jacobian (tangent, rates_tangent) is NaN/Inf at "
                                f"x = {x[:6]}{tail}")
    if rc == E_SINGULAR:
        what = "the mass matrix M = dr/da" if state.err_kind == 0 else "Radau's Newton matrix"
        return ConvergenceError(f"Radau failed at {where} (Singular matrix: {what}){tail}")
    if rc == E_SMALL:
        return ConvergenceError(f"Radau stopped at {where}: Required step size is less than spacing between "
                                f"numbers{tail}")
    if rc == E_BUDGET:
        return BudgetExceeded("Radau steps: stopped by the step budget", key="max_steps", reached=where)
    if rc == E_MEMORY:
        return MemoryError("the C Radau loop could not allocate its workspace")
    return RuntimeError(f"the C Radau loop refused its input (code {rc})")
