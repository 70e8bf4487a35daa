"""``mechgen bench multibody``: the n-link planar pendulum, the scaling problem of symbolic multibody tools.

n rigid massless links of length l, a point mass m at the end of each, angles theta_i from the downward
vertical, written as a user writes it (:func:`pendulum_model`): with x_k = l sum_{i<=k} sin(theta_i),
y_k = -l sum_{i<=k} cos(theta_i),

    T = m/2 sum_k (x_k'^2 + y_k'^2),      V = m g sum_k y_k        (SI units).

Its equations of motion in closed form (the independent reference of the tests) are

    sum_j m l^2 c_ij [cos(theta_i - theta_j) a_j + sin(theta_i - theta_j) w_j^2] + m g l (n - i) sin(theta_i) = 0,

c_ij = n - max(i, j) the number of masses beyond both links (0-based i, j).

The suite (:func:`run_multibody_benchmarks`) builds the pendulum for n = 2 ... 64 (``quick``: 2, 4, 8) and a
10 x 10 planar mass-spring lattice (:func:`lattice_model`; ``quick``: 3 x 3) with each tool of :data:`TOOLS`:
mechgen's flow kernel only (M and h: what an explicit simulation needs, as PyDy's mass matrix and forcing),
mechgen's every kernel (``mechgen.compile``'s default), each rebuilt from the cache it filled, the flow kernel
on mechgen's numpy backend, PyDy's Kane's
method with lambdify and with cython, and sympy's LagrangesMethod with lambdify. Each tool and size runs in a
child process of its own (:func:`cell_main`, $MECHGEN_CACHE a fresh folder, one BLAS thread), which reports:

* the first build, s: model declaration, derivation, code generation and compilation, imports excluded (one
  run; PyDy has no cache and pays it in every process), and mechgen's stages (derive, lower, emit, build, and
  within them declare, rewrite and cse: :data:`STAGES`, :data:`INNER_STAGES`);
* the right-hand side per call, s (median of 5 timed runs, each >= 20 ms of calls, after a warm-up; mechgen
  ``system.rhs(t, x)`` and ``system.acceleration(q, v)``; PyDy's generated function);
* a simulation: scipy ``solve_ivp`` DOP853 over 10 s at rtol 1e-8, atol 1e-10, 101 samples, from every link
  at 0.3 rad (the lattice from its rest grid, sagging under gravity): wall time, evaluations, end state;
* accelerations at 3 seeded random states, compared in the parent with the closed form (pendulum) or with
  the spring forces by numpy (lattice, :func:`lattice_accelerations`): the issue's criterion is 1e-10
  relative to the largest entry.

A cell whose build is predicted (from the tool's last two sizes) to exceed the cap is skipped, a child whose
build runs past it is ended, a simulation past SIM_CAP_S stops: each is marked ``skipped (> cap)``, never
waited for. The fitted growth exponent of each tool's build time (least squares of log t on log n over
n >= 8) is reported, not asserted. Reports: multibody_results.{csv,json,md}, multibody_ratios.json (peer
seconds / mechgen flow seconds, like for like) and multibody_build_time.png (build time against n, log-log).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import sympy as sp

from mechgen.bench.common import ROOT, repeat_times, timed
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param


def pendulum_model(n: int) -> Model:
    """The n-link planar pendulum as a mechgen model ``pendulum<n>`` (coordinates theta0 ... theta<n-1>)."""
    # file=: the compile cache is keyed by this file's bytes and the model's name, which carries n
    model = Model(f"pendulum{n}", doc=f"{n}-link planar pendulum, point masses at the link ends", file=__file__)
    model.params(Param("m", 1.0, "kg", "mass at each link end", positive=True),
                 Param("l", 1.0, "m", "link length", positive=True),
                 Param("g", 9.81, "m/s^2", "gravity"))
    names = [f"theta{i}" for i in range(n)]
    model.coordinates(*names)

    @model.kinetic
    def kinetic(q, v, p):
        xd = yd = T = 0
        for name in names:
            xd += p.l * sp.cos(q[name]) * v[name]
            yd += p.l * sp.sin(q[name]) * v[name]
            T += p.m / 2 * (xd**2 + yd**2)
        return T

    @model.potential
    def potential(q, p):
        y = V = 0
        for name in names:
            y -= p.l * sp.cos(q[name])
            V += p.m * p.g * y
        return V

    return model


def lattice_model(rows: int, cols: int) -> Model:
    """A planar mass-spring lattice ``lattice<rows>x<cols>`` as ONE lumped mechgen model.

    rows x cols point masses m on a square grid of spacing a (node (i, j) at rest at x = a j, y = -a i); the left
    column (j = 0) is anchored, every other node moves in the plane with displacements (ux_i_j, uy_i_j) (2 rows
    (cols - 1) coordinates). Nonlinear springs join the 4-neighbours:

        T = m/2 sum (ux'^2 + uy'^2),   V = sum_springs k/2 (|r_a - r_b| - a)^2 + m g sum y     (SI units),

    with r the node's position (rest position plus displacement).
    """
    model = Model(f"lattice{rows}x{cols}", doc=f"{rows} x {cols} planar mass-spring lattice, left column anchored",
                  file=__file__)
    model.params(Param("m", 1.0, "kg", "mass of each node", positive=True),
                 Param("k", 100.0, "N/m", "spring stiffness", positive=True),
                 Param("a", 1.0, "m", "spring rest length and grid spacing", positive=True),
                 Param("g", 9.81, "m/s^2", "gravity"))
    nodes = lattice_nodes(rows, cols)
    model.coordinates(*[f"u{ax}_{i}_{j}" for i, j in nodes for ax in "xy"])

    @model.kinetic
    def kinetic(q, v, p):
        return sum(p.m / 2 * (v[f"ux_{i}_{j}"]**2 + v[f"uy_{i}_{j}"]**2) for i, j in nodes)

    @model.potential
    def potential(q, p):
        def position(i, j):
            if j == 0:
                return p.a * j, -p.a * i
            return p.a * j + q[f"ux_{i}_{j}"], -p.a * i + q[f"uy_{i}_{j}"]
        V = sum(p.m * p.g * position(i, j)[1] for i, j in nodes)
        for (i, j), (k, l) in lattice_springs(rows, cols):
            (xa, ya), (xb, yb) = position(i, j), position(k, l)
            V += p.k / 2 * (sp.sqrt((xa - xb)**2 + (ya - yb)**2) - p.a)**2
        return V

    return model


def lattice_nodes(rows: int, cols: int) -> list[tuple[int, int]]:
    """The moving nodes (i, j) of the lattice, row by row (the order of the coordinates ux, uy of each)."""
    return [(i, j) for i in range(rows) for j in range(1, cols)]


def lattice_springs(rows: int, cols: int) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """Every 4-neighbour pair of nodes with at least one moving node (springs between anchored nodes do not
    matter)."""
    out = [((i, j), (i, j + 1)) for i in range(rows) for j in range(cols - 1)]
    out += [((i, j), (i + 1, j)) for i in range(rows - 1) for j in range(1, cols)]
    return out


# -- the same systems in PyDy / sympy.physics.mechanics ---------------------------------------------------------
def pydy_pendulum(n: int, method: str = "kane") -> dict:
    """The n-link pendulum in sympy.physics.mechanics as PyDy's examples write it: frames A_i rotated by q_i about
    N.z, P_i = P_{i-1} - l A_i.y, particles of mass m, gravity -m g N.y; Kane's method (u_i = q_i') or
    LagrangesMethod on L = T - V (q_i' renamed u_i afterwards). {"M", "F", "q", "u", "constants", "values"} with
    M u' = F (n x n, n)."""
    import sympy.physics.mechanics as me

    q, u = me.dynamicsymbols(f"q:{n}"), me.dynamicsymbols(f"u:{n}")
    m, l, g = sp.symbols("m l g")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    point, particles = O, []
    for i in range(n):
        frame = N.orientnew(f"A{i}", "Axis", [q[i], N.z])
        frame.set_ang_vel(N, (u[i] if method == "kane" else q[i].diff()) * N.z)
        point = point.locatenew(f"P{i}", -l * frame.y)
        point.v2pt_theory(O if i == 0 else previous, N, frame)
        particles.append(me.Particle(f"pa{i}", point, m))
        previous = point
    return _pydy_equations(method, N, q, u, particles, [(pa.point, -m * g * N.y) for pa in particles],
                           (m, l, g), (1.0, 1.0, 9.81), lambda pa: m * g * pa.point.pos_from(O).dot(N.y))


def pydy_lattice(rows: int, cols: int, method: str = "kane") -> dict:
    """:func:`lattice_model` in sympy.physics.mechanics: a particle per moving node located by its displacement
    (coordinates in :func:`lattice_nodes` order, x then y), spring forces along each 4-neighbour pair
    (-k (|d| - a) d/|d| on one end, the opposite on the other) and gravity. Same return as :func:`pydy_pendulum`."""
    import sympy.physics.mechanics as me

    nodes = lattice_nodes(rows, cols)
    q, u = me.dynamicsymbols(f"q:{2 * len(nodes)}"), me.dynamicsymbols(f"u:{2 * len(nodes)}")
    m, k, a, g = sp.symbols("m k a g")
    N, O = me.ReferenceFrame("N"), me.Point("O")
    O.set_vel(N, 0)
    points, particles = {}, []
    for idx, (i, j) in enumerate(nodes):
        P = O.locatenew(f"P{i}_{j}", (a * j + q[2 * idx]) * N.x + (-a * i + q[2 * idx + 1]) * N.y)
        P.set_vel(N, (u[2 * idx] if method == "kane" else q[2 * idx].diff()) * N.x
                  + (u[2 * idx + 1] if method == "kane" else q[2 * idx + 1].diff()) * N.y)
        points[i, j] = P
        particles.append(me.Particle(f"pa{i}_{j}", P, m))
    for i in range(rows):
        points[i, 0] = O.locatenew(f"W{i}", -a * i * N.y)
    loads = [(pa.point, -m * g * N.y) for pa in particles]
    springs = []
    for A, B in lattice_springs(rows, cols):
        d = points[A].pos_from(points[B])
        length = sp.sqrt(d.dot(d))
        springs.append(k / 2 * (length - a)**2)
        force = -k * (length - a) / length * d
        loads += [(points[A], force)] + ([(points[B], -force)] if B[1] > 0 else [])
    return _pydy_equations(method, N, q, u, particles, loads, (m, k, a, g), (1.0, 100.0, 1.0, 9.81),
                           lambda pa: m * g * pa.point.pos_from(O).dot(N.y), extra_potential=sum(springs))


def _pydy_equations(method, N, q, u, particles, loads, constants, values, potential, extra_potential=0) -> dict:
    """Kane's method with the given loads, or LagrangesMethod on T - V (V: ``potential`` of each particle plus
    ``extra_potential``), as M u' = F."""
    import sympy.physics.mechanics as me

    if method == "kane":
        kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)])
        kane.kanes_equations(particles, loads)
        M, F = kane.mass_matrix, kane.forcing
    else:
        V = sum(potential(pa) for pa in particles) + extra_potential
        lagrange = me.LagrangesMethod(me.Lagrangian(N, *particles) - V, q)
        lagrange.form_lagranges_equations()
        rename = {qi.diff(): ui for qi, ui in zip(q, u)}
        M, F = me.msubs(lagrange.mass_matrix, rename), me.msubs(lagrange.forcing, rename)
    return {"M": M, "F": F, "q": q, "u": u, "constants": list(constants), "values": np.array(values)}


