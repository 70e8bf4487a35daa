"""The compiled event loop: :func:`integrate_hybrid_c`, the rules of mechgen.runtime.integration.events in C.

A hybrid lumped system on the C backend is integrated by one C function (``mgh_run`` in
mechgen/runtime/csrc/hybrid_loop.c, built once into the compile cache as ``libmghybrid``)
that calls the model's own kernels through their addresses: in mode i

    dq/dt = v,   dv/dt = a = -M^-1 r(q, v, 0, z, t)   (M = dr/da, ``tangent__i``; LU with partial pivoting),
    dz/dt = rates__i(q, v, z, t),

stepped by DOP853 exactly as scipy.integrate.DOP853 steps it (same coefficients, error norm, step
control and initial step, 7th-order dense output), with the guards ``guards__i`` (g, g_t), the
resets ``reset__j`` and every event rule of mechgen.runtime.integration.events (sign tracking, splitting
of suspicious intervals, Brent location on the dense output, re-integration from the step's
start, one Newton correction, start-of-mode rule, ties, max_events, Zeno). Its results agree
with the Python loop's ``method="DOP853"`` to rounding; it is 10-100 times faster, since no
Python runs between the steps.

The C function returns at clean points (the start of a mode or of a step) to let Python grow the
sample and event buffers, count the step budget and check its clock (every :data:`SLICE` steps),
move the progress bar, and call a ``stop_after`` function after each event; errors come back as
codes that become the same exceptions, with the same messages, as the Python loop's.
"""
from __future__ import annotations

import ctypes
import logging
import math
import threading
from functools import lru_cache

import numpy as np

from mechgen.errors import BuildError, CompilerUnavailable, ConvergenceError, KernelError
from mechgen.runtime import csrc
from mechgen.runtime.core.budget import BudgetExceeded, Progress
from mechgen.runtime.integration.event_records import (ZENO_HINT, Event, HybridTrajectory, ZenoApproach,
                                                        diagnosis, unnoticed)
from mechgen.runtime.integration.run_options import RunOptions
from mechgen.runtime.core.pattern import extent

log = logging.getLogger("mechgen")

SOURCE = csrc.path("hybrid_loop.c")
STEM = "mghybrid"
#: the C loop hands back to Python (budget clock, progress bar) after this many steps
SLICE = 20_000
#: the rows the sample buffer (without t_eval) and the event buffer start with (doubled when full)
FIRST_ROWS = (256, 16)
PORTS = 8
INPUTS = {"q": 0, "v": 1, "a": 2, "z": 3, "t": 4, "p": 5}
#: the outputs each kernel kind gives the loop
PICKS = {"residual": ("r", "r"), "tangent": ("r_a", "r_a"), "rates": ("g", "g"), "guards": ("g", "g_t"),
         "reset": ("x", "x"), "flow_r": ("r", "r"), "flow_M": ("M", "M")}
KINDS = ("residual", "tangent", "rates", "guards", "reset")

DONE, TERMINATED, PAUSED, FULL_SAMPLES, FULL_EVENTS, SLICED = 0, 1, 2, 3, 4, 5
(E_KERNEL, E_RHS, E_STATE, E_RESET, E_SINGULAR, E_SMALL, E_EVENTS, E_ZENO, E_BUDGET, E_GUARD, E_MEMORY,
 E_INPUT, E_LEFT) = range(-1, -14, -1)

c_long, c_double, c_void_p = ctypes.c_long, ctypes.c_double, ctypes.c_void_p
#: numpy's dtype of a C long (the integer tables and buffers)
LONG = np.dtype(f"i{ctypes.sizeof(c_long)}")


class CKernel(ctypes.Structure):
    """mgh_kernel: a kernel's address, what its inputs are, its output lengths and the outputs used."""

    _fields_ = [("fn", c_void_p), ("nin", c_long), ("nout", c_long), ("ports", c_long * PORTS),
                ("out_len", c_long * PORTS), ("pick", c_long * 2)]


