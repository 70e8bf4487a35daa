"""A compiled continuum: pointwise kernels + a discretisation = the discretised system.

The generated kernels evaluate, at a batch of points, the local residual rho(j,
j_t, j_tt) of the jets and its Jacobians (see mechgen.symbolic.field); this
class supplies the repetition numerically: jets at the Gauss points from the dof
vector, one batched kernel call over all points, assembly, and the boundary
conditions. With x = Z q (constraints eliminated):

    r(q, q', q'') = Z^T sum_e B_e^T W_e rho(B_e Z q, B_e Z q', B_e Z q''),
    M = Z^T (sum_e B^T W m B) Z with m = d rho/dj_tt, and likewise D, G (from
    d rho/dj_t) and K (from d rho/dj, incl. centrifugal and geometric terms).

Linearisation about a base state uses its jets at the points: either from a dof
vector q, or given directly as data (``jets=``, shape (elements, points, jets)).
The interface matches :class:`~mechgen.runtime.core.system.System` (``n``, ``m``,
``linear``, ``residual``, ``tangent``, ``outputs``, ``rhs``, ``jacobian``), so
every analysis runs on it; :meth:`refined` gives the same model at another size.

A FieldSystem is immutable like a System: :meth:`FieldSystem.with_params` and
:meth:`FieldSystem.with_layout` give new ones.

The class holds the state and the public interface; the work lives in modules that take the system:
``point_kernels`` (kernel calls at points, per segment, end term and part), ``discretised`` (the discretisation at
the current size and length), ``conditions`` (essential conditions, joints, the reduction, the penalty),
``global_forms`` (the assembled residual, matrices and reactions), ``field_outputs`` (outputs, field and nodal
values) and ``time_rates`` (the first-order form of time integration).
"""
from __future__ import annotations

from dataclasses import InitVar, dataclass, field, replace
from typing import Callable

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.core.kernels import Kernel
from mechgen.runtime.core.meta import SystemMeta
from mechgen.runtime.core.system import Memo, frozen_vector, read_only, replacement_vector, with_values
from mechgen.runtime.fields import conditions, discretised, field_outputs, global_forms, point_kernels, time_rates
from mechgen.runtime.fields.assemble import Assembler
from mechgen.runtime.fields.constrain import PENALTY_FACTOR, PenaltyChoice, Reduction, penalty_errors
from mechgen.runtime.fields.discretise import DISCRETISATIONS, Discretisation
from mechgen.runtime.fields.mesh import Layout
from mechgen.runtime.fields.meta import FieldMeta

#: PENALTY_FACTOR: importable from here before the conditions moved out
__all__ = ["CHOICE_VALUES", "PENALTY_FACTOR", "SIZE_CHOICES", "FieldSystem"]

#: the values a continuum's runtime choices take (others, such as a model's own runtime choices, are strings)
CHOICE_VALUES = {"discretisation": DISCRETISATIONS, "constraints": ("eliminate", "penalty", "multiplier"),
                 "joints": ("assembly", "multiplier")}
#: runtime choices that are sizes (integers >= 1)
SIZE_CHOICES = ("N", "quadrature")