def pydy_rhs(eqs: dict, generator: str):
    """PyDy's generated right-hand side ``f(t, x) -> x'`` (x = q, u) of M u' = F, q' = u (generate_ode_function,
    ``generator`` "lambdify" or "cython", linear solve by numpy)."""
    from pydy.codegen.ode_function_generators import generate_ode_function

    rhs = generate_ode_function(eqs["F"], eqs["q"], eqs["u"], eqs["constants"], mass_matrix=eqs["M"],
                                coordinate_derivatives=sp.Matrix(eqs["u"]), generator=generator)
    values = eqs["values"]
    # a copy: PyDy's function returns arrays that its next call overwrites (odeint copies them, solve_ivp keeps
    # them as its stages: without the copy DOP853 takes 8x the steps to a wrong answer)
    return lambda t, x: np.array(rhs(x, t, values))


# -- the suite ----------------------------------------------------------------------------------------------------
#: the tools, in the order each size runs them; "cached" rows rebuild in a new process from the cache the row
#: before filled (PyDy has no cache: every process derives and generates again)
TOOLS = ("mechgen flow", "mechgen flow cached", "mechgen all", "mechgen all cached", "mechgen flow numpy",
         "sympy lambdify of mechgen's M, h", "PyDy Kane + lambdify", "PyDy Kane + cython", "PyDy Lagrange + lambdify")
