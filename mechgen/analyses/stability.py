"""One function per analysis kind: (system, options, context) -> outputs dict.

Each states the kernels it needs in :data:`NEEDS`, so a scene compiles only those.
Output names follow DESIGN.md: ``frequencies``; ``eigenvalues`` (list of [re, im])
and ``verdict``; ``grid`` plus one array per output for sweeps.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import SceneError
from mechgen.runtime.integrate import integrate_first_order, leapfrog
from mechgen.runtime.modes import modes as solve_modes
from mechgen.runtime.newton import newton
from mechgen.runtime.stability import stability as solve_stability
from mechgen.runtime.stability import stability_first_order, stability_sparse
from mechgen.runtime.system import System
from mechgen.scene.branches import linear_about_steady, run_continuation, run_steady_bvp
from mechgen.scene.whirl import is_gyroscopic, run_campbell, run_damped_modes

#: above this many unknowns, a stability analysis with a ``count`` of sparse matrices uses shift-invert
SPARSE_STABILITY_N = 400


def needs(kind: str, options: dict, *, internal: bool) -> set[str]:
    """Kernels an analysis needs."""
    if kind in ("modes", "stability", "campbell"):
        return {"linear"}
    if kind == "continuation":  # its steady start brings the BVP kernels
        return {"linear"} if options.get("stability", True) else set()
    if kind == "steady" and options.get("method", "newton") != "newton":
        linear = {"linear"} if options.get("stability") else set()
        if options.get("form", "lagrangian") == "hamiltonian":
            return {"hbvp_rates", "hbvp_rates_tangent", "hbvp_outputs"} | linear
        return {"bvp_residual", "bvp_tangent", "bvp_outputs"} | linear
    if kind == "steady":
        return {"residual", "tangent", "outputs"} | ({"rates", "rates_tangent"} if internal else set())
    if kind == "simulate":
        if options.get("method") == "leapfrog":
            return {"force", "outputs", "linear"}
        start = {"linear"} if options.get("initial_mode") else set()
        return {"residual", "tangent", "outputs"} | start | ({"rates", "rates_tangent"} if internal else set())
    if kind == "sweep":
        inner = options["analysis"]
        return needs(inner.kind, inner.options, internal=internal)
    raise KeyError(kind)


def _vector(system: System, table: dict | None, base: np.ndarray | None = None) -> np.ndarray:
    q = np.zeros(system.n) if base is None else np.array(base, dtype=float)
    names = system.coordinates
    for name, value in (table or {}).items():
        q[names.index(name)] = float(value)
    return q


def _linear(system, q, options: dict, context: dict) -> dict:
    """M, D, G, K about the operating point, or about a boundary-value steady state named by ``about``."""
    if options.get("about") and "_bvp" in context[options["about"]]:
        return linear_about_steady(system, context[options["about"]])
    return system.linear(q)


def operating_point(system: System, options: dict, context: dict) -> np.ndarray:
    """q about which to linearise: a previous steady state, an explicit point, or zero."""
    if options.get("about"):
        steady = context[options["about"]]
        return np.zeros(system.n) if "_bvp" in steady else np.asarray(steady["_q"])
    return _vector(system, options.get("at"))


def run_modes(system: System, options: dict, context: dict) -> dict:
    """Natural frequencies (rad/s or the model's unit) about the operating point.

    A system with damping, gyroscopic terms or a non-symmetric stiffness, and any
    rotor (a model with a whirl pair), gets its damped modes instead
    (mechgen.scene.whirl): ``frequencies`` are then the damped natural frequencies,
    with ``eigenvalues``, ``log_dec`` and (rotors) ``whirl``.
    """
    q = operating_point(system, options, context)
    mats = _linear(system, q, options, context)
    if is_gyroscopic(mats) or system.meta.get("whirl"):
        out = run_damped_modes(system, mats, options)
        if system.is_field and options.get("count"):
            out.update(_field_shapes(system, np.real(out["_shapes"]), "shapes"))
        return out
    res = solve_modes(mats["M"], mats["K"], count=options.get("count"),
                      allow_singular_mass=getattr(system, "has_multipliers", False))
    out = {"frequencies": [float(f) for f in res.frequencies], "_shapes": res.shapes}
    if system.is_field and options.get("count"):
        out.update(_field_shapes(system, res.shapes, "shapes"))
    return out


def _stability_of(system, q, options: dict, context: dict):
    tol = options.get("tolerance", 1e-8)
    if system.m:
        z = np.asarray(context[options["about"]]["_z"]) if options.get("about") else np.zeros(system.m)
        A = system.jacobian(0.0, np.concatenate([q, np.zeros(system.n), z]))
        return stability_first_order(A, np.eye(A.shape[0]), tolerance=tol)
    mats = _linear(system, q, options, context)
    if options.get("count") and hasattr(mats["M"], "toarray") and system.n > SPARSE_STABILITY_N:
        return stability_sparse(mats["M"], mats["D"] + mats["G"], mats["K"], 2 * options["count"], tolerance=tol)
    dense = {k: (v.toarray() if hasattr(v, "toarray") else v) for k, v in mats.items()}
    return solve_stability(dense["M"], dense["D"] + dense["G"], dense["K"], tolerance=tol)


def refinement_verdict(verdicts: list[str], growth: list[float], scales: list[float], tolerance: float,
                       rtol: float) -> str:
    """The continuum's verdict from verdicts at two refinements.

    Equal verdicts stand when stable, or when the growth rates agree to ``rtol``
    (relative); otherwise ``unconverged``.
    """
    if verdicts[0] != verdicts[1]:
        return "unconverged"
    if verdicts[0] == "stable":
        return "stable"
    g0, g1 = growth
    floor = tolerance * max(scales)
    return verdicts[0] if abs(g0 - g1) <= rtol * max(abs(g0), abs(g1)) + floor else "unconverged"


def run_stability(system: System, options: dict, context: dict) -> dict:
    """Eigenvalues of M q'' + (D + G) q' + K q = 0 and the verdict.

    With internal variables z the linearisation is the first-order one,
    x' = A x with A = d(dx/dt)/dx at (q, 0, z) (exact Jacobian, see System.jacobian).
    For a continuum (with ``refine``), the verdict is checked on the same model
    discretised twice as finely: ``unconverged`` when the verdict changes or the
    growth rate does not settle (``refinement`` reports both).
    """
    q = operating_point(system, options, context)
    res = _stability_of(system, q, options, context)
    eig = [[float(s.real), float(s.imag)] for s in res.eigenvalues]
    freqs = [float(f) for f in res.frequencies]
    if options.get("count"):
        freqs = freqs[: options["count"]]
    out = {"eigenvalues": eig, "verdict": res.verdict, "frequencies": freqs, "growth_rate": float(res.growth_rate)}
    if hasattr(system, "refined") and options.get("refine", True) and not options.get("about"):
        size = int(system.choices["N"])
        fine = system.refined(2 * size)
        res2 = _stability_of(fine, np.zeros(fine.n), options, context)
        out["verdict"] = refinement_verdict([res.verdict, res2.verdict], [res.growth_rate, res2.growth_rate],
                                            [res.scale, res2.scale], options.get("tolerance", 1e-8),
                                            options.get("refine_rtol", 1e-2))
        out["refinement"] = {"N": [size, 2 * size], "verdicts": [res.verdict, res2.verdict],
                             "growth_rates": [float(res.growth_rate), float(res2.growth_rate)]}
    return out


def _equilibrium_functions(system: System):
    """F(y) = [r(q, 0, 0, z); g(q, 0, z)] and dF/dy for y = (q, z)."""
    n = system.n

    def residual(y):
        q, z = y[:n], y[n:]
        r = system.residual(q, None, None, z if system.m else None)
        return np.concatenate([r, system.call("rates", q=q, z=z)["g"].ravel()]) if system.m else r

    def jacobian(y):
        q, z = y[:n], y[n:]
        tan = system.tangent(q, z=z if system.m else None)
        if not system.m:
            return tan["r_q"]
        g = system.call("rates_tangent", q=q, z=z)
        return np.block([[tan["r_q"], tan["r_z"]], [g["g_q"], g["g_z"]]])

    return residual, jacobian


def run_steady(system: System, options: dict, context: dict) -> dict:
    """Equilibrium r(q, 0, 0, z) = 0, g(q, 0, z) = 0 by Newton with the generated Jacobians.

    ``method`` shooting / multiple_shooting / collocation: a continuum's steady state as a
    boundary value problem in s (mechgen.scene.branches)."""
    if options.get("method", "newton") != "newton":
        if not system.is_field:
            raise SceneError(f"steady method {options['method']!r} is for continua", key="method",
                             expected="'newton' for a lumped or chain model")
        return run_steady_bvp(system, options, context)
    if system.is_field and system.info.get("boundary_values"):
        raise SceneError(f"model {system.meta.get('model')} fixes its ends at nonzero values: its steady state is "
                         "a boundary value problem in s", key="method",
                         expected="method = 'collocation', 'shooting' or 'multiple_shooting'")
    y0 = np.concatenate([_vector(system, options.get("guess")), np.zeros(system.m)])
    residual, jacobian = _equilibrium_functions(system)
    res = newton(residual, jacobian, y0, tol=options.get("tol", 1e-10), max_iter=options.get("max_iter", 50))
    q, z = res.x[:system.n], res.x[system.n:]
    out = {"iterations": int(res.iterations), "residual_norm": float(res.residual_norm)}
    if not system.is_lattice and not system.is_field:
        out["coordinates"] = {n: float(x) for n, x in zip(system.coordinates, q)}
    out.update(system.outputs(q, None, z if system.m else None))
    if system.is_field:
        out["reactions"] = system.reactions(q)
        out.update(_field_shapes(system, q[:, None], "deflection"))
    out["_q"], out["_z"] = q, z
    return out


def _field_shapes(system, columns: np.ndarray, name: str, samples: int = 101) -> dict:
    """Fields of each column of reduced states on an even grid: {"s": [...], name: {field: curves}}.

    Mode shapes ("shapes") are scaled to a largest |value| of 1 over all fields, that
    value positive; a deflection keeps its units (one curve per field).
    """
    s = np.linspace(0.0, system.disc.length, samples)
    curves: dict = {f: [] for f in system.disc.fields}
    for col in columns.T:
        values = system.field_values(col, s)
        if name == "shapes":
            stacked = np.concatenate(list(values.values()))
            peak = stacked[np.argmax(np.abs(stacked))]
            values = {f: v / peak if peak else v for f, v in values.items()}
        for f, v in values.items():
            curves[f].append([float(x) for x in v])
    if name == "deflection":
        curves = {f: c[0] for f, c in curves.items()}
    return {"s": [float(v) for v in s], name: curves}


def initial_state(system: System, options: dict) -> tuple[np.ndarray, np.ndarray]:
    """(q0, v0) from the options: tables of coordinates, or a linear mode times an amplitude."""
    q0, v0 = _vector(system, options.get("q0")), _vector(system, options.get("v0"))
    if options.get("initial_mode"):
        k = int(options["initial_mode"])
        if k > system.n:
            raise SceneError(f"initial_mode {k} exceeds the {system.n} degrees of freedom", key="initial_mode",
                             expected=f"an integer from 1 to {system.n}")
        mats = system.linear(np.zeros(system.n))
        shapes = solve_modes(mats["M"], mats["K"]).shapes
        shape = shapes[:, k - 1] / np.max(np.abs(shapes[:, k - 1]))
        q0 = q0 + options.get("amplitude", 1.0) * shape * np.sign(shape[np.argmax(np.abs(shape))])
    return q0, v0


def mode_energies(system: System, q: np.ndarray, v: np.ndarray, count: int = 8) -> list[float]:
    """Harmonic energies E_k = (P_k^2 + omega_k^2 Q_k^2)/2 of a fixed-end chain (FPU's observable).

    Q_k = sqrt(2/(N+1)) sum_n q_n sin(n k pi/(N+1)); omega_k from the linear stiffness.
    """
    n = system.n
    idx = np.arange(1, n + 1)
    k = np.arange(1, min(count, n) + 1)
    S = np.sqrt(2.0 / (n + 1)) * np.sin(np.outer(k, idx) * np.pi / (n + 1))
    mats = system.linear(np.zeros(n))
    omega2 = np.einsum("ki,ij,kj->k", S, mats["K"].toarray(), S)
    Q, P = S @ q, S @ v
    return [float(e) for e in 0.5 * (P**2 + omega2 * Q**2)]


def run_simulate(system: System, options: dict, context: dict) -> dict:
    """Time response; reports the model's outputs at t_end and the energy drift."""
    q0, v0 = initial_state(system, options)
    t_end = float(options["t_end"])
    energy = lambda q, v: system.outputs(q, v)["energy"]  # noqa: E731
    if options.get("method") == "leapfrog":
        dt = float(options["dt"])
        steps = int(round(t_end / dt))
        mats = system.linear(np.zeros(system.n))
        M = mats["M"]
        minv = 1.0 / (M.diagonal() if hasattr(M, "diagonal") else np.diag(M))
        traj = leapfrog(lambda q: system.force(q) * minv, q0, v0, dt, steps,
                        record_every=max(1, steps // 1000), energy=energy)
        q_end, v_end, ts, energies = traj.q[-1], traj.v[-1], traj.t, np.asarray(traj.energy)
        z_end = None
    else:
        x0 = np.concatenate([q0, v0, np.zeros(system.m)])
        n_out = int(options.get("samples", 201))
        t_eval = np.linspace(0.0, t_end, n_out)
        traj = integrate_first_order(system.rhs, x0, t_end, jac=system.jacobian, method=options.get("method", "BDF"),
                                     rtol=options.get("rtol", 1e-8), atol=options.get("atol", 1e-10), t_eval=t_eval)
        xs = traj.x if traj.x.shape[0] == len(traj.t) else traj.x.T
        n = system.n
        q_end, v_end, z_end = xs[-1, :n], xs[-1, n:2 * n], xs[-1, 2 * n:]
        ts = traj.t
        energies = np.array([system.outputs(x[:n], x[n:2 * n], x[2 * n:] if system.m else None)["energy"]
                             for x in xs])
    out = system.outputs(q_end, v_end, z_end if system.m else None)
    wanted = options.get("outputs")
    if wanted:
        out = {k: v for k, v in out.items() if k in wanted}
    e0 = energies[0]
    out["energy_drift"] = float(np.max(np.abs(energies - e0)) / max(abs(e0), 1e-300))
    out["t_end"] = t_end
    if system.is_lattice and system.meta.get("ends") == "fixed":
        out["mode_energies"] = mode_energies(system, q_end, v_end)
    if options.get("series"):
        out["t"] = [float(t) for t in ts]
        out["energy_series"] = [float(e) for e in energies]
    return out


RUNNERS = {"modes": run_modes, "stability": run_stability, "steady": run_steady, "simulate": run_simulate,
           "campbell": run_campbell, "continuation": run_continuation}