class CMode(ctypes.Structure):
    """mgh_mode: a mode's kernels and the table of its guards."""

    _fields_ = [("residual", CKernel), ("tangent", CKernel), ("rates", CKernel), ("guards", CKernel),
                ("nguards", c_long), ("direction", c_void_p), ("terminal", c_void_p), ("target", c_void_p),
                ("reset", c_void_p)]


class CProblem(ctypes.Structure):
    """mgh_problem: sizes, modes, resets, parameters, tolerances, bounds and the output buffers."""

    _fields_ = [("n", c_long), ("m", c_long), ("nmodes", c_long), ("nresets", c_long), ("max_guards", c_long),
                ("modes", c_void_p), ("resets", c_void_p), ("p", c_void_p),
                ("rtol", c_double), ("atol", c_double), ("t_end", c_double),
                ("max_events", c_long), ("zeno_events", c_long), ("zeno_span", c_double),
                ("stop_mode", c_long), ("pause", c_long), ("budget_left", c_long), ("slice", c_long),
                ("n_eval", c_long), ("t_eval", c_void_p), ("sample_cap", c_long), ("event_cap", c_long),
                ("s_t", c_void_p), ("s_x", c_void_p), ("s_mode", c_void_p),
                ("e_t", c_void_p), ("e_before", c_void_p), ("e_after", c_void_p),
                ("e_source", c_void_p), ("e_target", c_void_p), ("e_guard", c_void_p), ("carried", c_long),
                ("flow", c_void_p), ("flow_data", c_void_p)]


class CState(ctypes.Structure):
    """mgh_state: where the run is (a point it resumes from), its counters and the last error's place."""

    _fields_ = [("phase", c_long), ("mode", c_long), ("t", c_double), ("x", c_void_p), ("f", c_void_p),
                ("h_abs", c_double), ("sign", c_void_p), ("g_old", c_void_p), ("d_old", c_void_p),
                ("recent", c_void_p), ("n_recent", c_long), ("i_eval", c_long), ("n_samples", c_long),
                ("n_events", c_long), ("steps", c_long), ("nfev", c_long), ("nguard", c_long),
                ("counted", c_long), ("err_kind", c_long), ("err_mode", c_long), ("err_rc", c_long),
                ("err_guard", c_long), ("err_t", c_double), ("err_span", c_double), ("err_x", c_void_p),
                ("nrate", c_long), ("t_start", c_double)]


LAYOUT = (CKernel, CMode, CProblem, CState)


#: states (2n + m) up to which a run uses a loop library built for its own sizes (the compiler unrolls the loops
#: over the state: ~15-20 % less time per step on small models); larger states use the generic one
SPECIALISE_MAX_STATES = 16


@lru_cache(maxsize=None)
def _library(n: int | None = None, m: int | None = None):
    """(the loaded loop library, None) or (None, why it is unavailable); built once per machine (the compile
    cache) and loaded once per process. With sizes (n, m): the loop built for exactly those (MGH_FIXED_N/M)."""
    from mechgen.buildlock import load_shared_once as load_shared  # compiled once across processes

    source, stem = csrc.source(SOURCE), STEM
    if n is not None:
        source = f"#define MGH_FIXED_N {int(n)}\n#define MGH_FIXED_M {int(m)}\n" + source
        stem = f"{STEM}_{int(n)}_{int(m)}"
    try:
        lib = load_shared(source, stem=stem, ldflags=("-lm",), symbols=("mgh_run", "mgh_layout"))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("C event loop unavailable (%s)", exc)
        return None, f"the C event loop cannot be built ({exc})"
    lib.mgh_layout.argtypes, lib.mgh_layout.restype = [c_long], c_long
    for i, struct in enumerate(LAYOUT):
        if lib.mgh_layout(i) != ctypes.sizeof(struct):
            return None, f"the C event loop's {struct.__name__} layout differs from its Python mirror"
    lib.mgh_run.argtypes = [ctypes.POINTER(CProblem), ctypes.POINTER(CState)]
    lib.mgh_run.restype = ctypes.c_int
    return lib, None


