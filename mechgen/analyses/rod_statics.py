"""``rod_statics``: the static equilibrium of a model's Cosserat rod (Model.rod) under end and distributed loads.

The rod lies initially along its reference twist f0 from the origin (f0 = (1, 0, 0, 0, 0, 0): along x).
Equations (mechgen.runtime.rods.statics; seed 001, Grazioso): H' = H hat6(f), sigma' = ad_f^T sigma - gbar,
sigma = K (f - f0), with the ``rod`` kernel's K, f0, length L and distributed spatial load q(r) (gravity,
centrifugal). The tip force and torque are dead loads in the spatial frame. The load (tip wrench and
distributed load together) is applied by continuation in a factor lam from 0 to 1.

Scene keys: ``method`` (collocation, the default: Lie-group midpoint, order 2, robust at any load;
shooting: RKMK4, order 4, but single shooting's sensitivity grows like exp(L sqrt(P/EI)): it stalls
beyond PL^2/EI ~ 100 - 1000 and is slow there), ``elements``
(or ``N``: RKMK4 steps or collocation elements, default 40), ``base``/``tip`` (clamped, pinned, free;
default clamped/free), ``tip_force``, ``tip_torque`` ([x, y, z], N and N m; numbers or expressions of the
parameters), ``steps`` (initial continuation steps, default 10), ``tol`` (scaled Newton residual, 1e-10),
``min_step`` (the smallest load step before giving up, 1e-4),
``bending_axis`` (x, y or z: the axis ``tip_rotation`` turns about, default z), ``frame_rate`` ([x, y, z],
rad/s: the rate of the frame the state is steady in, for ``velocity``; default 0), ``jacobian`` (ad, the
default: Newton's Jacobian by CasADi AD of the element, step and end pieces; fd: finite differences).

Outputs: ``tip_position`` ([x, y, z], m), ``tip_rotation`` (rad about the bending axis, unwrapped: an end
torque tau gives tau L/EI even beyond 2 pi), ``tip_orientation`` (3 x 3), ``s`` (nodes), ``shape``
(centre line, n x 3), ``strain`` (eps = f - f0, n x 6: u1 u2 u3 w1 w2 w3), ``stress_resultant`` (sigma = (n, m)
in the section frame, n x 6: N, N m), ``branch`` (per load step: ``load`` factor, ``tip_force``,
``tip_torque``, ``tip_position``, ``tip_rotation``, ``shape``), ``velocity`` (eta = (R^T (Omega x r), R^T Omega),
n x 6, m/s and rad/s in the section frame), ``orthonormality_error`` (max |R^T R - I|),
``iterations`` (Newton, last step). Bad input (exit 2): K not symmetric positive definite (key ``params``),
L <= 0 (``params.L``), ends that leave the rod free to move rigidly (``<analysis>.tip``), ``elements`` whose
memory or least wall time (ceil(steps / 2) Newton iterations of ITERATION_SECONDS per element) exceeds the memory
limit or ``max_seconds`` (key ``elements``). A load path that does not converge is a ConvergenceError naming the last load factor reached (exit 1).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mechgen.analyses import schema
from mechgen.analyses.cross_section import STRAINS, checked_stiffness
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.analyses.schema import Option
from mechgen.errors import InputError
from mechgen.runtime.core.budget import DEFAULT_SECONDS, require_seconds
from mechgen.runtime.core.memory import require
from mechgen.runtime.rods.ends import ENDS, UNCONSTRAINED
from mechgen.scene.values import fail, show, type_name

if TYPE_CHECKING:
    from mechgen.runtime.rods.statics import Rod

AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def vector3(ctx, key: str, value: object) -> list[float]:
    """A scene's [x, y, z] (numbers or expressions of the parameters; spatial frame)."""
    if not isinstance(value, list) or len(value) != 3:
        raise fail(ctx.file, key, f"value is {show(value) if isinstance(value, list) else type_name(value)}",
                   "an array of 3 numbers [x, y, z] (spatial frame)")
    return [schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]


