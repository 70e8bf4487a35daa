"""The compiled DOP853 loop for a continuum: FieldSystem.rhs as sparse operators and one pointwise kernel call.

FieldSystem.rhs is precomputed once per parameter set as sparse operators around the pointwise residual
(mechgen.runtime.fields.operators: the jets J_b of each block of points, their weights w_b, the penalty P, the
banded Cholesky factor of the constant mass). In C
(``runtime/csrc/field_flow.c``, built once as ``libmgfield``) the rhs is then, for x = (q, v),

    dq/dt = v,   dv/dt = -M^-1 (sum_b J_b^T (w_b .* rho_b(J_b q, J_b v, 0, t, s_b, p_b)) + P q),

rho_b the model's C kernel called by address once per block over its points. That function is the event loop's
flow provider (``mgh_problem.flow`` in ``hybrid_loop.c``): the one DOP853 of mechgen.runtime.integration.events_c steps
it exactly as scipy's DOP853 steps FieldSystem.rhs (the same steps; the states agree to rounding, the sums taken
in another order). A mass matrix that depends on the state, Lagrange multipliers (a DAE), kernels without C
addresses and a mass that is not positive definite are refused (:func:`field_loop_problem` says why; simulate
then runs scipy's DOP853 in Python).
"""
from __future__ import annotations

import ctypes
import logging
from functools import lru_cache

import numpy as np

from mechgen.errors import BuildError, CompilerUnavailable
from mechgen.runtime import csrc
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.integration.events_c import LONG, integrate_hybrid_c
from mechgen.runtime.core.pattern import extent
from mechgen.runtime.fields.operators import Block, Operators, blocks_of, field_operators

sps = lazy_module("scipy.sparse")


log = logging.getLogger("mechgen")

SOURCE = csrc.path("field_flow.c")
STEM = "mgfield"
PORTS = 8
INPUTS = {"q": 0, "v": 1, "a": 2, "z": 3, "t": 4, "s": 5, "p": 6}
c_long, c_double, c_void_p = ctypes.c_long, ctypes.c_double, ctypes.c_void_p


class CBlock(ctypes.Structure):
    """mgf_block: a pointwise kernel over a batch of points, its jet operator J_b and row weights."""

    _fields_ = [("fn", c_void_p), ("nin", c_long), ("nout", c_long), ("pick", c_long), ("ports", c_long * PORTS),
                ("out_len", c_long * PORTS), ("npts", c_long), ("na", c_long), ("s", c_void_p), ("p", c_void_p),
                ("indptr", c_void_p), ("indices", c_void_p), ("data", c_void_p), ("w", c_void_p),
                ("t_indptr", c_void_p), ("t_indices", c_void_p), ("t_data", c_void_p)]


class CFlow(ctypes.Structure):
    """mgf_flow: the blocks, the penalty stiffness, the mass factor and the workspace."""

    _fields_ = [("n", c_long), ("nblocks", c_long), ("m", c_long), ("nrates", c_long), ("blocks", c_void_p),
                ("rates", c_void_p), ("p_indptr", c_void_p),
                ("p_indices", c_void_p), ("p_data", c_void_p), ("band", c_long), ("lrow", c_void_p), ("lcol", c_void_p),
                ("perm", c_void_p), ("jq", c_void_p), ("jv", c_void_p), ("ja", c_void_p), ("tt", c_void_p),
                ("out", c_void_p * PORTS), ("r", c_void_p), ("y", c_void_p), ("err_block", c_long),
                ("err_rc", c_long)]


@lru_cache(maxsize=1)
def _library():
    """(the loaded flow library, None) or (None, why it is unavailable); built once per process."""
    from mechgen.buildlock import load_shared_once as load_shared  # compiled once across processes

    try:
        lib = load_shared(csrc.source(SOURCE), stem=STEM, symbols=("mgf_rhs", "mgf_layout"))
    except (CompilerUnavailable, BuildError, OSError) as exc:
        log.info("C field flow unavailable (%s)", exc)
        return None, f"the C field flow cannot be built ({exc})"
    lib.mgf_layout.argtypes, lib.mgf_layout.restype = [c_long], c_long
    for i, struct in enumerate((CBlock, CFlow)):
        if lib.mgf_layout(i) != ctypes.sizeof(struct):
            return None, f"the C field flow's {struct.__name__} layout differs from its Python mirror"
    return lib, None


def kernel_problem(kernel, na: int, output: str = "r") -> str | None:
    """Why ``kernel`` cannot be called by field_flow.c for its ``output`` of ``na`` entries a point (None when it
    can)."""
    spec = kernel.spec
    if kernel.address is None:
        return f"kernel {kernel.name} has no C function address"
    if len(spec["inputs"]) > PORTS or len(spec["outputs"]) > PORTS or spec.get("sizes"):
        return f"kernel {kernel.name} has more than {PORTS} ports or size inputs"
    for port in spec["inputs"]:
        if port["name"] not in INPUTS or port.get("integer") or (port["batched"] == (port["name"] == "p")):
            return f"kernel {kernel.name} has inputs other than batched q, v, a, z, t, s and a parameter vector p"
    names = [p["name"] for p in spec["outputs"]]
    if output not in names or extent(spec["outputs"][names.index(output)]["extent"], {}) != na:
        return f"kernel {kernel.name} has no output {output} of {na} entries a point"
    return None