def forget_library() -> None:
    """Forget the loaded (or refused) loop libraries: the next run builds or finds them again (tests change CC)."""
    _library.cache_clear()


def loop_library(n: int | None = None, m: int | None = None):
    """The loaded C loop library (CompilerUnavailable or BuildError when it cannot be had); for a state of sizes
    (n, m) with 2n + m <= SPECIALISE_MAX_STATES the one built for them (the generic one if that build fails)."""
    if n is not None and 2 * n + m <= SPECIALISE_MAX_STATES:
        lib, _ = _library(int(n), int(m))
        if lib is not None:
            return lib
    lib, why = _library()
    if lib is None:
        raise CompilerUnavailable(why)
    return lib


class _Tables:
    """The C tables of a hybrid system's kernels and guards (independent of its parameter values)."""

    def __init__(self, system) -> None:
        self.keep = []
        self.names: list[tuple[str, ...]] = []  # the guards' names per mode
        n_modes = len(system.modes)
        self.modes = (CMode * n_modes)()
        self.max_guards = 0
        for i in range(n_modes):
            mode = self.modes[i]
            for kind in ("residual", "tangent", "rates", "guards"):
                name = f"{kind}__{i}"
                if name in system.kernels:
                    setattr(mode, kind, self.kernel(system.kernels[name], kind))
            if f"flow__{i}" in system.kernels:  # r and M from one call (the loop calls it once for both)
                mode.residual = self.kernel(system.kernels[f"flow__{i}"], "flow_r")
                mode.tangent = self.kernel(system.kernels[f"flow__{i}"], "flow_M")
            guards = system.guards(i)
            self.names.append(tuple(g.name for g in guards))
            mode.nguards = len(guards)
            self.max_guards = max(self.max_guards, len(guards))
            for field, values in (("direction", [g.direction for g in guards]),
                                  ("terminal", [int(g.terminal) for g in guards]),
                                  ("target", [-1 if g.to is None else g.to for g in guards]),
                                  ("reset", [-1 if g.reset is None else g.reset for g in guards])):
                arr = np.array(values + [0], dtype=LONG)
                self.keep.append(arr)
                setattr(mode, field, arr.ctypes.data)
        resets = sorted(int(k.rpartition("__")[2]) for k in system.kernels if k.startswith("reset__"))
        self.n_resets = len(resets)
        self.resets = (CKernel * max(1, self.n_resets))()
        for j in range(self.n_resets):
            self.resets[j] = self.kernel(system.kernels[f"reset__{j}"], "reset")

    @staticmethod
    def kernel(kernel, kind: str) -> CKernel:
        spec = kernel.spec
        out = CKernel()
        out.fn = kernel.address
        out.nin, out.nout = len(spec["inputs"]), len(spec["outputs"])
        for i, port in enumerate(spec["inputs"]):
            out.ports[i] = INPUTS[port["name"]]
        names = [p["name"] for p in spec["outputs"]]
        for j, port in enumerate(spec["outputs"]):
            out.out_len[j] = extent(port["extent"], {})
        out.pick[0], out.pick[1] = (names.index(p) for p in PICKS[kind])
        return out


