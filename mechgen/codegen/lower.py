"""lower: derived equations -> Kernel IR (renumbered symbols, one CSE pass per block).

Input: :class:`~mechgen.symbolic.derive.LumpedEquations` or
:class:`~mechgen.symbolic.lattice.LatticeEquations` and a kernel name.
Output: a :class:`~mechgen.codegen.ir.KernelIR` whose expressions use only
gathered locals ``g0, g1, ...`` and temporaries ``t0, t1, ...``, so user names
never become program identifiers and the signature depends on structure only.
With CSE on, writes equal up to sign share one temporary and polynomials in one
linear form of the locals are put in Horner form (:mod:`mechgen.codegen.rewrite`).
"""
from __future__ import annotations

import sympy as sp

from mechgen.codegen.ir import Block, Gather, KernelIR, Port, Write, fixed
from mechgen.codegen.rewrite import optimise
from mechgen.errors import ModelError
from mechgen.symbolic.finite import nonfinite_in


def canonical_block(gathers: list[tuple[sp.Symbol, str, int, bool]], writes: list[Write], *,
                    loop=None, cse: bool = True, model: str = "") -> Block:
    """Rename gathered symbols to g0.., check coverage, and CSE the write expressions.

    Gathers of symbols that no write uses are dropped. With ``cse`` the writes
    are also shared up to sign and put in Horner form (:func:`~mechgen.codegen.rewrite.optimise`);
    without it they are printed as derived.
    """
    used = set().union(*(w.expr.free_symbols for w in writes)) if writes else set()
    rename, kept = {}, []
    for sym, port, index, relative in gathers:
        if sym in used and sym not in rename:
            local = sp.Symbol(f"g{len(kept)}", real=True)
            rename[sym] = local
            kept.append(Gather(local, port, index, relative))
    # derivatives of sign/Abs/Heaviside are taken almost everywhere: their DiracDelta terms are dropped (a contact
    # law k |x|^n sign(x) has the stiffness k n |x|^(n-1), not a delta at x = 0)
    exprs = [_almost_everywhere(w.expr).xreplace(rename) for w in writes]
    stray = set().union(*(e.free_symbols for e in exprs)) - set(rename.values()) if exprs else set()
    if stray:
        names = ", ".join(sorted(s.name for s in stray))
        raise ModelError(f"expressions of model {model} use symbols {names} that are not coordinates, "
                         "velocities, internal variables, time or parameters", key=names,
                         expected="only declared names")
    bad = nonfinite_in(exprs)
    if bad:  # second line of defence: the declared functions' results are checked where they return
        raise ModelError(f"derived expressions of model {model} are singular at the fixed parameter values: they "
                         f"hold {'; '.join(bad)}", key="params",
                         expected="parameter values at which the model's laws and their derivatives are finite")
    assignments: list = []
    if cse and exprs:
        assignments, exprs = optimise(exprs, set(rename.values()))
    new_writes = tuple(Write(w.port, w.index, e, w.accumulate, w.relative, w.entry)
                       for w, e in zip(writes, exprs))
    return Block(tuple(kept), new_writes, tuple((s, e) for s, e in assignments), loop)


def _almost_everywhere(expr: sp.Expr) -> sp.Expr:
    """``expr`` with every DiracDelta (and derivative of one) replaced by 0."""
    if not expr.has(sp.DiracDelta):
        return expr
    return expr.replace(lambda e: isinstance(e, sp.DiracDelta), lambda e: sp.Integer(0))


def dense_writes(port: str, matrix: sp.Matrix) -> list[Write]:
    """Row-major writes of a matrix into a flat port, skipping structural zeros."""
    return [Write(port, i * matrix.cols + j, matrix[i, j]) for i in range(matrix.rows)
            for j in range(matrix.cols) if matrix[i, j] != 0]


def kernel(name: str, doc: str, inputs: list[Port], outputs: list[Port], blocks: list[Block],
           sizes: tuple[str, ...] = (), meta: dict | None = None) -> KernelIR:
    """Assemble a KernelIR, appending a slot table and an affine summary input per block with sparse writes."""
    ir = KernelIR(name, doc, tuple(inputs), tuple(outputs), tuple(blocks), sizes, meta or {})
    slots = [Port(port, _scaled(ir.blocks[i].loop.count, len(ir.blocks[i].entries)), batched=False,
                  integer=True, doc=f"CSR slots of block {i}") for i, port in ir.slot_ports()]
    affine = [Port(port, fixed(3 + len(ir.blocks[i].entries) + 2 * len(ir.stored_ports(i))), batched=False,
                   integer=True, doc=f"affine run of the slots of block {i}") for i, port in ir.affine_ports()]
    if slots:
        ir = KernelIR(name, doc, tuple(inputs) + tuple(slots) + tuple(affine), tuple(outputs), tuple(blocks), sizes,
                      meta or {})
    return ir


def _scaled(extent, factor: int):
    return extent.__class__(extent.const * factor, tuple((n, c * factor) for n, c in extent.terms))
