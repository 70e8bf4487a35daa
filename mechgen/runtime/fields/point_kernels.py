"""A continuum's pointwise kernels evaluated at points: per segment, at the end terms and at the placed parts.

The generated kernels of a continuum evaluate the local residual rho(j, j_t, j_tt) of the jets (and its
Jacobians, outputs, energy rates) at a batch of points s. The functions here take a
:class:`~mechgen.runtime.fields.continuum.FieldSystem` and supply what a call needs: the jets at the Gauss points
from a dof vector (j = B_e x), the parameter vector of each segment and part, the end terms and parts at their
positions (B_x, the jets at s = x), and the reshaping of flat kernel outputs into (jets x jets) coefficients.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import InputError, KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.fields.assemble import jets_at_points

sps = lazy_module("scipy.sparse")


def params_with(system, values: dict, prefix: str = "", what: str = "segment") -> np.ndarray:
    """The parameter vector with ``values`` (names prefixed by ``prefix``) in place of the current ones."""
    names = system.metadata.params
    params = np.array(system.params, float)
    for name, value in values.items():
        full = prefix + name
        if full not in names:
            raise InputError(f"{what} sets {name!r}, which the compiled kernels do not take as an input",
                             key=name, expected=f"a parameter kept free: {', '.join(names) or 'none'}")
        params[names.index(full)] = float(value)
    return params


def segment_params(system) -> list[np.ndarray] | None:
    """One parameter vector per segment, in mesh order (None: every element uses ``params``)."""
    if system.layout is None or not any(seg.values for seg in system.layout.segments):
        return None
    return [params_with(system, seg.values) for seg in system.layout.segments]


def evaluate(system, kernel: str, j, j_t, j_tt, t: float, s: np.ndarray, params=None) -> dict:
    """One batched call of a pointwise kernel at positions s; jets arrays (..., jets); outputs (..., length)."""
    na = system.field_meta.njets
    shape = s.shape
    npts = s.size
    flat = lambda x: np.zeros((npts, na)) if x is None else np.ascontiguousarray(np.reshape(x, (npts, na)))  # noqa: E731
    inputs = {"q": flat(j), "v": flat(j_t), "a": flat(j_tt), "z": np.zeros((npts, 0)),
              "t": np.full((npts, 1), float(t)), "s": s.reshape(npts, 1),
              "p": system.params if params is None else params}
    try:
        out = system.kernels[kernel].evaluate(inputs)
    except KernelError as exc:
        raise KernelError(f"{exc} (pointwise kernel of {system.metadata.model})") from None
    return {k: v.reshape(shape + (v.shape[-1],)) for k, v in out.items()}


def by_segment(system, kernel: str, segment: np.ndarray, jets: list, t: float, s: np.ndarray) -> dict:
    """A pointwise kernel over elements (first axis of s and jets), each segment with its parameters."""
    params = segment_params(system)
    if params is None:
        return evaluate(system, kernel, *jets, t, s)
    parts = []
    for k, p in enumerate(params):
        rows = np.flatnonzero(segment == k)
        sl = slice(rows[0], rows[-1] + 1)
        parts.append(evaluate(system, kernel, *[None if x is None else x[sl] for x in jets], t, s[sl], params=p))
    return {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}


def pointwise(system, kernel: str, j, j_t=None, j_tt=None, t: float = 0.0) -> dict:
    """The pointwise kernel's outputs at every Gauss point (arrays shaped like the points) from the jets
    j (and their rates), each segment with its own parameters."""
    disc = system.disc
    segment = disc.mesh.segment if disc.mesh is not None else np.zeros(len(disc.points), int)
    return by_segment(system, kernel, segment, [j, j_t, j_tt], t, disc.points)


def stiffness(system, s: np.ndarray, *, params=None, segment=None) -> np.ndarray:
    """Pointwise stiffness coefficients d rho / d j at rest at positions s: (len(s), jets, jets).

    From the linear kernel (its K) or else the tangent one (r_q); ``segment`` gives each point's
    segment (its parameters), ``params`` one parameter vector for all.
    """
    kernel, out = ("linear", "K") if "linear" in system.kernels else ("tangent", "r_q")
    na = system.field_meta.njets
    if segment is not None:
        values = by_segment(system, kernel, segment, [None, None, None], 0.0, s[:, None])[out][:, 0]
    else:
        values = evaluate(system, kernel, None, None, None, 0.0, s, params=params)[out]
    return values.reshape(len(s), na, na)


def coefficients(system, arr: np.ndarray) -> np.ndarray:
    """A flat (..., jets * jets) kernel output as (..., jets, jets) coefficients."""
    na = len(system.disc.jets)
    return arr.reshape(arr.shape[:-1] + (na, na))


def state_jets(system, x) -> np.ndarray:
    """Jets at the Gauss points (elements, points, jets) of the reduced state x (None: zeros)."""
    disc = system.disc
    if x is None:
        return np.zeros(disc.points.shape + (len(disc.jets),))
    return jets_at_points(disc.tables, disc.dofs, system.reduction.expand(x))


def full_states(system, states) -> list:
    """The full dof vectors x = Z q of reduced states (None stays None: a zero state)."""
    red = system.reduction
    return [None if x is None else red.expand(x) for x in states]


def jets_of(system, full) -> list:
    """Jets at the Gauss points of each full dof vector (None stays None: a zero state)."""
    disc = system.disc
    return [None if x is None else jets_at_points(disc.tables, disc.dofs, x) for x in full]


def point_table(system, x: float):
    """B_x (jets x full dofs, CSR): the jets at s = x from the full dof vector (memoised per position)."""
    disc = system.disc
    return system.memo(("point", *system.disc_key(float(x))),
                       lambda: sps.csr_matrix(np.array([disc.row(f, k, x) for f, k in disc.jets])))


def placed_points(system) -> list[tuple[str, float, np.ndarray | None]]:
    """(name, position s, parameter vector or None for ``params``) of every end term and placed part: its
    pointwise kernels are ``<kernel>_at_<name>``, evaluated at s with those parameters."""
    meta = system.field_meta
    placed = [(at, 0.0 if at == "start" else system.disc.length, None) for at in meta.points]
    kinds = meta.part_kinds
    for part in (system.layout.parts if system.layout is not None else ()):
        if part.kind not in kinds:
            raise InputError(f"part kind {part.kind!r} is not declared by model {system.metadata.model}",
                             key="parts.kind", expected=f"one of: {', '.join(kinds) or 'none'}")
        placed.append((part.kind, part.at, params_with(system, part.values, f"{part.kind}_", f"part {part.kind}")))
    return placed


def ends(system, kernel: str, states, t: float):
    """(B_x, local outputs) of every end term and placed part: states are full dof vectors (q, q', q'') or None."""
    for name, x, params in placed_points(system):
        B = point_table(system, x)
        at_point = [None if y is None else (B @ y)[None] for y in states]
        yield B, evaluate(system, f"{kernel}_at_{name}", *at_point, t, np.array([x]), params=params)
