"""A geometrically exact (Cosserat) rod: the local constitutive and load pieces, derived once.

Seed 001 (Grazioso, "Modeling of a soft link", slides 9-28). The rod's configuration is a curve of poses
H(s) = [[R, r], [0, 1]] in SE(3), s the reference arc length; its deformation twist is
f = vee6(H^-1 H') = (nu, kappa) (translational part first: nu the strain vector of the centre line in the
section frame, kappa the curvature-twist vector), the reference twist f0 (f0 = (e1, 0) for a rod initially
straight along its first section axis) and the strain eps = f - f0. The strain energy is

    V = 1/2 int_0^L eps^T K eps ds,     K = [[K_uu, K_uw], [K_wu, K_ww]]   (6 x 6, symmetric positive definite)

so the stress resultant (force n, moment m in the section frame) and its tangent are

    sigma = dW/df = K (f - f0),     C = d sigma / df = K        (W = eps^T K eps / 2).

K comes from :func:`rod_stiffness` (an initially straight rod on its principal axes:
diag(EA, GA2, GA3, GJ, EI2, EI3)) or from a declared section (Model.section_stiffness, e.g.
mechgen.symbolic.cross_section). A distributed load is a wrench per unit length given in the spatial
frame as a function of the centre-line position r (gravity rhoA g; a centrifugal load rhoA omega^2 r_perp):
load(r) = (force, torque) per unit length (N/m, N m/m), with its derivative d load/dr.

These are the local pieces of "symbolic on the local piece, numeric over the repetition": the ``rod``
kernel evaluates them at a batch of points; mechgen.runtime.rods.statics integrates the repetition.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import sympy as sp

from mechgen.errors import ModelError

#: the strain/stress component names in the twist order (v, w)
COMPONENTS = ("u1", "u2", "u3", "w1", "w2", "w3")


def rod_stiffness(EA, GA, GJ, EI, *, GA3=None, EI3=None) -> sp.Matrix:  # noqa: N803 - the issue's names
    """K = diag(EA, GA2, GA3, GJ, EI2, EI3) of an initially straight rod whose section axes are principal
    (seed 001, slide 18). ``GA`` and ``EI`` serve both directions unless ``GA3``/``EI3`` are given.
    Units: EA, GA in N; GJ, EI in N m^2."""
    GA3 = GA if GA3 is None else GA3
    EI3 = EI if EI3 is None else EI3
    return sp.diag(EA, GA, GA3, GJ, EI, EI3)


def rod_inertia(rhoA, rhoJ, rhoI, *, rhoI3=None) -> sp.Matrix:  # noqa: N803 - the issue's names
    """The mass per unit length M = diag(rhoA, rhoA, rhoA, rhoJ, rhoI2, rhoI3) of a section whose mass centre
    is on the centre line, on its principal axes: kinetic energy 1/2 int eta^T M eta ds with the velocity twist
    eta = (R^T r_t, omega) (seed 001, slide 24). rhoA in kg/m; rhoJ = rho J (polar) and rhoI = rho I (each
    bending axis, unless ``rhoI3`` is given) in kg m."""
    rhoI3 = rhoI if rhoI3 is None else rhoI3
    return sp.diag(rhoA, rhoA, rhoA, rhoJ, rhoI, rhoI3)


@dataclass(frozen=True)
class RodSpec:
    """A declared rod (Model.rod): the stiffness K(p) (None: the declared section), the reference twist
    f0(p) (None: straight, (1, 0, 0, 0, 0, 0)) and the distributed load(r, p) (None: unloaded)."""

    stiffness: Callable | None
    f0: Callable | None
    load: Callable | None
    length: Callable | None = None
    doc: str = ""
    inertia: Callable | None = None


@dataclass(frozen=True)
class RodPieces:
    """The derived local pieces: symbols f (6) and r (3); W, sigma (6), C (6 x 6), the reference twist f0 (6),
    the spatial load wrench g (6) and dg/dr (6 x 3), the length and the mass per length M (6 x 6; zero when
    the rod declares no inertia)."""

    f: tuple[sp.Symbol, ...]
    r: tuple[sp.Symbol, ...]
    energy: sp.Expr
    sigma: sp.Matrix
    C: sp.Matrix
    f0: sp.Matrix
    load: sp.Matrix
    load_r: sp.Matrix
    length: sp.Expr = sp.Integer(1)
    M: sp.Matrix = field(default_factory=lambda: sp.zeros(6, 6))


STRAIN_SYMBOLS = tuple(sp.Symbol(f"f_{c}", real=True) for c in COMPONENTS)
POSITION_SYMBOLS = tuple(sp.Symbol(f"r_{i}", real=True) for i in (1, 2, 3))


def _vector(raw, n: int, what: str, model, allowed: set) -> sp.Matrix:
    try:
        vec = sp.Matrix(raw).reshape(len(raw) if hasattr(raw, "__len__") else 1, 1)
    except (TypeError, ValueError, sp.SympifyError):
        vec = None
    if vec is None or vec.rows != n:
        raise ModelError(f"{what} of the rod of model {model.name} returned {raw!r}", file=model.file,
                         key=f"rod.{what}", expected=f"a sequence of {n} expressions of the parameters")
    vec = vec.applyfunc(sp.sympify)
    stray = set().union(*(e.free_symbols for e in vec)) - allowed
    if stray:
        raise ModelError(f"{what} of the rod of model {model.name} uses {sorted(map(str, stray))}", file=model.file,
                         key=f"rod.{what}", expected="expressions of the parameters (and the position r for load)")
    return vec


def derive_rod(model, p_ns, K: sp.Matrix | None, params: tuple[sp.Symbol, ...]) -> RodPieces | None:
    """The rod's local pieces (None when the model declares no rod). ``K`` is the declared section's
    stiffness, used when the rod names none."""
    from mechgen.symbolic.declared import call_declared
    from mechgen.symbolic.params import Namespace

    spec = getattr(model, "rod_spec", None)
    if spec is None:
        return None
    allowed = set(params)
    if spec.stiffness is not None:
        K = sp.Matrix(call_declared(spec.stiffness, p=p_ns))
    if K is None or K.shape != (6, 6):
        raise ModelError(f"the rod of model {model.name} has no 6 x 6 stiffness", file=model.file,
                         key="rod.stiffness", expected="stiffness=lambda p: rod_stiffness(p.EA, p.GA, p.GJ, p.EI), "
                                                        "or a declared section_stiffness")
    if any(sp.simplify(K[i, j] - K[j, i]) != 0 for i in range(6) for j in range(i)):
        raise ModelError(f"the rod stiffness of model {model.name} is not symmetric", file=model.file,
                         key="rod.stiffness", expected="K = K^T (a stiffness derived from an energy)")
    f0 = sp.Matrix([1, 0, 0, 0, 0, 0]) if spec.f0 is None else \
        _vector(call_declared(spec.f0, p=p_ns), 6, "f0", model, allowed)
    f, r = STRAIN_SYMBOLS, POSITION_SYMBOLS
    fv = sp.Matrix(f)
    eps = fv - f0
    W = sp.expand((eps.T * K * eps)[0, 0] / 2)
    sigma = sp.Matrix([sp.diff(W, x) for x in f])
    C = sigma.jacobian(fv)
    if spec.load is None:
        load = sp.zeros(6, 1)
    else:
        raw = call_declared(spec.load, r=Namespace({"x": r[0], "y": r[1], "z": r[2]}), p=p_ns)
        raw = list(raw)
        if len(raw) == 3:
            raw = raw + [0, 0, 0]
        load = _vector(raw, 6, "load", model, allowed | set(r))
    length = sp.Integer(1) if spec.length is None else \
        _vector([call_declared(spec.length, p=p_ns)], 1, "length", model, allowed)[0]
    M = sp.zeros(6, 6)
    if spec.inertia is not None:
        M = sp.Matrix(call_declared(spec.inertia, p=p_ns))
        stray = set().union(*(e.free_symbols for e in M)) - allowed if M.shape == (6, 6) else set()
        if M.shape != (6, 6) or stray or any(sp.simplify(M[i, j] - M[j, i]) != 0 for i in range(6) for j in range(i)):
            raise ModelError(f"the rod inertia of model {model.name} is not a symmetric 6 x 6 matrix of the "
                             "parameters", file=model.file, key="rod.inertia",
                             expected="inertia=lambda p: rod_inertia(p.rhoA, p.rhoJ, p.rhoI)")
    return RodPieces(f, r, W, sigma, C, f0, load, load.jacobian(sp.Matrix(r)), length, M)
