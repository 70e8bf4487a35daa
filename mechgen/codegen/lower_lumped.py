"""Kernels of a lumped model (no repetition): one straight-line block each.

Kernel names and what they compute (n coordinates, m internal variables):

* ``residual``  r(q, v, a, z, t)                       -> r[n]
* ``tangent``   dr/dq, dr/dv, dr/da, dr/dz            -> r_q[n*n], r_v[n*n], r_a[n*n], r_z[n*m]
* ``flow``      what a time step needs of the residual, in one block: r(q, v, 0, z, t), M = dr/da -> r[n], M[n*n]
* ``linear``    M, D, G, K at (q, v, z, t) with a = 0  -> M, D, G, K [n*n]
* ``force``     -dV/dq                                 -> f[n]  (meta ``separable``: fit for the splittings,
                mechgen.symbolic.separable; ``separable_why``: why not)
* ``rates``     dz/dt = g(q, v, z, t)                  -> g[m]
* ``lagrangian`` p = dT/dv, F = dL/dq + Q - dR/dv at (q, v, t) and their Jacobians (LumpedEquations.lagrangian)
                                                       -> mom[n] (p), F[n], mom_q, mom_v, F_q, F_v [n*n]
                (a smooth model without internal variables: the variational integrator's dp/dt = F)
* ``rates_tangent``                                    -> g_q[m*n], g_v[m*n], g_z[m*m]
* ``energy_rates`` the internal rates and the powers of the energy balance (mechgen.symbolic.derive.energy_powers)
                -> g[m + 3] = (dz/dt, Q.v, v.dR/dv, -dL/dt), excess[1] = v.dT/dv - 2 T
* ``outputs``   declared outputs and energies          -> one port of length 1 each
* ``section``   the declared section stiffness K(p)    -> K[36] (6 x 6, symmetric; Model.section_stiffness)
* ``rod``       a declared rod's local pieces at (f, r) -> sigma[6], C[36], W[1], f0[6], g[6], g_r[18], L[1], M[36]
                (Model.rod, mechgen.symbolic.rod: sigma = K (f - f0), the spatial load wrench g(r); batched)

A hybrid model (mechgen.symbolic.hybrid) has each of these per mode i, named ``<kernel>__i``, and

* ``guards__i`` the guards leaving mode i, g(q, v, z, t) and dg/dt(q, v, a, z, t) -> g[k], g_t[k]
* ``reset__j``  the state after reset j, (q+, v+, z+)(q, v, z, t)             -> x[2n+m]
"""
from __future__ import annotations

import sympy as sp

from mechgen.codegen.ir import KernelIR, Port, fixed
from mechgen.codegen.lower import canonical_block, dense_writes, kernel
from mechgen.errors import ModelError
from mechgen.symbolic.derive import LumpedEquations
from mechgen.symbolic.separable import separable_obstacle

LUMPED_KERNELS = ("residual", "tangent", "flow", "linear", "force", "rates", "rates_tangent", "energy_rates", "outputs",
                  "section", "rod", "lagrangian")


def state_ports(eqs: LumpedEquations, with_accel: bool = True) -> tuple[list[Port], list]:
    n, m = len(eqs.q), len(eqs.z)
    ports = [Port("q", fixed(n))] + [Port("v", fixed(n))]
    if with_accel:
        ports.append(Port("a", fixed(n)))
    ports += [Port("z", fixed(m)), Port("t", fixed(1))]
    if eqs.position:
        ports.append(Port("s", fixed(len(eqs.position)), doc="position along the domain"))
    ports.append(Port("p", fixed(len(eqs.params)), batched=False))
    gathers = [(s, "q", i, False) for i, s in enumerate(eqs.q)]
    gathers += [(s, "v", i, False) for i, s in enumerate(eqs.v)]
    if with_accel:
        gathers += [(s, "a", i, False) for i, s in enumerate(eqs.a)]
    gathers += [(s, "z", i, False) for i, s in enumerate(eqs.z)] + [(eqs.t, "t", 0, False)]
    gathers += [(s, "s", i, False) for i, s in enumerate(eqs.position)]
    gathers += [(s, "p", i, False) for i, s in enumerate(eqs.params)]
    return ports, gathers


def _matrix_kernel(eqs: LumpedEquations, name: str, doc: str, mats: dict[str, sp.Matrix], *, accel: bool,
                   cse: bool, symmetric: tuple[str, ...] = (), extra: dict | None = None) -> KernelIR:
    inputs, gathers = state_ports(eqs, accel)
    outputs = [Port(k, fixed(m.rows * m.cols), shape=(m.rows, m.cols), symmetric=k in symmetric)
               for k, m in mats.items()]
    writes = [w for k, m in mats.items() for w in dense_writes(k, m)]
    block = canonical_block(gathers, writes, cse=cse, model=eqs.model)
    return kernel(name, doc, inputs, outputs, [block], meta={**lumped_meta(eqs), **(extra or {})})


def separable_meta(why: str | None) -> dict:
    """The force kernel's record of mechgen.symbolic.separable: ``separable`` (H = v^T M v / 2 + V(q) with a
    constant diagonal M and nothing else: fit for the splittings) and ``separable_why`` (the reason when not)."""
    return {"separable": why is None, "separable_why": why or ""}


