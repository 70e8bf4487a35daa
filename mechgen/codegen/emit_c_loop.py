"""emit (C99), loop blocks: one repetition (sites, bonds) as C ``for`` loops.

Iterations split into the *interior*, lo <= e < hi, where every site e + k a
gather or write touches lies in [0, ns), and the *boundary* iterations around
it, which check their sites (``zero`` ends) or wrap them (``periodic``). The
interior runs first and carries no checks:

* A site vector written at two adjacent offsets k, k+1 carries the k+1 part of
  iteration e in a register to the k part of iteration e+1, so each site is
  written once.
* An output the block is first to write *stores* instead of accumulating in
  the interior; the block zeroes only the entries its interior does not store,
  and the boundary iterations (run afterwards) accumulate. Site vectors: the
  interior stores sites [lo+k, hi+k] (k, k+1 carried) or [lo+k, hi+k).
  Sparse (CSR) outputs: the runtime's affine summary of the slot table (see
  :meth:`~mechgen.codegen.ir.KernelIR.affine_ports`) gives a run ea <= e < eb
  of the interior where entry j sits at ``base_j + stride*e`` and the
  positions [zlo, zhi) stored there; carried pairs of entries (j, j') with
  entry j' = entry j + (1, 1) are merged in a register as above. Outside the
  run the interior addresses the CSR data through the slot table.

Every output other than those is zeroed at the start of each state by the kernel.
"""
from __future__ import annotations

import re

import sympy as sp

from mechgen.codegen.ir import Block, KernelIR
from mechgen.codegen.printing import c_code


def dense_stored(ir: KernelIR, i: int) -> dict[str, tuple[int, int]]:
    """Site vectors that loop block ``i`` (no sparse writes) stores in its interior: port -> (k, 1 or 2 offsets)."""
    b = ir.blocks[i]
    if b.loop is None or b.entries:
        return {}
    extents = {p.name: p.extent for p in ir.outputs}
    stored = {}
    for port in b.written_ports():
        offsets = _dense_offsets(b, port)
        if ir.first_writer(port) == i and extents[port] == b.loop.sites and offsets:
            stored[port] = (offsets[0], len(offsets))
    return stored


def _dense_offsets(b: Block, port: str) -> list[int]:
    """Offsets k or k, k+1 if ``port`` is written in ``b`` only by relative accumulating site writes, else []."""
    writes = [w for w in b.writes if w.port == port]
    if not all(w.relative and w.entry is None and w.accumulate for w in writes):
        return []
    offsets = sorted({w.index for w in writes})
    return offsets if len(offsets) == 1 or offsets == [offsets[0], offsets[0] + 1] else []


def stored_ports(ir: KernelIR, i: int) -> list[str]:
    """Outputs block ``i`` stores in its interior (and zeroes elsewhere itself)."""
    return list(dense_stored(ir, i)) + list(ir.stored_ports(i))


def _site(offset: int, periodic: bool, checked: bool) -> str:
    if offset == 0:
        return "e"
    if periodic and checked:
        return f"(e + {offset} + ns) % ns" if offset < 0 else f"(e + {offset}) % ns"
    return f"e + {offset}" if offset > 0 else f"e - {-offset}"


def _plus(name: str, k: int) -> str:
    return name if k == 0 else f"{name} + {k}" if k > 0 else f"{name} - {-k}"


def _guard(offset: int) -> str:
    return f"ok{offset + 8}"


def _sum(terms: list[str]) -> str:
    """C text of a sum of term texts (``a - b`` for a term ``-b``)."""
    if not terms:
        return "0.0"
    return terms[0] + "".join(f" - {t[1:]}" if t.startswith("-") else f" + {t}" for t in terms[1:])


class _Ctx:
    """One loop block and its C names: ports, stored outputs, carried values (and which carry a minus)."""

    def __init__(self, ir: KernelIR, i: int, inp: dict, out: dict) -> None:
        self.block = ir.blocks[i]
        self.inp, self.out = inp, out
        self.periodic = self.block.loop.boundary == "periodic"
        self.dense = dense_stored(ir, i)
        self.sparse = ir.stored_ports(i)
        self.width = len(self.block.entries)
        self.col = {entry: j for j, entry in enumerate(self.block.entries)}
        self.carried = {} if self.block.entries else {p: min(o) for p in self.block.written_ports()
                                                      for o in [_dense_offsets(self.block, p)] if len(o) == 2}
        self.pairs = {p: self.block.carried_entries(p) for p in self.block.written_ports()}
        self.negated = {self.carried_out(port, where, sparse) for (port, where, sparse, _, _), exprs
                        in _grouped(self.block).items() if sp.Add(*exprs).could_extract_minus_sign()} - {None}

    def carried_out(self, port: str, where, sparse: bool) -> str | None:
        """The carry variable a write group goes to in the interior (offset k+1, or entry j_out), else None."""
        if sparse and any(self.col[where] == j_out for _, j_out in self.pairs[port]):
            return f"carry_{self.out[port]}_{self.col[where]}"
        if not sparse and port in self.carried and where == self.carried[port] + 1:
            return f"carry_{self.out[port]}"
        return None