def kernel_call_problem(name: str, kernel, outputs) -> str | None:
    """Why a compiled loop cannot call ``kernel`` (named ``name``) by address for ``outputs`` (None when it can):
    a C function address, at most PORTS inputs and outputs, inputs among q, v, a, z, t, p (the event loop and
    radau_c read lumped kernels so; fields.flow_c's pointwise kernels also take s, and it checks them itself)."""
    if kernel.address is None:
        return f"kernel {name} has no C function address"
    spec = kernel.spec
    if len(spec["inputs"]) > PORTS or len(spec["outputs"]) > PORTS:
        return f"kernel {name} has more than {PORTS} ports"
    if any(p["name"] not in INPUTS or p.get("integer") for p in spec["inputs"]):
        return f"kernel {name} has inputs other than q, v, a, z, t, p"
    names = {p["name"] for p in spec["outputs"]}
    if any(p not in names for p in outputs):
        return f"kernel {name} lacks the outputs {', '.join(dict.fromkeys(outputs))}"
    return None


def _supported(system) -> str | None:
    """Why the kernels of ``system`` cannot be called from the C loop (None when they can)."""
    for name, kernel in system.kernels.items():
        base = name.rpartition("__")[0]
        if base not in KINDS and base != "flow":
            continue
        why = kernel_call_problem(name, kernel, PICKS["flow_r"] + PICKS["flow_M"] if base == "flow" else PICKS[base])
        if why is not None:
            return why
    provided = getattr(system, "flow", None) is not None  # a flow provider gives all of dx/dt
    for i in range(len(system.modes)):
        lumped = () if provided else (("residual", "tangent") if system.n else ()) + (("rates",) if system.m else ())
        for kind in lumped:
            if f"{kind}__{i}" not in system.kernels:
                return f"mode {system.modes[i]} has no {kind} kernel"
        if system.guards(i) and f"guards__{i}" not in system.kernels:
            return f"mode {system.modes[i]} has guards but no guards kernel"
    return None


def c_loop_problem(system, method: str = "DOP853", rtol=1e-8, atol=1e-10) -> str | None:
    """Why :func:`integrate_hybrid_c` cannot run ``system`` with ``method`` and these tolerances (None when it
    can): the loop is DOP853 with scalar tolerances on a lumped hybrid system of the C backend, and needs a
    C compiler (for its own library)."""
    if method != "DOP853":
        return f"the C event loop integrates with DOP853 only (method {method!r})"
    if np.ndim(rtol) or np.ndim(atol):
        return "the C event loop takes scalar tolerances rtol and atol only"
    if not hasattr(system, "modes"):
        return "the system has no modes"
    if getattr(system, "backend", None) != "c":
        return f"the system's kernels are {getattr(system, 'backend', 'unknown')} ones, not compiled C"
    if system.is_lattice or system.is_field:
        return "the C event loop integrates lumped systems only"
    key = ("c_loop", "supported")
    if key not in system.patterns:
        system.patterns[key] = _supported(system)
    if system.patterns[key] is not None:
        return system.patterns[key]
    return _library()[1]


def _tables(system) -> _Tables:
    key = ("c_loop", "tables")
    if key not in system.patterns:
        system.patterns[key] = _Tables(system)
    return system.patterns[key]


def _arena(dtype, shapes: dict) -> tuple[dict, dict]:
    """Arrays of the given shapes (name -> tuple) carved from one zeroed block, and their addresses (one
    address lookup for the block: the costly part of a short run's setup)."""
    dtype = np.dtype(dtype)
    counts = [math.prod(shape) for shape in shapes.values()]
    block = np.zeros(max(1, sum(counts)), dtype=dtype)
    base, size = block.ctypes.data, dtype.itemsize
    arrays, addresses, at = {}, {}, 0
    for (name, shape), count in zip(shapes.items(), counts):
        arrays[name] = block[at: at + count].reshape(shape)
        addresses[name] = base + at * size
        at += count
    return arrays, addresses


