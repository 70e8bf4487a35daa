"""emit (standalone C99): Kernel IR -> a header and a source a C program uses without mechgen.

The kernel bodies are those of :mod:`mechgen.codegen.emit_c` (:func:`kernel_context`); this
module adds, for model ``M`` and kernel ``K``:

* ``int M_K_batch(const double *const *in, double *const *out, const long *sizes, long nbatch)``:
  the mechgen kernel ABI (ports in the order the header lists);
* ``int M_K(long nbatch, <sizes>, const double *in_q, ..., double *out_M, ...)``: the same
  call with one named pointer per port;
* for a kernel with sparse (CSR) outputs, ``long M_K_nnz(long sites)`` and
  ``int M_K_pattern(long sites, long *indptr, long *indices, long *slots0, ...)``: the CSR
  pattern (sites x sites) and the slot tables the kernel reads, computed in C from the
  kernel's loop recipe exactly as :func:`mechgen.runtime.core.pattern.build_pattern` does, with
  the affine summaries of :func:`mechgen.runtime.core.pattern.affine_summary` (all zeros would
  also be valid: the kernel then addresses the CSR data through the slot table alone).

Free text (model doc, parameter docs, choice values) reaches the files only through
:func:`mechgen.codegen.escape.c_comment`; names are validated identifiers.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from mechgen.version import __version__
from mechgen.codegen.emit_c import kernel_context
from mechgen.codegen.escape import c_comment, c_comment_lines
from mechgen.codegen.ir import Extent, KernelIR, Port
from mechgen.codegen.templating import render


@dataclass(frozen=True)
class ExportFacts:
    """What the header documents beyond the IR: all free text is escaped here, on use.

    ``params``: name -> (unit, doc) of every parameter; ``fixed``: folded values by name;
    ``outputs``: name -> doc of the model's declared outputs.
    """

    model: str
    doc: str = ""
    title: str = ""
    params: dict = field(default_factory=dict)
    fixed: dict = field(default_factory=dict)
    outputs: dict = field(default_factory=dict)


_OUTPUT_DOC = {
    "r": "residual r = M(q) a - f(q, v, t) of Lagrange's equations",
    "f": "potential force -dV/dq",
    "g": "internal rates dz/dt",
    "M": "mass matrix M = dr/da",
    "D": "damping matrix D (symmetric part of dr/dv)",
    "G": "gyroscopic matrix G (skew part of dr/dv)",
    "K": "stiffness matrix K = dr/dq (incl. centrifugal/geometric terms)",
}


def _length(ext: Extent) -> str:
    return ext.c_expr()


def _entries(names: list[str], letter: str) -> str:
    return ", ".join(f"{letter}[{i}] {n}" for i, n in enumerate(names)) or "none"


def _input_doc(ir: KernelIR, p: Port, facts: ExportFacts, prefix: str) -> list[str]:
    meta = ir.meta
    lattice = meta.get("kind") == "lattice"
    coords = list(meta.get("coordinates", []))
    head = f"in_{p.name} [{_length(p.extent)}]{'' if p.batched else ' (one array for all nbatch states)'}: "
    if p.name == "q":
        if lattice:
            return [head + f"site displacements {coords[0]} at sites 0 .. sites-1 "
                    f"(ends: {meta.get('ends')}; site e is particle e+1)"]
        what = "jets at the point" if meta.get("kind") == "field" else "generalised coordinates"
        return [head + what + ": " + _entries(coords, "q")]
    if p.name == "v":
        return [head + "velocities dq/dt, in the order of q"]
    if p.name == "a":
        return [head + "accelerations d2q/dt2, in the order of q"]
    if p.name == "z":
        internal = list(meta.get("internal", []))
        return [head + "internal variables: " + (_entries(internal, "z") if internal else "none (pass NULL)")]
    if p.name == "t":
        return [head + "time t[0]"]
    if p.name == "s":
        return [head + "position s[0] of the point along the domain"]
    if p.name == "p":
        names = list(meta.get("params", []))
        lines = [head + (f"{len(names)} free parameters" if names else "no free parameters (pass NULL)")]
        for i, n in enumerate(names):
            unit, doc = facts.params.get(n, ("", ""))
            lines.append(f"    p[{i}] {n}{f' [{unit}]' if unit else ''}{': ' + doc if doc else ''}")
        return lines
    if p.name.endswith("_affine"):
        return [head + f"affine summary of a slot table (long), filled by {prefix}_pattern "
                "(all zeros is also valid: the kernel then uses the slot table alone)"]
    if p.name.startswith("slots"):
        return [head + f"slot table (long) of loop block {p.name[5:]}, filled by "
                f"{prefix}_pattern"]
    return [head + p.doc]


def _output_doc(ir: KernelIR, p: Port, facts: ExportFacts, prefix: str) -> list[str]:
    base = p.name.split("_")[0] if p.name.startswith(("r_", "g_")) else p.name
    if p.name in _OUTPUT_DOC:
        what = _OUTPUT_DOC[p.name]
    elif p.name.startswith(("r_", "g_")):
        what = f"Jacobian d{base}/d{p.name[2:]}"
    elif p.name in facts.outputs:
        what = f"output {p.name}{': ' + facts.outputs[p.name] if facts.outputs[p.name] else ''}"
    else:
        what = p.name.replace("_", " ")
    if ir.meta.get("kind") == "field" and p.name in _OUTPUT_DOC:
        what = (f"pointwise {_OUTPUT_DOC[p.name].split(' ')[0]} density: entry i pairs with the variation of "
                "jet q[i] (integrate over s against the basis)" if p.name == "r" else
                f"pointwise {_OUTPUT_DOC[p.name].split(' (')[0]} density over the jets (jets x jets)")
    if p.sparse:
        layout = (f"CSR data (length nnz) of a sites x sites matrix in the pattern of "
                  f"{prefix}_pattern")
    elif p.shape:
        layout = f"{p.shape[0]} x {p.shape[1]} row-major"
    else:
        layout = "one entry per site"
    sym = ", symmetric" if p.symmetric else ""
    return [f"out_{p.name} [{_length(p.extent)}]: {what}; {layout}{sym}"]


def _pattern_context(ir: KernelIR, prefix: str) -> dict | None:
    """Loop recipes of the sparse blocks, for the C pattern builder; None without sparse outputs."""
    slots = ir.slot_ports()
    if not slots:
        return None
    blocks = []
    for (i, slot), (_, affine) in zip(slots, ir.affine_ports()):
        b = ir.blocks[i]
        for ext in (b.loop.count, b.loop.sites):
            if any(name != "sites" for name, _ in ext.terms):
                raise ValueError(f"kernel {ir.name}: loop extent {ext} depends on more than the sites")
        stored = []
        for port in ir.stored_ports(i):
            outgoing = sorted({j_out for _, j_out in b.carried_entries(port)})
            entries = b.port_entries(port)
            stored.append({"nentries": len(entries), "entries": ", ".join(map(str, entries)),
                           "noutgoing": len(outgoing), "outgoing": ", ".join(map(str, outgoing))})
        blocks.append({"slot": slot, "affine": affine, "offsets": list(b.offset_range()), "stored": stored,
                       "count": [b.loop.count.const, sum(c for _, c in b.loop.count.terms)],
                       "sites": [b.loop.sites.const, sum(c for _, c in b.loop.sites.terms)],
                       "periodic": int(b.loop.boundary == "periodic"), "width": len(b.entries),
                       "entries": ", ".join(f"{r}, {c}" for r, c in b.entries)})
    return {"prefix": prefix, "blocks": blocks}


def _kernel(ir: KernelIR, facts: ExportFacts) -> dict:
    prefix = f"{facts.model}_{ir.name}"
    ctx = kernel_context(ir)
    args = ["long nbatch"] + [f"long {s}" for s in ir.sizes]
    args += [f"const {'long' if p.integer else 'double'} *in_{p.name}" for p in ir.inputs]
    args += [f"double *out_{p.name}" for p in ir.outputs]
    ins = [f"(const double *)(const void *)in_{p.name}" if p.integer else f"in_{p.name}" for p in ir.inputs]
    doc = [f"{prefix}: {c_comment(ir.doc)}"]
    if "_at_" in ir.name:
        at = ir.name.split("_at_", 1)[1]
        doc.append(f"point term of '{at}' (an end or a part of the continuum): evaluate it at the point where "
                   f"'{at}' sits (nbatch such points) and add it to the discretised equations there")
    elif ir.meta.get("kind") == "field":
        doc.append("pointwise kernel of a continuum: one state per point (nbatch points, e.g. quadrature points)")
    doc.append("inputs (state ports: nbatch x length, row-major):")
    doc += ["  " + line for p in ir.inputs for line in _input_doc(ir, p, facts, prefix)]
    doc.append("outputs (nbatch x length, row-major; the kernel zeroes them first):")
    doc += ["  " + line for p in ir.outputs for line in _output_doc(ir, p, facts, prefix)]
    if ir.sizes:
        doc.append("sizes (in this order in the batch ABI's sizes[]): " + ", ".join(ir.sizes)
                   + ("; nnz from " + prefix + "_nnz(sites)" if "nnz" in ir.sizes else ""))
    doc.append("returns 0")
    pattern = _pattern_context(ir, prefix)
    return {"prefix": prefix, "doc": [c_comment(line) for line in doc], "prologue": ctx["prologue"],
            "body": ctx["body"], "args": args, "ins": ins, "outs": [f"out_{p.name}" for p in ir.outputs],
            "sizes": list(ir.sizes), "nin": max(len(ir.inputs), 1), "nout": max(len(ir.outputs), 1),
            "nsizes": max(len(ir.sizes), 1), "pattern": pattern}


def emit_c_export(irs: list[KernelIR], facts: ExportFacts) -> tuple[str, str]:
    """(header text, source text) of the standalone C export of ``irs``."""
    kernels = [_kernel(ir, facts) for ir in irs]
    head = [f"Generated by mechgen {__version__} from model {facts.model}: do not edit.", ""]
    head += c_comment(facts.doc).split("\n") if facts.doc else []
    if facts.title:
        head += ["", "specialisation: " + c_comment(facts.title)]
    if facts.fixed:
        head += ["", "parameters folded into the code (not inputs):"]
        head += [f"  {n} = {c_comment(v)}" for n, v in facts.fixed.items()]
    context = {"model": facts.model, "guard": f"MECHGEN_EXPORT_{facts.model.upper()}_H",
               "head": [line.rstrip() for line in c_comment_lines("\n".join(head))], "kernels": kernels,
               "patterns": any(k["pattern"] for k in kernels)}
    return render("c99/export.h.j2", **context), render("c99/export.c.j2", **context)