def _gathers(ctx: _Ctx, checked: bool) -> list[str]:
    guard = checked and not ctx.periodic
    lines = []
    for g in ctx.block.gathers:
        if g.relative:
            src = f"{ctx.inp[g.port]}[{_site(g.index, ctx.periodic, checked)}]"
            lines.append(f"const double {g.symbol.name} = {f'{_guard(g.index)} ? {src} : 0.0' if guard else src};")
    return lines + [f"const double {s.name} = {c_code(e)};" for s, e in ctx.block.assignments]


def _grouped(block: Block) -> dict[tuple, list[sp.Expr]]:
    """Write expressions per (port, entry or offset, sparse, relative, accumulate), in first-use order."""
    groups: dict[tuple, list[sp.Expr]] = {}
    for w in block.writes:
        key = (w.port, w.entry if w.entry is not None else w.index, w.entry is not None, w.relative, w.accumulate)
        groups.setdefault(key, []).append(w.expr)
    return groups


def _text(exprs: list[sp.Expr]) -> str:
    return _sum([c_code(e) for e in exprs])


def _carry_value(name: str, exprs: list[sp.Expr], negated: set) -> str:
    """The text of a carried value; a value with a leading minus is carried positive (``name`` in ``negated``)."""
    return c_code(-sp.Add(*exprs)) if name in negated else _text(exprs)


def _with_carry(name: str, exprs: list[sp.Expr], negated: set) -> str:
    """The sum of ``exprs`` and the carried value ``name``."""
    terms = [c_code(e) for e in exprs]
    return _sum(terms + [f"-{name}"] if name in negated else [name] + terms)


def _store_carry(target: str, op: str, name: str, negated: set) -> str:
    """The trailing store of a carried value."""
    if name not in negated:
        return f"{target} {op} {name};"
    return f"{target} -= {name};" if op == "+=" else f"{target} = -{name};"


def _checked_body(ctx: _Ctx) -> list[str]:
    """One boundary iteration: checked (or wrapped) sites, slot-table entries, accumulate."""
    b = ctx.block
    guard = not ctx.periodic
    offsets = sorted({g.index for g in b.gathers if g.relative} | {w.index for w in b.writes
                                                                   if w.relative and w.entry is None})
    lines = [f"const int {_guard(k)} = (e + {k} >= 0) && (e + {k} < ns);" for k in offsets if guard]
    lines += _gathers(ctx, checked=True)
    for (port, where, sparse, relative, acc), exprs in _grouped(b).items():
        op, out = "+=" if acc else "=", ctx.out[port]
        if sparse:
            slot = f"slot[e * {ctx.width} + {ctx.col[where]}]"
            lines.append(f"if ({slot} >= 0) {out}[{slot}] {op} {_text(exprs)};")
        elif relative:
            target = f"{out}[{_site(where, ctx.periodic, True)}]"
            lines.append(f"{'if (' + _guard(where) + ') ' if guard else ''}{target} {op} {_text(exprs)};")
        else:
            lines.append(f"{out}[{where}] {op} {_text(exprs)};")
    return lines


def _interior_body(ctx: _Ctx, affine: bool) -> list[str]:
    """One interior iteration: unchecked sites; sparse entries direct (affine run) or through the slot table;
    the carried values taken for the next iteration last."""
    lines, carried = _interior_parts(ctx, affine)
    return lines + [f"{name} = {value};" for name, value in carried.items()]