#: the tools whose right-hand side is timed and integrated (mechgen all's flow kernel is mechgen flow's)
CALLERS = ("mechgen flow", "mechgen flow numpy", "sympy lambdify of mechgen's M, h", "PyDy Kane + lambdify",
           "PyDy Kane + cython", "PyDy Lagrange + lambdify")
#: the like-for-like peer of the numpy backend (issue 32 item 2): the same derived equations through sympy's lambdify
LAMBDIFY_OWN = "sympy lambdify of mechgen's M, h"
SIZES, QUICK_SIZES = (2, 4, 8, 12, 16, 24, 32, 64), (2, 4, 8)
LATTICE, QUICK_LATTICE = (10, 10), (3, 3)
#: a cell (one tool, one size) whose predicted build exceeds CAP_S is skipped; a child still running after
#: CAP_S s without a finished build, or CAP_S + SIM_CAP_S + 30 s in all, is ended; a simulation past SIM_CAP_S stops
CAP_S, SIM_CAP_S = 120.0, 30.0
T_END, RTOL, ATOL, SAMPLES = 10.0, 1e-8, 1e-10, 101
CHILD = "import sys; from mechgen.bench.multibody import cell_main; cell_main(sys.argv[1:])"


def closed_form_accelerations(theta, w, m=1.0, l=1.0, g=9.81) -> np.ndarray:
    """The n-link pendulum's accelerations (rad/s^2) from the closed form of the module docstring, by numpy."""
    n = len(theta)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    c = n - np.maximum(i, j)
    d = theta[:, None] - theta[None, :]
    f = m * l**2 * (c * np.sin(d)) @ (w**2) + m * g * l * (n - np.arange(n)) * np.sin(theta)
    return np.linalg.solve(m * l**2 * c * np.cos(d), -f)


