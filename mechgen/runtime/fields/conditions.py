"""A compiled continuum's essential conditions and substructure joints, and the reduction x = Z q they give.

The rows C x = 0 are the model's essential end conditions (a jet's value at s = 0 or s = L) and, with
``joints = "multiplier"``, the continuity of substructures at segment interfaces; the reduction
(mechgen.runtime.fields.constrain: elimination, penalty with its factor, Lagrange multipliers) maps the reduced
unknowns q to the full dof vector x. The functions take a :class:`~mechgen.runtime.fields.continuum.FieldSystem`.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.fields import constrain
from mechgen.runtime.fields.assemble import element_matrices
from mechgen.runtime.fields.constrain import PenaltyChoice, Reduction, penalty_choice, reduction
from mechgen.runtime.fields.point_kernels import coefficients, pointwise, segment_params, state_jets, stiffness


def reduction_key(system) -> tuple:
    """The reduction depends on the discretisation, and on the parameters through multiplier joints."""
    joints = system.choices.get("joints", "assembly") == "multiplier"
    return system.disc_key(system.param_key if joints else None)


def constraint_rows(system) -> tuple[list, list, list]:
    """(field, order, end), dense row C_i and the jet's table magnitude of every essential condition."""
    disc = system.disc
    keys, rows, scales = [], [], []
    for f, k, at in system.field_meta.constraints:
        keys.append((f, k, at))
        rows.append(disc.row(f, k, 0.0 if at == "start" else disc.length))
        scales.append(float(np.abs(disc.tables[:, :, disc.jets.index((f, k)), :]).max()))
    return keys, rows, scales


def joint_rows(system) -> list[np.ndarray]:
    """Continuity rows of substructures at segment interfaces (``joints = "multiplier"``), as in Yu & Cleghorn.

    At an interface s_j: every field's value from the left equals that from
    the right, and so do derivatives the energy needs continuous (orders below
    its highest); a derivative dof the energy does not need continuous (C1
    elements, first-order energy) is tied instead by continuity of the force
    conjugate to it (:func:`flux_row`). Rows are scaled to a largest entry of 1.
    """
    disc = system.disc
    mesh = disc.mesh
    if system.choices.get("joints", "assembly") != "multiplier" or mesh is None or not len(mesh.interfaces):
        return []
    top = max(k for _, k in disc.jets)
    orders = (0,) if disc.kind in ("lagrange1", "lagrange2", "timoshenko2") else (0, 1)
    seg_params = segment_params(system)
    rows = []
    for v in mesh.interfaces:
        x = float(mesh.nodes[v])
        for f in disc.fields:
            for k in orders:
                if k < top:
                    rows.append(disc.row(f, k, x, "left") - disc.row(f, k, x, "right"))
                else:
                    rows.append(flux_row(system, seg_params, v, x, (f, k)))
    return [r / max(np.abs(r).max(), 1e-300) for r in rows]


def flux_row(system, seg_params, vertex: int, x: float, jet: tuple) -> np.ndarray:
    """The jump, left minus right, at interface ``vertex`` (s = x) of the flux conjugate to ``jet`` = (f, 1):
    F_f = sum_b K[(f, 1), b] j_b with K the pointwise stiffness of each side's segment (kGA (u_s - psi) in N and
    EI psi_s in N m for a shaft)."""
    disc = system.disc
    mesh = disc.mesh
    jets = list(disc.jets)
    a = jets.index(jet)
    row = np.zeros(disc.ndof)
    for side, seg in (("left", mesh.segment[vertex - 1]), ("right", mesh.segment[vertex])):
        params = None if seg_params is None else seg_params[seg]
        K = stiffness(system, np.array([x]), params=params)[0]
        flux = sum(K[a, b] * disc.row(*jets[b], x, side) for b in np.flatnonzero(K[a]))
        row = row + (flux if side == "left" else -flux)
    return row


def build_reduction(system) -> Reduction:
    """x = Z q for the essential conditions (and multiplier joints) by the system's ``constraints`` method."""
    disc = system.disc
    _, rows, scales = constraint_rows(system)
    joints = joint_rows(system)
    red = reduction(np.array(rows), np.array(scales), disc.ndof, system.choices["constraints"],
                    sparse=not disc.is_global and not joints, joints=np.array(joints) if joints else None)
    if red.penalty_rows is not None and disc.is_global:
        raise InputError(f"penalty constraints with the global {disc.kind} basis couple every function "
                         "to the penalty and wreck the conditioning", key="constraints",
                         expected="'eliminate' for global bases (penalty with finite elements)")
    return red


def choose_penalty(system) -> PenaltyChoice | None:
    """The penalty factor and its error model from the unconstrained zero-state K and M (None without penalty
    rows; mechgen.runtime.fields.constrain.penalty_choice), memoised per reduction and parameters."""
    if system.reduction.penalty_rows is None:
        return None

    def choose() -> PenaltyChoice:
        local = pointwise(system, "linear", state_jets(system, None))
        disc = system.disc
        K, M = (system.assembler.matrix(element_matrices(disc.tables, disc.weights, coefficients(system, local[k])))
                for k in ("K", "M"))
        return penalty_choice(system.reduction, K, M, constrain.FIXED_FACTOR)

    return system.memo(("alpha", *reduction_key(system), system.param_key, constrain.FIXED_FACTOR), choose)


def row_penalties(system):
    """alpha_j of each penalty row (0.0 without penalty rows)."""
    choice = system.penalty_choice
    return 0.0 if choice is None else choice.alphas
