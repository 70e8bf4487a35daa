"""``rod_dynamics``: the motion of a model's Cosserat rod (Model.rod with ``inertia``) from rest or a rigid
initial velocity, under suddenly applied end and distributed loads.

Equations and discretisation: mechgen.runtime.rods.dynamics (N two-node elements on SO(3) x R^3, nodal
lumped mass from M = diag(rhoA I, J_rho), strain energy 1/2 int (f - f0)^T K (f - f0) ds by the element
midpoint rule, implicit Lie-group midpoint step of order 2). The rod starts in its reference configuration
(straight along x from the origin for the default f0). Loads (the model's distributed load, e.g. gravity
rhoA g, and the dead tip force/torque of the scene) act from t = 0.

Scene keys: ``elements`` (or ``N``, default 20), ``base``/``tip`` (clamped, pinned, free; default
clamped/free; free/free is a rod in free flight), ``tip_force``, ``tip_torque`` ([x, y, z], N and N m,
spatial), ``dt`` (s, required), ``t_end`` (s, required), ``damping`` (c, 1/s, mass-proportional:
v' = ... - c v, omega' = ... - c omega; default 0), ``initial_velocity``, ``initial_angular_velocity``
([x, y, z], m/s and rad/s, spatial: the rigid velocity field v(s) = v0 + w0 x r(s) at t = 0), ``save_every``
(steps between saved points, default 1), ``shape_every`` (saved points between saved shapes, 0: only the
final shape), ``tol`` (Newton increment, in units of L and rad, default 1e-10), ``bending_axis``, ``alpha``
(the step weight: 0.5 the energy-conserving midpoint rule of order 2, the default; up to 1, backward
Euler: numerical dissipation of the stiff shear/axial modes a sudden load excites, order 1), ``jacobian``
(ad, the default: the step's band Jacobian by CasADi AD of the element energy and the node rows; fd:
finite differences).

Newton (mechgen.runtime.rods.dynamics): a factorised band Jacobian kept while each correction is at most
REFRESH = 0.5 times the one before and the corrections still needed at that rate cost less than a new
Jacobian (JACOBIAN_COST = 10 corrections), taken again at the current iterate otherwise (or when a kept
Jacobian's full correction fails the monotonicity test); a step that still fails is split in halves
(``splits``).

Outputs: ``t`` (s), ``tip_trajectory`` (n x 3, m), ``tip_rotations`` (rad about the bending axis per saved
point, unwrapped along the rod), ``tip_position``, ``tip_rotation``, ``tip_orientation`` (final), ``energy``
(kinetic + elastic, J, per saved point), ``work`` (of the loads and the damping since t = 0, J),
``energy_error`` (max |E - E(0) - W| relative to max(|E|, |W|): zero for the exact motion; the integrator's
order-2 error), ``orthonormality_error`` (max |R^T R - I| over the final nodes), ``shape`` (final centre
line), ``shapes`` (saved), ``strain``/``stress_resultant`` (final, per element: eps = f - f0 and sigma =
K eps), ``steps``, ``newton_iterations``, ``jacobians``, ``splits`` (steps split in halves for Newton),
``dt``, ``elements``. Bad input (exit 2): M not diag(rhoA I, J) with rhoA > 0 and J SPD (key ``params``), the
stiffness checks of ``rod_statics``; dt > t_end or more than 10^7 steps (``<analysis>.dt``); ``elements`` whose
memory or least wall time (ceil(t_end / dt) Newton solves of SOLVE_SECONDS per element) exceeds the memory limit or
``max_seconds``. A step whose
Newton iteration fails even when split 12 times is a ConvergenceError naming the time reached (exit 1).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mechgen.analyses import schema
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.rod_statics import AXES, MAX_ELEMENTS, bounded, rod_of, vector3
from mechgen.analyses.schema import Option
from mechgen.errors import InputError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, require_seconds
from mechgen.runtime.core.memory import require
from mechgen.runtime.rods.ends import ENDS
from mechgen.scene.values import fail

if TYPE_CHECKING:
    from mechgen.runtime.rods.dynamics import RodBody

#: memory per element of a step (the Newton system's sparse Jacobian and factors, the saved shapes), bytes:
#: measured 25 KB/element between 1 000 and 4 000 elements (peak RSS 110 MB -> 183 MB), with a margin
ELEMENT_BYTES = 32_000

MAX_STEPS = 10_000_000
#: wall time per element of one Newton solve of a midpoint step (residual, banded solve; the Jacobian is refreshed
#: now and then), seconds: measured 1.27 us per element and solve on a 2-core machine (issue 30, the residual in
#: one C call: scenes/rod_dynamics.toml at 2 000 elements, 40 steps, 198 solves and 25 Jacobians in 0.50 s;
#: 2.85 us, then 1.9 us, before)
SOLVE_SECONDS = 1.2e-6


_elements = bounded(1, MAX_ELEMENTS)


def _non_negative(ctx, key: str, value: object) -> float:
    c = schema.number(ctx, key, value)
    if c < 0.0:
        raise fail(ctx.file, key, f"value {c!r} is negative", "a damping rate c >= 0 (1/s)")
    return c


def _alpha(ctx, key: str, value: object) -> float:
    a = schema.number(ctx, key, value)
    if not 0.5 <= a <= 1.0:
        raise fail(ctx.file, key, f"value {a!r} is outside [0.5, 1]",
                   "the step weight alpha: 0.5 the midpoint rule (order 2), up to 1 backward Euler (dissipative)")
    return a


SCHEMA = {
    "elements": Option(_elements, doc="two-node elements along the rod (default 20)"),
    "N": Option(_elements, doc="the same as elements"),
    "base": Option(schema.one_of("end condition", ENDS), "clamped", doc="the end condition at s = 0: clamped, "
                   "pinned or free"),
    "tip": Option(schema.one_of("end condition", ENDS), "free", doc="the end condition at s = L: clamped, "
                  "pinned or free (free/free: a rod in free flight)"),
    "tip_force": Option(vector3, [0.0, 0.0, 0.0], doc="the dead tip force [x, y, z], spatial, applied at t = 0 "
                        "(N)"),
    "tip_torque": Option(vector3, [0.0, 0.0, 0.0], doc="the dead tip torque [x, y, z], spatial, applied at "
                         "t = 0 (N m)"),
    "dt": Option(schema.positive, schema.REQUIRED, "the time step (s), a number > 0", doc="the time step (s)"),
    "t_end": Option(schema.positive, schema.REQUIRED, "the end time (s), a number > 0",
                    doc="end time of the run (s)"),
    "damping": Option(_non_negative, 0.0, doc="the mass-proportional damping rate c (1/s): v' = ... - c v, "
                      "omega' = ... - c omega"),
    "initial_velocity": Option(vector3, [0.0, 0.0, 0.0], doc="the rigid initial velocity v0 [x, y, z], "
                               "spatial (m/s)"),
    "initial_angular_velocity": Option(vector3, [0.0, 0.0, 0.0], doc="the rigid initial angular velocity w0 "
                                       "[x, y, z], spatial (rad/s): v(s) = v0 + w0 x r(s) at t = 0"),
    "save_every": Option(lambda ctx, key, v: schema.int_at_least(ctx, key, v, 1), 1,
                         doc="steps between saved points"),
    "shape_every": Option(lambda ctx, key, v: schema.int_at_least(ctx, key, v, 0), 0,
                          doc="saved points between saved shapes (0: only the final shape)"),
    "tol": Option(schema.positive, 1e-10, doc="Newton's increment at which a step has converged (in units of L "
                  "and rad)"),
    "alpha": Option(_alpha, 0.5, doc="the step weight: 0.5 the energy-conserving midpoint rule (order 2), up to "
                    "1 backward Euler (numerical dissipation of the stiff shear/axial modes a sudden load excites, "
                    "order 1)"),
    "bending_axis": Option(schema.one_of("axis", tuple(AXES)), "z", doc="the axis (x, y or z) tip_rotation "
                           "turns about"),
    "jacobian": Option(schema.one_of("Jacobian method", ("ad", "fd")), "ad", doc="the step's Jacobian: ad "
                       "(CasADi's algorithmic derivatives) or fd (finite differences)"),
}



def check(ctx, base: str, options: dict) -> None:
    """``elements`` or ``N`` (not both); dt and t_end given, with a bounded number of steps."""
    if "elements" in options and "N" in options:
        raise fail(ctx.file, f"{base}.N", "both 'elements' and 'N' are given", "one of them (the same thing)")
    options["elements"] = options.pop("N", options.get("elements", 20))
    if options["dt"] > options["t_end"]:
        raise fail(ctx.file, f"{base}.dt", f"dt = {options['dt']:g} s is longer than t_end = {options['t_end']:g} s",
                   "a time step no longer than t_end")
    if options["t_end"] / options["dt"] > MAX_STEPS:
        raise fail(ctx.file, f"{base}.dt", f"t_end/dt = {options['t_end'] / options['dt']:.3g} steps",
                   f"at most {MAX_STEPS:g} steps (a larger dt: the step is implicit)")


def needs(options: dict, *, internal: bool) -> set[str]:
    """The rod kernel (K, f0, L, load, M) and the section for the stiffness check."""
    return {"rod", "section"}


def body_of(system, options: dict) -> RodBody:
    """The runtime RodBody: the statics Rod (stiffness, loads, ends) with the rod kernel's M and the damping."""
    from mechgen.runtime.rods.dynamics import RodBody, check_inertia  # loaded with a rod scene only

    opts = dict(options)
    opts.setdefault("base", "clamped")
    opts.setdefault("tip", "free")
    rod = rod_of(system, opts)
    f0 = np.asarray(rod.f0, dtype=float)
    M = np.asarray(system.call("rod", f=f0[None, :], r=np.zeros((1, 3)))["M"], dtype=float).reshape(6, 6)
    problem = check_inertia(M)
    if problem:
        raise InputError(f"the rod of model {system.metadata.model}: {problem}", key="params",
                         expected="rhoA > 0 and a positive definite rotational inertia (rhoI, rhoJ > 0), "
                                  "from Model.rod(inertia=...)")
    return RodBody(rod, M, float(options.get("damping", 0.0)), float(options.get("alpha", 0.5)))