class _Buffers:
    """The state, sample and event arrays the C loop reads and writes (``arrays``, by name), set up with two
    allocations; the sample or event buffers are grown (doubled, in place of the old ones) when it asks."""

    def __init__(self, problem: CProblem, state: CState, nx: int, ng: int, ring: int, samples: int,
                 events: int) -> None:
        self.problem, self.nx = problem, nx
        reals = {"x": (nx,), "f": (nx,), "sign": (ng,), "g_old": (ng,), "d_old": (ng,), "recent": (ring,),
                 "err_x": (nx,), **self._reals("s", samples), **self._reals("e", events)}
        longs = {**self._longs("s", samples), **self._longs("e", events)}
        self.arrays, addresses = _arena(float, reals)
        more, at = _arena(LONG, longs)
        self.arrays.update(more)
        addresses.update(at)
        for name, address in addresses.items():
            setattr(state if name in self.STATE else problem, name, address)
        problem.sample_cap, problem.event_cap = samples, events

    STATE = ("x", "f", "sign", "g_old", "d_old", "recent", "err_x")

    def _reals(self, group: str, rows: int) -> dict:
        if group == "s":
            return {"s_t": (rows,), "s_x": (rows, self.nx)}
        return {"e_t": (rows,), "e_before": (rows, self.nx), "e_after": (rows, self.nx)}

    @staticmethod
    def _longs(group: str, rows: int) -> dict:
        return {"s_mode": (rows,)} if group == "s" else {"e_source": (rows,), "e_target": (rows,), "e_guard": (rows,)}

    def grow(self, group: str) -> None:
        """Double the sample (``group`` "s") or event ("e") buffers, keeping what they hold."""
        cap = "sample_cap" if group == "s" else "event_cap"
        keep = getattr(self.problem, cap)
        for dtype, shapes in ((float, self._reals(group, 2 * keep)), (LONG, self._longs(group, 2 * keep))):
            arrays, addresses = _arena(dtype, shapes)
            for name, arr in arrays.items():
                arr[:keep] = self.arrays[name][:keep]
                self.arrays[name] = arr
                setattr(self.problem, name, addresses[name])
        setattr(self.problem, cap, 2 * keep)


def _problem(system, tables: _Tables, params: np.ndarray, options: RunOptions, t_end: float) -> CProblem:
    """The loop's problem (read-only to the loop) for ``system`` with ``params`` kept alive by the caller."""
    rules = options.rules
    return CProblem(n=system.n, m=system.m, nmodes=len(system.modes), nresets=tables.n_resets,
                    max_guards=tables.max_guards, modes=ctypes.addressof(tables.modes),
                    resets=ctypes.addressof(tables.resets), p=params.ctypes.data if params.size else None,
                    rtol=float(options.rtol), atol=float(options.atol), t_end=float(t_end),
                    max_events=int(rules.max_events), zeno_events=int(rules.zeno_events),
                    zeno_span=1e-9 * float(t_end), stop_mode=-1, pause=0, budget_left=-1, slice=SLICE,
                    carried=int(getattr(system, "carried", 0)))