def band_rows(ab: np.ndarray) -> np.ndarray:
    """The rows of L within the band, out[j, i] = L[j, j - i] for i >= 1 (0 where j < i) and out[j, 0] =
    1 / L[j, j], from the lower band storage ab[i, j] = L[j + i, j] of a (band + 1) x n factor."""
    width, n = ab.shape
    out = np.zeros((n, width))
    for i in range(width):
        out[i:, i] = ab[i, :n - i]
    out[:, 0] = 1.0 / ab[0]
    return out


def band_columns(ab: np.ndarray) -> np.ndarray:
    """The columns of L within the band, out[j, i] = L[j + i, j] for i >= 1 and out[j, 0] = 1 / L[j, j]."""
    out = np.ascontiguousarray(ab.T)
    out[:, 0] = 1.0 / ab[0]
    return out


class FieldFlow:
    """The C structures of :class:`Operators` and a workspace: ``address`` is the mgf_flow the loop's flow
    provider reads; the arrays it points to are kept here for as long as this object lives."""

    def __init__(self, ops: Operators, rates: tuple = (), m: int = 0) -> None:
        self.keep: list = []
        self.blocks = (CBlock * max(1, len(ops.blocks)))()
        self.rates = (CBlock * max(1, len(rates)))()
        every = ops.blocks + tuple(rates)
        rows = max(1, max(b.J.shape[0] for b in every))
        points = max(1, max(b.s.size for b in every))
        out_len = [1] * PORTS
        for i, block in enumerate(ops.blocks):
            self.blocks[i] = self._block(block, out_len, "r")
        for i, block in enumerate(rates):
            self.rates[i] = self._block(block, out_len, "g")
        self.flow = CFlow(n=ops.n, nblocks=len(ops.blocks), blocks=ctypes.addressof(self.blocks), m=m,
                          nrates=len(rates), rates=ctypes.addressof(self.rates),
                          band=ops.chol.shape[0] - 1, lrow=self._address(band_rows(ops.chol)),
                          lcol=self._address(band_columns(ops.chol)),
                          perm=self._address(ops.perm.astype(LONG)))
        if ops.penalty is not None:
            P = ops.penalty
            self.flow.p_indptr, self.flow.p_indices = (self._address(P.indptr.astype(LONG)),
                                                      self._address(P.indices.astype(LONG)))
            self.flow.p_data = self._address(P.data)
        for name, size in (("jq", rows), ("jv", rows), ("ja", rows), ("tt", points), ("r", ops.n), ("y", ops.n)):
            setattr(self.flow, name, self._address(np.zeros(max(1, size))))
        for j in range(PORTS):
            self.flow.out[j] = self._address(np.zeros(points * out_len[j]))
        self.address = ctypes.addressof(self.flow)

    def _address(self, array: np.ndarray) -> int:
        array = np.ascontiguousarray(array)
        self.keep.append(array)
        return array.ctypes.data

    def _block(self, block: Block, out_len: list, output: str) -> CBlock:
        spec = block.kernel.spec
        out = CBlock(fn=block.kernel.address, nin=len(spec["inputs"]), nout=len(spec["outputs"]),
                     npts=block.s.size, na=block.J.shape[0] // max(1, block.s.size))
        names = [p["name"] for p in spec["outputs"]]
        out.pick = names.index(output)
        for i, port in enumerate(spec["inputs"]):
            out.ports[i] = INPUTS[port["name"]]
        for j, port in enumerate(spec["outputs"]):
            out.out_len[j] = extent(port["extent"], {})
            out_len[j] = max(out_len[j], out.out_len[j])
        out.s, out.p = self._address(block.s.astype(float)), self._address(block.params)
        out.indptr = self._address(block.J.indptr.astype(LONG))
        out.indices = self._address(block.J.indices.astype(LONG))
        out.data, out.w = self._address(block.J.data), self._address(block.w)
        S = (sps.diags(block.w) @ block.J).T.tocsr()  # the gather r += S rho
        S.sort_indices()
        out.t_indptr, out.t_indices = self._address(S.indptr.astype(LONG)), self._address(S.indices.astype(LONG))
        out.t_data = self._address(S.data)
        return out


class FieldView:
    """A continuum as the compiled event loop sees a system: one mode, no guards, no kernels of its own; its
    dx/dt comes from the flow provider ``flow`` = (mgf_rhs, the mgf_flow of a :class:`FieldFlow`)."""

    modes = ("smooth",)
    initial_mode = 0
    smooth = True
    is_lattice = False
    is_field = False
    backend = "c"

    def __init__(self, system, flow: FieldFlow, fn: int, extra: int = 0) -> None:
        self.system = system
        self.m = extra  # the integrals after (q, v): the energy balance's
        self.kernels: dict = {}
        self.patterns: dict = {}
        self.field_flow = flow  # (its arrays stay referenced while the loop runs)
        self.flow = (fn, flow.address)
        self.n = system.n
        self.params = np.zeros(0)

    @property
    def metadata(self):
        return self.system.metadata

    def guards(self, mode: int) -> tuple:
        return ()

    def mode(self, mode: int):
        return self.system


def field_loop_problem(system, rtol=1e-8, atol=1e-10, extra: int = 0) -> str | None:
    """Why the compiled loop cannot integrate the continuum ``system`` (None when it can): the C backend, a
    constant mass matrix that is symmetric positive definite, no Lagrange multipliers, C kernels of the
    pointwise residual (and of each end term and part; with ``extra`` integrals their energy_rates too, whose g
    has ``extra`` entries), scalar tolerances and a C compiler for both loops."""
    from mechgen.runtime.integration.events_c import c_loop_problem

    if getattr(system, "backend", None) != "c":
        return f"the system's kernels are {getattr(system, 'backend', 'unknown')} ones, not compiled C"
    if system.has_multipliers:
        return "the unknowns include Lagrange multipliers (a DAE)"
    if not system.field_meta.constant_mass:
        return "the mass matrix depends on the state"
    na = system.field_meta.njets
    wanted = [("residual", "r", na)] + ([("energy_rates", "g", extra)] if extra else [])
    for kernel, output, size in wanted:
        for name in [kernel] + [f"{kernel}_at_{at}" for at, _, _ in system.placed_points()]:
            if name not in system.kernels:
                return f"the system has no {name} kernel"
            why = kernel_problem(system.kernels[name], size, output)
            if why is not None:
                return why
    why = _library()[1]
    if why is not None:
        return why
    try:
        field_operators(system)
    except np.linalg.LinAlgError as exc:
        return f"the mass matrix cannot be factorised by Cholesky ({exc})"
    return c_loop_problem(FieldView(system, _EMPTY, 0, extra), "DOP853", rtol, atol)


class _Empty:
    """A stand-in flow for the loop's checks, which read no arrays."""

    address = 0


_EMPTY = _Empty()


def integrate_field_c(system, x0, t_end: float, options, *, extra: int = 0) -> tuple[np.ndarray, np.ndarray, dict]:
    """(t, x rows at the options' ``t_eval``, counts {steps, nfev}) of a continuum integrated by the compiled
    DOP853 loop (module doc; ``options``: mechgen.runtime.integration.run_options.RunOptions, ``method`` and ``loop``
    not read; ``extra`` > 0: the state (q, v) is followed by that many integrals of the energy_rates kernels' g,
    the energy balance's work and dissipated energy); failures raise the event loop's exceptions.
    CompilerUnavailable where :func:`field_loop_problem` gives a reason."""
    why = field_loop_problem(system, options.rtol, options.atol, extra)
    if why is not None:
        raise CompilerUnavailable(why)
    view = FieldView(system, flow_of(system, extra), _rhs_address(), extra)
    traj = integrate_hybrid_c(view, x0, t_end, mode=0, options=options)
    return traj.t, traj.x, {"steps": traj.steps, "nfev": traj.nfev}


def _rhs_address() -> int:
    lib, _ = _library()
    return ctypes.cast(lib.mgf_rhs, c_void_p).value


def flow_of(system, extra: int = 0) -> FieldFlow:
    """The C structures of the system's operators (and, with ``extra``, of its energy_rates blocks)."""
    rates = blocks_of(system, "energy_rates") if extra else ()
    return FieldFlow(field_operators(system), rates, extra)


def compiled_rhs(system, extra: int = 0):
    """dx/dt = ``f(t, x)`` of ``system`` computed by field_flow.c (what the loop steps; FieldSystem.rhs to
    rounding, followed by ``extra`` integrals' rates), one ctypes call each: for checks and tests.
    CompilerUnavailable where the loop cannot run."""
    why = field_loop_problem(system, extra=extra)
    if why is not None:
        raise CompilerUnavailable(why)
    lib, _ = _library()
    lib.mgf_rhs.argtypes, lib.mgf_rhs.restype = [c_void_p, c_double, c_void_p, c_void_p], ctypes.c_int
    flow = flow_of(system, extra)

    def f(t: float, x) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=float)
        out = np.zeros(2 * system.n + extra)
        rc = lib.mgf_rhs(flow.address, float(t), x.ctypes.data, out.ctypes.data)
        if rc:
            raise RuntimeError(f"kernel of block {flow.flow.err_block} returned error code {rc}")
        return out

    return f