@dataclass(frozen=True, eq=False)
class FieldSystem:
    """Kernels of a continuum's local piece, parameter values and the discretisation choices. Immutable.

    ``field_meta`` (:class:`~mechgen.runtime.fields.meta.FieldMeta`, from the kernel meta's ``info`` dict): fields,
    jets (field, order), length parameter, constraints (field, order, 'start'|'end'), end terms, part kinds,
    shear pairs; ``metadata`` the typed rest of the kernel meta (model, params). ``choices``:
    discretisation, N, quadrature, constraints (method), joints and the model's other
    runtime choices; ``fixed``: the numeric values folded into the kernels.

    ``params`` is a read-only array; ``kernels``, ``meta``, ``fixed``, ``choices`` and
    ``layout`` are read-only too, and no attribute can be assigned after construction:
    :meth:`with_params` and :meth:`with_layout` give new systems. The memo (shear ratios,
    discretisation, reduction, assembler, point tables, penalty, mass factor) holds pure
    functions of the frozen state: every key names what its value depends on (the length,
    the shear ratios, and the parameter vector where the value depends on it), so that
    systems differing only in parameter values share it. ``_cache`` is accepted for
    compatibility and ignored: a system built by ``dataclasses.replace`` starts with its own
    memo. ``rebuild(system, values)``, given by the compile layer,
    recompiles for names folded into the kernels (``fixed`` and ``folded``).
    """

    kernels: dict[str, Kernel]
    meta: dict
    params: np.ndarray
    fixed: dict
    choices: dict
    backend: str = "numpy"
    layout: Layout | None = None
    _cache: InitVar[dict | None] = None
    rebuild: Callable | None = field(default=None, repr=False)
    folded: tuple[str, ...] = ()
    #: the facts of the model it was compiled from (mechgen.scene.info.ModelInfo), set by the compile layer for
    #: a model given as an object (one a reference cannot find again); None: looked up by the model's reference
    facts: object = field(default=None, repr=False, compare=False)
    #: the typed view of ``meta`` (:class:`~mechgen.runtime.core.meta.SystemMeta`) and of its field facts
    #: (:class:`~mechgen.runtime.fields.meta.FieldMeta`), read once
    metadata: SystemMeta = field(init=False, repr=False)
    field_meta: FieldMeta = field(init=False, repr=False)
    _memo: Memo = field(init=False, repr=False)
    _pkey: bytes = field(init=False, repr=False)

    is_lattice = False
    is_field = True
    m = 0

    def __post_init__(self, _cache) -> None:
        params = frozen_vector(self.params)
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "kernels", read_only(self.kernels))
        object.__setattr__(self, "meta", read_only(self.meta))
        object.__setattr__(self, "fixed", read_only(self.fixed))
        object.__setattr__(self, "choices", read_only(self.choices))
        object.__setattr__(self, "folded", tuple(self.folded))
        object.__setattr__(self, "metadata", SystemMeta.of(self.meta))
        object.__setattr__(self, "field_meta", FieldMeta.of(self.meta["field"]))
        object.__setattr__(self, "_memo", Memo(256))
        object.__setattr__(self, "_pkey", params.tobytes())

    # -- new systems ----------------------------------------------------------
    def with_param_vector(self, params) -> "FieldSystem":
        """The same kernels, choices and layout with another vector of free parameter values (the memo shared)."""
        params = replacement_vector(self, params)
        if params is None:
            return self
        new = replace(self, params=params)
        object.__setattr__(new, "_memo", self._memo)
        return new

    def with_params(self, **values) -> "FieldSystem":
        """A new system with these values (this one is unchanged; itself when no value changes).

        Free numeric parameters give a new parameter vector with the same kernels; runtime
        choices (discretisation, N, quadrature, constraints, joints and the model's other
        ``Param(runtime=True)`` names) a system with those choices; a name folded into the
        kernels at compile time (``fixed``, ``folded``) a recompiled system through
        ``rebuild`` (InputError without one); any other name an InputError listing the known ones.
        """
        return with_values(self, values, _choice)

    def with_layout(self, layout: Layout | None) -> "FieldSystem":
        """The same kernels, parameters and choices with segments and parts ``layout`` (a new memo)."""
        if layout is not None and not isinstance(layout, Layout):
            raise InputError(f"layout is {type(layout).__name__}", key="layout",
                             expected="a mechgen.runtime.fields.mesh.Layout of segments and parts")
        if layout == self.layout:
            return self
        return replace(self, layout=layout)

    def refined(self, size: int) -> "FieldSystem":
        """The same model discretised with ``size`` elements or basis functions (segments: scaled alike)."""
        layout = self.layout
        if layout is not None and layout.segments:
            factor = size / int(self.choices["N"])
            layout = replace(layout, segments=tuple(replace(seg, elements=max(1, round(seg.elements * factor)))
                                                    for seg in layout.segments))
        return replace(self, choices={**self.choices, "N": int(size)}, layout=layout)

    # -- parameters and memo ----------------------------------------------------
    def param_values(self) -> dict:
        """The free parameters' current values and the runtime choices, by name."""
        return {**{n: float(v) for n, v in zip(self.metadata.params, self.params)}, **self.choices}

    def value(self, name: str) -> float:
        """Current value of a numeric parameter (free ones from ``params``; the length from the segments)."""
        if name == self.field_meta.length and self.layout is not None and self.layout.segments:
            return self.layout.length
        names = self.metadata.params
        return float(self.params[names.index(name)]) if name in names else float(self.fixed[name])

    @property
    def info(self) -> dict:
        """Field facts from the kernel meta, as the dict the lowering wrote (typed: :attr:`field_meta`)."""
        return self.meta["field"]

    @property
    def param_key(self) -> bytes:
        """The parameter vector as a memo key (its bytes)."""
        return self._pkey

    def memo(self, key: tuple, make: Callable):
        """A value memoised in this system's memo (shared by its with_param_vector copies): ``key`` must name
        everything the value depends on (:meth:`loop_key` for what depends on the discretisation, the
        reduction and the parameters)."""
        return self._memo.get(key, make)

    def disc_key(self, *depends) -> tuple:
        """A memo key: what the discretisation depends on plus ``depends``
        (mechgen.runtime.fields.discretised.disc_key)."""
        return discretised.disc_key(self, *depends)

    def loop_key(self) -> tuple:
        """What the discretised operators depend on: the discretisation, the reduction and the parameter vector."""
        return (*conditions.reduction_key(self), self._pkey)

    # -- discretisation, conditions, assembly ----------------------------------------
    def check_size(self) -> None:
        """Refuse (InputError at params.N / params.quadrature) a discretisation beyond the memory limit, before
        the mesh or any table is allocated (mechgen.runtime.fields.discretise.check_size)."""
        discretised.check_size(self)

    @property
    def disc(self) -> Discretisation:
        """The discretisation at the current length (one per length; for timoshenko2, whose shape
        functions hold EI / kGA, one per set of shear ratios phi = 12 EI / (kGA h^2))."""
        return self._memo.get(("disc", *self.disc_key()), lambda: discretised.discretisation(self))

    @property
    def reduction(self) -> Reduction:
        """x = Z q for the essential boundary conditions."""
        return self._memo.get(("red", *conditions.reduction_key(self)), lambda: conditions.build_reduction(self))

    @property
    def has_multipliers(self) -> bool:
        """True when the unknowns include Lagrange multipliers (massless: a singular M)."""
        return self.reduction.multiplier_rows is not None

    @property
    def assembler(self) -> Assembler:
        """Scatter into global dofs."""
        disc = self.disc
        return self._memo.get(("asm", *self.disc_key()), lambda: Assembler(disc.dofs, disc.ndof, dense=disc.is_global))

    @property
    def n(self) -> int:
        """Unknowns after the boundary conditions."""
        return self.reduction.n

    @property
    def coordinates(self) -> list[str]:
        """Names of the reduced unknowns."""
        return [f"q{i + 1}" for i in range(self.n)]

    # -- steady boundary value problem --------------------------------------------
    def steady_form(self):
        """The steady equations in s as a lumped :class:`~mechgen.runtime.core.system.System` (kernels ``bvp_*``).

        Its first-order form is the boundary value problem: ``rhs(s, y)`` and
        ``jacobian(s, y)`` with y = (u, u_s), and ``outputs(u, u_s, t=s)`` the model's
        outputs and the boundary values ``bc_<field>_<order>_<end>``.
        """
        from mechgen.runtime.core.system import System

        kernels = {k.removeprefix("bvp_"): v for k, v in self.kernels.items() if k.startswith("bvp_")}
        if "residual" not in kernels:
            raise InputError(f"the kernels of {self.metadata.model} were built without the steady form",
                             key="kernels", expected="bvp_residual, bvp_tangent and bvp_outputs (a steady bvp analysis)")
        return System(kernels, dict(kernels["residual"].spec["meta"]), self.params, 0, self.backend)

    # -- segments, parts and pointwise kernels -------------------------------------------
    def segment_params(self) -> list[np.ndarray] | None:
        """One parameter vector per segment, in mesh order (None: every element uses ``params``)."""
        return point_kernels.segment_params(self)

    def placed_points(self) -> list[tuple[str, float, np.ndarray | None]]:
        """(name, position s, parameter vector or None for ``params``) of every end term and placed part: its
        pointwise kernels are ``<kernel>_at_<name>``, evaluated at s with those parameters."""
        return point_kernels.placed_points(self)

    def point_table(self, x: float):
        """B_x (jets x full dofs, CSR): the jets at s = x from the full dof vector (memoised per position)."""
        return point_kernels.point_table(self, x)

    def pointwise(self, kernel: str, j, j_t=None, j_tt=None, t: float = 0.0) -> dict:
        """The pointwise kernel's outputs at every Gauss point (arrays shaped like the points) from the jets
        j (and their rates), each segment with its own parameters."""
        return point_kernels.pointwise(self, kernel, j, j_t, j_tt, t)

    # -- the discretised system ---------------------------------------------
    def reduced_matrices(self, kernel: str, names, q, v, a, t: float, jets=None) -> dict:
        """Reduced global matrices ``names`` of a tangent-type kernel at the state (q, v, a)
        (mechgen.runtime.fields.global_forms)."""
        return global_forms.reduced_matrices(self, kernel, names, q, v, a, t, jets)

    def linear(self, q=None, v=None, z=None, t: float = 0.0, *, jets=None) -> dict:
        """M, D, G, K about the base state q (or its jets at the Gauss points) with zero acceleration."""
        if "constraint" in self.kernels:
            raise InputError(f"{self.metadata.model} holds a pointwise constraint (its multiplier is part of a "
                             "steady state): small motions only about a boundary-value steady state",
                             key="about", expected="modes or stability 'about' a steady analysis with "
                             "form = 'hamiltonian' (mechgen.runtime.steady.constrained)")
        return self.reduced_matrices("linear", ("M", "D", "G", "K"), q, v, None, t, jets)

    def tangent(self, q, v=None, a=None, z=None, t: float = 0.0) -> dict:
        """dr/dq, dr/dq', dr/dq'' (reduced; the penalty term in dr/dq)."""
        return self.reduced_matrices("tangent", ("r_q", "r_v", "r_a"), q, v, a, t)

    def residual(self, q, v=None, a=None, z=None, t: float = 0.0) -> np.ndarray:
        """r(q, q', q'') = Z^T (sum_e B^T W rho + sum_ends B_at^T rho_at + penalty C^T C x)."""
        return global_forms.residual(self, q, v, a, t)

    def reactions(self, q, t: float = 0.0) -> list[dict]:
        """Boundary reactions of an equilibrium: the Lagrange multipliers lambda of C x = 0.

        r(x) + C^T lambda = 0 at the equilibrium x = Z q, solved in least squares;
        each reaction is the generalized force conjugate to its constrained jet
        (w: a transverse force, w_s: a moment), positive along the jet. Conditions
        that the basis satisfies by itself (sines at the ends) have none.
        """
        return global_forms.reactions(self, q, t)

    # -- penalty --------------------------------------------------------------
    @property
    def penalty(self) -> float:
        """alpha = f * max|diag K| of the unconstrained zero-state K (0 without penalty rows).

        f balances the penalty error of the lowest eigenvalue against the round-off
        (mechgen.runtime.fields.constrain.penalty_choice: f* = sqrt(P / R)); see :attr:`penalty_choice`.
        """
        choice = self.penalty_choice
        return 0.0 if choice is None else choice.alpha

    @property
    def penalty_choice(self) -> PenaltyChoice | None:
        """The penalty factor and its error model (predicted relative error of the lowest eigenvalue)."""
        return conditions.choose_penalty(self)

    def penalty_errors(self, shapes: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray:
        """A-posteriori relative eigenvalue error of each mass-normalised mode the penalty causes
        (mechgen.runtime.fields.constrain.penalty_errors; zeros without penalty rows)."""
        return penalty_errors(self.reduction, conditions.row_penalties(self), shapes, eigenvalues)

    # -- outputs and field values ----------------------------------------------------------
    def nodal_indices(self, fields) -> tuple[np.ndarray, ...] | None:
        """Reduced-unknown indices of the nodal values of ``fields`` at the vertices where none is eliminated.

        A nodal value dof *is* the field there: the whirl stations of a rotor, one
        array per field, paired by vertex. None when the unknowns are not a
        selection of dofs (substructures joined by a null-space reduction): see
        :meth:`nodal_rows`.
        """
        return field_outputs.nodal_indices(self, fields)

    def nodal_rows(self, fields) -> np.ndarray:
        """R with R q = the nodal values of ``fields`` (stacked field by field) for reduced unknowns q."""
        return field_outputs.nodal_rows(self, fields)

    def field_values(self, q, points: np.ndarray, order: int = 0) -> dict[str, np.ndarray]:
        """D_s^order of every field at ``points`` for the reduced state q (mode shapes, deflections): u_f = S_f x with
        x the full dof vector and S_f the sparse rows of the basis at the points. ``q`` may hold one state per column
        (then each field's values are points x columns): the rows are tabulated once for all of them (216 modes took
        9 s row by row)."""
        return field_outputs.field_values(self, q, points, order)

    def outputs(self, q, v=None, z=None, t: float = 0.0) -> dict[str, float]:
        """Energies: integrals of the kinetic and potential densities plus the end terms."""
        return field_outputs.outputs(self, q, v, t)

    def outputs_series(self, t, X) -> dict[str, np.ndarray]:
        """:meth:`outputs` at every sample (row k of X: the state (q, v) at t[k]), the samples of each block of
        points in one kernel call (mechgen.runtime.fields.operators.outputs_series)."""
        from mechgen.runtime.fields.operators import outputs_series

        return outputs_series(self, np.asarray(t, float), np.atleast_2d(np.asarray(X, float)))

    # -- first-order form (time integration: mechgen.runtime.fields.time_rates) --------------
    def split(self, x: np.ndarray):
        """(q, v, z) of a first-order state."""
        n = self.n
        return x[:n], x[n:2 * n], x[2 * n:]

    @property
    def first_order(self) -> bool:
        """True when no unknown carries mass (no kinetic density, a constant M = 0): every field obeys a first-order
        (or algebraic) law r(q, q', 0) = 0, D(q) q' + f(q) = 0 for a weak form linear in the rates (js_fluid)."""
        return time_rates.is_first_order(self)

    def first_order_rate(self, t: float, q: np.ndarray) -> np.ndarray:
        """q' of a first-order continuum: the root v of r(q, v, 0) = 0 by Newton on r_v (one step when r is linear
        in the rates); a singular r_v (an unknown without a rate: Re = 0 in js_fluid) is refused, a DAE."""
        return time_rates.first_order_rate(self, t, q)

    def first_order_jacobian(self, t: float, q: np.ndarray):
        """d q'/dq = -r_v^-1 r_q at (q, q'(q)) (dense; a first-order continuum's implicit integration)."""
        return time_rates.first_order_jacobian(self, t, q)

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """dx/dt = (v, -M^-1 r(q, v, 0))."""
        return time_rates.rhs(self, t, x)

    def jacobian(self, t: float, x: np.ndarray):
        """d(dx/dt)/dx with da/d(q, v) = -M^-1 [r_q, r_v] at the current acceleration."""
        return time_rates.jacobian(self, t, x)


def _choice(name: str, value):
    """A runtime choice's new value, validated where the runtime knows its values."""
    if name in SIZE_CHOICES:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < 1:
            raise InputError(f"{name} = {value!r} is not a size", key=name, expected="an integer >= 1")
        return int(value)
    allowed = CHOICE_VALUES.get(name)
    if allowed is not None and value not in allowed:
        raise InputError(f"{name} = {value!r} is not a choice the runtime knows", key=name,
                         expected="one of: " + ", ".join(allowed))
    return value
