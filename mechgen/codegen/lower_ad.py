"""Kernels of a lumped model derived by AD (mechgen.symbolic.derive_ad): SX graphs -> the Kernel IR.

The kernels, their ports and their meaning are those of :mod:`mechgen.codegen.lower_lumped` (``residual``,
``tangent``, ``flow``, ``linear``, ``force``, ``rates``, ``rates_tangent``, ``energy_rates``, ``outputs``,
``lagrangian``). Each is a ``casadi.Function`` of the state whose algorithm, CasADi's straight-line program
with its common subexpressions already shared, becomes one block: an input instruction a gathered local
``g``, each operation an :class:`~mechgen.codegen.ir.Operation` assigning a fresh temporary ``t`` (single
assignment: CasADi reuses its work registers, the IR does not), an output instruction a write. No sympy object
is made per operation and no sympy CSE or Horner pass runs over it (the backends print operations from
:mod:`mechgen.codegen.program_text`), so the lowering is linear in the program's length. Structural zeros (entries that are the constant 0) are not written,
as :func:`mechgen.codegen.lower.dense_writes` skips them.
"""
from __future__ import annotations

import hashlib

import casadi as ca
import sympy as sp

from mechgen.codegen.ir import Block, Gather, KernelIR, Operation, Port, Write, fixed
from mechgen.codegen.lower import kernel
from mechgen.codegen.lower_lumped import lumped_meta, separable_meta, state_ports
from mechgen.codegen.program_text import atom_expr
from mechgen.symbolic.casadi_form import NotConvertible

#: CasADi's operation codes -> the Kernel IR's operation names (mechgen.codegen.program_text)
_OPERATIONS = {ca.OP_ADD: "add", ca.OP_SUB: "sub", ca.OP_MUL: "mul", ca.OP_DIV: "div", ca.OP_POW: "pow",
               ca.OP_CONSTPOW: "constpow", ca.OP_ATAN2: "atan2", ca.OP_FMIN: "fmin", ca.OP_FMAX: "fmax",
               ca.OP_NEG: "neg", ca.OP_SQ: "sq", ca.OP_TWICE: "twice", ca.OP_INV: "inv", ca.OP_SQRT: "sqrt",
               ca.OP_EXP: "exp", ca.OP_LOG: "log", ca.OP_SIN: "sin", ca.OP_COS: "cos", ca.OP_TAN: "tan",
               ca.OP_ASIN: "asin", ca.OP_ACOS: "acos", ca.OP_ATAN: "atan", ca.OP_SINH: "sinh", ca.OP_COSH: "cosh",
               ca.OP_TANH: "tanh", ca.OP_ASINH: "asinh", ca.OP_ACOSH: "acosh", ca.OP_ATANH: "atanh",
               ca.OP_FABS: "fabs", ca.OP_SIGN: "sign"}
_TWO = frozenset({"add", "sub", "mul", "div", "pow", "constpow", "atan2", "fmin", "fmax"})


def program_block(fn: ca.Function, ports: list[str], writes: list[tuple[str, int]]) -> Block:
    """The Block of an SX function: inputs ``ports`` (in order), one output whose entries are ``writes``
    ((port, index) each). A work register holds a name (str) or a number (float); an assignment copies."""
    work: dict[int, str | float] = {}
    gathers: dict[tuple[str, int], Gather] = {}
    operations, out = [], []
    digest, ops = hashlib.sha256(repr((ports, writes)).encode()), 0
    for k in range(fn.n_instructions()):
        op, dst, src = fn.instruction_id(k), fn.instruction_output(k), fn.instruction_input(k)
        constant = fn.instruction_constant(k) if op == ca.OP_CONST else None
        digest.update(f"{op} {dst} {src} {constant!r};".encode())
        if op == ca.OP_INPUT:
            key = (ports[src[0]], src[1])
            if key not in gathers:
                gathers[key] = Gather(sp.Symbol(f"g{len(gathers)}", real=True), key[0], key[1], False)
            work[dst[0]] = gathers[key].symbol.name
        elif op == ca.OP_CONST:
            work[dst[0]] = float(constant)
        elif op == ca.OP_OUTPUT:
            port, index = writes[dst[1]]
            out.append(Write(port, index, atom_expr(work[src[0]])))
        elif op == ca.OP_ASSIGN:
            work[dst[0]] = work[src[0]]
        else:
            ops += 1
            operations.append(_operation(op, f"t{len(operations)}", [work[i] for i in src]))
            work[dst[0]] = operations[-1].target
    return Block(tuple(gathers.values()), tuple(out), (), None, (digest.hexdigest(), ops), tuple(operations))


def _operation(op: int, target: str, args: list) -> Operation:
    name = _OPERATIONS.get(op)
    if name is None or len(args) != (2 if name in _TWO else 1):
        raise NotConvertible(f"CasADi operation {op} has no Kernel IR form")
    return Operation(target, name, tuple(args))


