"""emit (C99): Kernel IR -> one C source with one function per kernel.

Every kernel loops over the batch; inside, straight blocks are plain
assignments and loop blocks become ``for`` loops over the repetition whose
interior iterations carry no bounds checks (the boundary iterations, where a
neighbour is a ghost, are peeled off with checks). The text does not grow
with the number of sites.
"""
from __future__ import annotations

from mechgen import __version__
from mechgen.codegen.ir import Block, KernelIR, Port
from mechgen.codegen.printing import c_code
from mechgen.codegen.templating import render


def _port_doc(ir: KernelIR) -> list[str]:
    lines = [f"in[{i}]  {p.name}: {'int64 ' if p.integer else ''}length {p.extent.c_expr()}"
             f"{' per state' if p.batched else ''}" for i, p in enumerate(ir.inputs)]
    lines += [f"out[{i}] {p.name}: length {p.extent.c_expr()} per state"
              f"{' (CSR data)' if p.sparse else ''}{f' shape {p.shape}' if p.shape else ''}"
              for i, p in enumerate(ir.outputs)]
    if ir.sizes:
        lines.append("sizes: " + ", ".join(ir.sizes))
    return lines


def _used_inputs(ir: KernelIR) -> set[str]:
    used = {g.port for b in ir.blocks for g in b.gathers}
    used |= {port for _, port in ir.slot_ports()}
    return used


def _prologue(ir: KernelIR) -> list[str]:
    lines = [f"const long {name} = sizes[{i}];" for i, name in enumerate(ir.sizes)]
    if not ir.sizes:
        lines.append("(void)sizes;")
    used = _used_inputs(ir)
    if not used:
        lines.append("(void)in;")
    for i, p in enumerate(ir.inputs):
        if p.name in used and p.batched:
            lines.append(f"const long len_in{i} = {p.extent.c_expr()};")
        elif p.name in used and p.integer:
            lines.append(f"const long *const in{i} = (const long *)(const void *)in[{i}];")
        elif p.name in used:
            lines.append(f"const double *const in{i} = in[{i}];")
    for i, p in enumerate(ir.outputs):
        lines.append(f"const long len_out{i} = {p.extent.c_expr()};")
    return lines


def _batch_pointers(ir: KernelIR) -> list[str]:
    used = _used_inputs(ir)
    lines = [f"const double *const in{i} = in[{i}] + b * len_in{i};"
             for i, p in enumerate(ir.inputs) if p.name in used and p.batched]
    for i, _ in enumerate(ir.outputs):
        lines.append(f"double *const out{i} = out[{i}] + b * len_out{i};")
        lines.append(f"for (long i = 0; i < len_out{i}; ++i) out{i}[i] = 0.0;")
    return lines


class _Names:
    def __init__(self, ir: KernelIR) -> None:
        self.inp = {p.name: f"in{i}" for i, p in enumerate(ir.inputs)}
        self.out = {p.name: f"out{i}" for i, p in enumerate(ir.outputs)}


def _straight(block: Block, names: _Names) -> list[str]:
    lines = [f"const double {g.symbol.name} = {names.inp[g.port]}[{g.index}];" for g in block.gathers]
    lines += [f"const double {s.name} = {c_code(e)};" for s, e in block.assignments]
    lines += [f"{names.out[w.port]}[{w.index}] {'+=' if w.accumulate else '='} {c_code(w.expr)};"
              for w in block.writes]
    return ["{"] + ["    " + line for line in lines] + ["}"]


def _site(offset: int, periodic: bool, checked: bool) -> str:
    if offset == 0:
        return "e"
    if periodic and checked:
        return f"(e + {offset} + ns) % ns" if offset < 0 else f"(e + {offset}) % ns"
    return f"e + {offset}" if offset > 0 else f"e - {-offset}"


def _guard(offset: int) -> str:
    return f"ok{offset + 8}"


def _carried_ports(block: Block) -> dict[str, int]:
    """Ports written at two adjacent site offsets (k, k+1): port -> k.

    In the unchecked interior, the contribution at offset k+1 of iteration e
    lands on the same site as the offset-k contribution of iteration e+1, so it
    is carried in a register instead of a read-modify-write of memory.
    """
    offsets: dict[str, set] = {}
    for w in block.writes:
        if w.relative and w.entry is None and w.accumulate:
            offsets.setdefault(w.port, set()).add(w.index)
    return {port: min(o) for port, o in offsets.items() if len(o) == 2 and max(o) == min(o) + 1}


