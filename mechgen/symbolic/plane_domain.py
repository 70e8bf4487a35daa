"""What a plane model declares of its domain: the generated shapes (:func:`disk`, :func:`annulus`,
:func:`rectangle`, :func:`slit_plate`, :func:`plate_with_hole`), their parameters and named boundaries, the
elements, and :class:`PlaneSpec` (fields, groups, domain). No derivation here: mechgen.symbolic.model records
these, mechgen.symbolic.plane derives the equations (and re-exports these names, where models import them)."""
from __future__ import annotations

from dataclasses import dataclass

from mechgen.errors import ModelError

SHAPES = {"disk": ("R",), "annulus": ("a", "b"), "rectangle": ("width", "height"),
          "slit_plate": ("W", "H", "a"), "plate_with_hole": ("W", "H", "r")}
#: the named boundaries of each generated shape (mechgen.runtime.plane.mesh)
BOUNDARIES = {"disk": ("outer",), "annulus": ("inner", "outer"), "rectangle": ("bottom", "right", "top", "left"),
              "slit_plate": ("bottom", "right", "top", "left", "crack_upper", "crack_lower"),
              "plate_with_hole": ("bottom", "right", "top", "left", "hole")}
ELEMENTS = ("P1", "P2", "Q1", "Q2")
#: the pseudo-boundary of ``fix("u", "rigid")``: pins that hold the rigid motions of a body loaded by
#: self-equilibrated tractions alone (mechgen.runtime.plane.discretise.rigid_pins)
RIGID = "rigid"


@dataclass(frozen=True)
class Domain:
    """A generated plane domain: its shape and the model parameters that size it (by role)."""

    shape: str
    sizes: tuple[tuple[str, str], ...]

    @property
    def boundaries(self) -> tuple[str, ...]:
        """The boundary names a mesh of this shape has."""
        return BOUNDARIES[self.shape]


def _domain(shape: str, names: tuple[str, ...]) -> Domain:
    if not all(isinstance(n, str) for n in names):
        raise ModelError(f"a {shape} domain is sized by parameter names, got {names!r}", key="domain",
                         expected=f"{shape}({', '.join(repr(r) for r in SHAPES[shape])}) with names of parameters")
    return Domain(shape, tuple(zip(SHAPES[shape], names)))


def disk(R: str = "R") -> Domain:
    """The disk ``x^2 + y^2 < R^2``; boundary ``outer``."""
    return _domain("disk", (R,))


def annulus(a: str = "a", b: str = "b") -> Domain:
    """The annulus ``a^2 < x^2 + y^2 < b^2``; boundaries ``inner`` and ``outer``."""
    return _domain("annulus", (a, b))


def rectangle(width: str = "Lx", height: str = "Ly") -> Domain:
    """The rectangle [0, width] x [0, height]; boundaries ``bottom``, ``right``, ``top``, ``left``."""
    return _domain("rectangle", (width, height))


def slit_plate(W: str = "W", H: str = "H", a: str = "a") -> Domain:
    """The plate [-W, W] x [-H, H] with a slit crack ``|x| < a`` on y = 0: the sides and ``crack_upper``/``crack_lower``."""
    return _domain("slit_plate", (W, H, a))


def plate_with_hole(W: str = "W", H: str = "H", r: str = "r") -> Domain:
    """The plate [-W, W] x [-H, H] with a circular hole of radius r at the origin: the sides and ``hole``."""
    return _domain("plate_with_hole", (W, H, r))


@dataclass(frozen=True)
class PlaneSpec:
    """The declared unknowns of a plane model: scalar fields, named groups of them (a displacement), the domain."""

    fields: tuple[str, ...]
    groups: tuple[tuple[str, tuple[str, ...]], ...]
    domain: Domain