def lower_sx(eqs, name: str, doc: str, mats: dict[str, ca.SX], *, accel: bool, symmetric: tuple[str, ...] = (),
             extra: dict | None = None) -> KernelIR:
    """A kernel of named SX matrices (row-major, as lower_lumped's ports) of the state."""
    inputs, _ = state_ports(eqs, accel)
    names = [p.name for p in inputs]
    sx_inputs = [eqs.inputs[n] if n != "t" else eqs.inputs["t"] for n in names]
    entries, writes = [], []
    for port, m in mats.items():
        m = ca.SX(m)
        for i in range(m.size1()):
            for j in range(m.size2()):
                e = m[i, j]
                if not e.is_zero():
                    entries.append(e)
                    writes.append((port, i * m.size2() + j))
    fn = ca.Function(f"k_{name}", sx_inputs, [ca.vertcat(*entries) if entries else ca.SX(0, 1)])
    block = program_block(fn, names, writes)
    outputs = [Port(k, fixed(ca.SX(m).numel()), shape=ca.SX(m).shape, symmetric=k in symmetric)
               for k, m in mats.items()]
    return kernel(name, doc, inputs, outputs, [block], meta={**lumped_meta(eqs), **(extra or {})})


def kernel_matrices(eqs, name: str) -> tuple[str, dict, bool, tuple]:
    """(doc, {port: SX}, whether the acceleration is an input, symmetric ports) of kernel ``name``."""
    x = eqs.inputs
    if name in ("residual", "tangent", "flow", "linear"):
        M, h, r = eqs.mass(), eqs.bias(), eqs.residual()
        if name == "residual":
            return "Lagrange residual r = M a + h (AD)", {"r": r}, True, ()
        if name == "tangent":
            mats = {"r_q": ca.jacobian(r, x["q"]), "r_v": ca.jacobian(r, x["v"]), "r_a": M,
                    "r_z": ca.jacobian(r, x["z"])}
            return "Jacobians of the residual (AD)", mats, True, ()
        if name == "flow":
            return "r at a = 0 and M = dr/da (AD)", {"r": h, "M": M}, False, ()
        C, K = ca.jacobian(h, x["v"]), ca.jacobian(h, x["q"])
        mats = {"M": M, "D": (C + C.T) / 2, "G": (C - C.T) / 2, "K": K}
        return "M, D, G, K of the linearisation, a = 0 (AD)", mats, False, ("M", "D")
    return _other_matrices(eqs, name)


def _other_matrices(eqs, name: str) -> tuple[str, dict, bool, tuple]:
    x, pc = eqs.inputs, eqs.pieces
    if name == "force":
        return "potential force -dV/dq (AD)", {"f": -ca.gradient(pc["V"], x["q"])}, False, ()
    if name == "rates":
        return "internal rates dz/dt", {"g": pc["g"]}, False, ()
    if name == "rates_tangent":
        return "Jacobians of the internal rates (AD)", {f"g_{w}": ca.jacobian(pc["g"], x[w]) for w in "qvz"}, False, ()
    if name == "energy_rates":
        return "internal rates and the energy balance's powers (AD)", _energy_rates(eqs), False, ()
    if name == "outputs":
        return "named outputs", {k: e for k, e in eqs.outputs.items()}, False, ()
    if name == "lagrangian":
        p = eqs.momentum()
        F = ca.gradient(pc["T"] - pc["V"], x["q"]) - ca.gradient(pc["R"], x["v"]) + pc["Q"]
        mats = {"mom": p, "F": F, "mom_q": ca.jacobian(p, x["q"]), "mom_v": ca.jacobian(p, x["v"]),
                "F_q": ca.jacobian(F, x["q"]), "F_v": ca.jacobian(F, x["v"])}
        return "momentum p = dT/dv, force F = dL/dq + Q - dR/dv and their Jacobians (AD)", mats, False, ()
    raise KeyError(name)


def _energy_rates(eqs) -> dict:
    """g = (dz/dt, Q.v, v.dR/dv, -dL/dt) and the excess v.dT/dv - 2 T, each exact zero where the declared pieces
    show it (ADEquations.zero_powers, .quadratic): the energy balance then calls the run conservative."""
    x, pc = eqs.inputs, eqs.pieces
    v, t = x["v"], x["t"]
    powers = [ca.dot(pc["Q"], v), ca.dot(v, ca.gradient(pc["R"], v)), ca.jacobian(pc["V"] - pc["T"], t)]
    powers = [ca.SX(0) if zero else e for e, zero in zip(powers, eqs.zero_powers)]
    excess = ca.SX(0) if eqs.quadratic else ca.dot(v, eqs.momentum()) - 2 * pc["T"]
    return {"g": ca.vertcat(pc["g"], *powers), "excess": excess}


def lower_ad(eqs, name: str) -> KernelIR:
    """Build the KernelIR of kernel ``name`` of AD-derived equations (mechgen.symbolic.derive_ad.ADEquations)."""
    doc, mats, accel, symmetric = kernel_matrices(eqs, name)
    extra = separable_meta(eqs.separable_why) if name == "force" else None
    return lower_sx(eqs, name, doc, mats, accel=accel, symmetric=symmetric, extra=extra)
