"""SUNDIALS' CVODES through CasADi: a compiled stiff integrator for a system's first-order form.

The first-order form of a lumped system (mechgen.runtime.core.system), x = (q, v, z):

    dx/dt = f(t, x; p) = (v,  a,  g),   a = -M^-1 r(q, v, 0, z, t),  M = dr/da,  g = rates(q, v, z, t)

is built as one CasADi expression from the system's own CasADi kernels (``residual``, ``tangent``,
``rates``: the same Kernel IR as the C and numpy backends), with M^-1 r a linear-solve node, not an
inverse. CVODES integrates it with variable-order (1 to 5) BDF and Newton iterations on the exact
Jacobian df/dx that CasADi differentiates from it; every step, Newton iteration and Jacobian
evaluation runs in compiled code, so a stiff run costs what its steps cost and not the Python around them.

The run is cut into at least :data:`CHUNKS` equal pieces (one integrator, reused: time enters as
t0 + tau with t0 a parameter), so that the work budget's wall time and the progress bar are checked
between pieces; ``max_steps`` bounds CVODES's steps within each piece (its ``max_num_steps``) and the
steps of the whole run. A failure (too much work, a step below round-off, repeated Newton or
error-test failures, a non-finite rate) ends the run with a ConvergenceError naming the CVODES flag,
the part of t it happened in (the failed piece re-run in :data:`LOCATE` parts: to 1/400 of t_end) and
what diagnose.explain_state finds at that part's start (the fastest rate, a non-finite kernel output).

Tolerances: CVODES's local error test ||e_i / (rtol |x_i| + atol)||_rms <= 1, the same form as scipy's.
"""
from __future__ import annotations

import re

import numpy as np

from mechgen.errors import ConvergenceError, KernelError
from mechgen.runtime.core.budget import Budget, BudgetExceeded, Progress
from mechgen.runtime.core.integrate import Trajectory

#: the sample grid is integrated in this many pieces (budget and progress are checked between them)
CHUNKS = 20
#: a failed piece is re-run in this many parts to say where it failed
LOCATE = 20
#: the method's name in scenes and in integrate_cvodes' results
NAME = "cvodes"


def cvodes_problem(system) -> str | None:
    """Why CVODES cannot run this system (None when it can): it needs the CasADi kernels of a lumped model."""
    try:
        import casadi  # noqa: F401
    except ImportError:  # pragma: no cover - casadi is a dependency
        return "CasADi is not installed"
    if getattr(system, "backend", None) != "casadi":
        return (f"method 'cvodes' runs on the CasADi kernels, and this system was built with the "
                f"{getattr(system, 'backend', '?')} backend: set backend = \"casadi\" in the scene (or "
                "mechgen.compile(..., backend=\"casadi\"))")
    if system.metadata.kind != "lumped":
        return f"method 'cvodes' integrates lumped models; this one is a {system.metadata.kind} model"
    for name in ("residual", "tangent") + (("rates",) if system.m else ()):
        if name not in system.kernels:
            return f"the system has no '{name}' kernel"
    return None


def first_order_expression(system, integrals: int = 0):
    """(x, t, p, f): CasADi MX symbols of the state, time and free parameters and the expression f(t, x; p)
    of the module doc, from the system's CasADi kernels. ``integrals`` = 3: the state also carries the energy
    balance's integrals (mechgen.runtime.integration.augmented), their rates the ``energy_rates`` kernel's powers."""
    import casadi as ca

    n, m = int(system.n), int(system.m)
    x, t, p = ca.MX.sym("x", 2 * n + m + integrals), ca.MX.sym("t"), ca.MX.sym("p", len(system.params))
    q, v, z = x[:n], x[n:2 * n], x[2 * n:2 * n + m]
    a0 = ca.MX.zeros(n)

    def call(kernel: str, **ports):
        fn = system.kernels[kernel].casadi_function(system.sizes(kernel))
        names = fn.name_in()
        out = fn(*[ports[name] for name in names])
        return dict(zip(fn.name_out(), out if isinstance(out, (list, tuple)) else [out]))

    state = {"q": q, "v": v, "a": a0, "z": z, "t": t, "p": p}
    r0 = call("residual", **state)["r"]
    M = ca.reshape(call("tangent", **state)["r_a"], n, n).T  # the kernels' matrices are row-major
    parts = [v, -ca.solve(M, r0)]
    if m:
        parts.append(call("rates", **{k: state[k] for k in ("q", "v", "z", "t", "p")})["g"])
    if integrals:  # g = (dz/dt, Q.v, v.dR/dv, -dL/dt): the powers follow the internal rates
        parts.append(call("energy_rates", **{k: state[k] for k in ("q", "v", "z", "t", "p")})["g"][m:])
    return x, t, p, ca.vertcat(*parts)


def _flag(message: str) -> str:
    found = re.search(r'"(CV_[A-Z_]+)"', message)
    return found.group(1) if found else message.strip().splitlines()[-1][:200]


