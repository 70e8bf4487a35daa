"""The Kernel IR: the only thing a backend sees.

A kernel has named input and output *ports* (flat float64 arrays whose length
is an :class:`Extent` in the runtime sizes, optionally batched over states)
and a list of *blocks*. A block is straight-line code, or a loop over a
repetition (bonds, sites) whose body is the same small set of expressions for
every index. Each block: gathers (port entries -> local symbols), CSE'd
assignments, writes (set or accumulate into an output entry, or into a sparse
output through a slot table that the runtime fills from the pattern).

A loop block with sparse writes also gets an *affine* input: where the slot of
entry j is ``base_j + stride*e`` over a run of loop indices (the interior of a
banded pattern) the runtime says so once, and the C interior addresses the CSR
data directly (:meth:`KernelIR.stored_ports` says which outputs it then stores
instead of accumulating).

Every C kernel has the signature
``int NAME(const double *const *in, double *const *out, const long *sizes, long nbatch)``.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import sympy as sp

FORMAT_VERSION = "mechgen-ir-1"


@dataclass(frozen=True)
class Extent:
    """A length ``const + sum(coef * sizes[name])`` known at call time."""

    const: int = 0
    terms: tuple[tuple[str, int], ...] = ()

    def evaluate(self, sizes: dict[str, int]) -> int:
        """The length for concrete runtime sizes."""
        return self.const + sum(coef * sizes[name] for name, coef in self.terms)

    def c_expr(self) -> str:
        """C text of the length (runtime sizes are local ``long`` variables)."""
        parts = [f"{coef}*{name}" if coef != 1 else name for name, coef in self.terms]
        if self.const or not parts:
            parts.append(str(self.const))
        return " + ".join(parts)

    def to_json(self) -> dict:
        """JSON form, for the runtime spec."""
        return {"const": self.const, "terms": [list(t) for t in self.terms]}


def fixed(n: int) -> Extent:
    """A constant length."""
    return Extent(n)


def sized(name: str, coef: int = 1, const: int = 0) -> Extent:
    """A length proportional to a runtime size."""
    return Extent(const, ((name, coef),))


@dataclass(frozen=True)
class Port:
    """A named flat float64 array of a kernel.

    ``shape`` is the logical shape of a dense output (row-major); ``sparse``
    marks an output stored as the data array of a CSR pattern of length ``nnz``.
    """

    name: str
    extent: Extent
    batched: bool = True
    integer: bool = False
    shape: tuple[int, ...] | None = None
    sparse: bool = False
    symmetric: bool = False
    doc: str = ""


@dataclass(frozen=True)
class Loop:
    """Repeat a block for e = 0 .. count-1; site arrays have length ``sites``.

    Gathers and writes at offset k touch site e + k; with ``boundary='zero'``
    sites outside [0, sites) read as 0 and are not written, with ``'periodic'``
    the index wraps.
    """

    count: Extent
    sites: Extent
    boundary: str = "zero"


@dataclass(frozen=True)
class Gather:
    """Local symbol = port[index] (index relative to the loop index in a loop block)."""

    symbol: sp.Symbol
    port: str
    index: int
    relative: bool = False


@dataclass(frozen=True)
class Write:
    """port[index] (op)= expr; ``entry`` = (row offset, col offset) for sparse outputs."""

    port: str
    index: int
    expr: sp.Expr
    accumulate: bool = False
    relative: bool = False
    entry: tuple[int, int] | None = None


@dataclass(frozen=True)
class Operation:
    """target = op(args): one operation of a program block (mechgen.codegen.lower_ad). ``op`` is one of
    :data:`mechgen.codegen.program_text.OPERATIONS` (add, sub, mul, div, neg, sq, sin, constpow ...), each
    argument the name of a temporary or gathered local (str) or a number (float)."""

    target: str
    op: str
    args: tuple


@dataclass(frozen=True)
class Block:
    """Straight-line code, or a loop body when ``loop`` is set."""

    gathers: tuple[Gather, ...]
    writes: tuple[Write, ...]
    assignments: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()
    loop: Loop | None = None
    #: a block lowered from a CasADi program (mechgen.codegen.lower_ad): (sha256 of its instructions, their
    #: operation count), from which the kernel's signature and op count are read instead of from every
    #: single-operation assignment (hundreds of thousands for a large model)
    program: tuple[str, int] | None = None
    #: a program block's operations, in order (its ``assignments`` are empty): printed by
    #: mechgen.codegen.program_text without a sympy object per operation
    operations: tuple[Operation, ...] = ()

    @property
    def entries(self) -> tuple[tuple[int, int], ...]:
        """Distinct sparse entries written by this block, in first-use order."""
        seen: dict = {}
        for w in self.writes:
            if w.entry is not None:
                seen.setdefault(w.entry, None)
        return tuple(seen)

    def offset_range(self) -> tuple[int, int]:
        """(lowest, highest) site offset a loop iteration reads or writes (0 included)."""
        offsets = [g.index for g in self.gathers if g.relative] + [w.index for w in self.writes if w.relative]
        return min(offsets, default=0), max(offsets, default=0)

    def written_ports(self) -> tuple[str, ...]:
        """Ports this block writes, in first-use order."""
        return tuple(dict.fromkeys(w.port for w in self.writes))

    def port_entries(self, port: str) -> tuple[int, ...]:
        """Columns (positions in :attr:`entries`) of the sparse entries ``port`` gets from this block."""
        cols = {entry: j for j, entry in enumerate(self.entries)}
        return tuple(dict.fromkeys(cols[w.entry] for w in self.writes if w.port == port and w.entry is not None))

    def carried_entries(self, port: str) -> tuple[tuple[int, int], ...]:
        """Pairs (j_in, j_out) of ``port``'s entries with entry j_out = entry j_in + (1, 1).

        Entry j_out of iteration e and entry j_in of iteration e + 1 are the same
        matrix entry, so the interior carries that value in a register. Entries
        in a chain of such pairs (a longer stencil) are not carried.
        """
        mine = self.port_entries(port)
        pos = {self.entries[j]: j for j in mine}
        pairs = [(j, pos[(r + 1, c + 1)]) for j in mine for r, c in [self.entries[j]] if (r + 1, c + 1) in pos]
        used = [j for pair in pairs for j in pair]
        return tuple(p for p in pairs if used.count(p[0]) == 1 and used.count(p[1]) == 1)


@dataclass(frozen=True)
class KernelIR:
    """A kernel: ports, runtime sizes and blocks."""

    name: str
    doc: str
    inputs: tuple[Port, ...]
    outputs: tuple[Port, ...]
    blocks: tuple[Block, ...]
    sizes: tuple[str, ...] = ()
    meta: dict = field(default_factory=dict, compare=False)

    def slot_ports(self) -> list[tuple[int, str]]:
        """(block index, slot port name) for blocks that write sparse entries."""
        return [(i, f"slots{i}") for i, b in enumerate(self.blocks) if b.entries]

    def affine_ports(self) -> list[tuple[int, str]]:
        """(block index, affine port name) for blocks that write sparse entries.

        The port holds ``[a, b, stride, base_0 .. base_{w-1}, (zlo, zhi) per stored port]``:
        for a <= e < b the slot of entry j is base_j + stride*e; each port of
        :meth:`stored_ports` is stored (not accumulated) there, exactly once per
        CSR position, on the positions zlo <= s < zhi (zlo = zhi = 0: positions
        not contiguous, zero all first). a = b when the runtime found no such run.
        """
        return [(i, f"slots{i}_affine") for i, b in enumerate(self.blocks) if b.entries]

    def first_writer(self, port: str) -> int | None:
        """Index of the first block that writes ``port`` (None if none does)."""
        return next((i for i, b in enumerate(self.blocks) if port in b.written_ports()), None)

    def stored_ports(self, i: int) -> tuple[str, ...]:
        """Ports that loop block ``i`` is first to write, each written only at sparse entries.

        In the block's affine interior these are stored, not accumulated, and the
        block zeroes the rest of them first.
        """
        b = self.blocks[i]
        if b.loop is None or not b.entries:
            return ()
        return tuple(p for p in b.written_ports() if self.first_writer(p) == i
                     and all(w.entry is not None and w.accumulate for w in b.writes if w.port == p))

    def op_count(self) -> int:
        """Arithmetic operations in the kernel text (sympy's count_ops)."""
        total = 0
        for b in self.blocks:
            if b.program is not None:
                total += b.program[1]
                continue
            total += sum(sp.count_ops(e) for _, e in b.assignments)
            total += sum(sp.count_ops(w.expr) for w in b.writes)
        return int(total)

    def canonical_text(self) -> str:
        """A text that identifies the kernel: ports, blocks and srepr of every expression."""
        lines = [FORMAT_VERSION, self.name, repr(self.sizes)]
        lines += [repr(p) for p in self.inputs + self.outputs]
        for b in self.blocks:
            lines.append(repr(b.loop))
            lines += [f"G {g.symbol.name} {g.port} {g.index} {g.relative}" for g in b.gathers]
            if b.program is not None:
                lines.append(f"P {b.program[0]} {b.program[1]}")
            else:
                lines += [f"A {s.name} {sp.srepr(e)}" for s, e in b.assignments]
            lines += [f"W {w.port} {w.index} {w.accumulate} {w.relative} {w.entry} {sp.srepr(w.expr)}"
                      for w in b.writes]
        return "\n".join(lines)

    def signature(self) -> str:
        """sha256 of :meth:`canonical_text`: the content key of the kernel."""
        return hashlib.sha256(self.canonical_text().encode()).hexdigest()