def initial_state(body: RodBody, elements: int, v0, w0):
    """The reference configuration moving rigidly: v(s) = v0 + w0 x r(s), body rates R^T w0."""
    from mechgen.runtime.rods.dynamics import reference_state

    st = reference_state(body, elements)
    v0, w0 = np.asarray(v0, dtype=float), np.asarray(w0, dtype=float)
    st.v = v0[None, :] + np.cross(w0[None, :], st.x)
    st.w = np.einsum("nji,j->ni", st.R, w0)
    return st


def require_dynamics_time(options: dict) -> None:
    """Refuse up front (exit 2 at ``elements``) a run whose least wall time exceeds ``max_seconds``: ceil(t_end / dt)
    steps of at least one Newton solve each, SOLVE_SECONDS per element a solve."""
    n, steps = int(options["elements"]), max(math.ceil(options["t_end"] / options["dt"] - 1e-9), 0)
    require_seconds(SOLVE_SECONDS * n * steps, float(options.get("max_seconds", DEFAULT_SECONDS)),
                    f"rod dynamics with {n} elements and {steps:,} steps", key="elements",
                    basis=f"at least one Newton solve a step, {SOLVE_SECONDS * 1e6:.3g} us per element, measured",
                    expected="fewer elements, or a larger dt or shorter t_end")