MAX_ELEMENTS = 100_000
#: memory per element of a collocation solve (its sparse Jacobian, LU factors and the load path's states), bytes:
#: measured 41 KB/element between 2 000 and 8 000 elements (peak RSS 171 MB -> 415 MB), with a margin; checked
#: against the memory available before the solve starts (mechgen.runtime.core.memory, issue 33: 100 000 elements
#: took 1.7 GiB within 15 s and ran on)
ELEMENT_BYTES = 48_000
MAX_STEPS = 10_000
#: wall time per element of one Newton iteration (the element residuals and Jacobian, the sparse or 12 x 12 solve),
#: seconds: measured on a 2-core machine (issue 33) for scenes/rod_end_torque.toml and rod_tip_load.toml:
#: collocation 40-51 us at 1 000-4 000 elements and 102 us at 16 000, shooting (RKMK4 with the AD Jacobian through
#: the steps) 395-408 us at 1 000-4 000 steps; rounded down
ITERATION_SECONDS = {"collocation": 4.0e-5, "shooting": 3.9e-4}


def bounded(low: int, high: int):
    """An option check: an integer from ``low`` to ``high``."""
    def check(ctx, key: str, value: object) -> int:
        n = schema.int_at_least(ctx, key, value, low)
        if n > high:
            raise fail(ctx.file, key, f"value {n} is above {high}", f"an integer from {low} to {high}")
        return n

    return check


_elements = bounded(2, MAX_ELEMENTS)


SCHEMA = {
    "method": Option(schema.one_of("rod statics method", ("collocation", "shooting")), "collocation",
                     doc="collocation (Lie-group midpoint, order 2, robust at any load) or shooting (RKMK4, "
                     "order 4; single shooting stalls beyond PL^2/EI ~ 100 - 1000 and is slow there)"),
    "elements": Option(_elements, doc="RKMK4 steps or collocation elements along the rod (default 40)"),
    "N": Option(_elements, doc="the same as elements"),
    "base": Option(schema.one_of("end condition", ENDS), "clamped", doc="the end condition at s = 0: clamped, "
                   "pinned or free"),
    "tip": Option(schema.one_of("end condition", ENDS), "free", doc="the end condition at s = L: clamped, "
                  "pinned or free"),
    "tip_force": Option(vector3, [0.0, 0.0, 0.0], doc="the dead tip force [x, y, z] in the spatial frame (N; numbers "
                        "or expressions of the parameters)"),
    "tip_torque": Option(vector3, [0.0, 0.0, 0.0], doc="the dead tip torque [x, y, z] in the spatial frame "
                         "(N m; numbers or expressions of the parameters)"),
    "steps": Option(bounded(1, MAX_STEPS), 10, doc="the initial number of load continuation steps"),
    "tol": Option(schema.positive, 1e-10, doc="the scaled Newton residual at which a load step has converged"),
    "min_step": Option(schema.positive, 1e-4, doc="the smallest load-factor step before giving up"),
    "bending_axis": Option(schema.one_of("axis", tuple(AXES)), "z", doc="the axis (x, y or z) tip_rotation "
                           "turns about"),
    "frame_rate": Option(vector3, [0.0, 0.0, 0.0], doc="the angular velocity [x, y, z] of the frame the state is "
                         "steady in, for velocity (rad/s)"),
    "jacobian": Option(schema.one_of("Jacobian method", ("ad", "fd")), "ad", doc="Newton's Jacobian: ad "
                       "(CasADi's algorithmic derivatives) or fd (finite differences)"),
}



def check(ctx, base: str, options: dict) -> None:
    """``elements`` or ``N`` (not both); ends that hold the rod."""
    if "elements" in options and "N" in options:
        raise fail(ctx.file, f"{base}.N", "both 'elements' and 'N' are given", "one of them (the same thing)")
    options["elements"] = options.pop("N", options.get("elements", 40))
    if (options["base"], options["tip"]) in UNCONSTRAINED:
        raise fail(ctx.file, f"{base}.tip", f"ends base = {options['base']!r}, tip = {options['tip']!r} leave the "
                   "rod free to move rigidly (no static equilibrium to solve for)",
                   "a clamped end, or pinned at both ends, or a free base with a clamped tip")


def needs(options: dict, *, internal: bool) -> set[str]:
    """The rod kernel, and the section for the stiffness check."""
    return {"rod", "section"}