def lumped_meta(eqs: LumpedEquations) -> dict:
    return {"model": eqs.model, "coordinates": list(eqs.coordinates), "internal": list(eqs.internal_names),
            "params": list(eqs.param_names), "kind": "field" if eqs.position else "lumped"}


def lower_matrices(eqs: LumpedEquations, name: str, doc: str, mats: dict[str, sp.Matrix], *,
                   cse: bool = True, accel: bool = False) -> KernelIR:
    """A kernel of named matrices of the state (an acceleration input with ``accel``), e.g. a constraint's
    derivatives, a hybrid model's guards."""
    return _matrix_kernel(eqs, name, doc, mats, accel=accel, cse=cse)


def lower_lumped(eqs: LumpedEquations, name: str, *, cse: bool = True) -> KernelIR:
    """Build the KernelIR of kernel ``name`` (one of :data:`LUMPED_KERNELS`)."""
    r = eqs.residual
    if name == "residual":
        return _matrix_kernel(eqs, name, "Lagrange residual r = M a - f", {"r": r}, accel=True, cse=cse)
    if name == "tangent":
        mats = {f"r_{w}": eqs.residual_jacobian(w) for w in ("q", "v", "a", "z")}
        return _matrix_kernel(eqs, name, "Jacobians of the residual", mats, accel=True, cse=cse)
    if name == "flow":
        M, h = eqs.split()
        mats = {"r": h, "M": M}
        return _matrix_kernel(eqs, name, "r at a = 0 and M = dr/da (dx/dt = (v, -M^-1 r))", mats, accel=False, cse=cse)
    if name == "linear":
        return _matrix_kernel(eqs, name, "M, D, G, K of the linearisation (a = 0)", eqs.linear_matrices(),
                              accel=False, cse=cse, symmetric=("M", "D"))
    if name == "force":
        why = separable_obstacle(eqs.kinetic, eqs.potential, eqs.residual, eqs.q, eqs.v, eqs.a, (eqs.t, *eqs.z),
                                 eqs.coordinates)
        return _matrix_kernel(eqs, name, "potential force -dV/dq", {"f": eqs.force()}, accel=False, cse=cse,
                              extra=separable_meta(why))
    if name == "lagrangian":
        return _matrix_kernel(eqs, name, "momentum p = dT/dv, force F = dL/dq + Q - dR/dv and their Jacobians",
                              eqs.lagrangian(), accel=False, cse=cse)
    if name == "rates":
        return _matrix_kernel(eqs, name, "internal rates dz/dt", {"g": eqs.rates}, accel=False, cse=cse)
    if name == "rates_tangent":
        mats = {f"g_{w}": eqs.jacobian(eqs.rates, w) for w in ("q", "v", "z")}
        return _matrix_kernel(eqs, name, "Jacobians of the internal rates", mats, accel=False, cse=cse)
    if name == "energy_rates":
        mats = {"g": eqs.rates.col_join(eqs.power), "excess": sp.Matrix([[eqs.excess]])}
        return _matrix_kernel(eqs, name, "internal rates and the energy balance's powers", mats, accel=False, cse=cse)
    if name == "outputs":
        mats = {k: sp.Matrix([[e]]) for k, e in eqs.outputs.items()}
        return _matrix_kernel(eqs, name, "named outputs", mats, accel=False, cse=cse)
    if name == "section":
        if eqs.section is None:
            raise ModelError(f"model {eqs.model} declares no section stiffness", key="section_stiffness",
                             expected="a model with @model.section_stiffness (the cross_section analysis)")
        return _matrix_kernel(eqs, name, "cross-section stiffness K (6 x 6)", {"K": eqs.section}, accel=False,
                              cse=cse, symmetric=("K",))
    if name == "rod":
        return _rod_kernel(eqs, cse)
    raise KeyError(name)


def _rod_kernel(eqs: LumpedEquations, cse: bool) -> KernelIR:
    """sigma, C, W, f0, g, g_r, L and the mass per length M of the declared rod at a batch of (f, r)."""
    rod = eqs.rod
    if rod is None:
        raise ModelError(f"model {eqs.model} declares no rod", key="rod",
                         expected="a model with Model.rod(...) (the rod_statics analysis)")
    inputs = [Port("f", fixed(6), doc="deformation twist (nu, kappa)"), Port("r", fixed(3), doc="centre-line point"),
              Port("p", fixed(len(eqs.params)), batched=False)]
    gathers = [(s, "f", i, False) for i, s in enumerate(rod.f)] + [(s, "r", i, False) for i, s in enumerate(rod.r)]
    gathers += [(s, "p", i, False) for i, s in enumerate(eqs.params)]
    mats = {"sigma": rod.sigma, "C": rod.C, "W": sp.Matrix([[rod.energy]]), "f0": rod.f0, "g": rod.load,
            "g_r": rod.load_r, "L": sp.Matrix([[rod.length]]), "M": rod.M}
    outputs = [Port(k, fixed(m.rows * m.cols), shape=(m.rows, m.cols), symmetric=k in ("C", "M"))
               for k, m in mats.items()]
    writes = [w for k, m in mats.items() for w in dense_writes(k, m)]
    block = canonical_block(gathers, writes, cse=cse, model=eqs.model)
    return kernel("rod", "Cosserat rod: stress resultant, tangent, energy density, load", inputs, outputs, [block],
                  meta=lumped_meta(eqs))
