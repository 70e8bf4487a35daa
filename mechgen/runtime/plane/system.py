"""A compiled plane continuum: pointwise kernels + a mesh = the discretised system.

The generated kernels evaluate, at a batch of points, the local residual rho(j, j_t, j_tt; x, y) of the
jets and its Jacobians (mechgen.symbolic.plane); this class supplies the repetition numerically: the mesh
(generated for the model's domain at the size ``h``, or given), the element tables, one batched kernel call
over every quadrature point, assembly (mechgen.runtime.plane.assemble) and the essential boundary
conditions, eliminated: with the free dofs F and x = Z q (zeros on the held dofs),

    r(q) = Z^T [ sum_e B_e^T W_e rho(B_e x) + sum_edges B_b^T W_b rho_b(B_b x) ],
    K = dr/dq = Z^T (sum_e B^T W (d rho/dj) B + edges) Z,  M from d rho/dj_tt, D + G from d rho/dj_t.

Like every system it is immutable: :meth:`PlaneSystem.with_params` and :meth:`PlaneSystem.with_mesh` give
new ones. Units are the model's (SI for the shipped ones; densities per unit thickness).
"""
from __future__ import annotations

from dataclasses import InitVar, dataclass, field, replace

import numpy as np

from mechgen.errors import InputError, KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense
from mechgen.runtime.core.meta import SystemMeta
from mechgen.runtime.core.system import Memo, frozen_vector, number, read_only, replacement_vector, with_values
from mechgen.runtime.plane import assemble
from mechgen.runtime.plane.discretise import PlaneDisc, discretise, generate_mesh

sps = lazy_module("scipy.sparse")


#: the runtime choices of every plane continuum and the values they take
CHOICE_VALUES = {"element": ("P1", "P2", "Q1", "Q2"), "edges": ("curved", "straight")}