class RepeatedRuns:
    """Many short runs of one system without guards (a smooth model's loop view) at fixed tolerances, for the
    shooting of periodic orbits (thousands of one-period runs along a branch): the loop's problem and buffers are
    set up once per sample count and thread, and each run resets what the loop reads (the start, t_end, t_eval,
    the step budget) and starts from a fresh state, so runs do not depend on one another. The loop only reads the
    problem and writes the state and the buffers. :meth:`__call__` returns the states at ``times``, or None where
    the run did not end cleanly within one slice of steps (a budget, a kernel error, buffers to grow): the caller
    then runs :func:`integrate_hybrid_c`, which says exactly what happened."""

    def __init__(self, system, rtol: float, atol: float, max_steps: int) -> None:
        if getattr(system, "guards", None) is None or any(system.guards(k) for k in range(len(system.modes))):
            raise ValueError("RepeatedRuns serves systems without guards")
        self.system, self.max_steps = system, int(max_steps)
        self.options = RunOptions(method="DOP853", rtol=float(rtol), atol=float(atol), loop="c")
        self.local = threading.local()

    def _prepared(self, samples: int) -> tuple:
        table = self.local.__dict__.setdefault("prepared", {})
        if samples not in table:
            system = self.system
            params = np.ascontiguousarray(system.params, dtype=float)
            problem = _problem(system, _tables(system), params, self.options, 1.0)
            scratch = CState(phase=-1, mode=0, t=0.0)
            buffers = _Buffers(problem, scratch, 2 * system.n + system.m, max(1, _tables(system).max_guards),
                               2, samples, FIRST_ROWS[1])
            addresses = {name: getattr(scratch, name) for name in _Buffers.STATE}
            table[samples] = (problem, buffers.arrays, addresses, params)
        return table[samples]

    def __call__(self, x0: np.ndarray, times: np.ndarray) -> np.ndarray | None:
        times = np.ascontiguousarray(times, dtype=float).reshape(-1)
        problem, arrays, addresses, _ = self._prepared(times.size)
        t_end = float(times[-1])
        problem.t_end, problem.zeno_span, problem.budget_left = t_end, 1e-9 * t_end, self.max_steps
        problem.n_eval, problem.t_eval = times.size, times.ctypes.data
        state = CState(phase=-1, mode=0, t=0.0, **addresses)
        arrays["x"][...] = np.asarray(x0, float).reshape(-1)
        rc = loop_library(self.system.n, self.system.m).mgh_run(ctypes.byref(problem), ctypes.byref(state))
        if rc != DONE or state.n_samples != times.size:
            return None
        return arrays["s_x"][:times.size].copy()


def integrate_hybrid_c(system, x0, t_end: float, *, mode: int | None = None, options: RunOptions | None = None,
                       **changes) -> HybridTrajectory:
    """:func:`mechgen.runtime.integration.events.integrate_hybrid` with ``method="DOP853"``, run by the C loop (module
    doc); the same options (RunOptions; ``method`` and ``loop`` are not read) and the same HybridTrajectory
    (``extra["loop"] = "c"``; ``nfev`` counts every evaluation of dx/dt, ``guard_evaluations`` every one of the
    guards). CompilerUnavailable when the loop cannot run ``system`` (:func:`c_loop_problem` says why)."""
    options = RunOptions.of(options, **changes)
    why = c_loop_problem(system, "DOP853")
    if why is not None:
        raise CompilerUnavailable(why)
    lib = loop_library(system.n, system.m)
    tables = _tables(system)
    t_end = float(t_end)
    nx = 2 * system.n + system.m
    x0 = np.array(x0, dtype=float).reshape(-1)
    if x0.size != nx:
        raise ValueError(f"x0 has {x0.size} entries for a state (q, v, z) of {nx}")
    start = system.initial_mode if mode is None else int(mode)
    if not 0 <= start < len(system.modes):
        raise ValueError(f"mode {start} is not a mode index of {len(system.modes)} modes")
    loop = _CLoop(system, tables, t_end, start, options)
    loop.arrays["x"][...] = x0
    with Progress(t_end, desc=options.desc, unit="t", enabled=options.progress) as bar:
        terminated = loop.drive(lib, bar)
    loop.new_events()
    return loop.trajectory(terminated)