def sample_states(problem: str, n: int, count: int = 3) -> list[np.ndarray]:
    """Seeded random states x = (q, v) at which every tool's accelerations are compared (n coordinates):
    pendulum angles and rates in [-1, 1]; lattice displacements and velocities in [-0.1, 0.1] (a = 1 m)."""
    rng = np.random.default_rng(32)
    scale = 1.0 if problem == "pendulum" else 0.1
    return [rng.uniform(-scale, scale, 2 * n) for _ in range(count)]


def initial_state(problem: str, n: int) -> np.ndarray:
    """The simulation's start: every link at 0.3 rad at rest (pendulum); the lattice at its rest grid, at rest
    (it sags under gravity)."""
    return np.r_[np.full(n, 0.3 if problem == "pendulum" else 0.0), np.zeros(n)]


def lattice_accelerations(x, rows: int, cols: int, m=1.0, k=100.0, a=1.0, g=9.81) -> np.ndarray:
    """The lattice's accelerations (m/s^2) at displacements x (:func:`lattice_nodes` order, x then y) by numpy:
    each spring pulls its ends with k (|d| - a) d/|d| along d = r_b - r_a, gravity -m g in y, divided by m."""
    nodes = lattice_nodes(rows, cols)
    slot = {node: 2 * s for s, node in enumerate(nodes)}
    rest = {(i, j): np.array([a * j, -a * i]) for i in range(rows) for j in range(cols)}
    pos = {node: rest[node] + (x[slot[node]:slot[node] + 2] if node in slot else 0.0) for node in rest}
    force = np.tile([0.0, -m * g], len(nodes))
    for A, B in lattice_springs(rows, cols):
        d = pos[B] - pos[A]
        pull = k * (np.linalg.norm(d) - a) * d / np.linalg.norm(d)
        for node, sign in ((A, 1.0), (B, -1.0)):
            if node in slot:
                force[slot[node]:slot[node] + 2] += sign * pull
    return force / m


def _build(tool: str, problem: str, size: tuple):
    """Build ``tool``'s right-hand side of the problem; returns f(t, x) and, for mechgen, the system."""
    if tool.startswith("mechgen"):
        import mechgen

        model = pendulum_model(*size) if problem == "pendulum" else lattice_model(*size)
        system = mechgen.compile(model, kernels=["flow"] if "flow" in tool else None,
                                 backend="numpy" if "numpy" in tool else "c")
        return system.rhs, system
    if tool == LAMBDIFY_OWN:
        model = pendulum_model(*size) if problem == "pendulum" else lattice_model(*size)
        return lambdified_equations(model), None
    method = "kane" if "Kane" in tool else "lagrange"
    eqs = pydy_pendulum(*size, method) if problem == "pendulum" else pydy_lattice(*size, method)
    return pydy_rhs(eqs, "cython" if "cython" in tool else "lambdify"), None


def lambdified_equations(model: Model):
    """f(t, x) = (v, M^-1 (-h)) with M(q, p) and h(q, v, p) of mechgen's own derivation (derive.lagrange_parts on the
    declared energies, every numeric parameter kept free as in mechgen's default build) through sympy's lambdify
    (numpy module, cse) and numpy's solve: the numpy backend's like-for-like peer."""
    import sympy as sp

    from mechgen.symbolic.derive import declared_lumped, lagrange_parts
    from mechgen.symbolic.specialize import specialize

    free = tuple(p.name for p in model.param_list if p.is_numeric)
    d = declared_lumped(model, specialize(model, {}, free=free))
    M, h = lagrange_parts(d.T, d.V, d.R, d.q, d.v)
    f = sp.lambdify([d.q, d.v, d.free], [M, sp.Matrix(h)], modules="numpy", cse=True)
    defaults = {p.name: p.default for p in model.param_list}
    values = np.array([defaults[s.name] for s in d.free], float)
    n = len(d.q)

    def rhs(t, x):
        M_, h_ = f(x[:n], x[n:], values)
        return np.concatenate([x[n:], np.linalg.solve(np.asarray(M_, float), -np.asarray(h_, float).ravel())])
    return rhs


def _emit(**record) -> None:
    """One JSON line on stdout, flushed (the parent keeps every line printed before a timeout)."""
    print(json.dumps(record, default=float), flush=True)


