"""Declaring a model: parameters, coordinates, energies, forces, internal variables, outputs.

A :class:`Model` only records what the user declares; nothing symbolic happens
until :func:`mechgen.symbolic.derive.derive` calls the declared functions on
symbols. Declared functions receive, by parameter name, any of

* ``q`` - generalized coordinates (a :class:`Namespace` of sympy symbols),
* ``v`` - generalized velocities dq/dt,
* ``z`` - internal variables (their own first-order evolution laws),
* ``p`` - parameters (symbols, numbers once a scene fixes them, strings for choices),
* ``t`` - time.

A lattice model (:meth:`Model.chain`) declares instead one *site* and one
*bond* energy; see :mod:`mechgen.symbolic.lattice`.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from mechgen.errors import ModelError
from mechgen.symbolic.discretisations import DISCRETISATIONS
from mechgen.symbolic.hybrid import DIRECTIONS, Guard, ModeScope
from mechgen.symbolic.names import RESERVED, check_identifier, name_clash_error, output_clash
from mechgen.symbolic.params import Namespace, Param
from mechgen.symbolic.plane_domain import ELEMENTS, SHAPES, Domain, PlaneSpec
from mechgen.symbolic.rod import RodSpec

ARG_NAMES = ("q", "v", "z", "p", "t")


@dataclass(frozen=True)
class Output:
    """A named output evaluated on demand from the state."""

    name: str
    fn: Callable
    unit: str = ""
    doc: str = ""
    #: a 1D continuum's output reported as the integral of ``fn`` over s (on Galerkin states), not pointwise
    integrate: bool = False


@dataclass(frozen=True)
class ShapeOutput:
    """A number measured on a sampled steady state of a continuum (e.g. a balloon's loop count).

    ``fn`` and ``start`` are plain numeric functions (nothing symbolic): see :meth:`Model.shape_output`.
    """

    name: str
    fn: Callable
    start: Callable | None = None
    doc: str = ""


@dataclass(frozen=True)
class Continuum:
    """Scalar fields on s in [0, L], L the value of parameter ``length``."""

    fields: tuple[str, ...]
    length: str


@dataclass(frozen=True)
class Internal:
    """An internal variable z with dz/dt = rate(q, v, z, p, t)."""

    name: str
    rate: Callable
    initial: float = 0.0
    doc: str = ""


@dataclass(frozen=True)
class Chain:
    """A one-dimensional lattice: ``sites`` (a size parameter) identical sites.

    ``ends`` is ``"fixed"`` (ghost sites 0 and N+1 held at zero) or
    ``"periodic"`` (site N+1 is site 1).
    """

    coordinate: str
    sites: str
    ends: str


def _caller_file() -> str | None:
    """``__file__`` of the module whose top level constructs a Model, else None.

    The file's bytes key the compile cache, so only a model declared at module level takes it: one
    built inside a function (a factory, a test) may depend on the function's arguments, which the
    file's bytes do not show; it passes ``file=`` itself or is derived afresh. None as well from an
    interactive session.
    """
    frame = sys._getframe(2)
    if frame.f_code.co_name != "<module>":
        return None
    file = frame.f_globals.get("__file__")
    return str(Path(file).resolve()) if isinstance(file, str) and Path(file).is_file() else None


class Model:
    """A mechanical model declared by its energies.

    Example::

        model = Model("spring_pendulum", doc=__doc__)
        model.params(Param("m", 1.0, "kg"), Param("k", 10.0, "N/m"))
        model.coordinates("r", "theta")

        @model.kinetic
        def kinetic(q, v, p):
            return p.m / 2 * (v.r**2 + q.r**2 * v.theta**2)
    """

    def __init__(self, name: str, doc: str = "", *, file: str | None = None) -> None:
        self.name = check_identifier(name, what="model")
        self.doc = (doc or "").strip()
        #: the Python file that declares the model (keys the compile cache); taken from the caller's module
        #: when not given and declared at its top level, so a model file need not pass ``file=__file__``
        self.file = file if file is not None else _caller_file()
        #: the canonical reference (mechgen.models.resolve) the model was loaded by; None when built in a script
        self.source: str | None = None
        self.param_list: list[Param] = []
        self.coordinate_names: list[str] = []
        #: how Lagrange's equations are derived (:meth:`derivation`)
        self.derivation_mode = "auto"
        self.internals: list[Internal] = []
        self.outputs: list[Output] = []
        self.shape_outputs: list[ShapeOutput] = []
        self.kinetic_fn: Callable | None = None
        self.potential_fn: Callable | None = None
        self.dissipation_fn: Callable | None = None
        self.complementary_fn: Callable | None = None
        self.constraint_fn: Callable | None = None
        self.strain_fn: Callable | None = None
        self.forces_fn: Callable | None = None
        self.initial_fn: Callable | None = None
        self.chain_spec: Chain | None = None
        self.site_kinetic_fn: Callable | None = None
        self.site_potential_fn: Callable | None = None
        self.bond_potential_fn: Callable | None = None
        self.continuum: Continuum | None = None
        #: a plane continuum's fields, groups and domain (:meth:`plane`), None otherwise
        self.plane_spec = None
        #: a plane continuum's edge terms {boundary: {"potential" | "dissipation" | "weak": fn}}
        self.edge_terms: dict[str, dict[str, Callable]] = {}
        #: a plane continuum's point terms {name: (x, y)}, numbers or parameter names (:meth:`point_potential_at`)
        self.plane_points: dict[str, tuple] = {}
        self.weak_fn: Callable | None = None
        self.boundary_fn: Callable | None = None
        self.point_terms: dict[str, dict[str, Callable]] = {}
        self.parts: dict[str, tuple[str, ...]] = {}
        #: each part kind's declared checks (:meth:`part`): (key, condition, expected) per check, in order
        self.part_checks: dict[str, tuple[tuple[str, str, str], ...]] = {}
        self.shear_pairs: list[tuple[str, str, int]] = []
        #: the whirl stations (Model.whirl_pair): x1, y1[, x2, y2, ...]; None when the model declares none
        self.whirl: tuple[str, ...] | None = None
        #: hybrid models (mechgen.symbolic.hybrid): the modes in declaration order, the initial one, the guards
        self.mode_scopes: dict = {}
        self.initial_mode: str | None = None
        self.guards: list = []
        #: the declared cross-section stiffness K(p) (6 x 6), or None (:meth:`section_stiffness`)
        self.section_fn: Callable | None = None
        #: the declared Cosserat rod (mechgen.symbolic.rod.RodSpec), or None (:meth:`rod`)
        self.rod_spec = None

    # -- declarations ---------------------------------------------------
    def params(self, *params: Param) -> Namespace:
        """Declare parameters (each a :class:`~mechgen.symbolic.params.Param`); returns a namespace of the symbols of
        every parameter declared so far.

        A numeric parameter is a real sympy symbol in the declared functions (``p.k``) until a scene or
        :func:`mechgen.compile` fixes it, when it becomes a number folded into the kernels; a *size*
        (``size=True``, a chain's site count) never enters an expression; a *choice* (a string default, or
        ``choices=(...)``) is a string in the declared functions, so a model branches on it while it is declared
        (``if p.law == "maxwell": ...``) and each choice derives its own kernels. Names must be identifiers
        that are neither Python/C keywords nor names mechgen derives (``x_dot`` beside a coordinate ``x``).

        Example: ``model.params(Param("m", 1.0, "kg", "mass", positive=True), Param("law", "linear",
        choices=("linear", "cubic")))``.
        """
        for prm in params:
            self._claim(prm.name, "parameter")
            self.param_list.append(prm)
        return Namespace({prm.name: prm.symbol for prm in self.param_list})

    def coordinates(self, *names: str) -> tuple[str, ...]:
        """Declare the generalized coordinates of a lumped model; returns their names.

        Each coordinate ``x`` is ``q.x`` in the declared functions, its velocity dx/dt ``v.x``; the state and the
        results name the velocity ``x_dot`` (and the acceleration ``x_ddot``). Example:
        ``model.coordinates("r", "theta")``.
        """
        for name in names:
            self._claim(name, "coordinate")
            self.coordinate_names.append(name)
        return tuple(names)

    def derivation(self, how: str) -> None:
        """Choose how a lumped model's equations are differentiated: ``"symbolic"`` (sympy, exact expressions),
        ``"ad"`` (CasADi's algorithmic differentiation on the energies' graph, mechgen.symbolic.derive_ad: the
        build grows with the model's size, not its expansion) or ``"auto"`` (the default: AD for a plain lumped
        model of 8 coordinates or more, or energies of more than 400 operations)."""
        if how not in ("auto", "symbolic", "ad"):
            raise ModelError(f"derivation {how!r} of model {self.name}", file=self.file, key="derivation",
                             expected="'auto', 'symbolic' or 'ad'")
        self.derivation_mode = how

    def internal(self, name: str, rate: Callable, *, initial: float = 0.0, doc: str = "") -> None:
        """Declare an internal variable z with its own first-order law dz/dt = rate(q, v, z, p, t).

        ``rate`` receives, by parameter name, any of ``q``, ``v``, ``z``, ``p``, ``t`` and returns one scalar
        expression (the rate, in the variable's unit per second); the variable is ``z.<name>`` in every declared
        function and part of the state after the velocities, starting at ``initial`` unless ``@model.initial``
        or a scene says otherwise. A friction state, a viscoelastic element's internal displacement:
        ``model.internal("y", lambda q, z, p: p.k / p.c * (q.x - z.y))``.
        """
        self._claim(name, "internal variable")
        self.internals.append(Internal(name, rate, float(initial), doc))

    def output(self, name: str, fn: Callable, *, unit: str = "", doc: str = "", integrate: bool = False) -> None:
        """Declare a named output: a scalar expression reported beside the state.

        In a lumped model ``fn`` receives, by parameter name, any of ``q``, ``v``, ``z``, ``p``, ``t`` and returns
        one scalar expression; ``simulate`` reports its time history (``trajectory[name]``), the other analyses its
        value where they report a state. In a continuum ``fn`` receives ``u`` (jets), ``p``, ``s`` and ``n`` (the
        stress resultants n = dV/du_s, a string's tension vector) and is reported on steady states. ``unit`` and
        ``doc`` document it. The name must not be one mechgen reports itself
        (:data:`mechgen.symbolic.names.BUILTIN_OUTPUTS`, :data:`~mechgen.symbolic.names.RESULT_KEYS`: ``energy``,
        ``iterations`` ...). Example: ``model.output("height", lambda q, p: -p.l * sp.cos(q.theta), unit="m")``.

        ``integrate=True`` (a continuum, after :meth:`field`): the output is the integral of ``fn`` over
        s in [0, L], reported on the Galerkin states (``steady`` by Newton, ``continuation``, ``simulate``) by the
        same quadrature as the residual, e.g. a channel's flow rate Q = int u dy,
        ``model.output("flow_rate", lambda u: u.u, integrate=True)``; a plane continuum's outputs are integrals
        over its domain always.
        """
        self._claim(name, "output")
        self._unreported(name, "output")
        if integrate and self.continuum is None and self.plane_spec is None:
            raise ModelError(f"output {name!r} of model {self.name} is integrated, but the model declares no "
                             "continuum", file=self.file, key=f"output.{name}",
                             expected="model.field(...) or model.plane(...) before an integrated output")
        self.outputs.append(Output(name, fn, unit, doc, bool(integrate)))

    def shape_output(self, name: str, fn: Callable, *, start: Callable | None = None, doc: str = "") -> None:
        """Declare a number measured on a steady state of a continuum, sampled along s (a balloon's loops).

        ``fn`` is numeric and receives, by parameter name, any of ``s`` (the sample
        positions on [0, L], an array), ``u`` (a :class:`Namespace` of arrays at
        them: every field and its slope ``<field>_s``), ``out`` (the model's outputs
        there) and ``p`` (the numeric parameter values); it returns a number.
        ``steady`` and ``continuation`` report it for every steady state. The
        optional ``start(value, s, p)`` gives starting guesses for a steady state
        with that value of the measure: an iterable of dicts with ``u`` and ``u_s``
        (field -> values at the positions s) and optionally ``n`` (field -> stress
        resultants, for the Hamiltonian form); a scene asks for it with
        ``shape = { name = value }``.
        """
        self._claim(name, "output")
        self._unreported(name, "shape output")
        if name in {o.name for o in self.shape_outputs}:
            raise ModelError(f"output name {name!r} is already used in model {self.name}", file=self.file, key=name,
                             expected="a name not yet declared")
        self.shape_outputs.append(ShapeOutput(name, fn, start, doc))

    def section_stiffness(self, fn: Callable) -> Callable:
        """Decorator (rod): a cross-section's stiffness K(p), a 6 x 6 symmetric matrix.

        The decorated function receives ``p`` and returns the matrix (a sympy Matrix or nested lists) of the
        parameters, ordered [K_uu, K_uw; K_wu, K_ww] (twist order (v, w), mechgen.symbolic.liegroup), e.g. from
        :func:`mechgen.symbolic.cross_section.cross_section_stiffness` (a section computed from Lame's lam, mu)
        or :func:`mechgen.symbolic.rod.rod_stiffness`. The ``section`` kernel evaluates it, the
        ``cross_section`` analysis reports it (N, N m, N m^2), and :meth:`rod` uses it when given no
        ``stiffness``.
        """
        if self.section_fn is not None:
            raise ModelError(f"model {self.name} declares its section stiffness twice", file=self.file,
                             key="section_stiffness", expected="one section_stiffness declaration")
        self.section_fn = fn
        return fn

    def rod(self, *, length: Callable | None = None, stiffness: Callable | None = None, f0: Callable | None = None,
            load: Callable | None = None, inertia: Callable | None = None, doc: str = "") -> None:
        """Declare a geometrically exact (Cosserat) rod with strain energy 1/2 int (f - f0)^T K (f - f0) ds,
        f = vee6(H^-1 H') = (nu, kappa) (mechgen.symbolic.rod).

        Every argument is a function that receives, by parameter name, ``p`` (and ``r`` for ``load``):

        * ``length(p)``: the reference length L (m; default 1), e.g. ``lambda p: p.L``.
        * ``stiffness(p)``: K (6 x 6, [K_uu, K_uw; K_wu, K_ww]), e.g.
          ``lambda p: rod_stiffness(p.EA, p.GA, p.GJ, p.EI)``; None uses the declared section
          (:meth:`section_stiffness`); a given one also serves as the section (the cross_section analysis).
        * ``f0(p)``: the reference twist (6 entries; default (1, 0, 0, 0, 0, 0), straight along the first
          section axis).
        * ``load(r, p)``: the distributed wrench per unit length in the spatial frame at the centre-line point
          ``r`` (``r.x``, ``r.y``, ``r.z``): 3 force components (N/m) or 6 (force, torque N m/m).
        * ``inertia(p)``: the mass per unit length M (6 x 6, kinetic energy 1/2 int eta^T M eta ds), e.g.
          ``lambda p: rod_inertia(p.rhoA, p.rhoJ, p.rhoI)`` (kg/m, kg m); needed by ``rod_dynamics``.

        The ``rod`` kernel evaluates sigma = K (f - f0), C = d sigma/df, W, f0, the load and d load/dr, L
        and M; the ``rod_statics`` analysis solves the rod's equilibrium, ``rod_dynamics`` its motion.
        """

        if self.rod_spec is not None:
            raise ModelError(f"model {self.name} declares its rod twice", file=self.file, key="rod",
                             expected="one rod declaration")
        if stiffness is not None and self.section_fn is None:
            self.section_fn = stiffness
        self.rod_spec = RodSpec(stiffness, f0, load, length, doc, inertia)

    def chain(self, coordinate: str, *, sites: str, ends: str = "fixed") -> None:
        """Declare a lattice (a chain) of identical sites; ``sites`` names a size parameter.

        The chain's one coordinate ``coordinate`` is repeated at every site; its energies are
        :meth:`site_kinetic`, :meth:`site_potential` and :meth:`bond_potential`, derived once for one site and
        one bond, so the kernels do not grow with the number of sites. ``ends`` is ``"fixed"`` (ghost sites 0
        and N+1 held at zero), ``"periodic"`` (site N+1 is site 1) or the name of a choice parameter among those
        two (the scene picks the ends; the one bond energy serves both). Example:
        ``model.chain("u", sites="N", ends="fixed")`` with ``Param("N", 32, size=True)``.
        """
        self._claim(coordinate, "coordinate")
        if ends not in ("fixed", "periodic"):
            choice = next((p for p in self.param_list if p.name == ends), None)
            if choice is None or not choice.is_choice or not set(choice.choices) <= {"fixed", "periodic"}:
                raise ModelError(f"unknown chain ends {ends!r}", file=self.file, key="chain.ends",
                                 expected="'fixed', 'periodic' or a choice parameter among them")
        prm = self.param(sites)
        if not prm.size:
            raise ModelError(f"chain sites parameter {sites!r} is not a size parameter", file=self.file,
                             key="chain.sites", expected="a Param declared with size=True")
        self.chain_spec = Chain(coordinate, sites, ends)

    def field(self, *names: str, length: str = "L", discretisation: str = "hermite", N: int = 16) -> None:
        """Declare scalar fields on s in [0, p.<length>] (a continuum model).

        The densities then receive the fields' *jets* ``u``: ``u.w`` (w), ``u.w_s`` (dw/ds), ``u.w_ss``,
        ``u.w_t`` (dw/dt), ``u.w_st``, ``u.w_tt`` ... (mechgen.symbolic.field). ``length`` names the length
        parameter (declared first). Adds the discretisation parameters every continuum has: ``discretisation``
        (a choice, see :data:`mechgen.runtime.fields.discretise.DISCRETISATIONS`; the default given here), ``N``
        (elements, or basis functions per field), ``quadrature`` (Gauss points per
        element, 0 = chosen from the basis), ``constraints`` (``eliminate``,
        ``penalty`` or ``multiplier``) and ``joints`` (``assembly``: segments share
        their interface nodes; ``multiplier``: substructures joined by continuity
        constraints). Densities are then declared with :meth:`kinetic_density`,
        :meth:`potential_density`, :meth:`dissipation_density` or :meth:`weak_form`; a model has either
        coordinates or fields, not both.
        """

        if self.continuum is not None or self.coordinate_names or self.chain_spec:
            raise ModelError(f"model {self.name} already declares its unknowns", file=self.file, key="field",
                             expected="one field(...) call and no coordinates or chain")
        self.param(length)
        for name in names:
            self._claim(name, "field")
        self.continuum = Continuum(tuple(names), length)
        self.params(Param("discretisation", discretisation, "", "basis or element family", choices=DISCRETISATIONS,
                          runtime=True),
                    Param("N", N, "", "elements, or basis functions per field", size=True, runtime=True),
                    Param("quadrature", 0, "", "Gauss points per element (0: chosen from the basis)", size=True,
                          runtime=True),
                    Param("constraints", "eliminate", "", "essential boundary conditions by",
                          choices=("eliminate", "penalty", "multiplier"), runtime=True),
                    Param("joints", "assembly", "", "segments of a scene joined by",
                          choices=("assembly", "multiplier"), runtime=True))

    def plane(self, *fields: str, domain, group: str | None = None, element: str = "P2", h: float = 0.1) -> None:
        """Declare scalar fields on a plane domain (a plane continuum, :mod:`mechgen.symbolic.plane`).

        ``domain`` is a generated shape sized by parameters (declared first): ``disk("R")``,
        ``annulus("a", "b")``, ``rectangle("Lx", "Ly")``, ``slit_plate("W", "H", "a")``,
        ``plate_with_hole("W", "H", "r")``; ``group`` names the fields together (a displacement
        ``u`` = (ux, uy), so that ``fix("u", "outer")`` holds both). The densities then receive the jets
        ``u.ux``, ``u.ux_x``, ``u.ux_y``, ``u.ux_t`` ... and the position ``x``, ``y``. Adds the discretisation
        parameters every plane continuum has: ``element`` (P1, P2, Q1, Q2 Lagrange elements), ``h`` (the
        target edge length of the generated mesh, in the domain's length unit), ``edges`` (``curved``:
        isoparametric P2/Q2 edges on a curved boundary; ``straight``: straight-sided) and ``quadrature``
        (the degree of the rule, 0: twice the element's); a ``slit_plate`` also ``grading`` (power grading of
        the cells toward the crack tips, 1: uniform).
        """

        if self.plane_spec is not None or self.continuum is not None or self.coordinate_names or self.chain_spec:
            raise ModelError(f"model {self.name} already declares its unknowns", file=self.file, key="plane",
                             expected="one plane(...) call and no coordinates, chain or field")
        if not isinstance(domain, Domain) or domain.shape not in SHAPES:
            raise ModelError(f"domain {domain!r} of model {self.name} is not a plane domain", file=self.file,
                             key="plane.domain", expected="disk(...), annulus(...), rectangle(...), slit_plate(...) "
                                                          "or plate_with_hole(...) of mechgen.symbolic.plane")
        for _, name in domain.sizes:
            self.param(name)
        for name in fields + ((group,) if group else ()):
            self._claim(name, "field")
        if not fields:
            raise ModelError(f"model {self.name} declares a plane continuum without fields", file=self.file,
                             key="plane", expected="plane('ux', 'uy', domain=..., group='u')")
        self.plane_spec = PlaneSpec(tuple(fields), ((group, tuple(fields)),) if group else (), domain)
        self.params(Param("element", element, "", "Lagrange element of the mesh", choices=ELEMENTS, runtime=True),
                    Param("h", h, "", "target edge length of the generated mesh (the domain's length unit)",
                          positive=True, runtime=True),
                    Param("edges", "curved", "", "boundary edges of P2/Q2 elements on a curved boundary",
                          choices=("curved", "straight"), runtime=True),
                    Param("quadrature", 0, "", "degree of the quadrature rule (0: twice the element's)", size=True,
                          runtime=True))
        if domain.shape == "slit_plate":  # a crack's r^(1/2) field: cells graded toward the tips (h_tip ~ h^grading)
            self.params(Param("grading", 1.0, "", "power grading of the cells toward the crack tips (1: uniform)",
                              minimum=1.0, maximum=4.0, runtime=True))

    def _edge(self, kind: str, boundary: str) -> Callable:
        if self.plane_spec is None or boundary not in self.plane_spec.domain.boundaries:
            known = ", ".join(self.plane_spec.domain.boundaries) if self.plane_spec else "none (declare plane first)"
            raise ModelError(f"edge term on {boundary!r} of model {self.name}: not a boundary of its domain",
                             file=self.file, key="edge", expected=f"one of {known}")

        def register(fn: Callable) -> Callable:
            self.edge_terms.setdefault(boundary, {})[kind] = fn
            return fn
        return register

    def edge_potential(self, boundary: str) -> Callable:
        """Decorator (plane continuum): potential per unit length of a boundary, V_e(u, p, x, y, n) (J/m per unit
        thickness). A traction t gives V_e = -(t_x u.ux + t_y u.uy); a pressure P on the edge with outward normal
        ``n`` (``n.x``, ``n.y``) gives V_e = P (n.x u.ux + n.y u.uy). Only the fields' values may appear."""
        return self._edge("potential", boundary)

    def edge_dissipation(self, boundary: str) -> Callable:
        """Decorator (plane continuum): Rayleigh dissipation per unit length of a boundary, R_e(u, p, x, y, n): a
        dashpot layer (an absorbing boundary R_e = c/2 (u.ux_t^2 + u.uy_t^2))."""
        return self._edge("dissipation", boundary)

    def point_potential_at(self, name: str, x, y) -> Callable:
        """Decorator (plane continuum): a potential concentrated at the point (x, y) of the domain, V_P(u, p) (J per
        unit thickness): a point load F is V_P = -(F_x u.ux + F_y u.uy), a spring to ground k/2 u.ux^2. ``x`` and
        ``y`` are numbers or names of length parameters (m); only the fields' values may appear. The point must lie
        in the mesh (InputError naming it otherwise); its load enters through the shape functions of the cell that
        holds it, r += N(x_P)^T dV_P/du."""
        check_identifier(name, what="point", file=self.file)
        if self.plane_spec is None or name in self.plane_spec.domain.boundaries or name in self.plane_points:
            raise ModelError(f"point term {name!r} of model {self.name}: declare plane(...) first, and name it "
                             "apart from the boundaries and the other points", file=self.file, key="point",
                             expected="a new name, e.g. load_point")
        for value in (x, y):
            if isinstance(value, str):
                self.param(value)
            elif isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ModelError(f"point {name!r} of model {self.name}: coordinate {value!r} is neither a number "
                                 "nor a parameter name", file=self.file, key=f"point.{name}",
                                 expected="x and y as numbers (m) or names of declared parameters")
        self.plane_points[name] = (x if isinstance(x, str) else float(x), y if isinstance(y, str) else float(y))

        def register(fn: Callable) -> Callable:
            self.edge_terms.setdefault(name, {})["potential"] = fn
            return fn
        return register

    def edge_weak_form(self, boundary: str) -> Callable:
        """Decorator (plane continuum): a residual per unit length of a boundary, W_e(test, u, p, x, y, n), linear in
        the test jets (a follower load that is not the derivative of a potential)."""
        return self._edge("weak", boundary)

    def kinetic_density(self, fn: Callable) -> Callable:
        """Decorator (continuum): kinetic energy per unit length T(u, p, s, t) of the jets u.

        The decorated function receives, by parameter name, any of ``u`` (the jets), ``p``, ``s`` (the position,
        m) and ``t``, and returns one scalar expression (J/m), e.g. ``p.rhoA / 2 * u.w_t**2``.
        """
        self.kinetic_fn = fn
        return fn

    def potential_density(self, fn: Callable) -> Callable:
        """Decorator (continuum): strain/potential energy per unit length V(u, p, s, t).

        Receives ``u``, ``p``, ``s``, ``t`` by name and returns one scalar expression (J/m), e.g.
        ``p.EI / 2 * u.w_ss**2 - p.q * u.w``; the highest slope it uses sets the basis' continuity.
        """
        self.potential_fn = fn
        return fn

    def dissipation_density(self, fn: Callable) -> Callable:
        """Decorator (continuum): Rayleigh dissipation per unit length R(u, p, s), the force density -dR/du_t.

        Receives ``u``, ``p``, ``s``, ``t`` by name and returns one scalar expression (W/m), e.g.
        ``p.c / 2 * u.w_t**2``.
        """
        self.dissipation_fn = fn
        return fn

    def complementary_density(self, fn: Callable) -> Callable:
        """Decorator (continuum): complementary (stress) energy C(u, n, p, s) per unit length.

        C is the Legendre transform of the potential density in the slopes,
        C(u, n) = sup_{u_s} (n . u_s - V(u, u_s)), with n.w the stress resultant
        conjugate to w_s (n = dV/du_s: a string's tension vector). It gives the
        steady equations their Hamiltonian (stress) form u_s = dH/dn,
        n_s = -dH/du (mechgen.symbolic.steady.derive_steady_hamiltonian), which
        stays well conditioned for stiff and constrained (inextensible) laws where
        the displacement form does not; a law without V (a constraint) declares C only.
        The decorated function receives ``u``, ``n`` (a namespace with one entry per field), ``p`` and ``s`` by
        name and returns one scalar expression.
        """
        self.complementary_fn = fn
        return fn

    def constraint_density(self, fn: Callable) -> Callable:
        """Decorator (continuum): a pointwise constraint g(u, p) = 0 on the jets.

        An inextensible string: ``(u.x_s**2 + u.y_s**2 - 1) / 2``, held by a multiplier field mu(s) (the
        energy mu g). The decorated function receives ``u``, ``p`` and ``s`` by name and returns one scalar
        expression; returning 0 means none (a law without it). Small motions about a steady state satisfy
        dg/dj . j' = 0 and feel the geometric stiffness mu d2g/dj2 (mechgen.runtime.steady.constrained); steady
        states use the Hamiltonian form, with n = mu dg/du_s.
        """
        self.constraint_fn = fn
        return fn

    def strain_density(self, fn: Callable) -> Callable:
        """Decorator (continuum): the scalar strain measure g(u, p) through which the slopes enter the strain
        energy (V = W(g, u): a string's stretch).

        The decorated function receives ``u``, ``p`` and ``s`` by name and returns one scalar expression;
        returning 0 means none. With the runtime choice ``strain = "projected"`` the axial stiffness
        W_gg g_j g_j^T is replaced by its projection on cos(k pi s/L) (a mixed, locking-free Galerkin stiffness;
        mechgen.runtime.steady.constrained).
        """
        self.strain_fn = fn
        return fn

    def weak_form(self, fn: Callable) -> Callable:
        """Decorator (continuum): a residual density W(test, u, p, s, t), linear in the test jets.

        For a model that is not variational (a follower load, a moving contact): the decorated function
        receives ``test`` (the test jets, named like ``u``'s), ``u``, ``p``, ``s`` and ``t`` by name and returns one
        scalar expression, a sum of test jets times expressions of the trial jets; dW/dtest is added to
        the residual of Lagrange's equations. Example: ``test.w * p.c * u.w_t`` (viscous damping written
        as a force).
        """
        self.weak_fn = fn
        return fn

    def part(self, kind: str, *params: Param, doc: str = "", checks: dict | None = None) -> None:
        """Declare a kind of lumped part that a scene places along a continuum (a disk, a bearing).

        Its energies are point terms, ``@model.point_kinetic(kind)`` etc., whose
        functions may ask for ``part``: a namespace of the part's own parameters
        ``params`` (each instance in the scene gives its own values). They are
        model parameters named ``<kind>_<name>``, always kept symbolic (kernel
        inputs), so one kernel serves every instance. A scene places parts with
        ``[[parts]]`` tables (``kind``, ``at`` = s in m, and the part's parameters) and cuts a stepped
        continuum into ``[[segments]]`` (``length``, ``elements`` and per-segment values of numeric model
        parameters); :func:`mechgen.compile` takes the same as ``parts=[...]`` and ``segments=[...]``.
        Call :meth:`field` first.

        ``checks`` states what the values of one part must satisfy together (each parameter's own
        bounds, ``positive``/``minimum``/``maximum``, are checked alone): ``{key: (condition, expected)}``,
        ``condition`` comparisons (``< <= > >= == !=``) of arithmetic expressions of the part's parameters
        joined by ``and``/``or`` (the scene expression grammar, mechgen.scene.expr.Condition), evaluated on
        each part's values (the declared defaults where a part leaves one out) when a scene is loaded or
        :func:`mechgen.compile` is called; a part for which it fails is refused there (exit 2) at
        ``parts[i].<key>``, with ``expected`` as what would be accepted. Example, a disk whose bore must be
        smaller than its outer diameter unless both are left at 0::

            model.part("disk", Param("outer", 0.0, "m"), Param("inner", 0.0, "m"),
                       checks={"inner": ("inner < outer or inner == 0 and outer == 0",
                                         "an inner (bore) diameter below the outer diameter")})
        """
        if self.continuum is None:
            raise ModelError(f"part {kind!r} of model {self.name} declared before its fields", file=self.file,
                             key="part", expected="model.field(...) first")
        check_identifier(kind, what="part kind", file=self.file)
        if kind in ("start", "end") or kind in self.parts:
            raise ModelError(f"part kind {kind!r} is reserved or declared twice", file=self.file, key="part",
                             expected="a new name other than 'start' and 'end'")
        names = []
        for prm in params:
            full = replace(prm, name=f"{kind}_{prm.name}")
            self.params(full)
            names.append(prm.name)
        self.parts[kind] = tuple(names)
        self.part_checks[kind] = self._part_checks(kind, names, checks or {})

    def _part_checks(self, kind: str, names: list[str], checks) -> tuple[tuple[str, str, str], ...]:
        """The checks of :meth:`part` as (key, condition, expected) triples; ModelError for a malformed one (the
        condition's grammar and names are checked when the model's facts are made, mechgen.scene.info)."""
        if not isinstance(checks, dict):
            raise ModelError(f"checks of part {kind!r} is {type(checks).__name__}", file=self.file, key="part",
                             expected="a dict {key: (condition, expected)}")
        out = []
        for key, value in checks.items():
            if key not in names:
                raise ModelError(f"check of part {kind!r} at {key!r}, not a parameter of the part", file=self.file,
                                 key="part", expected="one of: " + ", ".join(names))
            if not (isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, str) and v for v in value)):
                raise ModelError(f"check of part {kind!r} at {key!r} is {value!r}", file=self.file, key="part",
                                 expected="a pair of non-empty strings (condition, expected)")
            out.append((key, value[0], value[1]))
        return tuple(out)

    def shear_pair(self, displacement: str, rotation: str, sign: int = 1) -> None:
        """Declare that field ``rotation`` is the section rotation whose shear-free value is sign * d(displacement)/ds.

        A Timoshenko-type model with shear strain gamma = u_s - sign * psi. The
        two-node shaft element (discretisation ``timoshenko2``) interpolates each
        pair with the shape functions that solve the static, unloaded equations
        exactly (Friedman & Kosmatka 1993; the usual rotordynamics shaft element), and the quintic
        element splits the pair's slope dofs at segment interfaces and parts.
        Example: ``model.shear_pair("ux", "psiy")``, ``model.shear_pair("uy", "psix", sign=-1)``.
        """
        for name in (displacement, rotation):
            if name not in self.field_names:
                raise ModelError(f"shear pair names {name!r}, which is not a field of {self.name}", file=self.file,
                                 key="shear_pair", expected=f"fields among {', '.join(self.field_names)}")
        if sign not in (1, -1):
            raise ModelError(f"shear pair sign {sign!r}", file=self.file, key="shear_pair", expected="1 or -1")
        self.shear_pairs.append((displacement, rotation, int(sign)))

    def whirl_pair(self, x: str, y: str) -> None:
        """Declare the lateral displacements (coordinates or fields) whose orbit classifies whirl.

        A mode whirls *forward* when its orbit turns from x towards y, the sense of a
        positive spin about z = x cross y, and *backward* otherwise; ``modes`` of
        gyroscopic systems then reports ``whirl`` per mode, and ``campbell`` requires at least
        one pair (it labels each branch of the diagram by its whirl). A lumped model may call this
        again to add stations (a disk's translations and its tilts): each mode is judged at
        the station where its orbit is largest. A continuum declares one pair (its stations
        are the mesh's nodes). Example: ``model.whirl_pair("x", "y")``.
        """
        names = set(self.coordinates_all) | set(self.field_names)
        for name in (x, y):
            if name not in names:
                raise ModelError(f"whirl pair names {name!r}, which is not a coordinate or field of {self.name}",
                                 file=self.file, key="whirl_pair", expected=f"names among {', '.join(sorted(names))}")
        if x == y or (self.whirl and {x, y} & set(self.whirl)):
            raise ModelError(f"whirl pair ({x!r}, {y!r}) repeats a name", file=self.file, key="whirl_pair",
                             expected="two names not yet in a whirl pair")
        if self.whirl and self.field_names:
            raise ModelError(f"a second whirl pair ({x!r}, {y!r}) for a continuum", file=self.file, key="whirl_pair",
                             expected="one whirl pair for a model with fields (its stations are the mesh's nodes)")
        self.whirl = (self.whirl or ()) + (x, y)

    def part_params(self) -> tuple[str, ...]:
        """Model parameter names of every part kind's parameters (``<kind>_<name>``, always symbolic)."""
        return tuple(f"{kind}_{name}" for kind, names in self.parts.items() for name in names)

    def _point(self, kind: str, at: str) -> Callable:
        if at not in ("start", "end") and at not in self.parts:
            raise ModelError(f"point term at {at!r}", file=self.file, key=f"point_{kind}",
                             expected="'start', 'end' or a part kind declared with model.part(...)")

        def register(fn: Callable) -> Callable:
            self.point_terms.setdefault(at, {})[kind] = fn
            return fn

        return register

    def point_kinetic(self, at: str) -> Callable:
        """Decorator (continuum): kinetic energy of a point mass/inertia at ``at`` ('start', 'end' or a part kind).

        The function receives, by parameter name, the jets ``u`` at the point, ``p``, ``s``, ``t`` and, for a
        part, ``part`` (the part's own parameters); it returns one scalar expression (J), e.g. a disk's
        ``part.m / 2 * (u.ux_t**2 + u.uy_t**2)``.
        """
        return self._point("kinetic", at)

    def point_potential(self, at: str) -> Callable:
        """Decorator (continuum): potential energy at an end or a part, V(u, p) (J): a spring, a dead load.

        Receives ``u``, ``p``, ``s``, ``t`` (and ``part``) like :meth:`point_kinetic`, e.g.
        ``p.k_end / 2 * u.w**2``.
        """
        return self._point("potential", at)

    def point_dissipation(self, at: str) -> Callable:
        """Decorator (continuum): Rayleigh dissipation at an end or a part, R(u, p) (W): a dashpot.

        Receives ``u``, ``p``, ``s``, ``t`` (and ``part``) like :meth:`point_kinetic`, e.g.
        ``p.c_end / 2 * u.w_t**2``.
        """
        return self._point("dissipation", at)

    def point_weak_form(self, at: str) -> Callable:
        """Decorator (continuum): a residual at an end or a part, W(test, u, p), linear in the test jets.

        Receives ``test``, ``u``, ``p``, ``s``, ``t`` (and ``part``): follower loads, a bearing's cross-coupled
        forces ``test.ux * (part.kxx * u.ux + part.kxy * u.uy) + ...``.
        """
        return self._point("weak", at)

    def boundary(self, fn: Callable) -> Callable:
        """Decorator (continuum): essential boundary conditions.

        The decorated function receives ``p`` and returns a list of :func:`~mechgen.symbolic.field.fix` entries:
        ``[fix("w", "start"), fix("w_s", "start")]`` clamps the start (w = dw/ds = 0). A value other than 0
        (``fix("z", "end", p.h)``) is for steady boundary value problems; perturbations (modes, stability) hold
        the jet at 0. Conditions left out are natural (free). ``fix_ends(p.bc, {...})`` builds the list from a
        'start-end' choice parameter.
        """
        self.boundary_fn = fn
        return fn

    def initial(self, fn: Callable) -> Callable:
        """Decorator: the initial state as a function of the parameters.

        The decorated function receives ``p`` (and ``t``, 0) by name and returns a dict {name: value}: a
        coordinate ``x``, its velocity ``x_dot`` or an internal variable (others start at 0), e.g.
        ``{"x_dot": p.v_in}``. It is generated as the kernel ``initial`` (mechgen.symbolic.initial), so a sweep or
        a fit starts where the model says at every parameter value; a scene's ``q0`` / ``v0`` replace the
        entries they name.
        """
        self.initial_fn = fn
        return fn

    def kinetic(self, fn: Callable) -> Callable:
        """Decorator: kinetic energy T(q, v, z, p, t).

        The decorated function receives, by parameter name, any of ``q``, ``v``, ``z``, ``p``, ``t`` and returns
        one scalar expression (J), e.g. ``p.m / 2 * (v.r**2 + q.r**2 * v.theta**2)``. The mass matrix is its
        Hessian in v, so it must be positive definite at the states an analysis visits.
        """
        self.kinetic_fn = fn
        return fn

    def potential(self, fn: Callable) -> Callable:
        """Decorator: potential (strain) energy V(q, z, p, t).

        Receives ``q``, ``v``, ``z``, ``p``, ``t`` by name (V should not depend on ``v``) and returns one scalar
        expression (J), e.g. ``p.k / 2 * q.x**2 - p.m * p.g * q.y``; its gradient is the conservative force,
        its Hessian the stiffness matrix.
        """
        self.potential_fn = fn
        return fn

    def dissipation(self, fn: Callable) -> Callable:
        """Decorator: Rayleigh dissipation function R(q, v, p), the force -dR/dv.

        Receives ``q``, ``v``, ``z``, ``p``, ``t`` by name and returns one scalar expression (W), e.g.
        ``p.c / 2 * v.x**2`` for a dashpot c; v . dR/dv is the dissipated power the energy balance reports.
        """
        self.dissipation_fn = fn
        return fn

    def forces(self, fn: Callable) -> Callable:
        """Decorator: generalized non-conservative forces Q(q, v, z, p, t).

        Receives ``q``, ``v``, ``z``, ``p``, ``t`` by name and returns a dict {coordinate: expression} (N for a
        length, N m for an angle; coordinates left out get 0) or a list in the coordinates' order, e.g.
        ``{"x": p.F * sp.cos(p.w * t)}``. They enter Lagrange's equations as d/dt dT/dv - dT/dq + dV/dq + dR/dv = Q.
        """
        self.forces_fn = fn
        return fn

    def site_kinetic(self, fn: Callable) -> Callable:
        """Decorator (lattice): kinetic energy of one site, fn(s, p) with ``s.q``, ``s.v`` the site's coordinate and
        velocity; returns one scalar expression, e.g. ``s.v**2 / 2``.
        """
        self.site_kinetic_fn = fn
        return fn

    def site_potential(self, fn: Callable) -> Callable:
        """Decorator (lattice): on-site potential energy (a substrate), fn(s, p) with ``s.q``, ``s.v``; returns one
        scalar expression, e.g. ``p.k0 * s.q**2 / 2``.
        """
        self.site_potential_fn = fn
        return fn

    def bond_potential(self, fn: Callable) -> Callable:
        """Decorator (lattice): energy of the bond between neighbours, fn(a, b, p) with ``a.q`` the left site's and
        ``b.q`` the right site's coordinate; returns one scalar expression, e.g. the FPU bond
        ``p.gamma * (b.q - a.q)**2 / 2 + p.alpha * (b.q - a.q)**3 / 3``.
        """
        self.bond_potential_fn = fn
        return fn

    # -- hybrid models (mechgen.symbolic.hybrid) ---------------------------
    def mode(self, name: str, *, initial: bool = False):
        """Declare a mode of a hybrid model; returns its :class:`~mechgen.symbolic.hybrid.ModeScope`.

        The scope's decorators (kinetic, potential, dissipation, forces, internal, output, guard, terminal) act in
        that mode only, added to the model-wide declarations. The first mode declared is the initial one unless
        another says ``initial=True``; a scene's ``mode`` key starts elsewhere. Example::

            flight = model.mode("flight", initial=True)

            @flight.guard(to="flight", direction="falling", reset=lambda v, p: {"y_dot": -p.e * v.y})
            def floor(q):
                return q.y
        """

        if self.continuum is not None or self.chain_spec is not None:
            raise ModelError(f"mode {name!r} of model {self.name}: modes are for lumped models", file=self.file,
                             key=f"mode {name}", expected="a model of coordinates (no fields, no chain)")
        check_identifier(name, what="mode", file=self.file)
        if name in self.mode_scopes:
            raise ModelError(f"mode {name!r} is declared twice in model {self.name}", file=self.file,
                             key=f"mode {name}", expected="each mode once")
        scope = ModeScope(self, name)
        self.mode_scopes[name] = scope
        if initial or self.initial_mode is None:
            self.initial_mode = name
        return scope

    def hybrid_internal(self, name: str, *, initial: float = 0.0, doc: str = "") -> None:
        """Add internal variable ``name`` to the state (once; a mode's law declares it, frozen elsewhere).

        Called by :meth:`ModeScope.internal <mechgen.symbolic.hybrid.ModeScope.internal>`; a model file
        declares a mode's internal law there, not with this.
        """
        if any(i.name == name for i in self.internals):
            return
        self.internal(name, rate=lambda: 0, initial=initial, doc=doc)

    def add_guard(self, guard) -> None:
        """Record a :class:`~mechgen.symbolic.hybrid.Guard` (declared through a mode or :meth:`terminal`).

        Called by the guard decorators; a model file declares guards with ``@mode.guard(...)``,
        ``@mode.terminal(...)`` or ``@model.terminal(...)``.
        """
        self.guards.append(guard)

    def terminal(self, *, direction: str = "both") -> Callable:
        """Decorator (hybrid): an event function g(q, v, z, p, t) that ends the run in every mode when it
        changes sign in ``direction`` (rising, falling, both): a projectile at rest.

        The decorated function receives ``q``, ``v``, ``z``, ``p``, ``t`` by name and returns one scalar
        expression; its name names the event in ``events``. Example::

            @model.terminal(direction="falling")
            def at_rest(v):
                return v.x
        """

        def register(fn: Callable) -> Callable:
            if direction not in DIRECTIONS:
                raise ModelError(f"terminal direction {direction!r} of model {self.name}", file=self.file,
                                 key="terminal.direction", expected="one of: " + ", ".join(DIRECTIONS))
            name = check_identifier(getattr(fn, "__name__", "terminal"), what="guard", file=self.file)
            self.add_guard(Guard(name, fn, None, None, DIRECTIONS[direction], None, True))
            return fn
        return register

    @property
    def is_hybrid(self) -> bool:
        """True for a model with modes (mechgen.symbolic.hybrid)."""
        return bool(self.mode_scopes)

    @property
    def mode_names(self) -> tuple[str, ...]:
        """The modes in declaration order (empty for a smooth model)."""
        return tuple(self.mode_scopes)

    # -- queries ----------------------------------------------------------
    def param(self, name: str) -> Param:
        """The :class:`~mechgen.symbolic.params.Param` called ``name`` (ModelError when there is none)."""
        for prm in self.param_list:
            if prm.name == name:
                return prm
        raise ModelError(f"model {self.name} has no parameter {name!r}", file=self.file, key=name,
                         expected=f"one of {', '.join(p.name for p in self.param_list)}")

    @property
    def is_lattice(self) -> bool:
        """True for a chain model (site and bond energies)."""
        return self.chain_spec is not None

    @property
    def is_field(self) -> bool:
        """True for a continuum model (fields and densities)."""
        return self.continuum is not None

    @property
    def is_plane(self) -> bool:
        """True for a plane continuum model (fields on a 2D domain, :meth:`plane`)."""
        return self.plane_spec is not None

    @property
    def field_names(self) -> tuple[str, ...]:
        """Names of the declared fields."""
        return self.continuum.fields if self.continuum else ()

    @property
    def coordinates_all(self) -> tuple[str, ...]:
        """Names of the coordinates (the chain's coordinate for a lattice)."""
        if self.chain_spec:
            return (self.chain_spec.coordinate,)
        return tuple(self.coordinate_names)

    @property
    def output_names(self) -> tuple[str, ...]:
        """Declared output names plus the energies every model provides."""
        return tuple(o.name for o in self.outputs) + ("kinetic_energy", "potential_energy", "energy")

    def summary(self) -> str:
        """The first line of the model's docstring (its name when it has none): what ``mechgen models`` lists."""
        return self.doc.splitlines()[0] if self.doc else self.name

    def _unreported(self, name: str, what: str) -> None:
        clash = output_clash(name, self) if isinstance(name, str) else None
        if clash is not None:
            raise name_clash_error(self, name, what, clash)

    def _claim(self, name: str, what: str) -> None:
        check_identifier(name, what=what, file=self.file)
        if name in RESERVED:
            raise ModelError(f"{what} name {name!r} is reserved", file=self.file, key=name,
                             expected=f"a name other than {', '.join(sorted(RESERVED))}")
        taken = ({p.name for p in self.param_list} | set(self.coordinate_names)
                 | {i.name for i in self.internals} | {o.name for o in self.outputs})
        if self.chain_spec:
            taken.add(self.chain_spec.coordinate)
        taken |= set(self.field_names)
        if self.plane_spec is not None:
            taken |= set(self.plane_spec.fields) | {g for g, _ in self.plane_spec.groups}
        if name in taken or name.endswith(("_dot", "_ddot")) and name.rsplit("_", 1)[0] in taken:
            raise ModelError(f"{what} name {name!r} is already used in model {self.name}", file=self.file,
                             key=name, expected="a name not yet declared")
        if what == "coordinate" and {f"{name}_dot", f"{name}_ddot"} & taken:
            used = sorted({f"{name}_dot", f"{name}_ddot"} & taken)[0]
            raise ModelError(f"coordinate name {name!r} of model {self.name} derives the velocity/acceleration "
                             f"name {used!r}, which is already declared", file=self.file, key=name,
                             expected=f"a coordinate whose {name}_dot and {name}_ddot are not declared names")
