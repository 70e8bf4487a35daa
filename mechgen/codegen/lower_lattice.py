"""Kernels of a chain model: a site loop and a bond loop, the same IR for every N.

Sites e = 0..N-1 (runtime size ``sites``). Bonds join neighbours: with fixed
ends bond e (e = 0..N) joins sites e-1 and e, the ghost sites -1 and N being
zero; with periodic ends bond e (e = 0..N-1) joins sites e and e+1 mod N.
Sparse matrices are written into the data array of one CSR pattern (runtime
size ``nnz``) through slot tables the runtime fills once.

Kernel names as for lumped models (:mod:`mechgen.codegen.lower_lumped`):
``residual``, ``tangent``, ``linear``, ``force`` (with the meta ``separable``), ``outputs``; plus ``stiffness``,
K = d2V/du2 alone (at a = 0), the Jacobian Newton and the benchmarks need.
"""
from __future__ import annotations

import sympy as sp

from mechgen.codegen.ir import Block, Extent, KernelIR, Loop, Port, Write, fixed, sized
from mechgen.codegen.lower import canonical_block, kernel
from mechgen.codegen.lower_lumped import separable_meta
from mechgen.symbolic.lattice import LatticeEquations
from mechgen.symbolic.separable import lattice_obstacle

LATTICE_KERNELS = ("residual", "tangent", "linear", "stiffness", "force", "outputs")
SITES = sized("sites")
NNZ = sized("nnz")


def _loops(eqs: LatticeEquations) -> tuple[Loop, Loop, tuple[int, int]]:
    site_loop = Loop(SITES, SITES, "zero")
    if eqs.ends == "periodic":
        return site_loop, Loop(SITES, SITES, "periodic"), (0, 1)
    return site_loop, Loop(sized("sites", 1, 1), SITES, "zero"), (-1, 0)


def _inputs(eqs: LatticeEquations, accel: bool) -> tuple[list[Port], list]:
    ports = [Port("q", SITES), Port("v", SITES)] + ([Port("a", SITES)] if accel else [])
    ports.append(Port("p", fixed(len(eqs.params)), batched=False))
    params = [(s, "p", i, False) for i, s in enumerate(eqs.params)]
    return ports, params


def _site_gathers(eqs: LatticeEquations) -> list:
    return [(eqs.site_q, "q", 0, True), (eqs.site_v, "v", 0, True), (eqs.site_a, "a", 0, True)]


def _bond_gathers(eqs: LatticeEquations, offsets: tuple[int, int]) -> list:
    return [(s, "q", k, True) for s, k in zip(eqs.bond_q, offsets)]


def _block(gathers, writes, loop, eqs, cse) -> list[Block]:
    writes = [w for w in writes if w.expr != 0]
    return [canonical_block(gathers, writes, loop=loop, cse=cse, model=eqs.model)] if writes else []


def _blocks(eqs: LatticeEquations, site_writes, bond_writes, params, cse) -> list[Block]:
    site_loop, bond_loop, offsets = _loops(eqs)
    return (_block(_site_gathers(eqs) + params, site_writes, site_loop, eqs, cse)
            + _block(_bond_gathers(eqs, offsets) + params, bond_writes, bond_loop, eqs, cse))


def _vector_writes(port: str, site_expr: sp.Expr, bond_exprs, offsets) -> tuple[list, list]:
    site = [Write(port, 0, site_expr, accumulate=True, relative=True)]
    bond = [Write(port, k, e, accumulate=True, relative=True) for k, e in zip(offsets, bond_exprs)]
    return site, bond


def _matrix_writes(ports_site: dict, hessian, offsets) -> tuple[list, list]:
    site = [Write(port, 0, e, accumulate=True, relative=True, entry=(0, 0)) for port, e in ports_site.items()]
    bond = [Write("K" if "K" in ports_site else "r_q", 0, hessian[i][j], accumulate=True, relative=True,
                  entry=(offsets[i], offsets[j])) for i in range(2) for j in range(2)]
    return site, bond


def lower_lattice(eqs: LatticeEquations, name: str, *, cse: bool = True) -> KernelIR:
    """Build the KernelIR of kernel ``name`` (one of :data:`LATTICE_KERNELS`)."""
    _, _, offsets = _loops(eqs)
    meta = {"model": eqs.model, "coordinates": [eqs.coordinate], "params": list(eqs.param_names),
            "kind": "lattice", "sites_param": eqs.sites, "ends": eqs.ends, "bond_offsets": list(offsets)}
    accel = name in ("residual", "tangent")
    inputs, params = _inputs(eqs, accel)
    at_rest = {eqs.site_a: 0}
    sizes: tuple[str, ...] = ("sites",)
    if name in ("residual", "force"):
        sign = 1 if name == "residual" else -1
        site_expr = eqs.site_residual if name == "residual" else sp.diff(eqs.site_potential, eqs.site_q)
        port = "r" if name == "residual" else "f"
        site, bond = _vector_writes(port, sign * site_expr, [sign * g for g in eqs.bond_gradient()], offsets)
        outputs = [Port(port, SITES)]
        if name == "force":
            meta.update(separable_meta(lattice_obstacle(eqs.site_kinetic, eqs.site_potential, eqs.bond_potential,
                                                        eqs.site_q, eqs.site_v, eqs.coordinate)))
    elif name in ("tangent", "linear", "stiffness"):
        tan = eqs.site_tangent()
        if name == "tangent":
            mats = {"r_q": tan["q"], "r_v": tan["v"], "r_a": tan["a"]}
        elif name == "linear":
            mats = {"M": tan["a"].subs(at_rest), "D": tan["v"].subs(at_rest), "K": tan["q"].subs(at_rest)}
        else:
            mats = {"K": tan["q"].subs(at_rest)}
        site, bond = _matrix_writes(mats, eqs.bond_hessian(), offsets)
        names = {"tangent": list(mats), "linear": ["M", "D", "G", "K"], "stiffness": ["K"]}[name]
        outputs = [Port(k, NNZ, sparse=True, symmetric=k in ("M", "D", "K")) for k in names]
        sizes = ("sites", "nnz")
    elif name == "outputs":
        T, Vs = eqs.site_kinetic, eqs.site_potential
        site = [Write("kinetic_energy", 0, T, accumulate=True), Write("potential_energy", 0, Vs, accumulate=True),
                Write("energy", 0, T + Vs, accumulate=True)]
        bond = [Write("potential_energy", 0, eqs.bond_potential, accumulate=True),
                Write("energy", 0, eqs.bond_potential, accumulate=True)]
        outputs = [Port(k, fixed(1), shape=(1, 1)) for k in ("kinetic_energy", "potential_energy", "energy")]
    else:
        raise KeyError(name)
    blocks = _blocks(eqs, site, bond, params, cse)
    return kernel(name, f"chain kernel {name}", inputs, outputs, blocks, sizes, meta)


__all__ = ["LATTICE_KERNELS", "lower_lattice", "Extent"]
