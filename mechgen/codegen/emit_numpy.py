"""emit (numpy): Kernel IR -> a vectorised Python module.

Batched ports are (nbatch, length) arrays; a loop block is evaluated for all
indices at once (gathers are fancy-indexed columns, writes at one offset hit
distinct entries so ``+=`` on an index array is exact).
"""
from __future__ import annotations

from mechgen.version import __version__
from mechgen.codegen.escape import code_identifier, py_docstring, py_literal
from mechgen.codegen.ir import Block, KernelIR
from mechgen.codegen.printing import math_code, numpy_code
from mechgen.codegen.program_text import operation_text
from mechgen.codegen.spec import kernel_spec
from mechgen.codegen.templating import render


def extent_expr(ext) -> str:
    """Python text of an extent's length, sum_k c_k sizes['name_k'] + const (the numpy and CasADi emitters)."""
    parts = [f"{c} * sizes[{ext_name!r}]" for ext_name, c in ext.terms]
    if ext.const or not parts:
        parts.append(str(ext.const))
    return " + ".join(parts)


def _head(ir: KernelIR) -> list[str]:
    lines = [f"in{i} = ins[{i}]" for i, _ in enumerate(ir.inputs)]
    lines += [f"out{i} = outs[{i}]" for i, _ in enumerate(ir.outputs)]
    lines.append("nb = outs[0].shape[0]" if ir.outputs else "nb = 1")
    return lines


def _straight(block: Block, idx: "_Indexed") -> list[str]:
    lines = [f"{code_identifier(g.symbol.name)} = in{idx.inp[g.port][0]}[{':, ' if idx.inp[g.port][1] else ''}"
             f"{g.index}]" for g in block.gathers]
    lines += [f"{o.target} = {operation_text(o, 'numpy')}" for o in block.operations]
    lines += [f"{code_identifier(s.name)} = {numpy_code(e)}" for s, e in block.assignments]
    lines += [f"out{idx.out[w.port]}[:, {w.index}] {'+=' if w.accumulate else '='} {numpy_code(w.expr)}"
              for w in block.writes]
    return lines


def _loop(block: Block, slot_index: int | None, idx: "_Indexed") -> list[str]:
    loop = block.loop
    periodic = loop.boundary == "periodic"
    lines = [f"cnt = {extent_expr(loop.count)}", f"ns = {extent_expr(loop.sites)}", "e = np.arange(cnt)",
             "shape = (nb, cnt)"]
    offsets = sorted({g.index for g in block.gathers if g.relative} | {w.index for w in block.writes if w.relative
                                                                       and w.entry is None})
    for k in offsets:
        if periodic:
            lines.append(f"i{k + 8} = (e + {k}) % ns")
        else:
            lines += [f"i{k + 8} = e + {k}", f"ok{k + 8} = (i{k + 8} >= 0) & (i{k + 8} < ns)",
                      f"i{k + 8} = np.clip(i{k + 8}, 0, max(ns - 1, 0))"]
    for g in block.gathers:
        code_identifier(g.symbol.name)
        if not g.relative:
            lines.append(f"{g.symbol.name} = in{idx.inp[g.port][0]}[{g.index}]")
        elif periodic:
            lines.append(f"{g.symbol.name} = in{idx.inp[g.port][0]}[:, i{g.index + 8}]")
        else:
            lines.append(f"{g.symbol.name} = np.where(ok{g.index + 8}, in{idx.inp[g.port][0]}[:, i{g.index + 8}], 0.0)")
    lines += [f"{code_identifier(s.name)} = {numpy_code(e)}" for s, e in block.assignments]
    entries = {entry: col for col, entry in enumerate(block.entries)}
    for w in block.writes:
        val = f"_bc({numpy_code(w.expr)}, shape)"
        if w.entry is not None:
            col = entries[w.entry]
            lines += [f"s = in{slot_index}.reshape(cnt, {len(entries)})[:, {col}]", "m = s >= 0",
                      f"out{idx.out[w.port]}[:, s[m]] += {val}[:, m]"]
        elif w.relative:
            mask = "" if periodic else f"ok{w.index + 8}"
            where = f"i{w.index + 8}[{mask}]" if mask else f"i{w.index + 8}"
            lines.append(f"out{idx.out[w.port]}[:, {where}] += {val}{'[:, ' + mask + ']' if mask else ''}")
        else:
            lines.append(f"out{idx.out[w.port]}[:, {w.index}] += np.sum({val}, axis=-1)")
    return lines


class _Indexed:
    """Port positions by name: inputs -> (position, batched), outputs -> position."""

    def __init__(self, ir: KernelIR) -> None:
        self.inp = {p.name: (i, p.batched) for i, p in enumerate(ir.inputs)}
        self.out = {p.name: i for i, p in enumerate(ir.outputs)}


def kernel_body(ir: KernelIR) -> list[str]:
    """Python lines of one kernel function."""
    idx = _Indexed(ir)
    slots = {i: idx.inp[port][0] for i, port in ir.slot_ports()}
    lines = _head(ir)
    for i, block in enumerate(ir.blocks):
        lines += _loop(block, slots.get(i), idx) if block.loop else _straight(block, idx)
    return lines


def point_body(ir: KernelIR) -> list[str] | None:
    """Python lines of the kernel at one point on Python floats (module ``math``), or None for a kernel with a
    loop block: the inputs read once as lists, each output gathered in a list and stored in one assignment, so that
    a domain error (raised by ``math``) leaves the outputs untouched for the numpy path that follows."""
    if any(block.loop for block in ir.blocks):
        return None
    idx = _Indexed(ir)
    lines = [f"in{i} = ins[{i}]{'[0]' if port.batched else ''}.tolist()" for i, port in enumerate(ir.inputs)]
    lines += [f"out{i} = [0.0] * outs[{i}].shape[1]" for i, _ in enumerate(ir.outputs)]
    for block in ir.blocks:
        lines += [f"{code_identifier(g.symbol.name)} = in{idx.inp[g.port][0]}[{g.index}]" for g in block.gathers]
        lines += [f"{o.target} = {operation_text(o, 'math')}" for o in block.operations]
        lines += [f"{code_identifier(sym.name)} = {math_code(e)}" for sym, e in block.assignments]
        lines += [f"out{idx.out[w.port]}[{w.index}] {'+=' if w.accumulate else '='} {math_code(w.expr)}"
                  for w in block.writes]
    lines += [f"outs[{i}][0] = out{i}" for i, _ in enumerate(ir.outputs)]
    return lines


def emit_numpy(irs: list[KernelIR], *, model: str, title: str) -> str:
    """The module text of all kernels of one model specialisation (numpy).

    The model name, ``title`` (the specialisation's key, choice values included) and kernel docs
    reach the module only through :func:`~mechgen.codegen.escape.py_docstring`, the spec only
    through :func:`~mechgen.codegen.escape.py_literal`.
    """
    spec = py_literal({ir.name: kernel_spec(ir) for ir in irs})
    return render("numpy/kernels.py.j2", version=__version__, model=py_docstring(model), title=py_docstring(title),
                  spec=spec, kernels=[{"name": code_identifier(ir.name), "doc": py_docstring(ir.doc),
                                       "body": kernel_body(ir), "point": point_body(ir)} for ir in irs])