class _CLoop:
    """One run of the C loop: the problem and state that ``mgh_run`` reads and writes, the arrays they point into
    (``params``, ``t_eval`` and the buffers: kept referenced here while the loop runs) and the events read back."""

    def __init__(self, system, tables: _Tables, t_end: float, start: int, options: RunOptions) -> None:
        self.system, self.tables, self.t_end, self.options = system, tables, t_end, options
        rules = options.rules
        self.t_eval = None if options.t_eval is None else np.ascontiguousarray(options.t_eval, dtype=float).reshape(-1)
        self.zeno_span = rules.zeno_span if rules.zeno_span is not None else 1e-9 * t_end
        self.params = np.ascontiguousarray(system.params, dtype=float)
        self.problem = problem = _problem(system, tables, self.params, options, t_end)
        problem.zeno_span, problem.pause = float(self.zeno_span), int(options.stop_after is not None)
        flow = getattr(system, "flow", None)  # (fn, data) addresses of a provider of dx/dt (a continuum)
        if flow is not None:
            problem.flow, problem.flow_data = flow
        t_eval = self.t_eval
        if t_eval is not None:
            problem.n_eval, problem.t_eval = (len(t_eval), t_eval.ctypes.data) if len(t_eval) else (-1, None)
        self.state = CState(phase=-1, mode=start, t=0.0)
        self.buffers = _Buffers(problem, self.state, 2 * system.n + system.m, max(1, tables.max_guards),
                                max(2, rules.zeno_events + 1), len(t_eval) if t_eval is not None else FIRST_ROWS[0],
                                FIRST_ROWS[1])
        self.arrays = self.buffers.arrays
        self.events: list[Event] = []

    def where(self, tk: float, seg: int) -> str:
        mode = "" if getattr(self.system, "smooth", False) else f" in mode {self.system.modes[seg]}"
        return f"t = {tk:.9g} of t_end = {self.t_end:.6g}{mode}"

    def new_events(self) -> None:
        """The events the loop has logged since the last call, appended to ``events``."""
        arrays = self.arrays
        for e in range(len(self.events), self.state.n_events):
            target = int(arrays["e_target"][e])
            source = int(arrays["e_source"][e])
            self.events.append(Event(float(arrays["e_t"][e]), source, None if target < 0 else target,
                                     self.tables.names[source][int(arrays["e_guard"][e])],
                                     arrays["e_before"][e].copy(), arrays["e_after"][e].copy()))

    def run(self, lib) -> int:
        """One call of mgh_run (within the step budget left), its steps spent; raises its error (rc < 0)."""
        budget, state = self.options.budget, self.state
        if budget is not None and budget.limit is not None:
            self.problem.budget_left = max(0, budget.limit - budget.used)
        rc = lib.mgh_run(ctypes.byref(self.problem), ctypes.byref(state))
        if state.counted and budget is not None:
            budget.spend(state.counted, lambda: self.where(state.t, state.mode))
        if rc < 0:
            self.new_events()
            error = _error(rc, self)
            if isinstance(error, ZenoApproach):  # the run so far, up to the event that made it Zeno
                raise error.with_trajectory(_zeno_trajectory(self.arrays, state, self.events))
            raise error
        return rc

    def drive(self, lib, bar) -> bool:
        """Call the loop until it is done (growing the buffers it fills, asking ``stop_after`` where it pauses);
        whether the run was terminated (a terminal event or stop_after)."""
        while True:
            rc = self.run(lib)
            bar.to(self.state.t)
            if rc == FULL_SAMPLES:
                self.buffers.grow("s")
            elif rc == FULL_EVENTS:
                self.buffers.grow("e")
            elif rc == PAUSED:
                self.new_events()
                if self.options.stop_after(self.events[-1]):
                    return True
            elif rc == TERMINATED:
                return True
            elif rc == DONE:
                return False

    def trajectory(self, terminated: bool) -> HybridTrajectory:
        arrays, state, count = self.arrays, self.state, self.state.n_samples
        return HybridTrajectory(arrays["s_t"][:count].copy(), arrays["s_x"][:count].copy(),
                                arrays["s_mode"][:count].astype(int), tuple(self.events), int(state.mode),
                                float(state.t), arrays["x"].copy(), terminated, int(state.steps), int(state.nfev), 0,
                                int(state.nguard), {"loop": "c", "rate_evaluations": int(state.nrate)})


