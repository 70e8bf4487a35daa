"""The discretisation of a compiled continuum at its current size, length and parameters.

A :class:`~mechgen.runtime.fields.continuum.FieldSystem` holds choices (discretisation, N, quadrature, joints),
a layout (segments, parts) and parameter values; the functions here turn them into the
:class:`~mechgen.runtime.fields.discretise.Discretisation` (mesh, bases, jet tables at the Gauss points) and the
memo key of everything built on it. The key names what the discretisation depends on: the length, and for the
two-node Timoshenko element (timoshenko2), whose shape functions hold phi = 12 EI / (kGA h^2), the shear ratios
phi per element, so that a new spin speed reuses the tables while a new G does not.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.fields import discretise as builder
from mechgen.runtime.fields.mesh import build_mesh
from mechgen.runtime.fields.point_kernels import stiffness

#: the message of a discretisation the model's energies refuse (InputError at params.discretisation)
FITS = "a discretisation that fits the model's energies"


def disc_key(system, *depends) -> tuple:
    """A memo key: what the discretisation depends on (the length; for timoshenko2 the shear ratios phi of its
    shape functions, not the whole parameter vector, so that a new spin speed reuses it) plus ``depends``."""
    length = system.value(system.field_meta.length)
    if system.choices["discretisation"] != "timoshenko2":
        return (length, None, *depends)
    return (length, shear(system, length)[1].tobytes(), *depends)


def check_size(system) -> None:
    """Refuse (InputError at params.N / params.quadrature) a discretisation beyond the memory limit, before
    the mesh or any table is allocated (mechgen.runtime.fields.discretise.check_size)."""
    segments = system.layout.segments if system.layout is not None else ()
    size = sum(int(seg.elements) for seg in segments) if segments else int(system.choices["N"])
    meta = system.field_meta
    builder.check_size(system.choices["discretisation"], size, len(meta.fields), meta.njets,
                       int(system.choices["quadrature"]), key="segments.elements" if segments else "params.N")


def shear(system, length: float) -> tuple[list, np.ndarray]:
    """timoshenko2's shear pairs and ratios at this length and these parameters (memoised)."""
    def make():
        check_size(system)
        try:
            return shear_ratios(system, build_mesh(system.layout, int(system.choices["N"]), length))
        except ValueError as exc:
            raise InputError(str(exc), key="discretisation", expected=FITS) from None

    return system.memo(("shear", length, system.param_key), make)


def shear_ratios(system, mesh) -> tuple[list, np.ndarray]:
    """Shear pairs and phi = 12 EI / (kGA h^2) per element and pair, from the pointwise stiffness.

    EI (N m^2) is the coefficient of psi_s^2 and kGA (N) that of w_s^2 in the linearised
    stiffness density (d rho / d j), at each element's midpoint; h (m) the element length.
    """
    pairs = list(system.field_meta.shear_pairs)
    if not pairs:
        raise ValueError("the timoshenko2 element needs shear pairs (model.shear_pair) in the model")
    jets = list(system.field_meta.jets)
    mids = (mesh.nodes[:-1] + mesh.nodes[1:]) / 2
    K = stiffness(system, mids, segment=mesh.segment)
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


def discretisation(system) -> builder.Discretisation:
    """The discretisation at the current choices, layout and length (InputError when the energies refuse it)."""
    meta = system.field_meta
    length = system.value(meta.length)
    kind = system.choices["discretisation"]
    check_size(system)
    try:
        if kind in builder.GLOBAL:
            if system.layout is not None and system.layout.segments:
                raise ValueError(f"segments need finite elements; {kind} is a global basis")
            mesh = None
        else:
            mesh = build_mesh(system.layout, int(system.choices["N"]), length)
        pairs = shear(system, length) if kind == "timoshenko2" else None
        return builder.discretise(kind, int(system.choices["N"]), length, meta.fields, meta.jets,
                                  quadrature=int(system.choices["quadrature"]), constraints=list(meta.constraints),
                                  mesh=mesh, shear=pairs, joints=system.choices.get("joints", "assembly"))
    except ValueError as exc:
        raise InputError(str(exc), key="discretisation", expected=FITS) from None