def rod_of(system, options: dict) -> Rod:
    """The runtime Rod from the system's ``rod`` kernel and the analysis's ends and tip loads."""
    from mechgen.runtime.rods.statics import Rod  # the rod solvers (and scipy.sparse) load with a rod scene

    if "rod" not in system.kernels:
        raise InputError(f"model {system.metadata.model} declares no rod (the rod_statics analysis needs one)",
                         key="kind", expected="a model with Model.rod(...), or another analysis kind")
    f0_in = np.zeros((1, 6))
    base = system.call("rod", f=f0_in, r=np.zeros((1, 3)))
    f0 = np.asarray(base["f0"], dtype=float).reshape(6)
    at = system.call("rod", f=f0[None, :], r=np.zeros((1, 3)))
    K = np.asarray(at["C"], dtype=float).reshape(6, 6)
    if "section" in system.kernels:
        checked_stiffness(system)
    _check_spd(system, K)
    L = float(np.asarray(at["L"]).ravel()[0])
    if not np.isfinite(L) or L <= 0.0:
        raise InputError(f"the rod of model {system.metadata.model} has length L = {L:g}", key="params.L",
                         expected="a positive length (m)")
    probe = np.random.default_rng(0).normal(size=(3, 3)) * L
    test = system.call("rod", f=np.tile(f0, (3, 1)), r=probe)
    loaded = bool(np.any(np.asarray(test["g"]) != 0.0) or np.any(np.asarray(test["g_r"]) != 0.0))

    def load(r):
        r = np.asarray(r, dtype=float).reshape(-1, 3)
        return np.asarray(system.call("rod", f=np.tile(f0, (len(r), 1)), r=r)["g"], dtype=float).reshape(-1, 6)

    def load_jacobian(r):
        """d g / d r (n, 6, 3): the kernel's g_r (the generated Jacobian of the declared load)."""
        r = np.asarray(r, dtype=float).reshape(-1, 3)
        out = system.call("rod", f=np.tile(f0, (len(r), 1)), r=r)["g_r"]
        return np.asarray(out, dtype=float).reshape(-1, 6, 3)

    g = np.asarray(test["g"], dtype=float).reshape(3, 6)
    uniform = bool(loaded and not np.any(np.asarray(test["g_r"]) != 0.0) and np.all(g == g[0]))
    if uniform:
        # independent of the position (uniform gravity): evaluated once, not at every Newton iterate
        value = g[0].copy()

        def load(r):  # noqa: F811
            return np.broadcast_to(value, (len(np.asarray(r).reshape(-1, 3)), 6))

        def load_jacobian(r):  # noqa: F811
            return np.zeros((len(np.asarray(r).reshape(-1, 3)), 6, 3))

    return Rod(L, K, f0, load if loaded else None, np.array(options["tip_force"], dtype=float),
               np.array(options["tip_torque"], dtype=float), options["base"], options["tip"],
               load_jacobian if loaded else None, uniform)


def _check_spd(system, K: np.ndarray) -> None:
    model = system.metadata.model
    if not np.all(np.isfinite(K)) or np.max(np.abs(K - K.T)) > 1e-12 * max(float(np.max(np.abs(K))), 1e-300):
        raise InputError(f"the rod stiffness of model {model} is not finite and symmetric", key="params",
                         expected="parameters giving a symmetric positive definite K")
    eig, vec = np.linalg.eigh(K)
    if eig[0] <= 1e-14 * max(abs(eig[-1]), 1e-300):
        along = STRAINS[int(np.argmax(np.abs(vec[:, 0])))]
        raise InputError(f"the rod stiffness K of model {model} is not positive definite: smallest eigenvalue "
                         f"{eig[0]:.6g} (mostly along {along})", key="params",
                         expected="EA, GA, GJ, EI > 0 (a symmetric positive definite K)")