def cell_main(argv: list[str]) -> None:
    """A child process: build TOOL for PROBLEM SIZE (``n`` or ``rowsxcols``) and print JSON lines: build_s, then
    (for :data:`CALLERS`) per-call seconds, accelerations at :func:`sample_states` and a simulation."""
    tool, problem, size = argv[0], argv[1], tuple(int(s) for s in argv[2].split("x"))
    if tool.startswith("mechgen") or tool == LAMBDIFY_OWN:  # imports before the clock starts
        import mechgen  # noqa: F401
        import sympy  # noqa: F401
    else:
        import pydy.codegen.ode_function_generators  # noqa: F401
        import sympy.physics.mechanics  # noqa: F401
    stages = _stage_clock()
    seconds, (rhs, system) = timed(lambda: _build(tool, problem, size))
    _emit(build_s=seconds, **({"stages_s": stages} if stages else {}))
    if tool not in CALLERS:
        return
    n = _coordinates(problem, size)
    states = sample_states(problem, n)
    calls = {"rhs": lambda: rhs(0.0, states[0])}
    if system is not None:
        calls["acceleration"] = lambda: system.acceleration(states[0][:n], states[0][n:])
    _emit(per_call_s={k: float(np.median(repeat_times(f, 5, min_time=0.02))) for k, f in calls.items()})
    _emit(accelerations=[list(rhs(0.0, x)[n:]) for x in states])
    _emit(simulation=_simulate(rhs, initial_state(problem, n)))


#: mechgen's build stages, which add up to its build (BuildReport.seconds), and the inner ones within them
STAGES = ("derive", "lower", "emit", "build")
INNER_STAGES = ("declare", "rewrite", "cse")


def _stage_clock() -> dict:
    """A dict that fills with mechgen's build stages (derive, lower, emit, build: C compile and load; seconds)
    when the pipeline logs "built ..." (its BuildReport's times)."""
    import logging

    stages: dict = {}

    class Stages(logging.Handler):
        def emit(self, record):
            if str(record.msg).startswith("built") and len(record.args) > 3 and isinstance(record.args[3], dict):
                stages.update(record.args[3])

    logger = logging.getLogger("mechgen")
    logger.setLevel(logging.INFO)
    logger.addHandler(Stages(logging.INFO))
    return stages


def _coordinates(problem: str, size: tuple) -> int:
    """The number of coordinates of the problem."""
    return size[0] if problem == "pendulum" else 2 * len(lattice_nodes(*size))


def _simulate(rhs, x0: np.ndarray) -> dict:
    """solve_ivp DOP853 over T_END at RTOL/ATOL, SAMPLES equally spaced outputs: wall seconds and the end state,
    or ``skipped`` when it runs past SIM_CAP_S."""
    from scipy.integrate import solve_ivp

    deadline = time.perf_counter() + SIM_CAP_S

    def f(t, x):
        if time.perf_counter() > deadline:
            raise TimeoutError
        return rhs(t, x)

    try:
        seconds, sol = timed(lambda: solve_ivp(f, (0.0, T_END), x0, method="DOP853", rtol=RTOL, atol=ATOL,
                                               t_eval=np.linspace(0.0, T_END, SAMPLES)))
    except TimeoutError:
        return {"skipped": f"skipped (> {SIM_CAP_S:g} s cap)"}
    return {"wall_s": seconds, "nfev": int(sol.nfev), "end": list(sol.y[:, -1])}


def run_cell(tool: str, problem: str, size: tuple, cache: Path, cap: float) -> dict:
    """One child process (:func:`cell_main`) with $MECHGEN_CACHE = ``cache``: its records merged, ``status``
    "ok", or "skipped (> cap)" when it was ended: its build not done after ``cap`` seconds, or the whole child
    after cap + SIM_CAP_S + 30 s (what it printed before is kept)."""
    import select
    import tempfile

    env = {**os.environ, "MECHGEN_CACHE": str(cache), "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    cmd = [sys.executable, "-c", CHILD, tool, problem, "x".join(map(str, size))]
    record, status, start = {}, "ok", time.perf_counter()
    with tempfile.TemporaryFile(mode="w+") as err:
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, text=True, env=env, cwd=ROOT)
        while True:
            ready, _, _ = select.select([proc.stdout], [], [], 0.5)
            line = proc.stdout.readline() if ready else ""
            if line.startswith("{"):
                record.update(json.loads(line))
            elif ready and not line:  # end of output
                break
            elapsed = time.perf_counter() - start
            if elapsed > (cap if "build_s" not in record else cap + SIM_CAP_S + 30):
                proc.kill()
                status = f"skipped (> {cap:g} s cap)" if "build_s" not in record else "stopped (> cap)"
                break
        proc.wait()
        if status == "ok" and proc.returncode != 0:
            err.seek(0)
            tail = err.read().strip().splitlines()
            status = f"failed: {tail[-1] if tail else proc.returncode}"
    return {"status": status, **record}


def predicted_seconds(points: list[tuple[int, float]], n: int) -> float:
    """A tool's build seconds at size n extrapolated from its measured (size, seconds): the last point grown by
    the exponent of the last two (clipped to [1.5, 4]; 3 from one point); 0 with none."""
    if not points:
        return 0.0
    (n1, t1) = points[-1]
    slope = 3.0
    if len(points) > 1 and points[-2][1] > 0 and t1 > 0:
        (n0, t0) = points[-2]
        slope = min(4.0, max(1.5, float(np.log(t1 / t0) / np.log(n1 / n0))))
    return t1 * (n / n1) ** slope