@dataclass(frozen=True)
class PlaneSystem:
    """Kernels, meta, free parameter values, folded values and runtime choices of a plane continuum (and,
    optionally, a mesh given instead of the generated one)."""

    kernels: dict
    meta: dict
    params: np.ndarray
    fixed: dict
    choices: dict
    backend: str = "numpy"
    given_mesh: object = None
    _cache: InitVar[dict | None] = None
    rebuild: object = field(default=None, repr=False)
    folded: tuple[str, ...] = ()
    facts: object = field(default=None, repr=False, compare=False)
    #: the model's choices folded into the kernels (a plane law's ``plane = "strain"``), for reading only
    selections: dict = field(default_factory=dict)
    _memo: Memo = field(init=False, repr=False)

    is_plane = True
    is_field = False
    is_lattice = False
    m = 0

    def __post_init__(self, _cache) -> None:
        object.__setattr__(self, "params", frozen_vector(self.params))
        for name in ("kernels", "meta", "fixed", "choices", "selections"):
            object.__setattr__(self, name, read_only(getattr(self, name)))
        object.__setattr__(self, "folded", tuple(self.folded))
        object.__setattr__(self, "_memo", Memo(32))

    # -- new systems ----------------------------------------------------------
    def with_param_vector(self, params) -> "PlaneSystem":
        """The same kernels, choices and mesh with another vector of free parameter values (memo shared)."""
        params = replacement_vector(self, params)
        if params is None:
            return self
        new = replace(self, params=params)
        object.__setattr__(new, "_memo", self._memo)
        return new

    def with_params(self, **values) -> "PlaneSystem":
        """A new system with these values: free numeric parameters, runtime choices (element, h, edges,
        quadrature and the model's own), or a folded name through ``rebuild``."""
        return with_values(self, values, _choice)

    def with_mesh(self, mesh) -> "PlaneSystem":
        """The same kernels on a given :class:`~mechgen.runtime.plane.mesh.PlaneMesh` (a gmsh file read by
        :func:`~mechgen.runtime.plane.mesh.read_msh`): its boundaries must hold the ones the model names."""
        missing = sorted(({c[1] for c in self.info["constraints"] if c[1] != "rigid"}
                          | (set(self.info["edges"]) - set(self.info.get("points", {}))))
                         - set(mesh.boundaries))
        if missing:
            raise InputError(f"the mesh has no boundary {missing[0]!r} that model {self.meta.get('model')} names",
                             key="mesh", expected="a mesh whose boundaries (physical groups) include "
                                                  + ", ".join(missing) + f"; it has {', '.join(mesh.boundaries)}")
        return replace(self, given_mesh=mesh)

    def param_values(self) -> dict:
        """The free parameters' current values and the runtime choices, by name."""
        return {**{n: float(v) for n, v in zip(self.meta.get("params", []), self.params)}, **self.choices}

    # -- facts ------------------------------------------------------------------
    @property
    def metadata(self) -> SystemMeta:
        """The typed view of ``meta``."""
        return SystemMeta.of(self.meta)

    @property
    def info(self) -> dict:
        """Plane facts from the kernel meta (mechgen.codegen.lower_plane.plane_meta)."""
        return self.meta["plane"]

    def value(self, name: str) -> float:
        """Current value of a numeric parameter (free from ``params``, else folded)."""
        names = self.meta.get("params", [])
        return float(self.params[names.index(name)]) if name in names else float(self.fixed[name])

    def _mesh_key(self) -> tuple:
        sizes = tuple(self.value(n) for n in self.info["sizes"].values())
        return (sizes, float(self.choices["h"]), self.choices["element"], self.choices["edges"],
                float(self.choices.get("grading", 1.0)))

    @property
    def mesh(self):
        """The mesh: the given one, else generated for the domain (memoised by sizes, h, element, edges)."""
        if self.given_mesh is not None:
            return self.given_mesh
        sizes = {role: self.value(n) for role, n in self.info["sizes"].items()}
        return self._memo.get(("mesh", *self._mesh_key()), lambda: generate_mesh(
            self.info["shape"], sizes, float(self.choices["h"]), self.choices["element"],
            self.choices["edges"] == "curved", float(self.choices.get("grading", 1.0))))

    @property
    def disc(self) -> PlaneDisc:
        """Tables, dof maps, held dofs and the assembler of the current mesh."""
        points = self.point_positions()
        key = ("disc", id(self.given_mesh) if self.given_mesh is not None else self._mesh_key(),
               int(self.choices["quadrature"]), tuple(sorted(points.items())))
        return self._memo.get(key, lambda: discretise(self.mesh, self.info, int(self.choices["quadrature"]), points))

    def point_positions(self) -> dict:
        """{name: (x, y)} of the model's point terms at the current parameter values (m)."""
        return {name: tuple(self.value(v) if isinstance(v, str) else float(v) for v in xy)
                for name, xy in self.info.get("points", {}).items()}

    @property
    def n(self) -> int:
        """Unknowns after the boundary conditions are eliminated."""
        return len(self.disc.free)

    @property
    def coordinates(self) -> list[str]:
        """Names of the unknowns: ``<field>[<node>]``."""
        fields = self.info["fields"]
        return [f"{fields[d % len(fields)]}[{d // len(fields)}]" for d in self.disc.free]

    # -- kernels ------------------------------------------------------------------
    def expand(self, q) -> np.ndarray:
        """The full dof vector x = Z q (zeros on the held dofs)."""
        disc = self.disc
        x = np.zeros(disc.ndof)
        if q is not None:
            x[disc.free] = np.asarray(q, float)
        return x

    def _evaluate(self, kernel: str, states, position: np.ndarray, t: float) -> dict:
        """One batched call of a pointwise kernel; states (j, j_t, j_tt) arrays (..., jets)."""
        shape = position.shape[:-1]
        npts = int(np.prod(shape))
        na = states[0].shape[-1]
        flat = lambda x: np.ascontiguousarray(np.reshape(x, (npts, na)))  # noqa: E731
        inputs = {"q": flat(states[0]), "v": flat(states[1]), "a": flat(states[2]), "z": np.zeros((npts, 0)),
                  "t": np.full((npts, 1), float(t)), "s": np.ascontiguousarray(position.reshape(npts, -1)),
                  "p": self.params}
        try:
            out = self.kernels[kernel].evaluate(inputs)
        except KernelError as exc:
            raise KernelError(f"{exc} (pointwise kernel of {self.meta.get('model')})") from None
        return {k: v.reshape(shape + (v.shape[-1],)) for k, v in out.items()}

    def _pieces(self, kernel: str, full: tuple, t: float):
        """(tables, jet index, weights, dof map, kernel outputs) of the domain and of each edge term."""
        disc = self.disc
        nf = len(self.info["fields"])
        for piece in disc.pieces:
            name = kernel if piece.edge is None else f"{kernel}_at_{piece.edge}"
            states = [assemble.point_jets(piece.T, piece.index, x[piece.dofs].reshape(len(piece.dofs), -1, nf))
                      for x in full]
            yield piece, self._evaluate(name, states, piece.position, t)

    def _states(self, q, v, a) -> tuple:
        return tuple(self.expand(x) for x in (q, v, a))

    def full_residual(self, q, v=None, a=None, t: float = 0.0) -> np.ndarray:
        """r over every dof (held ones included: their entries are the reactions)."""
        disc = self.disc
        nf = len(self.info["fields"])
        out = np.zeros(disc.ndof)
        for piece, local in self._pieces("residual", self._states(q, v, a), t):
            r_e = assemble.element_vectors(piece.T, piece.index, piece.weights, local["r"], nf)
            out += np.bincount(piece.dofs.ravel(), weights=r_e.ravel(), minlength=disc.ndof)
        _require_finite(self, "residual", out)
        return out

    def residual(self, q, v=None, a=None, z=None, t: float = 0.0) -> np.ndarray:
        """The reduced residual Z^T r."""
        return self.full_residual(q, v, a, t)[self.disc.free]

    def _matrices(self, kernel: str, names, q, v, a, t: float) -> dict:
        disc = self.disc
        nf = len(self.info["fields"])
        total = {k: None for k in names}
        for piece, local in self._pieces(kernel, self._states(q, v, a), t):
            na = len(piece.index)
            for k in names:
                coeff = local[k].reshape(local[k].shape[:-1] + (na, na))
                if not coeff.any():  # NaN counts as non-zero: it reaches the finiteness check
                    continue  # identically zero here (r_v, r_a of a static model): nothing to scatter
                K_e = assemble.element_matrices(piece.T, piece.index, piece.weights, coeff, nf)
                mat = piece.assembler.matrix(K_e)
                total[k] = mat if total[k] is None else total[k] + mat
        free = disc.free
        out = {}
        for k, mat in total.items():
            if mat is None:
                out[k] = sps.csr_matrix((len(free), len(free)))
                continue
            reduced = mat.tocsr()[free][:, free].tocsr()
            _require_finite(self, k, reduced.data)
            out[k] = reduced
        return out

    def tangent(self, q, v=None, a=None, z=None, t: float = 0.0) -> dict:
        """r_q, r_v, r_a (reduced, CSR) at the state."""
        return self._matrices("tangent", ("r_q", "r_v", "r_a"), q, v, a, t)

    def acceleration(self, q, v, z=None, t: float = 0.0):
        """(a, M): the acceleration solving r(q, v, a) = 0 for a residual linear in a, a = -M^-1 r(q, v, 0),
        M = dr/da (sparse LU; m/s^2 for a displacement), and M."""
        try:
            M, lu = self.mass_factor(q, v, t)
            return lu.solve(-self.residual(q, v, None, t=t)), M
        except RuntimeError:
            raise InputError(f"the mass matrix of plane model {self.meta.get('model')} is singular: a field "
                             "without kinetic energy, so its motion has no acceleration", key="kind",
                             expected="a model whose kinetic density holds every field's rate (or steady, "
                                      "continuation)") from None

    def mass_factor(self, q, v, t: float = 0.0):
        """(M, its sparse LU) at the state; a model whose mass is constant (meta ``constant_mass``) assembles and
        factors it once per parameter vector and mesh (memoised), not at every call of :meth:`rhs`."""
        import scipy.sparse.linalg as spla

        def make():
            M = self._matrices("tangent", ("r_a",), q, v, None, t)["r_a"].tocsc()
            return M, spla.splu(M)
        if not self.info.get("constant_mass"):
            return make()
        key = ("mass", self.params.tobytes(), id(self.given_mesh) if self.given_mesh is not None else self._mesh_key(),
               int(self.choices["quadrature"]))
        return self._memo.get(key, make)

    def rhs(self, t: float, x) -> np.ndarray:
        """dx/dt = (v, a) of the first-order form x = (q, v), a from :meth:`acceleration`."""
        n = self.n
        x = np.asarray(x, float)
        a, _ = self.acceleration(x[:n], x[n:2 * n], t=t)
        out = np.concatenate([x[n:2 * n], a])
        _require_finite(self, "rate of the state", out)
        return out

    def jacobian(self, t: float, x):
        """d(dx/dt)/dx = [[0, I], [-M^-1 r_q, -M^-1 r_v]] at the current acceleration (sparse CSC; M^-1 applied by a
        sparse LU to the sparse blocks: for the small systems an explicit or implicit flow integrates)."""
        import scipy.sparse as sps

        n = self.n
        x = np.asarray(x, float)
        q, v = x[:n], x[n:2 * n]
        a, M = self.acceleration(q, v, t=t)
        tan = self.tangent(q, v, a, t=t)
        require_dense(n, 6, "the Jacobian of a plane model's flow (implicit methods)", key="method",
                      expected="an explicit method (DOP853, RK45) for a plane model this large, or a coarser mesh")
        lu = self.mass_factor(q, v, t)[1]
        blocks = np.hstack([tan["r_q"].toarray(), tan["r_v"].toarray()])
        da = -lu.solve(blocks)
        top = sps.hstack([sps.csr_matrix((n, n)), sps.identity(n, format="csr")])
        return sps.vstack([top, sps.csr_matrix(da)]).tocsc()

    def linear(self, q=None, v=None, z=None, t: float = 0.0) -> dict:
        """M, D, G, K (reduced, CSR) of the linearisation about q with zero rates."""
        return self._matrices("linear", ("M", "D", "G", "K"), q, None, None, t)

    def outputs(self, q, v=None, z=None, t: float = 0.0) -> dict[str, float]:
        """The domain integrals of the model's output densities and of the energies; the edge terms' energies
        (a traction's potential -t.u) are added to ``potential_energy``, ``kinetic_energy`` and ``energy``."""
        out: dict[str, float] = {}
        for piece, local in self._pieces("outputs", self._states(q, v, None), t):
            for k, val in local.items():
                out[k] = out.get(k, 0.0) + float(np.sum(piece.weights * val[..., 0]))
        return out

    def field_at(self, q, points) -> tuple[np.ndarray, np.ndarray]:
        """Values (p, fields) and gradients (p, fields, 2) of the fields at points (x, y) of the mesh."""
        from mechgen.runtime.plane.points import locate, point_shapes

        mesh = self.mesh
        cells, refs = locate(mesh, points)
        N, dN = point_shapes(mesh, cells, refs)
        nf = len(self.info["fields"])
        local = self.expand(q).reshape(-1, nf)[mesh.cells[cells]]  # (p, l, fields)
        return np.einsum("pl,plf->pf", N, local), np.einsum("pld,plf->pfd", dN, local)

    def stress_at(self, q, points) -> np.ndarray:
        """dV/dH at points: rows per field f, columns d/dx, d/dy (the first Piola stress of a displacement,
        sigma_ij = dV/d(du_i/dx_j); Pa, the energy density's unit), from the residual kernel at zero rates."""
        points = np.atleast_2d(np.asarray(points, float))
        values, grads = self.field_at(q, points)
        fields = self.info["fields"]
        index = [(fields.index(f), k) for f, k in self.info["jets"]]
        jets = np.array([[values[i, c] if k == "" else grads[i, c, "xy".index(k)] for c, k in index]
                         for i in range(len(points))])
        rho = self._evaluate("residual", (jets, 0 * jets, 0 * jets), points, 0.0)["r"]
        out = np.full((len(points), len(fields), 2), np.nan)
        for a, (c, k) in enumerate(index):
            if k:
                out[:, c, "xy".index(k)] = rho[:, a]
        return out

    def cell_stress(self, q) -> np.ndarray | None:
        """dV/dH averaged over each element (e, fields, 2), None for a model without gradient jets."""
        from mechgen.runtime.plane.plotting import cell_means

        piece = self.disc.pieces[0]
        index = piece.index
        if not any(k for _, k in index):
            return None
        nf = len(self.info["fields"])
        x = self.expand(q)
        jets = assemble.point_jets(piece.T, index, x[piece.dofs].reshape(len(piece.dofs), -1, nf))
        rho = self._evaluate("residual", (jets, 0 * jets, 0 * jets), piece.position, 0.0)["r"]
        out = np.zeros(rho.shape[:2] + (nf, 2))
        for a, (c, k) in enumerate(index):
            if k:
                out[:, :, c, k - 1] = rho[:, :, a]
        return cell_means(piece.weights, out)

    def quadrature_state(self, q) -> dict:
        """A state at the domain's quadrature points: ``x`` (e, g, 2), ``w`` (e, g), ``u`` (e, g, fields),
        ``grad_u`` (e, g, fields, 2), ``stress`` dV/d(grad u) (e, g, fields, 2), ``body`` the residual's value
        entries at zero rates (e, g, fields: minus the body force), ``N`` (g, l) and ``dN`` (e, g, l, 2)."""
        piece = self.disc.pieces[0]
        nf = len(self.info["fields"])
        x = self.expand(q)
        local = x[piece.dofs].reshape(len(piece.dofs), -1, nf)
        T0, Tx, Ty = piece.T
        u = np.einsum("egl,elf->egf", T0, local)
        grad = np.stack([np.einsum("egl,elf->egf", Tx, local), np.einsum("egl,elf->egf", Ty, local)], axis=-1)
        jets = assemble.point_jets(piece.T, piece.index, local)
        rho = self._evaluate("residual", (jets, 0 * jets, 0 * jets), piece.position, 0.0)["r"]
        stress, body = np.zeros_like(grad), np.zeros_like(u)
        for a, (c, k) in enumerate(piece.index):
            if k:
                stress[..., c, k - 1] = rho[..., a]
            else:
                body[..., c] = rho[..., a]
        return {"x": piece.position, "w": piece.weights, "u": u, "grad_u": grad, "stress": stress, "body": body,
                "N": T0[0], "dN": np.stack([Tx, Ty], axis=-1)}

    def require_no_body_force(self, q) -> None:
        """InputError when the residual has value entries at rest (a body force): the crack integrals' domain
        forms here hold without one."""
        data = self.quadrature_state(q)
        scale = max(float(np.abs(data["stress"]).max()), 1e-300)
        if np.abs(data["body"]).max() > 1e-12 * scale:
            raise InputError(f"model {self.meta.get('model')} has a body force (or a value-dependent energy): M, L, "
                             "Bueckner's and the interaction integrals are implemented without one", key="kind",
                             expected="a model whose energy depends on the displacement gradient only")

    def figure_data(self, columns) -> dict:
        """What a figure of fields on this mesh needs (lists, JSON-ready): node ``x``, ``y``, sub-triangles
        ``triangles`` and their element ``cell``, ``fields`` names and ``values`` (columns of full nodal values,
        one per state of ``columns``: dofs x states, free dofs only)."""
        from mechgen.runtime.plane.plotting import triangulation

        mesh = self.mesh
        nf = len(self.info["fields"])
        tris, cell = triangulation(mesh.cells, mesh.element)
        cols = np.asarray(columns, float)
        cols = cols[:, None] if cols.ndim == 1 else cols
        values = [self.expand(cols[:, j]).reshape(-1, nf).T for j in range(cols.shape[1])]
        return {"x": mesh.points[:, 0], "y": mesh.points[:, 1], "triangles": tris, "cell": cell,
                "fields": list(self.info["fields"]), "values": values}

    def nodal_fields(self, q) -> dict:
        """The state at the mesh's nodes: ``x``, ``y`` (n,), ``values`` (n, fields), ``gradients`` (n, fields, 2)
        (each cell's gradient at its nodes, averaged over the cells that share a node: mechgen.runtime.plane
        .elements.node_gradients) and ``stress`` (n, fields, 2), dV/d(grad u) from the residual kernel at those
        nodal jets (a node's position as the kernel's (x, y))."""
        from mechgen.runtime.plane.elements import node_gradients

        mesh = self.mesh
        nf = len(self.info["fields"])
        values = self.expand(q).reshape(-1, nf)
        grads = node_gradients(mesh, values)
        fields = self.info["fields"]
        index = [(fields.index(f), k) for f, k in self.info["jets"]]
        jets = np.stack([values[:, c] if k == "" else grads[:, c, "xy".index(k)] for c, k in index], axis=1)
        stress = np.full(grads.shape, np.nan)
        if any(k for _, k in index):
            rho = self._evaluate("residual", (jets, 0 * jets, 0 * jets), mesh.points, 0.0)["r"]
            for a, (c, k) in enumerate(index):
                if k:
                    stress[:, c, "xy".index(k)] = rho[:, a]
        return {"x": mesh.points[:, 0], "y": mesh.points[:, 1], "values": values, "gradients": grads,
                "stress": stress}

    def reactions(self, q, t: float = 0.0) -> dict:
        """The force each held boundary exerts on the body, per field: sum of r over its held dofs (N per unit
        thickness, the fields' force unit)."""
        r = self.full_residual(q, t=t)
        return {name: {f: float(r[dofs].sum()) for f, dofs in held.items()}
                for name, held in self.disc.held.items()}


def _require_finite(system: PlaneSystem, what: str, data) -> None:
    if not np.isfinite(data).all():
        raise KernelError(f"the assembled {what} of {system.meta.get('model')} holds NaN/Inf entries: a value "
                          "overflows double precision, or the kernel is singular at the state")


def _choice(name: str, value):
    """A runtime choice's new value, validated."""
    if name == "quadrature":
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < 0:
            raise InputError(f"quadrature = {value!r} is not a degree", key=name, expected="an integer >= 0")
        return int(value)
    if name == "h":
        h = number(name, value)
        if not h > 0:
            raise InputError(f"h = {value!r} is not a positive mesh size", key=name, expected="a number > 0")
        return h
    if name == "grading":
        g = number(name, value)
        if not 1.0 <= g <= 4.0:
            raise InputError(f"grading = {value!r} is outside [1, 4]", key=name, expected="a number from 1 to 4")
        return g
    allowed = CHOICE_VALUES.get(name)
    if allowed is not None and value not in allowed:
        raise InputError(f"{name} = {value!r} is not a choice the runtime knows", key=name,
                         expected="one of: " + ", ".join(allowed))
    return value