def require_statics_time(options: dict) -> None:
    """Refuse up front (exit 2 at ``elements``) a solve whose least wall time exceeds ``max_seconds``: every load
    step takes at least one Newton iteration and the load path at least ceil(steps / 2) steps (a step grows to at
    most 2 / steps; shooting solves the unloaded state first), at ITERATION_SECONDS[method] per element each."""
    method, n = options["method"], int(options["elements"])
    iterations = -(-int(options["steps"]) // 2) + (method == "shooting")
    seconds = ITERATION_SECONDS[method] * n * iterations
    require_seconds(seconds, float(options.get("max_seconds", DEFAULT_SECONDS)), f"rod statics ({method}) with {n} "
                    "elements", key="elements", basis=f"at least {iterations} Newton iterations of "
                    f"{ITERATION_SECONDS[method] * 1e6:.3g} us per element, measured",
                    expected="fewer elements (a few hundred resolve most rods)")


def _point(rod: Rod, state, axis) -> dict:
    from mechgen.runtime.rods.statics import turning_angle

    return {"load": float(state.lam), "tip_force": [float(state.lam * x) for x in rod.tip_force],
            "tip_torque": [float(state.lam * x) for x in rod.tip_torque],
            "tip_position": [float(x) + 0.0 for x in state.H[-1, :3, 3]],
            "tip_rotation": turning_angle(state.H, axis),
            "shape": [[float(x) for x in row] for row in state.H[:, :3, 3]]}


def run_rod_statics(system, options: dict, context: dict) -> dict:
    """Solve along the load path; the final state's tip pose and fields, and the branch."""
    from mechgen.runtime.rods.liegroup import orthonormality_error
    from mechgen.runtime.rods.statics import solve_statics, turning_angle

    rod = rod_of(system, options)
    require(ELEMENT_BYTES * options["elements"], f"rod statics ({options['method']}) with {options['elements']} "
            "elements", key="elements", expected="fewer elements (the midpoint collocation converges at order 2: "
            "a few hundred elements resolve most rods)")
    require_statics_time(options)
    path = solve_statics(rod, method=options["method"], elements=options["elements"], steps=options["steps"],
                         tol=options["tol"], min_step=options["min_step"], jacobian=options["jacobian"])
    final, axis = path.final, AXES[options["bending_axis"]]
    rows = lambda a: [[float(x) + 0.0 for x in row] for row in a]  # noqa: E731
    return {"tip_position": [float(x) + 0.0 for x in final.H[-1, :3, 3]],
            "tip_rotation": turning_angle(final.H, axis),
            "tip_orientation": rows(final.H[-1, :3, :3]),
            "s": [float(x) for x in final.s], "shape": rows(final.H[:, :3, 3]),
            "strain": rows(final.f - rod.f0), "stress_resultant": rows(final.sigma),
            "branch": [_point(rod, st, axis) for st in path.states],
            "orthonormality_error": orthonormality_error(final.H[:, :3, :3]),
            "velocity": rows(_velocity(final.H, np.array(options["frame_rate"], dtype=float))),
            "iterations": int(final.iterations), "method": options["method"], "elements": int(options["elements"])}


def _velocity(H: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The sections' velocity twists eta = (R^T (Omega x r), R^T Omega) (section frame) of a state held steady
    in a frame turning at Omega about the origin (a rotating beam's centrifugal load comes with it)."""
    R, r = H[:, :3, :3], H[:, :3, 3]
    Rt = np.swapaxes(R, -1, -2)
    return np.concatenate([np.einsum("nij,nj->ni", Rt, np.cross(omega, r)), np.einsum("nij,j->ni", Rt, omega)], axis=1)


def lines(outputs: dict) -> list[str]:
    """Tip pose and the branch's length."""
    tip = ", ".join(f"{x:.6g}" for x in outputs["tip_position"])
    return [f"    tip_position: [{tip}] m", f"    tip_rotation: {outputs['tip_rotation']:.6g} rad",
            f"    load steps: {len(outputs['branch']) - 1} ({outputs['method']}, {outputs['elements']} elements)",
            f"    orthonormality_error: {outputs['orthonormality_error']:.3g}"]


def plot(plt, a: dict, path: Path) -> list[Path]:
    """The deformed centre lines along the load path in 3D (the final one bold)."""
    branch = a["outputs"]["branch"]
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    for k, point in enumerate(branch):
        xyz = np.asarray(point["shape"])
        last = k == len(branch) - 1
        ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], color="k" if last else "tab:blue", lw=2 if last else 0.8,
                alpha=1.0 if last else 0.4)
    pts = np.concatenate([np.asarray(p["shape"]) for p in branch])
    centre, half = (pts.max(0) + pts.min(0)) / 2, max(float(np.max(pts.max(0) - pts.min(0))) / 2, 1e-12)
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):   # equal scales: arcs look round
        setter(c - half, c + half)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax.set_title(f"{a['name']}: deformed shapes, load factor 0 to 1", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


register(AnalysisKind("rod_statics", SCHEMA, run_rod_statics, needs, lines, check=check, plot=plot, sweepable=True))