def _interior_parts(ctx: _Ctx, affine: bool) -> tuple[list[str], dict[str, str]]:
    """An interior iteration's lines but the carried values' updates, and those values' texts by carry name."""
    b = ctx.block
    lines = _gathers(ctx, checked=False)
    pending: dict[str, list[sp.Expr]] = {}
    for (port, where, sparse, relative, acc), exprs in _grouped(b).items():
        out = ctx.out[port]
        stored = port in ctx.sparse or port in ctx.dense
        op = "=" if stored or not acc else "+="
        carry = ctx.carried_out(port, where, sparse)
        if carry and (affine or not sparse):
            pending[carry] = exprs
        elif sparse and affine:
            j = ctx.col[where]
            carried = [f"carry_{out}_{j_out}" for j_in, j_out in ctx.pairs[port] if j_in == j]
            value = _with_carry(carried[0], exprs, ctx.negated) if carried else _text(exprs)
            lines.append(f"{out}[base{j} + stride * e] {op} {value};")
        elif sparse:
            slot = f"slot[e * {ctx.width} + {ctx.col[where]}]"
            lines.append(f"if ({slot} >= 0) {out}[{slot}] += {_text(exprs)};")
        elif relative and port in ctx.carried:
            lines.append(f"{out}[{_site(where, ctx.periodic, False)}] {op} "
                         f"{_with_carry(f'carry_{out}', exprs, ctx.negated)};")
        elif relative:
            lines.append(f"{out}[{_site(where, ctx.periodic, False)}] {op} {_text(exprs)};")
        else:
            lines.append(f"{out}[{where}] {'+=' if acc else '='} {_text(exprs)};")
    return lines, {name: _carry_value(name, exprs, ctx.negated) for name, exprs in pending.items()}


def _zero(out: str, zlo: str, zhi: str, length: str) -> list[str]:
    return [f"for (long i = 0; i < {zlo}; ++i) {out}[i] = 0.0;",
            f"for (long i = {zhi}; i < {length}; ++i) {out}[i] = 0.0;"]


def _for(lo: str, hi: str, body: list[str]) -> list[str]:
    return [f"for (long e = {lo}; e < {hi}; ++e) {{"] + ["    " + s for s in body] + ["}"]


def _dense_interior(ctx: _Ctx, out_len: dict) -> list[str]:
    lines = []
    for port, (k, n) in ctx.dense.items():
        out = ctx.out[port]
        lines += [f"const long zlo_{out} = hi > lo ? {_plus('lo', k)} : 0;",
                  f"const long zhi_{out} = hi > lo ? {_plus('hi', k + n - 1)} : 0;"]
        lines += _zero(out, f"zlo_{out}", f"zhi_{out}", out_len[port])
    if not ctx.carried:
        return lines + _for("lo", "hi", _interior_body(ctx, affine=False))
    return lines + _recomputed_interior(ctx)


_DECLARED = re.compile(r"^const double (\w+) = (.*);$")
_NAME = re.compile(r"\b[A-Za-z_]\w*\b")


def _kept(declarations: list[str], uses: list[str]) -> list[str]:
    """The declarations (``const double x = ...;``) that the texts ``uses`` need, directly or through others."""
    needed = {name for text in uses for name in _NAME.findall(text)}
    kept = []
    for line in reversed(declarations):
        name, value = _DECLARED.match(line).groups()
        if name in needed:
            kept.append(line)
            needed |= set(_NAME.findall(value))
    return kept[::-1]


def _suffixed(ctx: _Ctx, text: str) -> str:
    """``text`` with the loop block's gathered and assigned names suffixed ``_p`` (iteration e - 1's)."""
    names = {g.symbol.name for g in ctx.block.gathers if g.relative} | {s.name for s, _ in ctx.block.assignments}
    return _NAME.sub(lambda m: m.group(0) + "_p" if m.group(0) in names else m.group(0), text)


def _previous_iteration(ctx: _Ctx, values: list[str]) -> list[str]:
    """Declarations computing, at iteration e, the carried ``values`` (texts) of iteration e - 1: its gathers at
    one site less and its assignments, every name suffixed ``_p``; only those the values need."""
    prev = [f"const double {g.symbol.name}_p = {ctx.inp[g.port]}[{_site(g.index - 1, ctx.periodic, False)}];"
            for g in ctx.block.gathers if g.relative]
    prev += [_suffixed(ctx, f"const double {s.name} = {c_code(e)};") for s, e in ctx.block.assignments]
    return _kept(prev, [_suffixed(ctx, v) for v in values])


