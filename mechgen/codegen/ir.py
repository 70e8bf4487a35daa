"""The Kernel IR: the only thing a backend sees.

A kernel has named input and output *ports* (flat float64 arrays whose length
is an :class:`Extent` in the runtime sizes, optionally batched over states)
and a list of *blocks*. A block is straight-line code, or a loop over a
repetition (bonds, sites) whose body is the same small set of expressions for
every index. Each block: gathers (port entries -> local symbols), CSE'd
assignments, writes (set or accumulate into an output entry, or into a sparse
output through a slot table that the runtime fills from the pattern).

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
class Block:
    """Straight-line code, or a loop body when ``loop`` is set."""

    gathers: tuple[Gather, ...]
    writes: tuple[Write, ...]
    assignments: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()
    loop: Loop | None = None

    @property
    def entries(self) -> tuple[tuple[int, int], ...]:
        """Distinct sparse entries written by this block, in first-use order."""
        seen: dict = {}
        for w in self.writes:
            if w.entry is not None:
                seen.setdefault(w.entry, None)
        return tuple(seen)


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

    def op_count(self) -> int:
        """Arithmetic operations in the kernel text (sympy's count_ops)."""
        total = 0
        for b in self.blocks:
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
            lines += [f"A {s.name} {sp.srepr(e)}" for s, e in b.assignments]
            lines += [f"W {w.port} {w.index} {w.accumulate} {w.relative} {w.entry} {sp.srepr(w.expr)}"
                      for w in b.writes]
        return "\n".join(lines)

    def signature(self) -> str:
        """sha256 of :meth:`canonical_text`: the content key of the kernel."""
        return hashlib.sha256(self.canonical_text().encode()).hexdigest()