def growth_exponent(points: list[tuple[int, float]], n_min: int = 8) -> float | None:
    """The least-squares slope of log t against log n over the sizes n >= n_min (None from fewer than 2)."""
    use = [(n, t) for n, t in points if n >= n_min and t > 0]
    if len(use) < 2:
        return None
    return float(np.polyfit(np.log([n for n, _ in use]), np.log([t for _, t in use]), 1)[0])


def _size_cells(problem: str, size: tuple, tools: tuple, history: dict, cap: float, tmp: Path) -> dict:
    """Every tool at one size: a child each (cached rows reuse the cache their first build filled), skipped when
    the predicted build exceeds ``cap`` or its first build was not made."""
    cells = {}
    for tool in tools:
        first = tool.replace(" cached", "")
        n = size[0] if problem == "pendulum" else _coordinates(problem, size)
        if tool != first and cells.get(first, {}).get("status") != "ok":
            cells[tool] = {"status": "skipped (no first build)"}
            continue
        guess = predicted_seconds(history.setdefault(first, []), n)
        if tool == first and guess > cap:
            cells[tool] = {"status": f"skipped (> cap: {guess:.0f} s predicted, cap {cap:g} s)"}
            continue
        print(f"[multibody] {problem} {'x'.join(map(str, size))}: {tool} ...", file=sys.stderr, flush=True)
        cells[tool] = run_cell(tool, problem, size, tmp / f"{problem}{n}-{first}", cap)
        if tool == first and "build_s" in cells[tool]:
            history[first].append((n, cells[tool]["build_s"]))
        print(f"[multibody]   {cells[tool]['status']}, build {cells[tool].get('build_s', float('nan')):.2f} s",
              file=sys.stderr, flush=True)
    return cells


def agreement(problem: str, size: tuple, cells: dict) -> dict:
    """Accelerations of every tool at :func:`sample_states` against the reference (the closed form for the
    pendulum, :func:`lattice_accelerations` for the lattice), relative to its largest entry; the end states of
    the simulations against mechgen flow's."""
    n = _coordinates(problem, size)
    got = {t: np.array(c["accelerations"]) for t, c in cells.items() if "accelerations" in c}
    if problem == "pendulum":
        ref = np.array([closed_form_accelerations(x[:n], x[n:]) for x in sample_states(problem, n)])
        name = "closed form"
    else:
        rows, cols = size
        ref = np.array([lattice_accelerations(x[:n], rows, cols) for x in sample_states(problem, n)])
        name = "spring forces by numpy"
    errors = {t: float(np.abs(a - ref).max() / np.abs(ref).max()) for t, a in got.items()} if ref is not None else {}
    ends = {t: np.array(c["simulation"]["end"]) for t, c in cells.items() if "end" in c.get("simulation", {})}
    base = ends.get("mechgen flow")
    end_diff = {t: float(np.abs(e - base).max()) for t, e in ends.items()} if base is not None else {}
    return {"reference": name, "relative_error": errors, "within_1e-10": all(e <= 1e-10 for e in errors.values()),
            "end_state_difference": end_diff}


def run_multibody_benchmarks(out: Path, quick: bool = False, *, sizes=None, lattice=None, tools=None,
                             cap_s: float | None = None) -> dict:
    """Run the suite (module doc), write its reports into ``out`` and return the results. ``sizes``, ``lattice``
    (rows, cols; () for none), ``tools`` and ``cap_s`` override the defaults (QUICK_* when ``quick``); PyDy's
    tools are left out, with the reason, when pydy is not installed."""
    import importlib.util
    import tempfile

    from mechgen.bench.common import environment

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = tuple(sizes or (QUICK_SIZES if quick else SIZES))
    lattice = tuple(QUICK_LATTICE if quick else LATTICE) if lattice is None else tuple(lattice)
    tools = tuple(tools or TOOLS)
    missing = {t: "unavailable (pydy not installed)" for t in tools
               if t.startswith("PyDy") and importlib.util.find_spec("pydy") is None}
    missing.update({t: "unavailable (Cython not installed)" for t in tools
                    if "cython" in t and importlib.util.find_spec("Cython") is None})
    run_tools = tuple(t for t in tools if t not in missing)
    cap = cap_s if cap_s is not None else (60.0 if quick else CAP_S)
    env = environment(pydy=_version("pydy"), sympy=sp.__version__, cython=_version("Cython"))
    history: dict = {}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        problems = [("pendulum", (n,)) for n in sizes] + ([("lattice", lattice)] if lattice else [])
        for problem, size in problems:
            n = _coordinates(problem, size)
            cells = _size_cells(problem, size, run_tools, history if problem == "pendulum" else {}, cap, Path(tmp))
            cells.update({t: {"status": why} for t, why in missing.items()})
            rows.append({"problem": problem, "size": "x".join(map(str, size)), "n": n, "cells": cells,
                         "agreement": agreement(problem, size, cells)})
    env["loadavg_after"] = list(os.getloadavg())
    pend = {t: [(r["n"], r["cells"][t]["build_s"]) for r in rows
                if r["problem"] == "pendulum" and "build_s" in r["cells"].get(t, {})] for t in tools}
    data = {"tools": list(tools), "cap_s": cap, "sim": {"t_end": T_END, "rtol": RTOL, "atol": ATOL, "samples": SAMPLES,
                                                       "method": "DOP853 (scipy solve_ivp)"},
            "rows": rows, "growth_exponent": {t: growth_exponent(p) for t, p in pend.items()},
            "ratios": _ratios(rows), "environment": env}
    write_reports(out, data, pend)
    return data


