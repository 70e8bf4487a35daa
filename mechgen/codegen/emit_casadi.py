"""emit (CasADi): Kernel IR -> a module of functions building casadi.Function objects.

Straight blocks become SX expressions. A loop block becomes one local
``Function`` of the gathered values, ``map``-ped over the repetition; gathers
and scatters are constant sparse selection matrices built for the concrete sizes,
so the SX graph holds the local expressions once.
"""
from __future__ import annotations

import re

from mechgen.version import __version__
from mechgen.codegen.emit_numpy import extent_expr
from mechgen.codegen.escape import code_identifier, py_docstring, py_literal
from mechgen.codegen.ir import Block, KernelIR
from mechgen.codegen.printing import casadi_code
from mechgen.codegen.program_text import operation_expr
from mechgen.codegen.spec import kernel_spec
from mechgen.codegen.templating import render


def _head(ir: KernelIR) -> list[str]:
    lines = []
    for i, p in enumerate(ir.inputs):
        if not p.integer:
            lines.append(f"in{i} = ca.SX.sym({p.name!r}, {extent_expr(p.extent)})")
    lines += [f"out{i} = ca.SX.zeros({extent_expr(p.extent)})" for i, p in enumerate(ir.outputs)]
    return lines


def _straight(block: Block, inp: dict, out: dict) -> list[str]:
    lines = [f"{code_identifier(g.symbol.name)} = in{inp[g.port]}[{g.index}]" for g in block.gathers]
    lines += [f"{o.target} = {casadi_code(operation_expr(o))}" for o in block.operations]
    lines += [f"{code_identifier(s.name)} = {casadi_code(e)}" for s, e in block.assignments]
    for w in block.writes:
        op = "+" if w.accumulate else ""
        lines.append(f"out{out[w.port]}[{w.index}] = {'out' + str(out[w.port]) + f'[{w.index}] + ' if op else ''}"
                     f"{casadi_code(w.expr)}")
    return lines


def _loop(block: Block, k: int, inp: dict, out: dict, slot_port: str | None) -> list[str]:
    periodic = block.loop.boundary == "periodic"
    rel = [g for g in block.gathers if g.relative]
    absolute = [g for g in block.gathers if not g.relative]
    lines = [f"cnt = {extent_expr(block.loop.count)}", f"ns = {extent_expr(block.loop.sites)}"]
    lines += [f"{code_identifier(g.symbol.name)} = ca.SX.sym({g.symbol.name!r})" for g in rel + absolute]
    lines += [f"{code_identifier(s.name)} = {casadi_code(e)}" for s, e in block.assignments]
    exprs = ", ".join(casadi_code(w.expr) for w in block.writes)
    args = ", ".join(g.symbol.name for g in rel + absolute)
    lines.append(f"local = ca.Function('local{k}', [{args}], [ca.vertcat({exprs})])")
    lines.append("mapped = local.map(cnt)")
    gathered = [f"(_shift(ns, cnt, {g.index}, {periodic}).T @ in{inp[g.port]}).T" for g in rel]
    gathered += [f"in{inp[g.port]}[{g.index}]" for g in absolute]
    if gathered:
        lines.append(f"vals = mapped({', '.join(gathered)})")
    else:
        lines.append(f"vals = ca.repmat(ca.vertcat({exprs}), 1, cnt)")
    entries = {entry: col for col, entry in enumerate(block.entries)}
    for row, w in enumerate(block.writes):
        o = f"out{out[w.port]}"
        if w.entry is not None:
            cols = f"np.asarray(slots[{slot_port!r}]).reshape(cnt, {len(entries)})[:, {entries[w.entry]}]"
            lines.append(f"{o} = {o} + _scatter({o}.numel(), cnt, {cols}) @ vals[{row}, :].T")
        elif w.relative:
            lines.append(f"{o} = {o} + _shift(ns, cnt, {w.index}, {periodic}) @ vals[{row}, :].T")
        else:
            lines.append(f"{o}[{w.index}] = {o}[{w.index}] + ca.sum2(vals[{row}, :])")
    return lines


def kernel_body(ir: KernelIR) -> list[str]:
    """Python lines building one casadi.Function."""
    inp = {p.name: i for i, p in enumerate(ir.inputs)}
    out = {p.name: i for i, p in enumerate(ir.outputs)}
    slots = dict(ir.slot_ports())
    lines = _head(ir)
    for k, block in enumerate(ir.blocks):
        lines += _loop(block, k, inp, out, slots.get(k)) if block.loop else _straight(block, inp, out)
    ins = ", ".join(f"in{i}" for i, p in enumerate(ir.inputs) if not p.integer)
    outs = ", ".join(f"out{i}" for i, _ in enumerate(ir.outputs))
    names_in = [p.name for p in ir.inputs if not p.integer]
    names_out = [p.name for p in ir.outputs]
    lines.append(f"return ca.Function({casadi_name(ir.name)!r}, [{ins}], [{outs}], {names_in!r}, {names_out!r})")
    return lines


def casadi_name(name: str) -> str:
    """The label of a kernel's casadi.Function: CasADi refuses consecutive underscores, which the kernels of a
    hybrid model's modes carry (``residual__0``, mechgen.codegen.lower_model.lower_hybrid), so runs of them become one."""
    return re.sub(r"_{2,}", "_", name)


def emit_casadi(irs: list[KernelIR], *, model: str, title: str) -> str:
    """The CasADi module text of all kernels of one model specialisation.

    Free text reaches it only through :func:`~mechgen.codegen.escape.py_docstring`, the spec only
    through :func:`~mechgen.codegen.escape.py_literal` (as in :func:`~mechgen.codegen.emit_numpy.emit_numpy`).
    """
    spec = py_literal({ir.name: kernel_spec(ir) for ir in irs})
    return render("casadi/kernels.py.j2", version=__version__, model=py_docstring(model), title=py_docstring(title),
                  spec=spec, kernels=[{"name": code_identifier(ir.name), "doc": py_docstring(ir.doc),
                                       "body": kernel_body(ir)} for ir in irs])