def run_rod_dynamics(system, options: dict, context: dict) -> dict:
    """March the midpoint step; the saved tip path and energies and the final fields."""
    from mechgen.runtime.rods.dynamics import Discrete, simulate
    from mechgen.runtime.rods.liegroup import orthonormality_error

    body = body_of(system, options)
    n = options["elements"]
    require(ELEMENT_BYTES * n, f"rod dynamics with {n} elements", key="elements",
            expected="fewer elements (the midpoint rule converges at order 2 in space)")
    require_dynamics_time(options)
    disc = Discrete(body, n, options["base"], options["tip"])
    st = initial_state(body, n, options["initial_velocity"], options["initial_angular_velocity"])
    axis = AXES[options["bending_axis"]]
    tr = simulate(disc, st, dt=options["dt"], t_end=options["t_end"], save_every=options["save_every"],
                  shape_every=options["shape_every"], tol=options["tol"], axis=axis, jacobian=options["jacobian"])
    fin = tr.final
    rows = lambda a: [[float(x) + 0.0 for x in row] for row in np.asarray(a)]  # noqa: E731
    energy, work = np.asarray(tr.energy), np.asarray(tr.work)
    scale = max(float(np.max(np.abs(energy))), float(np.max(np.abs(work))), 1e-300)
    Psi, Re, f = disc.strains(fin.x, fin.R)
    eps = f - body.rod.f0
    return {"t": [float(t) for t in tr.t], "tip_trajectory": rows(tr.tip),
            "tip_rotations": [float(a) for a in tr.tip_rotation],
            "tip_position": [float(x) + 0.0 for x in fin.x[-1]], "tip_rotation": float(tr.tip_rotation[-1]),
            "tip_orientation": rows(fin.R[-1]), "energy": [float(e) for e in energy], "work": [float(w) for w in work],
            "energy_error": float(np.max(np.abs(energy - energy[0] - work)) / scale),
            "orthonormality_error": orthonormality_error(fin.R), "shape": rows(fin.x),
            "shapes": [rows(s) for s in tr.shapes], "strain": rows(eps), "stress_resultant": rows(eps @ body.rod.K),
            "steps": int(tr.steps), "newton_iterations": int(tr.newton_iterations), "jacobians": int(tr.jacobians),
            "splits": int(tr.splits), "dt": float(options["dt"]), "elements": int(n)}