def _recomputed_interior(ctx: _Ctx) -> list[str]:
    """The interior of a block whose site vectors are written at offsets k and k + 1 (a bond's two ends).

    Iteration e stores site e + k = (its own offset-k part) + (the offset-(k+1) part of iteration e - 1). That
    part is recomputed from iteration e - 1's gathers, not carried in a register from the previous iteration: a
    loop-carried value keeps GCC from vectorising the loop (the FPU force at N = 10^6: 456 -> 361 us with
    SSE2, 556 -> 243 us with AVX2), and the recomputed operations are the same, so the values are too. The
    first interior iteration has nothing carried in (iteration lo - 1 is a boundary one, which accumulates
    afterwards), and the last iteration's offset-(k+1) part is stored after the loop, recomputed at e = hi."""
    core, values = _interior_parts(ctx, affine=False)
    declared = [line for line in core if _DECLARED.match(line)]
    writes = [line for line in core if not _DECLARED.match(line)]
    first = [f"double {name} = 0.0;" for name in values] + core + [f"{n} = {v};" for n, v in values.items()]
    loop = _previous_iteration(ctx, list(values.values()))
    loop += [f"const double {name} = {_suffixed(ctx, value)};" for name, value in values.items()]
    loop += _kept(declared, writes) + writes
    last = _previous_iteration(ctx, list(values.values()))
    for port, k in ctx.carried.items():
        name = f"carry_{ctx.out[port]}"
        last.append(f"const double {name} = {_suffixed(ctx, values[name])};")
        target = f"{ctx.out[port]}[{_plus('hi', k)}]"
        last.append(_store_carry(target, "=" if port in ctx.dense else "+=", name, ctx.negated))
    return (["if (hi > lo) {", "    const long e = lo;"] + ["    " + line for line in first] + ["}"]
            + _for("lo + 1", "hi", loop)
            + ["if (hi > lo) {", "    const long e = hi;"] + ["    " + line for line in last] + ["}"])


def _sparse_interior(ctx: _Ctx, out_len: dict, affine_port: str) -> list[str]:
    aff = ctx.inp[affine_port]
    lines = [f"const long ea = {aff}[0] < lo ? lo : ({aff}[0] > hi ? hi : {aff}[0]);",
             f"const long eb = {aff}[1] < ea ? ea : ({aff}[1] > hi ? hi : {aff}[1]);",
             f"const long stride = {aff}[2];"]
    lines += [f"const long base{j} = {aff}[{3 + j}];" for j in range(ctx.width)]
    for m, port in enumerate(ctx.sparse):
        out = ctx.out[port]
        lines += [f"const long zlo_{out} = {aff}[{3 + ctx.width + 2 * m}];",
                  f"const long zhi_{out} = {aff}[{4 + ctx.width + 2 * m}];"]
        lines += _zero(out, f"zlo_{out}", f"zhi_{out}", out_len[port])
    carries = [(ctx.out[p], j_out) for p, pairs in ctx.pairs.items() for _, j_out in pairs]
    lines += [f"double carry_{out}_{j} = 0.0;" for out, j in carries]
    lines += _for("ea", "eb", _interior_body(ctx, affine=True))
    for out, j in carries:
        port = next(p for p, name in ctx.out.items() if name == out)
        op, target = "=" if port in ctx.sparse else "+=", f"{out}[base{j} + stride * (eb - 1)]"
        lines.append(f"if (eb > ea) {_store_carry(target, op, f'carry_{out}_{j}', ctx.negated)}")
    table = _interior_body(ctx, affine=False)
    return lines + _for("lo", "ea", table) + _for("eb", "hi", table)


def loop_block(ir: KernelIR, i: int, inp: dict, out: dict, out_len: dict) -> list[str]:
    """C lines of loop block ``i`` (inside the batch loop); ``inp``/``out``/``out_len`` map port names to C names."""
    ctx = _Ctx(ir, i, inp, out)
    b, loop = ctx.block, ctx.block.loop
    lo_off, hi_off = b.offset_range()
    head = [f"const long cnt = {loop.count.c_expr()};", f"const long ns = {loop.sites.c_expr()};"]
    slots = dict(ir.slot_ports())
    if i in slots:
        head.append(f"const long *const slot = {inp[slots[i]]};")
    head += [f"const double {g.symbol.name} = {inp[g.port]}[{g.index}];" for g in b.gathers if not g.relative]
    head.append(f"const long lo = {-lo_off} < cnt ? {max(0, -lo_off)} : cnt;")
    head.append(f"const long hi = ns - {hi_off} > lo ? (ns - {hi_off} < cnt ? ns - {hi_off} : cnt) : lo;")
    if b.entries:
        body = _sparse_interior(ctx, out_len, dict(ir.affine_ports())[i])
    else:
        body = _dense_interior(ctx, out_len)
    checked = _checked_body(ctx)
    lines = head + body + _for("0", "lo", checked) + _for("hi", "cnt", checked)
    return ["{"] + ["    " + s for s in lines] + ["}"]
