"""emit (C99): Kernel IR -> one C source with one function per kernel.

Every kernel loops over the batch; inside, straight blocks are plain
assignments and loop blocks become ``for`` loops over the repetition whose
interior iterations carry no bounds checks (the boundary iterations, where a
neighbour is a ghost, are peeled off with checks; see
:mod:`mechgen.codegen.emit_c_loop`). Outputs start at zero, zeroed up front
or, for those a loop's interior stores, by that loop. The text does not grow
with the number of sites.
"""
from __future__ import annotations

from mechgen.version import __version__
from mechgen.codegen.emit_c_loop import loop_block, stored_ports
from mechgen.codegen.escape import c_comment, c_comment_lines, code_identifier
from mechgen.codegen.ir import Block, KernelIR, Port
from mechgen.codegen.printing import c_code
from mechgen.codegen.program_text import operation_text
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
    used |= {port for _, port in ir.slot_ports() + ir.affine_ports()}
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


def _zeroed_by_kernel(ir: KernelIR) -> set[str]:
    """Outputs the kernel zeroes up front: all but those their first writer stores (see emit_c_loop)."""
    stored = {p for i, b in enumerate(ir.blocks) if b.loop for p in stored_ports(ir, i)}
    return {p.name for p in ir.outputs} - stored


def _batch_pointers(ir: KernelIR) -> list[str]:
    used = _used_inputs(ir)
    zeroed = _zeroed_by_kernel(ir)
    lines = [f"const double *const in{i} = in[{i}] + b * len_in{i};"
             for i, p in enumerate(ir.inputs) if p.name in used and p.batched]
    for i, p in enumerate(ir.outputs):
        lines.append(f"double *const out{i} = out[{i}] + b * len_out{i};")
        if p.name in zeroed:
            lines.append(f"for (long i = 0; i < len_out{i}; ++i) out{i}[i] = 0.0;")
    return lines


class _Names:
    def __init__(self, ir: KernelIR) -> None:
        self.inp = {p.name: f"in{i}" for i, p in enumerate(ir.inputs)}
        self.out = {p.name: f"out{i}" for i, p in enumerate(ir.outputs)}
        self.out_len = {p.name: f"len_out{i}" for i, p in enumerate(ir.outputs)}


def _straight(block: Block, names: _Names) -> list[str]:
    lines = [f"const double {code_identifier(g.symbol.name)} = {names.inp[g.port]}[{g.index}];" for g in block.gathers]
    lines += [f"const double {o.target} = {operation_text(o, 'c')};" for o in block.operations]
    lines += [f"const double {code_identifier(s.name)} = {c_code(e)};" for s, e in block.assignments]
    lines += [f"{names.out[w.port]}[{w.index}] {'+=' if w.accumulate else '='} {c_code(w.expr)};"
              for w in block.writes]
    return ["{"] + ["    " + line for line in lines] + ["}"]


def kernel_context(ir: KernelIR) -> dict:
    """Template context of one kernel: prologue lines and batch-loop body lines."""
    names = _Names(ir)
    body = _batch_pointers(ir)
    for i, block in enumerate(ir.blocks):
        body += loop_block(ir, i, names.inp, names.out, names.out_len) if block.loop else _straight(block, names)
    return {"name": code_identifier(ir.name), "doc": c_comment(ir.doc).replace("\n", " "),
            "port_doc": [line for doc in _port_doc(ir) for line in c_comment_lines(doc, "")],
            "prologue": _prologue(ir), "body": body, "quick_build": quick_build(ir)}


#: straight-line statements (assignments and writes) above which GCC builds a kernel at -O1, and at -O0
QUICK_BUILD_STATEMENTS = (4000, 15000)


def quick_build(ir: KernelIR) -> str:
    """GCC's optimisation level for the kernel where it is not the default -O3 ("" where it is).

    A straight-line block of thousands of single-assignment temporaries (an AD-derived kernel of a large model,
    mechgen.codegen.lower_ad) costs GCC's register allocator time superlinear in its length: an n = 64
    pendulum's flow kernel (41,000 lines) builds in 25 s of CPU at -O1 and 1.1 s at -O0, an n = 24 one's (6,800
    lines) in 1.2 s at -O1 and runs at 3.9 us a call (13 us at -O0, 4.0 us at -O3). So blocks over 4,000
    statements are built at -O1 and over 15,000 at -O0, where compiling would cost more than the calls save.
    Small and looping kernels keep -O3; Clang ignores the request (it has no such pragma).
    """
    statements = sum(len(b.assignments) + len(b.operations) + len(b.writes) for b in ir.blocks if not b.loop)
    low, none = QUICK_BUILD_STATEMENTS
    return "O0" if statements > none else "O1" if statements > low else ""


def emit_c(irs: list[KernelIR], *, model: str, title: str) -> str:
    """The C99 source of all kernels of one model specialisation.

    The model name, ``title`` (the specialisation's key, choice values included) and kernel and
    port docs reach the source only through :func:`~mechgen.codegen.escape.c_comment`.
    """
    return render("c99/kernels.c.j2", version=__version__, model=c_comment(model).replace("\n", " "),
                  title="\n * ".join(c_comment_lines(title, "")), kernels=[kernel_context(ir) for ir in irs])


__all__ = ["emit_c", "kernel_context", "Port"]