def lines(outputs: dict) -> list[str]:
    """Final tip, the energy balance and the work of the solver."""
    tip = ", ".join(f"{x:.6g}" for x in outputs["tip_position"])
    return [f"    tip_position (t = {outputs['t'][-1]:.6g} s): [{tip}] m",
            f"    tip_rotation: {outputs['tip_rotation']:.6g} rad",
            f"    energy_error: {outputs['energy_error']:.3g}   orthonormality_error: {outputs['orthonormality_error']:.3g}",
            f"    {outputs['steps']} steps of {outputs['dt']:.3g} s, {outputs['elements']} elements, "
            f"{outputs['newton_iterations']} Newton iterations, {outputs['jacobians']} Jacobians"]


def plot(plt, a: dict, path: Path) -> list[Path]:
    """The tip's path against time and the saved (or final) shapes in 3D."""
    out = a["outputs"]
    t, tip = np.asarray(out["t"]), np.asarray(out["tip_trajectory"])
    fig = plt.figure(figsize=(10, 4.5))
    ax = fig.add_subplot(1, 2, 1)
    for k, label in enumerate("xyz"):
        ax.plot(t, tip[:, k], label=f"tip {label}")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("tip position (m)")
    ax.legend(fontsize=8)
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    shapes = out["shapes"] or [out["shape"]]
    for k, s in enumerate(shapes):
        xyz = np.asarray(s)
        ax3.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], color="k" if k == len(shapes) - 1 else "tab:blue", lw=0.8)
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("z (m)")
    fig.suptitle(f"{a['name']}: rod dynamics", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("rod_dynamics", SCHEMA, run_rod_dynamics, needs, lines, check=check, plot=plot, sweepable=True))
