"""``modes``: natural frequencies and mode shapes about an operating point.

Scene keys: ``about`` (an earlier steady analysis), ``at`` (coordinates of the operating point),
``count`` (the lowest this many modes). Outputs: ``frequencies`` (ascending, rad/s or the model's
unit; elastic modes only); ``rigid_modes`` (how many rigid-body modes, K phi = 0 to the solver's
accuracy, mechgen.runtime.linear.modes.rigid_count; they are not frequencies, and ``count`` counts
the elastic modes after them) with, for a lumped model, ``rigid_shapes`` (one {coordinate: value}
per rigid mode, largest entry 1); ``operating_point`` when the point given (``at``, or zero) was
not an equilibrium and Newton found one (mechgen.analyses.operating_point.equilibrium_point).
A continuum's ``count`` (the sparse shift-invert path) is estimated before it starts, memory and wall time
(c n^(4/3), mechgen.runtime.linear.stability.sparse_seconds), and refused with exit 2 at ``params.N`` beyond the
memory limit or ``max_seconds``.

A lumped model (not a continuum, not a chain) also gets ``shapes``: one {coordinate: value} per elastic
mode, in the order of ``frequencies``, mass-normalised (phi^T M phi = 1) and signed so that the first
largest |entry| is positive; ``modal_mass`` (phi^T M phi as computed from the model's M: 1 to round-off)
and ``modal_stiffness`` (phi^T K phi = omega^2, (rad/s)^2) per mode (:func:`modal_outputs`). A continuum
with ``count`` gets ``s`` and ``shapes`` (per field, one curve per mode, largest |value| 1); a chain
reports frequencies only (its shapes would be N x N). A continuum's undamped modes also report ``roundoff_bound``,
the bound on the lowest frequency's relative error from round-off in the assembled M and K (:func:`require_roundoff`,
about eps (omega_max / omega_1)^2, N^4 eps for a beam), and are refused with exit 2 at ``params.N`` when it exceeds
``roundoff_rtol`` (default 1e-2: a Hermite beam near N = 4000 elements).

A system with damping, gyroscopic terms or a non-symmetric stiffness, and any rotor, gets its damped
modes (mechgen.analyses.whirl) with ``eigenvalues``, ``log_dec``, for a lumped model complex ``shapes``
(amplitude and phase per coordinate) and for a rotor ``whirl``, ``whirl_ratio`` and ``orbits``.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import figures, summary
from mechgen.analyses.fields import field_shapes
from mechgen.analyses.operating_point import equilibrium_point, linear_about
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import LINEAR_OPTIONS
from mechgen.analyses.whirl import is_gyroscopic, run_damped_modes
from mechgen.runtime.core.budget import DEFAULT_SECONDS, require_seconds
from mechgen.runtime.core.memory import require
from mechgen.runtime.fields.constrain import warn_penalty_errors
from mechgen.errors import InputError
from mechgen.runtime.linear.modes import modes as solve_modes
from mechgen.runtime.linear.modes import roundoff_bound
from mechgen.runtime.linear.stability import SPARSE_BYTES_PER_UNKNOWN, sparse_seconds

def needs(options: dict, *, internal: bool) -> set[str]:
    """M, D, G, K: the linear kernel; the residual too, to check that the point is an equilibrium (no ``about``)."""
    return {"linear"} if options.get("about") else {"linear", "residual"}


def run_modes(system, options: dict, context: dict) -> dict:
    """Natural frequencies (rad/s or the model's unit) about the operating point.

    Solves K x = w^2 M x (symmetric); a system with damping, gyroscopic terms or a
    non-symmetric stiffness, and any rotor (a model with a whirl pair), gets its damped
    modes instead (mechgen.analyses.whirl): ``frequencies`` are then the damped natural
    frequencies, with ``eigenvalues``, ``log_dec`` and (rotors) ``whirl``.
    """
    require_sparse_modes(system, options)
    q, found = equilibrium_point(system, options, context)
    mats = linear_about(system, q, options, context)
    if is_gyroscopic(mats) or system.metadata.whirl:
        out = run_damped_modes(system, mats, options)
        if system.is_field and options.get("count"):
            out.update(field_shapes(system, np.real(out["_shapes"]), "shapes"))
        return _with_point(out, found)
    res = solve_modes(mats["M"], mats["K"], count=options.get("count"),
                      allow_singular_mass=getattr(system, "has_multipliers", False))
    if getattr(system, "penalty_choice", None) is not None:  # penalty constraints: a-posteriori error of each mode
        warn_penalty_errors(system.penalty_errors(res.shapes, res.eigenvalues))
    elastic = res.shapes[:, res.rigid:]
    out = {"frequencies": [float(f) for f in res.frequencies[res.rigid:]], "rigid_modes": int(res.rigid),
           "_shapes": elastic}
    if system.is_field and elastic.shape[1]:
        out["roundoff_bound"] = require_roundoff(system, mats["M"], mats["K"], elastic[:, 0],
                                                 float(res.eigenvalues[res.rigid]), options)
    if not system.is_field and not system.is_lattice and not getattr(system, "is_plane", False):
        out.update(modal_outputs(system.coordinates, mats["M"], mats["K"], elastic))
        if res.rigid:
            out["rigid_shapes"] = [_largest_one(system, res.shapes[:, j]) for j in range(res.rigid)]
    if system.is_field and options.get("count"):
        out.update(field_shapes(system, elastic, "shapes"))
    if getattr(system, "is_plane", False):
        out["_figure"] = system.figure_data(elastic[:, :8])
    return _with_point(out, found)


def require_sparse_modes(system, options: dict) -> None:
    """Refuse up front (exit 2 at params.N) a continuum's sparse modes solve (``count`` of a large N) whose memory,
    SPARSE_BYTES_PER_UNKNOWN x its unknowns (2n for a rotor's first-order whirl problem), exceeds the limit: the
    symmetric solve measured 1.7 kB per unknown (Euler-Bernoulli beam, quintic, count = 5: peak RSS 154 MB at
    N = 10^4, 769 MB at N = 10^5, 4 unknowns per element), under the stability solve's 2.8 kB.
    Refused too when its wall time, sparse_seconds(n) (the non-symmetric one for a rotor's whirl), exceeds
    ``max_seconds``."""
    if not (options.get("count") and getattr(system, "is_field", False)):
        return
    n = int(system.n)
    largest = 2 * n if system.metadata.whirl else n
    if largest > 200:
        require(SPARSE_BYTES_PER_UNKNOWN * largest, f"the sparse modes solve of {largest} unknowns", key="params.N",
                expected="a smaller N")
        require_seconds(sparse_seconds(n, general=bool(system.metadata.whirl)),
                        float(options.get("max_seconds", DEFAULT_SECONDS)), f"the sparse modes solve of {n} unknowns",
                        key="params.N", basis="c n^(4/3), measured", expected="a smaller N")


def require_roundoff(system, M, K, phi: np.ndarray, lam: float, options: dict, what: str = "modes") -> float:
    """The bound on the relative error of a continuum's lowest elastic frequency omega_1 = sqrt(lam) that round-off in
    the assembled M and K allows, half that on lam (mechgen.runtime.linear.modes.roundoff_bound: about
    eps (omega_max / omega_1)^2, growing as N^4 for a beam); refused (InputError, exit 2 at params.N) above the
    analysis's ``roundoff_rtol`` (default 1e-2): a Hermite beam near N = 4000 elements, where refining further
    only loses accuracy."""
    bound = 0.5 * roundoff_bound(M, K, phi, lam)
    tol = float(options.get("roundoff_rtol", 1e-2))
    if not bound <= tol:
        size = system.choices.get("N") if hasattr(system, "choices") else None
        raise InputError(f"{what}: round-off in the assembled K and M bounds the lowest frequency's relative error "
                         f"by {bound:.2g}" + (f" at N = {size}" if size is not None else "") + " (eps (|phi|^T |K| "
                         "|phi| + lam |phi|^T |M| |phi|) / (2 lam phi^T M phi), about eps (omega_max / omega_1)^2: it "
                         f"grows with N), more than roundoff_rtol = {tol:g}", key="params.N",
                         expected="a smaller N (the elements' own error falls with N while round-off grows), or a "
                         "larger roundoff_rtol")
    return bound


def modal_outputs(names, M, K, phi: np.ndarray) -> dict:
    """Mass-normalised real mode shapes: ``shapes`` [{coordinate: phi_i}], ``modal_mass`` phi^T M phi (1 up to
    round-off) and ``modal_stiffness`` phi^T K phi (= omega^2, (rad/s)^2), computed from M and K as given.

    The solver's columns satisfy phi^T M phi = 1; each is signed so that its first largest |entry| (the
    first within 1e-9 of the largest) is positive.
    """
    phi = np.asarray(phi, dtype=float)
    if phi.size:
        mag = np.abs(phi)
        top = np.argmax(mag >= (1.0 - 1e-9) * mag.max(axis=0)[None, :], axis=0)
        phi = phi * np.where(phi[top, np.arange(phi.shape[1])] < 0, -1.0, 1.0)[None, :]
    Mphi, Kphi = np.asarray(M @ phi), np.asarray(K @ phi)
    return {"shapes": [{n: float(x) + 0.0 for n, x in zip(names, col)} for col in phi.T],
            "modal_mass": [float(v) for v in np.einsum("ik,ik->k", phi, Mphi)],
            "modal_stiffness": [float(v) for v in np.einsum("ik,ik->k", phi, Kphi)]}


def _largest_one(system, phi: np.ndarray) -> dict[str, float]:
    """A mode shape as {coordinate: value}, scaled so that its largest |entry| is 1 (and positive)."""
    top = phi[np.argmax(np.abs(phi))]
    return {n: float(x / top) + 0.0 for n, x in zip(system.coordinates, phi)}


def _with_point(out: dict, found: dict | None) -> dict:
    """The outputs with ``operating_point`` (how the equilibrium was found) when the given point was not one."""
    if found is not None:
        out["operating_point"] = found
    return out


register(AnalysisKind("modes", dict(LINEAR_OPTIONS), run_modes, needs, summary.lines, plot=figures.linear,
                      sweepable=True))