def _loop_body(block: Block, names: _Names, *, checked: bool) -> list[str]:
    periodic = block.loop.boundary == "periodic"
    guard = checked and not periodic
    carried = {} if checked else _carried_ports(block)
    offsets = sorted({g.index for g in block.gathers if g.relative} | {w.index for w in block.writes if w.relative
                                                                       and w.entry is None})
    lines = [f"const int {_guard(k)} = (e + {k} >= 0) && (e + {k} < ns);" for k in offsets if guard]
    for g in block.gathers:
        if g.relative:
            idx = _site(g.index, periodic, checked)
            src = f"{names.inp[g.port]}[{idx}]"
            lines.append(f"const double {g.symbol.name} = {f'{_guard(g.index)} ? {src} : 0.0' if guard else src};")
    lines += [f"const double {s.name} = {c_code(e)};" for s, e in block.assignments]
    entries = {entry: col for col, entry in enumerate(block.entries)}
    width = len(entries)
    pending: dict[str, list[str]] = {}
    for w in block.writes:
        op = "+=" if w.accumulate else "="
        if w.entry is not None:
            slot = f"slot[e * {width} + {entries[w.entry]}]"
            lines.append(f"if ({slot} >= 0) {names.out[w.port]}[{slot}] {op} {c_code(w.expr)};")
        elif w.port in carried:
            pending.setdefault(f"{w.port}:{w.index - carried[w.port]}", []).append(c_code(w.expr))
        elif w.relative:
            target = f"{names.out[w.port]}[{_site(w.index, periodic, checked)}]"
            lines.append(f"{'if (' + _guard(w.index) + ') ' if guard else ''}{target} {op} {c_code(w.expr)};")
        else:
            lines.append(f"{names.out[w.port]}[{w.index}] {op} {c_code(w.expr)};")
    for port, k in carried.items():
        out = names.out[port]
        now = " + ".join(pending.get(f"{port}:0", ["0.0"]))
        nxt = " + ".join(pending.get(f"{port}:1", ["0.0"]))
        lines.append(f"{out}[{_site(k, periodic, checked)}] += carry_{out} + {now};")
        lines.append(f"carry_{out} = {nxt};")
    return lines


def _loop(block: Block, names: _Names, slot_port: str | None) -> list[str]:
    loop = block.loop
    offsets = [g.index for g in block.gathers if g.relative] + [w.index for w in block.writes if w.relative]
    lo_off, hi_off = min(offsets, default=0), max(offsets, default=0)
    head = [f"const long cnt = {loop.count.c_expr()};", f"const long ns = {loop.sites.c_expr()};"]
    if slot_port:
        head.append(f"const long *const slot = {names.inp[slot_port]};")
    head += [f"const double {g.symbol.name} = {names.inp[g.port]}[{g.index}];" for g in block.gathers
             if not g.relative]
    head.append(f"const long lo = {-lo_off} < cnt ? {max(0, -lo_off)} : cnt;")
    head.append(f"const long hi = ns - {hi_off} > lo ? (ns - {hi_off} < cnt ? ns - {hi_off} : cnt) : lo;")
    checked = ["    " + s for s in _loop_body(block, names, checked=True)]
    fast = ["    " + s for s in _loop_body(block, names, checked=False)]
    lines = head + ["for (long e = 0; e < lo; ++e) {"] + checked + ["}"]
    carried = {names.out[port]: k for port, k in _carried_ports(block).items()}
    lines += [f"double carry_{out} = 0.0;" for out in carried]
    lines += ["for (long e = lo; e < hi; ++e) {"] + fast + ["}"]
    lines += [f"if (hi > lo) {out}[hi + {k}] += carry_{out};" for out, k in carried.items()]
    lines += ["for (long e = hi; e < cnt; ++e) {"] + checked + ["}"]
    return ["{"] + ["    " + s for s in lines] + ["}"]


def kernel_context(ir: KernelIR) -> dict:
    """Template context of one kernel: prologue lines and batch-loop body lines."""
    names = _Names(ir)
    slots = dict(ir.slot_ports())
    body = _batch_pointers(ir)
    for i, block in enumerate(ir.blocks):
        body += _loop(block, names, slots.get(i)) if block.loop else _straight(block, names)
    return {"name": ir.name, "doc": ir.doc, "port_doc": _port_doc(ir), "prologue": _prologue(ir), "body": body}


def emit_c(irs: list[KernelIR], *, model: str, title: str) -> str:
    """The C99 source of all kernels of one model specialisation."""
    return render("c99/kernels.c.j2", version=__version__, model=model, title=title,
                  kernels=[kernel_context(ir) for ir in irs])


__all__ = ["emit_c", "kernel_context", "Port"]