def _version(package: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(package)
    except PackageNotFoundError:
        return None


def _ratios(rows: list[dict]) -> list[dict]:
    """Like for like, peer seconds / mechgen seconds (> 1: mechgen faster): the first build of mechgen's flow
    kernel against each PyDy tool (both give M and the forcing), and the right-hand side per call."""
    out = []
    for r in rows:
        ours = r["cells"].get("mechgen flow", {})
        for peer, cell in r["cells"].items():
            if not peer.startswith("PyDy"):
                continue
            for what, key in (("first build", "build_s"), ("rhs per call", "per_call_s")):
                a, b = ours.get(key), cell.get(key)
                if isinstance(a, dict):
                    a, b = a.get("rhs"), (b or {}).get("rhs")
                if a and b:
                    out.append({"peer": peer, "what": what, "ours_s": a, "peer_s": b, "ratio": b / a,
                                "condition": f"{r['problem']} {r['size']} ({r['n']} coordinates), mechgen builds "
                                             "'flow' only (M and h), PyDy M and the forcing"})
        ours, peer = r["cells"].get("mechgen flow numpy", {}), r["cells"].get(LAMBDIFY_OWN, {})
        a, b = (ours.get("per_call_s") or {}).get("rhs"), (peer.get("per_call_s") or {}).get("rhs")
        if a and b:
            out.append({"peer": LAMBDIFY_OWN, "what": "rhs per call, numpy backend", "ours_s": a, "peer_s": b,
                        "ratio": b / a, "condition": f"{r['problem']} {r['size']} ({r['n']} coordinates): the same "
                                                     "derived M and h, parameters free on both sides, numpy's solve"})
    return out


def _cell_values(r: dict, tool: str) -> dict:
    """One CSV row: a tool at one size."""
    c = r["cells"].get(tool, {})
    calls, sim = c.get("per_call_s", {}), c.get("simulation", {})
    return {"problem": r["problem"], "size": r["size"], "coordinates": r["n"], "tool": tool,
            "builds": _builds(tool),
            "status": c.get("status", ""), "build_s": c.get("build_s", ""),
            "rhs_us": calls["rhs"] * 1e6 if "rhs" in calls else "",
            "acceleration_us": calls["acceleration"] * 1e6 if "acceleration" in calls else "",
            "simulation_s": sim.get("wall_s", sim.get("skipped", "")), "simulation_nfev": sim.get("nfev", ""),
            "acceleration_relative_error": r["agreement"]["relative_error"].get(tool, ""),
            "end_state_difference": r["agreement"]["end_state_difference"].get(tool, "")}


def _builds(tool: str) -> str:
    """What the tool builds, in words."""
    if tool == LAMBDIFY_OWN:
        return "mechgen's derived M and h, lambdified"
    if not tool.startswith("mechgen"):
        return "M and forcing"
    return ("flow only" if "flow" in tool else "every kernel") + (", numpy backend" if "numpy" in tool else "")


def write_reports(out: Path, data: dict, pend: dict) -> list[Path]:
    """multibody_results.{csv,json,md}, multibody_ratios.json and multibody_build_time.png (build seconds
    against n, log-log, one line per tool; skipped without matplotlib)."""
    from mechgen.bench.common import loglog_plot, write_csv, write_json, write_text

    rows = [_cell_values(r, t) for r in data["rows"] for t in data["tools"]]
    files = [write_csv(out / "multibody_results.csv", rows), write_json(out / "multibody_results.json", data),
             write_json(out / "multibody_ratios.json", {"suite": "multibody", "ratios": data["ratios"]}),
             write_text(out / "multibody_results.md", markdown(data))]
    series = {t: [(n, s, f"{s:.2g}") for n, s in p] for t, p in pend.items() if p and "cached" not in t}
    png = out / "multibody_build_time.png"
    if series and loglog_plot(png, series, xlabel="links n", ylabel="first build (s)",
                              title="n-link pendulum: first build against n (fresh process, empty cache)"):
        files.append(png)
    return files


def _fmt(cell: dict, key: str, scale: float = 1.0, digits: str = ".3g") -> str:
    value = cell.get(key)
    if isinstance(value, (int, float)):
        return format(value * scale, digits)
    return cell.get("status", "") if cell.get("status", "ok") != "ok" else "-"


def markdown(data: dict) -> str:
    """The report: first build, cached build, per call, simulation and agreement, one row per size."""
    tools = data["tools"]
    env = data["environment"]
    head = "| problem | n | " + " | ".join(tools) + " |\n|---|---|" + "---|" * len(tools)
    parts = [f"# multibody: n-link pendulum and a planar lattice, mechgen against PyDy {env.get('pydy')}\n",
             f"Load average before {env['loadavg_before'][0]:.2f}, after {env['loadavg_after'][0]:.2f} "
             f"({env['cpu_count']} CPUs); cap {data['cap_s']:g} s per build. 'mechgen flow': the flow kernel only "
             "(M and h, what an explicit simulation needs: as PyDy's mass matrix and forcing); 'mechgen all': every "
             "kernel (mechgen.compile's default). PyDy has no cache: it derives and generates in every process.\n"]
    tables = (("First build, s (new process, empty cache; imports excluded; one run)", "build_s", 1.0, ".3g"),
              ("Right-hand side per call, us (median of 5 runs after a warm-up; mechgen: system.rhs)",
               "rhs", 1e6, ".3g"),
              ("mechgen system.acceleration per call, us", "acceleration", 1e6, ".3g"))
    for title, key, scale, digits in tables:
        parts += [f"## {title}\n", head]
        for r in data["rows"]:
            cells = [_fmt(r["cells"].get(t, {}).get("per_call_s", {}) if key != "build_s" else r["cells"].get(t, {}),
                          key, scale, digits) if _has(r["cells"].get(t, {}), key) or key == "build_s" else "-"
                     for t in tools]
            parts.append(f"| {r['problem']} {r['size']} | {r['n']} | " + " | ".join(cells) + " |")
        parts.append("")
    parts += [f"## Simulation: {data['sim']['method']}, t = 0 .. {data['sim']['t_end']:g} s, rtol "
              f"{data['sim']['rtol']:g}, atol {data['sim']['atol']:g}, {data['sim']['samples']} samples: wall s "
              "(evaluations), max |x_end - x_end(mechgen flow)|\n", head]
    for r in data["rows"]:
        cells = [_sim(r, t) for t in tools]
        parts.append(f"| {r['problem']} {r['size']} | {r['n']} | " + " | ".join(cells) + " |")
    parts += ["", "## mechgen's first build by stage, s (derive, lower, emit, build = C compile and load; other = "
              "cache and load bookkeeping; declare = calling the declared energies and specialising them, within "
              "derive; rewrite = Horner rewrites and cse = sympy's CSE, within lower, symbolic derivation only)\n",
              "| problem | n | tool | " + " | ".join(STAGES + INNER_STAGES) + " | other | total |",
              "|---" * (5 + len(STAGES + INNER_STAGES)) + "|"]
    for r in data["rows"]:
        for t in tools:
            stages = r["cells"].get(t, {}).get("stages_s")
            if stages and "cached" not in t:
                other = r["cells"][t]["build_s"] - sum(stages.get(k, 0.0) for k in STAGES)
                parts.append(f"| {r['problem']} {r['size']} | {r['n']} | {t} | " + " | ".join(
                    f"{stages[k]:.3g}" if k in stages else "-" for k in STAGES + INNER_STAGES)
                    + f" | {other:.3g} | {r['cells'][t]['build_s']:.3g} |")
    parts += ["", "## Agreement of the accelerations (3 random states, relative to the largest entry)\n",
              "| problem | n | reference | largest error | all within 1e-10 |", "|---|---|---|---|---|"]
    for r in data["rows"]:
        a = r["agreement"]
        worst = max(a["relative_error"].values(), default=float("nan"))
        parts.append(f"| {r['problem']} {r['size']} | {r['n']} | {a['reference']} | {worst:.1e} | "
                     f"{a['within_1e-10']} |")
    parts += ["", "## Growth exponent of the first build (least squares, log t on log n, n >= 8; reported, not "
              "asserted)\n", "| tool | exponent |", "|---|---|"]
    parts += [f"| {t} | {e:.2f} |" for t, e in data["growth_exponent"].items() if e is not None]
    return "\n".join(parts) + "\n"


def _has(cell: dict, key: str) -> bool:
    return key in cell.get("per_call_s", {}) or cell.get("status", "ok") != "ok"


def _sim(r: dict, tool: str) -> str:
    cell = r["cells"].get(tool, {})
    sim = cell.get("simulation")
    if sim is None:
        return cell.get("status", "-") if cell.get("status", "ok") != "ok" else "-"
    if "skipped" in sim:
        return sim["skipped"]
    diff = r["agreement"]["end_state_difference"].get(tool)
    text = f"{sim['wall_s']:.3g} ({sim['nfev']})"
    return text if diff is None else f"{text}, {diff:.1e}"
