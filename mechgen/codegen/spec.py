"""The kernel spec: the JSON-able description of a kernel that the runtime reads.

The runtime never imports sympy; everything it needs to call a kernel (port
order and lengths, sizes, sparse pattern recipe) is in this dict, which is
stored beside every generated artefact.
"""
from __future__ import annotations

from mechgen.codegen.ir import KernelIR, Port


def _port(p: Port) -> dict:
    return {"name": p.name, "extent": p.extent.to_json(), "batched": p.batched, "integer": p.integer,
            "shape": list(p.shape) if p.shape else None, "sparse": p.sparse, "symmetric": p.symmetric}


def kernel_spec(ir: KernelIR) -> dict:
    """Spec of one kernel: ports, sizes, slot recipes and op count.

    A slot recipe has the loop count, sites and boundary, the entry offsets, the
    block's site offset range (its unchecked interior) and, for the affine
    summary, the ports stored there with their entries and carried pairs
    (see :meth:`~mechgen.codegen.ir.KernelIR.affine_ports`).
    """
    slots = []
    for (i, port), (_, affine) in zip(ir.slot_ports(), ir.affine_ports()):
        b = ir.blocks[i]
        stored = [{"port": p, "entries": list(b.port_entries(p)), "carried": [list(c) for c in b.carried_entries(p)]}
                  for p in ir.stored_ports(i)]
        slots.append({"port": port, "count": b.loop.count.to_json(), "sites": b.loop.sites.to_json(),
                      "boundary": b.loop.boundary, "entries": [list(e) for e in b.entries],
                      "affine": affine, "offsets": list(b.offset_range()), "stored": stored})
    return {"name": ir.name, "doc": ir.doc, "inputs": [_port(p) for p in ir.inputs],
            "outputs": [_port(p) for p in ir.outputs], "sizes": list(ir.sizes), "slots": slots,
            "ops": ir.op_count(), "signature": ir.signature(), "meta": ir.meta}
