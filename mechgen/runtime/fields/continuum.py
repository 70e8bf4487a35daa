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
"""
from __future__ import annotations

from dataclasses import InitVar, dataclass, field, replace
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from mechgen.errors import ConvergenceError, InputError, KernelError
from mechgen.runtime.fields.assemble import Assembler, element_matrices, element_vectors, jets_at_points
from mechgen.runtime.fields import constrain
from mechgen.runtime.fields.constrain import (  # noqa: F401 (PENALTY_FACTOR: importable from here before)
    PENALTY_FACTOR, PenaltyChoice, Reduction, binding, penalty_choice, penalty_errors, reduction)
from mechgen.runtime.fields.discretise import DISCRETISATIONS, GLOBAL, Discretisation, check_size, discretise
from mechgen.runtime.fields.elements import reference
from mechgen.runtime.core.kernels import Kernel
from mechgen.runtime.core.memory import dense_bytes, require, require_dense
from mechgen.runtime.core.meta import SystemMeta
from mechgen.runtime.fields.mesh import Layout, build_mesh
from mechgen.runtime.core.system import Memo, frozen_vector, read_only, replacement_vector, with_values


#: the values a continuum's runtime choices take (others, such as a model's own runtime choices, are strings)
CHOICE_VALUES = {"discretisation": DISCRETISATIONS, "constraints": ("eliminate", "penalty", "multiplier"),
                 "joints": ("assembly", "multiplier")}
#: runtime choices that are sizes (integers >= 1)
SIZE_CHOICES = ("N", "quadrature")


def point_terms(terms, shape) -> sps.csr_matrix:
    """sum_p B_p^T C_p B_p of the end terms and placed parts, as one sparse matrix of ``shape``.

    B_p (jets x dofs, CSR) touches a few dofs only: each product is formed densely on those
    (B_p restricted to its nonzero columns) and all of them are scattered at once (duplicates
    summed), instead of two sparse products and a sparse sum per part and matrix.
    """
    rows, cols, vals = [], [], []
    for B, C in terms:
        idx = np.unique(B.indices)
        Bd = B.toarray()[:, idx]
        rows.append(np.repeat(idx, idx.size))
        cols.append(np.tile(idx, idx.size))
        vals.append((Bd.T @ np.asarray(C) @ Bd).ravel())
    return sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=shape)


@dataclass(frozen=True, eq=False)
class FieldSystem:
    """Kernels of a continuum's local piece, parameter values and the discretisation choices. Immutable.

    ``info`` (from the kernel meta): fields, jets [[field, order]], length
    parameter, constraints [[field, order, 'start'|'end']]. ``choices``:
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

    def param_values(self) -> dict:
        """The free parameters' current values and the runtime choices, by name."""
        return {**{n: float(v) for n, v in zip(self.meta.get("params", []), self.params)}, **self.choices}

    def _key(self, *depends) -> tuple:
        """A memo key: what the discretisation depends on (the length; for timoshenko2 the shear ratios phi of its
        shape functions, not the whole parameter vector, so that a new spin speed reuses it) plus ``depends``."""
        length = self.value(self.info["length"])
        if self.choices["discretisation"] != "timoshenko2":
            return (length, None, *depends)
        return (length, self._shear(length)[1].tobytes(), *depends)

    def check_size(self) -> None:
        """Refuse (InputError at params.N / params.quadrature) a discretisation beyond the memory limit, before
        the mesh or any table is allocated (mechgen.runtime.fields.discretise.check_size)."""
        segments = self.layout.segments if self.layout is not None else ()
        size = sum(int(seg.elements) for seg in segments) if segments else int(self.choices["N"])
        check_size(self.choices["discretisation"], size, len(self.info["fields"]), len(self.info["jets"]),
                   int(self.choices["quadrature"]), key="segments.elements" if segments else "params.N")

    def _shear(self, length: float) -> tuple[list, np.ndarray]:
        """timoshenko2's shear pairs and ratios at this length and these parameters (memoised)."""
        def make():
            self.check_size()
            try:
                return self._shear_ratios(build_mesh(self.layout, int(self.choices["N"]), length))
            except ValueError as exc:
                raise InputError(str(exc), key="discretisation",
                                 expected="a discretisation that fits the model's energies") from None

        return self._memo.get(("shear", length, self._pkey), make)

    # -- discretisation -------------------------------------------------------
    @property
    def metadata(self) -> SystemMeta:
        """The typed view of ``meta`` (:class:`~mechgen.runtime.core.meta.SystemMeta`)."""
        return SystemMeta.of(self.meta)

    @property
    def info(self) -> dict:
        """Field facts from the kernel meta."""
        return self.meta["field"]

    def value(self, name: str) -> float:
        """Current value of a numeric parameter (free ones from ``params``; the length from the segments)."""
        if name == self.info["length"] and self.layout is not None and self.layout.segments:
            return self.layout.length
        names = self.meta.get("params", [])
        return float(self.params[names.index(name)]) if name in names else float(self.fixed[name])

    @property
    def disc(self) -> Discretisation:
        """The discretisation at the current length (one per length; for timoshenko2, whose shape
        functions hold EI / kGA, one per set of shear ratios phi = 12 EI / (kGA h^2))."""
        return self._memo.get(("disc", *self._key()), self._discretise)

    def _discretise(self) -> Discretisation:
        length = self.value(self.info["length"])
        jets = tuple((f, int(k)) for f, k in self.info["jets"])
        kind = self.choices["discretisation"]
        self.check_size()
        try:
            if kind in GLOBAL:
                if self.layout is not None and self.layout.segments:
                    raise ValueError(f"segments need finite elements; {kind} is a global basis")
                mesh = None
            else:
                mesh = build_mesh(self.layout, int(self.choices["N"]), length)
            shear = self._shear(length) if kind == "timoshenko2" else None
            return discretise(kind, int(self.choices["N"]), length, self.info["fields"], jets,
                              quadrature=int(self.choices["quadrature"]),
                              constraints=[tuple(c) for c in self.info["constraints"]], mesh=mesh,
                              shear=shear, joints=self.choices.get("joints", "assembly"))
        except ValueError as exc:
            raise InputError(str(exc), key="discretisation",
                             expected="a discretisation that fits the model's energies") from None

    def _reduction_key(self) -> tuple:
        """The reduction depends on the discretisation, and on the parameters through multiplier joints."""
        joints = self.choices.get("joints", "assembly") == "multiplier"
        return self._key(self._pkey if joints else None)

    @property
    def reduction(self) -> Reduction:
        """x = Z q for the essential boundary conditions."""
        return self._memo.get(("red", *self._reduction_key()), self._reduce)

    def _reduce(self) -> Reduction:
        disc = self.disc
        _, rows, scales = self._constraint_rows()
        joints = self._joint_rows()
        red = reduction(np.array(rows), np.array(scales), disc.ndof, self.choices["constraints"],
                        sparse=not disc.is_global and not joints, joints=np.array(joints) if joints else None)
        if red.penalty_rows is not None and disc.is_global:
            raise InputError(f"penalty constraints with the global {disc.kind} basis couple every function "
                             "to the penalty and wreck the conditioning", key="constraints",
                             expected="'eliminate' for global bases (penalty with finite elements)")
        return red

    def _constraint_rows(self) -> tuple[list, list, list]:
        """(field, order, end), dense row C_i and the jet's table magnitude of every essential condition."""
        disc = self.disc
        keys, rows, scales = [], [], []
        for f, k, at in self.info["constraints"]:
            keys.append((f, int(k), at))
            rows.append(disc.row(f, int(k), 0.0 if at == "start" else disc.length))
            scales.append(float(np.abs(disc.tables[:, :, disc.jets.index((f, int(k))), :]).max()))
        return keys, rows, scales

    def _joint_rows(self) -> list[np.ndarray]:
        """Continuity rows of substructures at segment interfaces (``joints = "multiplier"``), as in Yu & Cleghorn.

        At an interface s_j: every field's value from the left equals that from
        the right, and so do derivatives the energy needs continuous (orders below
        its highest); a derivative dof the energy does not need continuous (C1
        elements, first-order energy) is tied instead by continuity of the force
        conjugate to it, the flux F_f = sum_b K[(f, 1), b] j_b with K the pointwise
        stiffness of each side's segment (kGA (u_s - psi) and EI psi_s for a shaft).
        Rows are scaled to a largest entry of 1.
        """
        disc = self.disc
        mesh = disc.mesh
        if self.choices.get("joints", "assembly") != "multiplier" or mesh is None or not len(mesh.interfaces):
            return []
        jets = list(disc.jets)
        top = max(k for _, k in jets)
        orders = (0,) if disc.kind in ("lagrange1", "lagrange2", "timoshenko2") else (0, 1)
        seg_params = self._segment_params()
        rows = []
        for v in mesh.interfaces:
            x = float(mesh.nodes[v])
            for f in disc.fields:
                for k in orders:
                    if k < top:
                        rows.append(disc.row(f, k, x, "left") - disc.row(f, k, x, "right"))
                        continue
                    a = jets.index((f, k))
                    row = np.zeros(disc.ndof)
                    for side, seg in (("left", mesh.segment[v - 1]), ("right", mesh.segment[v])):
                        params = None if seg_params is None else seg_params[seg]
                        K = self._stiffness(np.array([x]), params=params)[0]
                        flux = sum(K[a, b] * disc.row(*jets[b], x, side) for b in np.flatnonzero(K[a]))
                        row = row + (flux if side == "left" else -flux)
                    rows.append(row)
        return [r / max(np.abs(r).max(), 1e-300) for r in rows]

    @property
    def has_multipliers(self) -> bool:
        """True when the unknowns include Lagrange multipliers (massless: a singular M)."""
        return self.reduction.multiplier_rows is not None

    @property
    def assembler(self) -> Assembler:
        """Scatter into global dofs."""
        disc = self.disc
        return self._memo.get(("asm", *self._key()), lambda: Assembler(disc.dofs, disc.ndof, dense=disc.is_global))

    @property
    def n(self) -> int:
        """Unknowns after the boundary conditions."""
        return self.reduction.n

    @property
    def coordinates(self) -> list[str]:
        """Names of the reduced unknowns."""
        return [f"q{i + 1}" for i in range(self.n)]

    def refined(self, size: int) -> "FieldSystem":
        """The same model discretised with ``size`` elements or basis functions (segments: scaled alike)."""
        layout = self.layout
        if layout is not None and layout.segments:
            factor = size / int(self.choices["N"])
            layout = replace(layout, segments=tuple(replace(seg, elements=max(1, round(seg.elements * factor)))
                                                    for seg in layout.segments))
        return replace(self, choices={**self.choices, "N": int(size)}, layout=layout)

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
            raise InputError(f"the kernels of {self.meta.get('model')} were built without the steady form",
                             key="kernels", expected="bvp_residual, bvp_tangent and bvp_outputs (a steady bvp analysis)")
        return System(kernels, dict(kernels["residual"].spec["meta"]), self.params, 0, self.backend)

    # -- segments and parts -----------------------------------------------------
    def _with(self, values: dict, prefix: str = "", what: str = "segment") -> np.ndarray:
        """The parameter vector with ``values`` (names prefixed by ``prefix``) in place of the current ones."""
        names = self.meta.get("params", [])
        params = np.array(self.params, float)
        for name, value in values.items():
            full = prefix + name
            if full not in names:
                raise InputError(f"{what} sets {name!r}, which the compiled kernels do not take as an input",
                                 key=name, expected=f"a parameter kept free: {', '.join(names) or 'none'}")
            params[names.index(full)] = float(value)
        return params

    def segment_params(self) -> list[np.ndarray] | None:
        """One parameter vector per segment, in mesh order (None: every element uses ``params``)."""
        return self._segment_params()

    def _segment_params(self) -> list[np.ndarray] | None:
        """One parameter vector per segment (None: every element uses ``params``)."""
        if self.layout is None or not any(seg.values for seg in self.layout.segments):
            return None
        return [self._with(seg.values) for seg in self.layout.segments]

    def _stiffness(self, s: np.ndarray, *, params=None, segment=None) -> np.ndarray:
        """Pointwise stiffness coefficients d rho / d j at rest at positions s: (len(s), jets, jets).

        From the linear kernel (its K) or else the tangent one (r_q); ``segment`` gives each point's
        segment (its parameters), ``params`` one parameter vector for all.
        """
        kernel, out = ("linear", "K") if "linear" in self.kernels else ("tangent", "r_q")
        na = len(self.info["jets"])
        if segment is not None:
            values = self._by_segment(kernel, segment, [None, None, None], 0.0, s[:, None])[out][:, 0]
        else:
            values = self._evaluate(kernel, None, None, None, 0.0, s, params=params)[out]
        return values.reshape(len(s), na, na)

    def _shear_ratios(self, mesh) -> tuple[list, np.ndarray]:
        """Shear pairs and phi = 12 EI / (kGA h^2) per element and pair, from the pointwise stiffness.

        EI is the coefficient of psi_s^2 and kGA that of w_s^2 in the linearised
        stiffness density (d rho / d j), at each element's midpoint.
        """
        pairs = [tuple(p) for p in self.info.get("shear_pairs", [])]
        if not pairs:
            raise ValueError("the timoshenko2 element needs shear pairs (model.shear_pair) in the model")
        jets = [tuple(j) for j in self.info["jets"]]
        mids = (mesh.nodes[:-1] + mesh.nodes[1:]) / 2
        K = self._stiffness(mids, segment=mesh.segment)
        h = np.diff(mesh.nodes)
        phi = np.zeros((len(mids), len(pairs)))
        for k, (w, psi, _) in enumerate(pairs):
            if (w, 1) not in jets or (psi, 1) not in jets:
                raise ValueError(f"shear pair ({w}, {psi}): the energy uses no {w}_s or {psi}_s")
            EI = K[:, jets.index((psi, 1)), jets.index((psi, 1))]
            kGA = K[:, jets.index((w, 1)), jets.index((w, 1))]
            if np.any(kGA <= 0) or np.any(EI < 0):
                raise ValueError(f"shear pair ({w}, {psi}): the stiffness of {w}_s^2 ({kGA.min():g}) and of "
                                 f"{psi}_s^2 ({EI.min():g}) must be positive")
            phi[:, k] = 12 * EI / (kGA * h**2)
        return pairs, phi

    def _by_segment(self, kernel: str, segment: np.ndarray, jets: list, t: float, s: np.ndarray) -> dict:
        """A pointwise kernel over elements (first axis of s and jets), each segment with its parameters."""
        params = self._segment_params()
        if params is None:
            return self._evaluate(kernel, *jets, t, s)
        parts = []
        for k, p in enumerate(params):
            rows = np.flatnonzero(segment == k)
            sl = slice(rows[0], rows[-1] + 1)
            parts.append(self._evaluate(kernel, *[None if x is None else x[sl] for x in jets], t, s[sl], params=p))
        return {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}

    # -- pointwise kernels ----------------------------------------------------
    def _jets(self, x) -> np.ndarray:
        disc = self.disc
        if x is None:
            return np.zeros(disc.points.shape + (len(disc.jets),))
        return jets_at_points(disc.tables, disc.dofs, self.reduction.expand(x))

    def _evaluate(self, kernel: str, j, j_t, j_tt, t: float, s: np.ndarray, params=None) -> dict:
        """One batched call of a pointwise kernel at positions s; jets arrays (..., jets); outputs (..., length)."""
        na = len(self.info["jets"])
        shape = s.shape
        npts = s.size
        flat = lambda x: np.zeros((npts, na)) if x is None else np.ascontiguousarray(np.reshape(x, (npts, na)))  # noqa: E731
        inputs = {"q": flat(j), "v": flat(j_t), "a": flat(j_tt), "z": np.zeros((npts, 0)),
                  "t": np.full((npts, 1), float(t)), "s": s.reshape(npts, 1),
                  "p": self.params if params is None else params}
        try:
            out = self.kernels[kernel].evaluate(inputs)
        except KernelError as exc:
            raise KernelError(f"{exc} (pointwise kernel of {self.meta.get('model')})") from None
        return {k: v.reshape(shape + (v.shape[-1],)) for k, v in out.items()}

    def pointwise(self, kernel: str, j, j_t=None, j_tt=None, t: float = 0.0) -> dict:
        """The pointwise kernel's outputs at every Gauss point (arrays shaped like the points) from the jets
        j (and their rates), each segment with its own parameters."""
        disc = self.disc
        segment = disc.mesh.segment if disc.mesh is not None else np.zeros(len(disc.points), int)
        return self._by_segment(kernel, segment, [j, j_t, j_tt], t, disc.points)

    def _point_table(self, x: float):
        """B_x (jets x dofs, CSR): the jets at s = x from the full dof vector."""
        disc = self.disc
        return self._memo.get(("point", *self._key(float(x))),
                              lambda: sps.csr_matrix(np.array([disc.row(f, k, x) for f, k in disc.jets])))

    def placed_points(self) -> list[tuple[str, float, np.ndarray | None]]:
        """(name, position s, parameter vector or None for ``params``) of every end term and placed part: its
        pointwise kernels are ``<kernel>_at_<name>``, evaluated at s with those parameters."""
        placed = [(at, 0.0 if at == "start" else self.disc.length, None) for at in self.info.get("points", [])]
        kinds = self.info.get("parts", {})
        for part in (self.layout.parts if self.layout is not None else ()):
            if part.kind not in kinds:
                raise InputError(f"part kind {part.kind!r} is not declared by model {self.meta.get('model')}",
                                 key="parts.kind", expected=f"one of: {', '.join(kinds) or 'none'}")
            placed.append((part.kind, part.at, self._with(part.values, f"{part.kind}_", f"part {part.kind}")))
        return placed

    def point_table(self, x: float):
        """B_x (jets x full dofs, CSR): the jets at s = x from the full dof vector (memoised per position)."""
        return self._point_table(x)

    def memo(self, key: tuple, make: Callable):
        """A value memoised in this system's memo (shared by its with_param_vector copies): ``key`` must name
        everything the value depends on (:meth:`loop_key` for what depends on the discretisation, the
        reduction and the parameters)."""
        return self._memo.get(key, make)

    def loop_key(self) -> tuple:
        """What the discretised operators depend on: the discretisation, the reduction and the parameter vector."""
        return (*self._reduction_key(), self._pkey)

    def _ends(self, kernel: str, states, t: float):
        """(B_x, local outputs) of every end term and placed part: states are full dof vectors (q, q', q'') or None."""
        for name, x, params in self.placed_points():
            B = self._point_table(x)
            at_point = [None if y is None else (B @ y)[None] for y in states]
            yield B, self._evaluate(f"{kernel}_at_{name}", *at_point, t, np.array([x]), params=params)

    def _full(self, states):
        red = self.reduction
        return [None if x is None else red.expand(x) for x in states]

    def _jets_of(self, full) -> list:
        """Jets at the Gauss points of each full dof vector (None stays None: a zero state)."""
        disc = self.disc
        return [None if x is None else jets_at_points(disc.tables, disc.dofs, x) for x in full]

    def reduced_matrices(self, kernel: str, names, q, v, a, t: float, jets=None) -> dict:
        """Reduced global matrices ``names`` of a tangent-type kernel at the state (q, v, a)."""
        disc = self.disc
        full = self._full((q, v, a))
        j = self._jets_of(full)
        if jets is not None:
            j[0] = np.asarray(jets, float)
        local = self.pointwise(kernel, *j, t=t)
        mats = {}
        for k in names:
            coeff = self._coeff(local[k])
            pairs = [tuple(ab) for ab in np.argwhere(np.any(coeff != 0, axis=(0, 1)))]
            mats[k] = self.assembler.matrix(element_matrices(disc.tables, disc.weights, coeff, pairs))
        ends = list(self._ends(kernel, full, t))
        if ends:
            for k in names:
                extra = point_terms([(B, self._coeff(loc[k])[0]) for B, loc in ends], mats[k].shape)
                mats[k] = mats[k] + (extra if sps.issparse(mats[k]) else extra.toarray())
        stiff = {"linear": "K", "tangent": "r_q"}[kernel]
        reduced = {k: self.reduction.matrix(mats[k], self._row_penalties if k == stiff else 0.0, border=k == stiff)
                   for k in names}
        for k, m in reduced.items():
            self._require_finite(kernel, k, m)
        return reduced

    def _require_finite(self, kernel: str, name: str, matrix) -> None:
        """KernelError when an assembled matrix holds NaN/Inf (a kernel overflowed, or the element sums did:
        a length such as 1e200 gives EI/h^3 = 0 and rhoA h = inf), naming the matrix and the values that set it."""
        data = matrix.data if sps.issparse(matrix) else np.asarray(matrix)
        if np.isfinite(data).all():
            return
        values = {**self.param_values(), **{k: v for k, v in self.fixed.items() if isinstance(v, (int, float))},
                  self.info["length"]: self.value(self.info["length"])}
        shown = ", ".join(f"{n} = {v:.6g}" for n, v in values.items() if isinstance(v, float) and v != 0
                          and not 1e-150 < abs(v) < 1e150) or "none beyond 1e+/-150"
        raise KernelError(f"the assembled {name} of {self.meta.get('model')} (kernel {kernel!r}) holds "
                          f"{int(np.size(data) - np.isfinite(data).sum())} NaN/Inf entries: a value overflows double "
                          f"precision in the element sums (extreme values: {shown})")

    def _coeff(self, arr: np.ndarray) -> np.ndarray:
        """A flat (..., jets * jets) kernel output as (..., jets, jets) coefficients."""
        na = len(self.disc.jets)
        return arr.reshape(arr.shape[:-1] + (na, na))

    # -- the discretised system ---------------------------------------------
    def linear(self, q=None, v=None, z=None, t: float = 0.0, *, jets=None) -> dict:
        """M, D, G, K about the base state q (or its jets at the Gauss points) with zero acceleration."""
        if "constraint" in self.kernels:
            raise InputError(f"{self.meta.get('model')} holds a pointwise constraint (its multiplier is part of a "
                             "steady state): small motions only about a boundary-value steady state",
                             key="about", expected="modes or stability 'about' a steady analysis with "
                             "form = 'hamiltonian' (mechgen.runtime.steady.constrained)")
        return self.reduced_matrices("linear", ("M", "D", "G", "K"), q, v, None, t, jets)

    def tangent(self, q, v=None, a=None, z=None, t: float = 0.0) -> dict:
        """dr/dq, dr/dq', dr/dq'' (reduced; the penalty term in dr/dq)."""
        return self.reduced_matrices("tangent", ("r_q", "r_v", "r_a"), q, v, a, t)

    def _full_residual(self, full, t: float) -> np.ndarray:
        """sum_e B^T W rho + sum_ends B_at^T rho_at over all dofs (no boundary conditions)."""
        disc = self.disc
        j = self._jets_of(full)
        rho = self.pointwise("residual", *j, t=t)["r"]
        r = self.assembler.vector(element_vectors(disc.tables, disc.weights, rho))
        for B, loc in self._ends("residual", full, t):
            r = r + B.T @ loc["r"][0]
        return r

    def residual(self, q, v=None, a=None, z=None, t: float = 0.0) -> np.ndarray:
        """r(q, q', q'') = Z^T (sum_e B^T W rho + sum_ends B_at^T rho_at + penalty C^T C x)."""
        full = self._full((q, v, a))
        red = self.reduction
        return red.vector(self._full_residual(full, t) + red.penalty_force(full[0], self._row_penalties), q)

    def reactions(self, q, t: float = 0.0) -> list[dict]:
        """Boundary reactions of an equilibrium: the Lagrange multipliers lambda of C x = 0.

        r(x) + C^T lambda = 0 at the equilibrium x = Z q, solved in least squares;
        each reaction is the generalized force conjugate to its constrained jet
        (w: a transverse force, w_s: a moment), positive along the jet. Conditions
        that the basis satisfies by itself (sines at the ends) have none.
        """
        kept, rows = [], []
        for key, row, scale in zip(*self._constraint_rows()):
            if binding(row, scale):
                kept.append(key)
                rows.append(row)
        if not rows:
            return []
        r = self._full_residual(self._full((q, None, None)), t)
        lam = np.linalg.lstsq(np.array(rows).T, -r, rcond=None)[0]
        return [{"jet": f + ("_" + "s" * k if k else ""), "at": at, "value": float(v)}
                for (f, k, at), v in zip(kept, lam)]

    def _nodal_dofs(self, fields) -> list[np.ndarray]:
        """Full-dof numbers of the nodal values of ``fields`` at every mesh vertex (element discretisations)."""
        disc = self.disc
        if disc.mesh is None:
            raise InputError(f"whirl stations need finite elements; {disc.kind} is a global basis",
                             key="discretisation", expected="an element discretisation (quintic, timoshenko2, ...)")
        nloc = disc.dofs.shape[1] // len(disc.fields)
        nodes = 2 if disc.kind == "timoshenko2" else len(reference(disc.kind).nodes)
        last = nloc - nloc // nodes  # the value dof of an element's last node
        out = []
        for f in fields:
            i = disc.fields.index(f)
            block = disc.dofs[:, i * nloc:(i + 1) * nloc]
            out.append(np.concatenate([block[:, 0], block[-1:, last]]))
        return out

    def nodal_indices(self, fields) -> tuple[np.ndarray, ...] | None:
        """Reduced-unknown indices of the nodal values of ``fields`` at the vertices where none is eliminated.

        A nodal value dof *is* the field there: the whirl stations of a rotor, one
        array per field, paired by vertex. None when the unknowns are not a
        selection of dofs (substructures joined by a null-space reduction): see
        :meth:`nodal_rows`.
        """
        red = self.reduction
        if red.Z is not None and red.keep is None:
            return None
        index = np.arange(red.ndof) if red.keep is None else np.full(red.ndof, -1)
        if red.keep is not None:
            index[red.keep] = np.arange(len(red.keep))
        mapped = [index[dofs] for dofs in self._nodal_dofs(fields)]
        kept = np.all([m >= 0 for m in mapped], axis=0)
        return tuple(m[kept] for m in mapped)

    def nodal_rows(self, fields) -> np.ndarray:
        """R with R q = the nodal values of ``fields`` (stacked field by field) for reduced unknowns q."""
        red = self.reduction
        dofs = np.concatenate(self._nodal_dofs(fields))
        require(dense_bytes(len(dofs), red.n) + (dense_bytes(red.ndof, red.n) if red.Z is not None else 0),
                f"the dense map of {red.n} unknowns to {len(dofs)} nodal values", key="params.N")
        if red.Z is None:
            R = np.zeros((len(dofs), red.n))
            R[np.arange(len(dofs)), dofs] = 1.0
            return R
        Z = red.Z.toarray() if sps.issparse(red.Z) else np.asarray(red.Z)
        return Z[dofs]

    def field_values(self, q, points: np.ndarray, order: int = 0) -> dict[str, np.ndarray]:
        """D_s^order of every field at ``points`` for the reduced state q (mode shapes, deflections): u_f = S_f x with
        x the full dof vector and S_f the sparse rows of the basis at the points. ``q`` may hold one state per column
        (then each field's values are points x columns): the rows are tabulated once for all of them (216 modes took
        9 s row by row)."""
        disc = self.disc
        q = np.asarray(q, dtype=float)
        x = self.reduction.expand(q) if q.ndim == 1 else np.column_stack([self.reduction.expand(c) for c in q.T])
        return {f: np.asarray(sps.vstack([sps.csr_matrix(disc.row(f, order, float(p))) for p in points]) @ x)
                for f in disc.fields}

    @property
    def penalty(self) -> float:
        """alpha = f * max|diag K| of the unconstrained zero-state K (0 without penalty rows).

        f balances the penalty error of the lowest eigenvalue against the round-off
        (mechgen.runtime.fields.constrain.penalty_choice: f* = sqrt(P / R)); see :attr:`penalty_choice`.
        """
        choice = self.penalty_choice
        return 0.0 if choice is None else choice.alpha

    def penalty_errors(self, shapes: np.ndarray, eigenvalues: np.ndarray) -> np.ndarray:
        """A-posteriori relative eigenvalue error of each mass-normalised mode the penalty causes
        (mechgen.runtime.fields.constrain.penalty_errors; zeros without penalty rows)."""
        return penalty_errors(self.reduction, self._row_penalties, shapes, eigenvalues)

    @property
    def _row_penalties(self):
        """alpha_j of each penalty row (0.0 without penalty rows)."""
        choice = self.penalty_choice
        return 0.0 if choice is None else choice.alphas

    @property
    def penalty_choice(self) -> PenaltyChoice | None:
        """The penalty factor and its error model (predicted relative error of the lowest eigenvalue)."""
        if self.reduction.penalty_rows is None:
            return None

        def choose() -> PenaltyChoice:
            local = self.pointwise("linear", self._jets(None))
            K, M = (self.assembler.matrix(element_matrices(self.disc.tables, self.disc.weights, self._coeff(local[k])))
                    for k in ("K", "M"))
            return penalty_choice(self.reduction, K, M, constrain.FIXED_FACTOR)

        return self._memo.get(("alpha", *self._reduction_key(), self._pkey, constrain.FIXED_FACTOR), choose)

    def outputs(self, q, v=None, z=None, t: float = 0.0) -> dict[str, float]:
        """Energies: integrals of the kinetic and potential densities plus the end terms."""
        disc = self.disc
        full = self._full((q, v))
        j = self._jets_of(full)
        local = self.pointwise("outputs", *j, t=t)
        values = {k: float(np.sum(disc.weights * arr[..., 0])) for k, arr in local.items()}
        for _, loc in self._ends("outputs", full + [None], t):
            for k, arr in loc.items():
                values[k] += float(arr.ravel()[0])
        bad = [k for k, val in values.items() if not np.isfinite(val)]
        if bad:
            raise KernelError(f"outputs of {self.meta.get('model')} are NaN/Inf: {', '.join(bad)}")
        return values

    def outputs_series(self, t, X) -> dict[str, np.ndarray]:
        """:meth:`outputs` at every sample (row k of X: the state (q, v) at t[k]), the samples of each block of
        points in one kernel call (mechgen.runtime.fields.operators.outputs_series)."""
        from mechgen.runtime.fields.operators import outputs_series

        return outputs_series(self, np.asarray(t, float), np.atleast_2d(np.asarray(X, float)))

    # -- first-order form (time integration) ------------------------------------
    def split(self, x: np.ndarray):
        """(q, v, z) of a first-order state."""
        n = self.n
        return x[:n], x[n:2 * n], x[2 * n:]

    def _mass_solve(self, q, v, t: float, rhs: np.ndarray) -> np.ndarray:
        """M^-1 rhs; a state-independent M (the usual case, known from the derivation) is factorised once."""
        if self.reduction.multiplier_rows is not None:
            raise InputError("time integration with Lagrange multipliers is a DAE (singular mass)",
                             key="constraints", expected="'eliminate' or 'penalty' for simulate")
        if self.info.get("constant_mass"):
            def factor():
                M = self.tangent(np.zeros(self.n), t=t)["r_a"]
                self._require_mass(M)
                return (spla.splu(sps.csc_matrix(M)).solve if sps.issparse(M)
                        else (lambda b, f=sla.cho_factor(M): sla.cho_solve(f, b)))

            return self._memo.get(("mass", *self._reduction_key(), self._pkey), factor)(rhs)
        M = self.tangent(q, v, t=t)["r_a"]
        self._require_mass(M)
        return spla.spsolve(sps.csc_matrix(M), rhs) if sps.issparse(M) else sla.solve(M, rhs)

    @property
    def first_order(self) -> bool:
        """True when no unknown carries mass (no kinetic density, a constant M = 0): every field obeys a first-order
        (or algebraic) law r(q, q', 0) = 0, D(q) q' + f(q) = 0 for a weak form linear in the rates (js_fluid)."""
        if not self.info.get("constant_mass") or self.reduction.multiplier_rows is not None:
            return False

        def empty() -> bool:
            M = self.tangent(np.zeros(self.n))["r_a"]
            return not (M.count_nonzero() if sps.issparse(M) else np.count_nonzero(M))
        return self._memo.get(("first_order", *self._reduction_key(), self._pkey), empty)

    def first_order_rate(self, t: float, q: np.ndarray) -> np.ndarray:
        """q' of a first-order continuum: the root v of r(q, v, 0) = 0 by Newton on r_v (one step when r is linear
        in the rates); a singular r_v (an unknown without a rate: Re = 0 in js_fluid) is refused, a DAE."""
        q = np.asarray(q, float)
        v = np.zeros(self.n)
        r = self.residual(q, v, None, None, t)
        start = np.linalg.norm(r)
        for _ in range(FIRST_ORDER_NEWTON):
            if not np.all(np.isfinite(r)):
                raise KernelError(f"residual of {self.meta.get('model')} gave NaN/Inf at t = {t}")
            tan = self.tangent(q, v, t=t)
            v = v + self._rate_solve(tan["r_v"], -r)
            r = self.residual(q, v, None, None, t)
            # converged: |r| down by 1/FIRST_ORDER_RTOL, or at the round-off of its terms (a state near steady has a
            # tiny |r(q, 0, 0)| itself), eps |terms| ~ eps (|r_q| |q| + |r_v| |v| + |r(q, 0, 0)|)
            terms = np.linalg.norm(abs(tan["r_q"]) @ np.abs(q) + abs(tan["r_v"]) @ np.abs(v)) + start
            if np.linalg.norm(r) <= max(FIRST_ORDER_RTOL * start, ROUND_OFF * terms):
                return v
        raise ConvergenceError(f"the rates of {self.meta.get('model')} at t = {t}: Newton on r(q, q', 0) = 0 left "
                               f"|r| = {np.linalg.norm(r):.3g} after {FIRST_ORDER_NEWTON} steps (from {start:.3g})")

    def first_order_jacobian(self, t: float, q: np.ndarray):
        """d q'/dq = -r_v^-1 r_q at (q, q'(q)) (dense; a first-order continuum's implicit integration)."""
        v = self.first_order_rate(t, q)
        require_dense(self.n, 8, "the dense first-order Jacobian (implicit time integration)",
                      expected="a smaller N, or an explicit method (RK45, DOP853)")
        tan = self.tangent(q, v, t=t)
        r_q = tan["r_q"].toarray() if sps.issparse(tan["r_q"]) else np.asarray(tan["r_q"])
        return -self._rate_solve(tan["r_v"], r_q)

    def _rate_solve(self, r_v, rhs: np.ndarray) -> np.ndarray:
        """r_v^-1 rhs, refusing rows without a rate (an algebraic unknown: a DAE)."""
        empty = empty_rows(r_v)
        if empty:
            raise InputError(f"model {self.meta.get('model')}: {empty} of {self.n} unknowns have neither mass nor a "
                             "rate (algebraic, a DAE: an inertialess field); simulate integrates ODEs",
                             key="kind", expected="a rate on every field (js_fluid: Re > 0), or steady / stability")
        A = sps.csc_matrix(r_v) if sps.issparse(r_v) else np.asarray(r_v)
        return spla.spsolve(A, rhs) if sps.issparse(r_v) else sla.solve(A, rhs)

    def _require_mass(self, M) -> None:
        """Refuse a mass matrix with zero rows: fields without kinetic energy obey first-order (or algebraic) laws,
        D(q) q' + f(q) = 0, which the second-order integration (q, v) cannot run."""
        empty = empty_rows(M)
        if empty:
            raise InputError(f"model {self.meta.get('model')}: {empty} of {self.n} unknowns carry no mass (fields "
                             "without a kinetic density obey first-order or algebraic laws, D(q) q' + f(q) = 0); "
                             "simulate integrates continua with a mass on every field, or on none (first-order fields)",
                             key="kind", expected="a kinetic density on every field, or on none of them")

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """dx/dt = (v, -M^-1 r(q, v, 0))."""
        q, v, _ = self.split(x)
        a = self._mass_solve(q, v, t, -self.residual(q, v, None, None, t))
        out = np.concatenate([v, a])
        if not np.all(np.isfinite(out)):
            raise KernelError(f"residual of {self.meta.get('model')} gave NaN/Inf at t = {t}")
        return out

    def jacobian(self, t: float, x: np.ndarray):
        """d(dx/dt)/dx with da/d(q, v) = -M^-1 [r_q, r_v] at the current acceleration."""
        q, v, _ = self.split(x)
        a = None if self.info.get("constant_mass") else self.rhs(t, x)[self.n:]
        require_dense(self.n, 12, "the dense first-order Jacobian (implicit time integration)",
                      expected="a smaller N, or an explicit method (RK45, DOP853) or leapfrog")
        tan = self.tangent(q, v, a, t=t)
        dense = lambda A: A.toarray() if sps.issparse(A) else A  # noqa: E731
        da = -self._mass_solve(q, v, t, np.hstack([dense(tan["r_q"]), dense(tan["r_v"])]))
        n = self.n
        return np.block([[np.zeros((n, n)), np.eye(n)], [da]])


def empty_rows(A) -> int:
    """How many rows of A (dense or sparse) are entirely zero."""
    rows = np.asarray(abs(A).sum(axis=1)).ravel() if sps.issparse(A) else np.abs(np.asarray(A)).sum(axis=1)
    return int(np.count_nonzero(rows == 0.0))


#: Newton steps of a first-order continuum's rate q' (one suffices when r is linear in the rates)
FIRST_ORDER_NEWTON = 20
#: ... until |r(q, q', 0)| falls below this fraction of |r(q, 0, 0)| (a linear r: round-off, ~1e-15, at once)
FIRST_ORDER_RTOL = 1e-10
#: ... or below this many machine epsilons of the size of its terms
ROUND_OFF = 1e3 * np.finfo(float).eps


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