def integrate_cvodes(system, x0, t_end: float, *, t_eval, rtol: float = 1e-8, atol: float = 1e-10,
                     budget: Budget | None = None, progress: bool = False, desc: str = "simulate",
                     explain=None, integrals: int = 0) -> Trajectory:
    """Integrate the system's dx/dt = f(t, x) from 0 to t_end with CVODES; states at the uniform ``t_eval``
    (from 0 to t_end; module doc for pieces, budget and failures); ``integrals`` = 3: x0 and the states carry
    the energy balance's integrals after (q, v, z) (first_order_expression)."""
    t_eval = np.asarray(t_eval, float)
    if t_eval.size < 2 or t_eval[0] != 0.0 or not np.allclose(np.diff(t_eval), t_eval[1] - t_eval[0], rtol=1e-9):
        raise ValueError("integrate_cvodes samples a uniform grid from t = 0")
    run = _CvodesRun(system, t_end, (rtol, atol), budget, explain, integrals)
    sub = max(1, -(-CHUNKS // (t_eval.size - 1)))  # grid points per sample interval: at least CHUNKS pieces
    h = float(t_eval[1] - t_eval[0]) / sub
    with Progress(t_end, desc=desc, unit="t", enabled=progress) as bar:
        grid = run.march(np.asarray(x0, float).copy(), h, (t_eval.size - 1) * sub, bar)
    rows = np.array(grid)[::sub]
    return Trajectory(t_eval.copy(), rows, nfev=run.nfev, njev=run.njev, success=True,
                      message="CVODES reached the end of the integration interval.", steps=run.steps)


class _CvodesRun:
    """One run of :func:`integrate_cvodes`: the CasADi problem (time as t0 + tau, t0 a parameter), the CVODES
    integrators built on use per (outputs, step), the statistics so far (steps, nfev, njev) and what a failure
    reports (``budget``, ``explain``)."""

    def __init__(self, system, t_end: float, tolerances: tuple, budget: Budget | None, explain, integrals: int):
        import casadi as ca

        rtol, atol = tolerances
        x_sym, t_sym, p_sym, f = first_order_expression(system, integrals)
        t0, tau = ca.MX.sym("t0"), ca.MX.sym("tau")
        self.dae = {"x": x_sym, "t": tau, "p": ca.vertcat(p_sym, t0), "ode": ca.substitute(f, t_sym, t0 + tau)}
        self.limit = budget.limit if budget is not None and budget.limit is not None else 100_000
        self.options = {"abstol": float(atol), "reltol": float(rtol), "max_num_steps": int(self.limit),
                        "disable_internal_warnings": True, "show_eval_warnings": False, "newton_scheme": "direct",
                        "linear_solver": "csparse"}
        self.integrators: dict = {}
        self.params = np.asarray(system.params, float)
        self.t_end, self.budget, self.explain = t_end, budget, explain
        self.steps = self.nfev = self.njev = 0

    def integrator(self, k: int, step: float):
        """CVODES from tau = 0 with outputs at step, 2 step, ... k step (built once per (k, step))."""
        if (k, step) not in self.integrators:
            import casadi as ca

            self.integrators[k, step] = ca.integrator("cvodes", "cvodes", self.dae, 0.0,
                                                      [step * (i + 1) for i in range(k)], self.options)
        return self.integrators[k, step]

    def advance(self, x, start: float, k: int, step: float):
        """States at start + step, ..., start + k step (rows), and CVODES's statistics."""
        F = self.integrator(k, step)
        out = F(x0=x, p=np.concatenate([self.params, [start]]))
        return np.asarray(out["xf"], float).reshape(x.size, k).T, F.stats()

    def march(self, x, h: float, intervals: int, bar) -> list:
        """The states at 0, h, ..., intervals h from x, in pieces of at least intervals / CHUNKS steps h; the
        budget is spent and the bar moved after every piece."""
        per = max(1, -(-intervals // CHUNKS))  # grid intervals per piece
        grid, done, t_end = [x.copy()], 0, float(self.t_end)
        while done < intervals:
            k = min(per, intervals - done)
            start = done * h
            try:
                block, stats = self.advance(x, start, k, h)
            except RuntimeError as exc:
                raise self.failure(exc, x, start, k * h) from exc
            self.steps += int(stats.get("nsteps", 0))
            self.nfev += int(stats.get("nfevals", 0))
            self.njev += int(stats.get("nlinsetups", 0))
            if not np.all(np.isfinite(block)):
                raise KernelError(f"{NAME}: state became NaN/Inf between t = {start:.6g} and {start + k * h:.6g} "
                                  f"of t_end = {t_end:.6g}")
            grid.extend(block)
            x = block[-1].copy()
            done += k
            t_now = done * h
            if self.budget is not None:
                self.budget.spend(int(stats.get("nsteps", 0)), lambda: f"t = {t_now:.6g} of t_end = {t_end:.6g}")
            bar.to(t_now)
        return grid

    def failure(self, exc: RuntimeError, x, start: float, span: float) -> Exception:
        """The error of a piece that failed: located to one of LOCATE parts of it, diagnosed at that part's start."""
        flag = _flag(str(exc))
        step, t_a = span / LOCATE, start
        for _ in range(LOCATE):
            try:
                x = self.advance(x, t_a, 1, step)[0][-1]
            except RuntimeError:
                break
            t_a += step
        where = f"between t = {t_a:.6g} and {t_a + step:.6g} of t_end = {float(self.t_end):.6g}"
        if flag == "CV_TOO_MUCH_WORK":
            budget = self.budget
            return BudgetExceeded(f"{NAME} steps: more than max_steps = {self.limit:,} steps within {span:.3g} of t",
                                  key=budget.key if budget is not None else "max_steps", reached=where)
        why = self.explain(t_a, x) if self.explain is not None and np.all(np.isfinite(x)) else ""
        return ConvergenceError(f"{NAME} failed {where} ({flag})" + (f"; {why}" if why else ""))