def _zeno_trajectory(arrays: dict, state: CState, events: list) -> HybridTrajectory:
    """The C loop's run up to the event that tipped its Zeno bound (ZenoApproach's ``trajectory``)."""
    count, last = state.n_samples, events[-1]
    return HybridTrajectory(arrays["s_t"][:count].copy(), arrays["s_x"][:count].copy(),
                            arrays["s_mode"][:count].astype(int), tuple(events),
                            last.source if last.target is None else last.target, float(last.t),
                            last.x_after.copy(), True, int(state.steps), int(state.nfev), 0, int(state.nguard),
                            {"loop": "c", "rate_evaluations": int(state.nrate)})


def _error(rc: int, loop: _CLoop) -> Exception:
    """The exception the Python loop raises for the C loop's error code ``rc``."""
    if rc in (E_KERNEL, E_RHS, E_STATE, E_RESET, E_GUARD):
        return _kernel_error(rc, loop)
    state, where, rules = loop.state, loop.where, loop.options.rules
    system, t, seg = loop.system, float(state.err_t), int(state.err_mode)
    if rc in (E_SINGULAR, E_SMALL):
        if rc == E_SMALL:
            return ConvergenceError(f"DOP853 stopped at {where(t, seg)}: Required step size is less than "
                                    "spacing between numbers")
        err_x, explain = loop.arrays["err_x"], loop.options.explain
        why = diagnosis(system, seg, t, err_x.copy()) or (explain(t, err_x.copy()) if explain is not None else "")
        return ConvergenceError(f"DOP853 failed near {where(t, seg)} (Singular matrix)" + (f"; {why}" if why else ""))
    if rc == E_EVENTS:
        return BudgetExceeded(f"events: more than max_events = {rules.max_events:,} events", key="max_events",
                              reached=where(t, seg))
    if rc == E_ZENO:
        count = max(2, rules.zeno_events + 1)
        return ZenoApproach(f"events: {count} events within {state.err_span:.3g} (more than zeno_events = "
                            f"{rules.zeno_events} within zeno_span = {loop.zeno_span:.3g}): a Zeno or chattering "
                            f"approach (guard {system.guards(seg)[state.err_guard].name} of mode {system.modes[seg]}); "
                            f"{ZENO_HINT}", key="zeno_events", reached=where(t, seg))
    if rc == E_LEFT:
        guard = system.guards(seg)[state.err_guard]
        return unnoticed(guard.name, guard.direction, system.modes[seg], float(state.err_span), t, where(t, seg))
    if rc == E_BUDGET:
        return BudgetExceeded("DOP853 steps: stopped by the step budget", key="max_steps", reached=where(t, seg))
    if rc == E_MEMORY:
        return MemoryError("the C event loop could not allocate its workspace")
    return RuntimeError(f"the C event loop refused its input (code {rc})")


def _kernel_error(rc: int, loop: _CLoop) -> KernelError:
    """The KernelError of a kernel's error code or a NaN/Inf (in dx/dt, the state, a reset or a guard)."""
    state, where, system, err_x = loop.state, loop.where, loop.system, loop.arrays["err_x"]
    t, seg = float(state.err_t), int(state.err_mode)
    model = system.metadata.model
    if rc == E_KERNEL:
        return KernelError(f"kernel {KINDS[state.err_kind]}__{state.err_guard} returned error code {state.err_rc}")
    if rc == E_RHS:
        why = diagnosis(system, seg, t, err_x.copy())
        mode = "" if getattr(system, "smooth", False) else f" in mode {system.modes[seg]}"
        return KernelError(f"kernel residual/tangent of {model} gave NaN/Inf at t = {t}, x = {err_x[:6]}{mode}"
                           + (f"; {why}" if why else ""))
    if rc == E_STATE:
        return KernelError(f"DOP853: state became NaN/Inf by {where(t, seg)}")
    if rc == E_RESET:
        return KernelError(f"reset of guard {system.guards(seg)[state.err_guard].name} gave NaN/Inf at "
                           f"{where(t, seg)}")
    return KernelError(f"guard {system.guards(seg)[state.err_guard].name} of {model} gave NaN/Inf at "
                       f"{where(t, seg)}, x = {err_x[:6]}")
