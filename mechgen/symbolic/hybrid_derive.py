"""A hybrid model's derived equations: every mode's Lagrange equations (mechgen.symbolic.derive), the guards
leaving it with their rates along the mode's flow, and the reset maps (:func:`derive_hybrid`). What the model
declares of its modes and guards, and the checks of it, are mechgen.symbolic.hybrid's."""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from mechgen.symbolic.declared import as_expr, call_declared
from mechgen.symbolic.derive import TIME, derive_lumped
from mechgen.symbolic.hybrid import Guard, check_hybrid, guards_of, reset_state
from mechgen.symbolic.params import Namespace
from mechgen.symbolic.specialize import param_namespace


@dataclass(frozen=True)
class GuardEquations:
    """One guard of a mode as derived: its value g and total time derivative g_t along the mode's flow."""

    guard: Guard
    g: sp.Expr
    g_t: sp.Expr
    reset: int | None  # index into HybridEquations.resets (None: no reset, the state is kept)


@dataclass(frozen=True)
class HybridEquations:
    """Per mode, the derived equations (mechgen.symbolic.derive.LumpedEquations) and the guards leaving it;
    the reset maps (new state as a column of 2n + m entries)."""

    modes: tuple[str, ...]
    initial: int
    equations: tuple
    guards: tuple[tuple[GuardEquations, ...], ...]
    resets: tuple[sp.Matrix, ...]

    def meta(self) -> dict:
        """What the runtime needs to know of the modes and guards (JSON, in every kernel's meta)."""
        return {"modes": list(self.modes), "initial": self.initial,
                "guards": [[{"name": ge.guard.name, "direction": ge.guard.direction, "terminal": ge.guard.terminal,
                             "to": None if ge.guard.to is None else self.modes.index(ge.guard.to),
                             "reset": ge.reset} for ge in mode] for mode in self.guards]}


def derive_hybrid(model, spec) -> HybridEquations:
    """Derive every mode's equations, its guards (g and dg/dt) and the reset maps of a hybrid model."""
    check_hybrid(model)
    modes = model.mode_names
    equations = tuple(derive_lumped(model, spec, mode) for mode in modes)
    first = equations[0]
    q_ns = Namespace({**{n: s for n, s in zip(first.coordinates, first.q)},
                      **{n: sp.Integer(0) for n in model.coordinate_names if n not in first.coordinates}})
    v_ns = Namespace({**{n: s for n, s in zip(first.coordinates, first.v)},
                      **{n: sp.Integer(0) for n in model.coordinate_names if n not in first.coordinates}})
    z_ns = Namespace(dict(zip(first.internal_names, first.z)))
    p_ns, _ = param_namespace(model, spec)
    env = {"q": q_ns, "v": v_ns, "z": z_ns, "p": p_ns, "t": TIME}
    resets: list[sp.Matrix] = []
    reset_of: dict[int, int] = {}
    per_mode = []
    for mode, eqs in zip(modes, equations):
        out = []
        for guard in guards_of(model, mode):
            g = as_expr(call_declared(guard.fn, **env), f"guard {guard.name}", model)
            zdot = dict(zip(eqs.z, eqs.rates))
            g_t = (sum((sp.diff(g, s) * d for s, d in zip(eqs.q, eqs.v)), sp.Integer(0))
                   + sum((sp.diff(g, s) * d for s, d in zip(eqs.v, eqs.a)), sp.Integer(0))
                   + sum((sp.diff(g, s) * zdot[s] for s in eqs.z), sp.Integer(0)) + sp.diff(g, TIME))
            index = None
            if guard.reset is not None:
                key = id(guard)
                if key not in reset_of:
                    raw = call_declared(guard.reset, **env)
                    new = reset_state(model, guard, raw, eqs.coordinates, eqs.q, eqs.v, eqs.z)
                    column = [as_expr(e, f"reset of guard {guard.name}", model) for e in new]
                    reset_of[key] = len(resets)
                    resets.append(sp.Matrix(column))
                index = reset_of[key]
            out.append(GuardEquations(guard, g, g_t, index))
        per_mode.append(tuple(out))
    return HybridEquations(modes, modes.index(model.initial_mode), equations, tuple(per_mode), tuple(resets))
