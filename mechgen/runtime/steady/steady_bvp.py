"""Steady states of a continuum as a two-point boundary value problem, solved with the generated kernels.

The steady equations in s (mechgen.symbolic.steady) have the first-order form
y' = F(s, y), y = (u, u_s) (fields, then slopes), with the exact Jacobian dF/dy
from the generated tangent kernel (FieldSystem.steady_form). On the unit
interval sigma = s / L (L the model's length parameter, so that a branch may
vary it):

    dy/dsigma = L F(L sigma, y),   y_i(0) or y_i(1) = the boundary values,

one condition per essential boundary condition of the model (a field or its
slope at an end; 2n of them). The BVP's parameter vector is the kernels' free
parameters (so a branch may follow any of them: dF/dp by central differences);
L is one of them when the length parameter is free. Solved by shooting, multiple shooting or
collocation (mechgen.runtime.steady.bvp). The solution's jets at any points feed the
linearisation about it (FieldSystem.linear(jets=...)): modes and stability of
the steady state with the model's Galerkin discretisation.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.steady.bvp import BVP, BVPResult, collocate, multiple_shoot, shoot

METHODS = ("shooting", "multiple_shooting", "collocation")


@dataclass(frozen=True)
class SteadyBVP:
    """The boundary value problem of a continuum's steady state, and how to read its solutions.

    ``params`` names the BVP's parameters (the kernels' free parameters, in order);
    ``length_index`` is the length's among them (None: the length is fixed, ``length``).
    ``form``: 'lagrangian' (the unknowns are y = (u, u_s)) or 'hamiltonian' (y = (u, n),
    the stress resultants; the slopes are u_s = dH/dn from the rates kernel).
    """

    problem: BVP
    fields: tuple[str, ...]
    length: float
    system: object
    params: tuple[str, ...] = ()
    length_index: int | None = None
    start: np.ndarray | None = None
    form: str = "lagrangian"

    @property
    def n(self) -> int:
        """Number of fields."""
        return len(self.fields)

    def length_of(self, result: BVPResult) -> float:
        """The domain length L of a solution."""
        return float(result.p[self.length_index]) if self.length_index is not None else self.length

    def unknowns(self, result: BVPResult, s: np.ndarray) -> np.ndarray:
        """The BVP's own unknowns y at positions s (in [0, L]): (u, u_s) or (u, n), shape (2n, len(s))."""
        sigma = np.atleast_1d(np.asarray(s, float)) / self.length_of(result)
        return np.asarray(result(sigma), float).reshape(2 * self.n, -1)

    def _state(self, y: np.ndarray, s: np.ndarray, p) -> dict:
        m = y.shape[1]
        if self.form == "hamiltonian":
            return {"q": np.zeros((m, 0)), "v": np.zeros((m, 0)), "z": np.ascontiguousarray(y.T),
                    "t": np.reshape(s, (m, 1)), "p": np.asarray(p, float)}
        return {"q": np.ascontiguousarray(y[:self.n].T), "v": np.ascontiguousarray(y[self.n:].T),
                "z": np.zeros((m, 0)), "t": np.reshape(s, (m, 1)), "p": np.asarray(p, float)}

    def values(self, result: BVPResult, s: np.ndarray) -> np.ndarray:
        """(u, u_s) at positions s (in [0, L]) of a solution: shape (2n, len(s))."""
        s = np.atleast_1d(np.asarray(s, float))
        y = self.unknowns(result, s)
        if self.form == "hamiltonian":
            g = self.system.kernels["rates"].evaluate(self._state(y, s, result.p))["g"].reshape(len(s), -1)
            y = np.vstack([y[:self.n], g[:, :self.n].T])
        return y

    def jets(self, result: BVPResult, points: np.ndarray, jets) -> np.ndarray:
        """The solution's jets (field, order <= 1) at ``points`` (any shape): array points.shape + (len(jets),)."""
        y = self.values(result, np.ravel(points))
        cols = [y[self.fields.index(f) + self.n * k] for f, k in jets]
        return np.stack(cols, axis=-1).reshape(np.shape(points) + (len(jets),))

    def outputs(self, result: BVPResult, s: np.ndarray) -> dict[str, np.ndarray]:
        """The model's outputs along the solution at positions s (one batched kernel call)."""
        s = np.atleast_1d(np.asarray(s, float))
        state = self._state(self.unknowns(result, s), s, result.p)
        out = self.system.kernels["outputs"].evaluate(state)
        return {k: np.asarray(v).reshape(len(s)) for k, v in out.items() if not k.startswith("bc_")}


def _differences(f, sigma, y, p, cols=None) -> np.ndarray:
    """d f / d p_j (columns ``cols``, default all) by central differences, relative steps 1e-6: (2n, cols, m)."""
    p = np.asarray(p, float)
    cols = range(len(p)) if cols is None else [int(j) for j in cols]
    out = np.zeros((np.shape(y)[0], len(cols), np.shape(y)[1]))
    for k, j in enumerate(cols):
        step = 1e-6 * max(abs(p[j]), 1e-3)
        up, down = p.copy(), p.copy()
        up[j] += step
        down[j] -= step
        out[:, k] = (f(sigma, y, up) - f(sigma, y, down)) / (2 * step)
    return out


def _end_conditions(start, end, size: int, n_p: int) -> tuple:
    """g = y_i(0) - v (start) and y_i(1) - v (end) for the (index, value) pairs, and its Jacobians."""
    eye = np.eye(size)
    rows_a = np.vstack([eye[[i for i, _ in start]], np.zeros((len(end), size))])
    rows_b = np.vstack([np.zeros((len(start), size)), eye[[i for i, _ in end]]])

    def g(ya, yb, p):
        return np.array([ya[i] - v for i, v in start] + [yb[i] - v for i, v in end])

    return g, lambda ya, yb, p: rows_a, lambda ya, yb, p: rows_b, lambda ya, yb, p: np.zeros((size, n_p))


def _layout(field_system) -> tuple:
    """(fields, the free parameters' names, the length's index among them or None, the fixed length)."""
    names = tuple(field_system.metadata.params)
    length = field_system.field_meta.length
    return (field_system.field_meta.fields, names, names.index(length) if length in names else None,
            field_system.value(length))


def steady_bvp(field_system) -> SteadyBVP:
    """The BVP of ``field_system``'s steady state (kernels bvp_*); its parameters are the free ones."""
    st = field_system.steady_form()
    fields, names, length_index, fixed_length = _layout(field_system)
    n = len(fields)
    start, end = _lagrangian_conditions(field_system, fields, st.outputs(np.zeros(n), np.ones(n)))
    rhs = _LagrangianRates(st, n, length_index, fixed_length)
    g, g_ya, g_yb, g_p = _end_conditions(start, end, 2 * n, len(names))
    problem = BVP(rhs.f, rhs.f_y, g, g_ya, g_yb, (0.0, 1.0), 2 * n, n_p=len(names), f_p=rhs.f_p if names else None,
                  g_p=g_p if names else None, vectorized=True,
                  name=f"steady state of {field_system.metadata.model}")
    return SteadyBVP(problem, fields, fixed_length, st, names, length_index,
                     np.array(field_system.params, float))


def _lagrangian_conditions(field_system, fields, bc: dict) -> tuple[list, list]:
    """The (index into y = (u, u_s), value) pairs fixed at the start and at the end, from the model's
    constraints and the boundary values ``bc`` (the outputs bc_<field>_<order>_<end>); 2n of them."""
    n = len(fields)
    conditions = []
    for f, k, at in field_system.field_meta.constraints:
        if k > 1:
            raise InputError(f"steady BVP: condition on {f} of order {k}", key="boundary",
                             expected="values and slopes only (first-order densities)")
        conditions.append((fields.index(f) + n * int(k), at, bc[f"bc_{f}_{k}_{at}"]))
    if len(conditions) != 2 * n:
        raise InputError(f"the steady BVP of {field_system.metadata.model} has {len(conditions)} boundary "
                         f"conditions for {2 * n} first-order unknowns", key="boundary",
                         expected="n conditions per field pair: values or slopes at the two ends")
    start = [(i, v) for i, at, v in conditions if at == "start"]
    end = [(i, v) for i, at, v in conditions if at == "end"]
    return start, end


class _LagrangianRates:
    """dy/dsigma = f(sigma, y, p) = L F(L sigma, y), y = (u, u_s), F = (u_s, u_ss) with u_ss = -H^-1 r(u, u_s, 0)
    from the steady form ``st``'s kernels, and its Jacobians f_y (exact) and f_p; L = p[length_index] or the
    fixed length."""

    def __init__(self, st, n: int, length_index, fixed_length) -> None:
        self.n, self.length_index, self.fixed_length = n, length_index, fixed_length
        self.residual, self.tangent = st.kernels["residual"], st.kernels["tangent"]
        self.impl = None
        self.at_params = st  # the steady form at the parameters of the last single-state call

    def L_of(self, p):
        return p[self.length_index] if self.length_index is not None else self.fixed_length

    def accelerations(self, s_pts, y, p, with_jacobian: bool):
        """u_ss = -H^-1 r(u, u_s, 0) at every point (batched kernels), and optionally
        d u_ss / d y = -H^-1 [r_u, r_us] at that u_ss (prepared kernel calls, the last
        batches memoised: mechgen.runtime.steady.steady_kernels)."""
        if self.impl is None:
            from mechgen.runtime.steady.steady_kernels import SteadyAccelerations

            self.impl = SteadyAccelerations(self.residual, self.tangent, self.n)
        if not with_jacobian:
            return self.impl.accelerations(s_pts, y, p), None
        return self.impl.jacobian(s_pts, y, p)

    def use(self, p):
        """The steady form with the parameters p for the single-state kernels (shooting's hot path): the last
        one again when p has not changed, else a new system sharing its kernels and prepared calls."""
        if not np.array_equal(self.at_params.params, p):
            self.at_params = self.at_params.with_param_vector(p)
        return self.at_params

    def F(self, s_pts, y, p):
        if y.shape[1] == 1:  # one state (shooting): the prepared single-state kernels
            return self.use(p).rhs(float(np.ravel(s_pts)[0]), y[:, 0])[:, None]
        acc, _ = self.accelerations(s_pts, y, p, False)
        return np.vstack([y[self.n:], acc.T])

    def f(self, sigma, y, p):
        L = self.L_of(p)
        return L * self.F(L * np.asarray(sigma), y, p)

    def f_y(self, sigma, y, p):
        L, n = self.L_of(p), self.n
        if y.shape[1] == 1:
            return L * self.use(p).jacobian(L * float(np.ravel(sigma)[0]), y[:, 0])[:, :, None]
        _, jac = self.accelerations(L * np.asarray(sigma), y, p, True)
        J = np.zeros((2 * n, 2 * n, y.shape[1]))
        J[:n, n:] = np.eye(n)[:, :, None]
        J[n:] = np.transpose(jac, (1, 2, 0))
        return L * J

    def f_p(self, sigma, y, p, cols=None):
        """d f / d p (columns ``cols``, default all) for continuation's F_lam: f = L [u_s; u_ss],
        d u_ss / d p_j = -H^-1 d r / d p_j at the actual u_ss (central differences of the residual,
        relative steps 1e-6), plus [u_s; u_ss] for the length parameter."""
        p = np.asarray(p, float)
        cols = range(len(p)) if cols is None else [int(j) for j in cols]
        n, m = self.n, y.shape[1]
        out = np.zeros((2 * n, len(cols), m))
        if not len(cols):
            return out
        if m == 1:  # one state (shooting's variational equations): differences of f
            return _differences(self.f, sigma, y, p, cols)
        sigma = np.asarray(sigma, float)
        L = self.L_of(p)
        self.accelerations(L * sigma, y, p, False)  # the memoised batch (and the implementation)
        d_acc = self.impl.parameter_derivatives(lambda q: self.L_of(q) * sigma, y, p, cols)
        out[n:] = L * np.transpose(d_acc, (1, 2, 0))
        if self.length_index is not None and self.length_index in cols:
            out[:, list(cols).index(self.length_index)] += self.F(L * sigma, y, p)
        return out


def hamiltonian_bvp(field_system) -> SteadyBVP:
    """The BVP of the steady state in Hamiltonian (stress) form y = (u, n) (kernels hbvp_*).

    dy/dsigma = L rates(L sigma, y) with the exact Jacobian L rates_z; the
    boundary conditions fix the fields' values at the ends (n is free there).
    """
    kernels = {k.removeprefix("hbvp_"): v for k, v in field_system.kernels.items() if k.startswith("hbvp_")}
    if "rates" not in kernels:
        raise InputError(f"the kernels of {field_system.metadata.model} were built without the Hamiltonian "
                         "steady form", key="form", expected="a model with a complementary_density and the "
                         "hbvp_rates, hbvp_rates_tangent and hbvp_outputs kernels")
    fields, names, length_index, fixed_length = _layout(field_system)
    n = len(fields)
    params0 = np.array(field_system.params, float)
    reader = SteadyBVP(None, fields, fixed_length, SimpleNamespace(kernels=kernels), names, length_index, params0,
                       form="hamiltonian")
    bc = kernels["outputs"].evaluate(reader._state(np.ones((2 * n, 1)), np.zeros(1), params0))
    start, end = _hamiltonian_conditions(field_system, fields, bc)
    rhs = _HamiltonianRates(reader, kernels["rates"], kernels["rates_tangent"])
    g, g_ya, g_yb, g_p = _end_conditions(start, end, 2 * n, len(names))
    problem = BVP(rhs.f, rhs.f_y, g, g_ya, g_yb, (0.0, 1.0), 2 * n, n_p=len(names), f_p=rhs.f_p if names else None,
                  g_p=g_p if names else None, vectorized=True,
                  name=f"steady state of {field_system.metadata.model} (Hamiltonian form)")
    return replace(reader, problem=problem)


def _hamiltonian_conditions(field_system, fields, bc: dict) -> tuple[list, list]:
    """The (field index, value) pairs fixed at the start and at the end (field values only; every field's
    value at both ends) from the model's constraints and the boundary-value outputs ``bc``."""
    n = len(fields)
    start, end = [], []
    for f, k, at in field_system.field_meta.constraints:
        if k > 0:
            raise InputError(f"the Hamiltonian steady form fixes field values only, not {f} of order {k}",
                             key="form", expected="form = 'lagrangian' for conditions on slopes")
        (start if at == "start" else end).append((fields.index(f), float(np.ravel(bc[f"bc_{f}_{k}_{at}"])[0])))
    if len(start) + len(end) != 2 * n:
        raise InputError(f"the Hamiltonian steady BVP of {field_system.metadata.model} has {len(start) + len(end)} "
                         f"boundary conditions for {2 * n} unknowns", key="boundary",
                         expected="every field's value fixed at both ends")
    return start, end


class _HamiltonianRates:
    """dy/dsigma = f(sigma, y, p) = L rates(L sigma, y), y = (u, n), with f_y = L rates_z (the rates' tangent
    kernel) and f_p by central differences; ``reader`` (a SteadyBVP) lays out the kernels' state and L."""

    def __init__(self, reader: SteadyBVP, rates, tangent) -> None:
        self.reader, self.rates, self.tangent, self.n = reader, rates, tangent, reader.n

    def state(self, sigma, y, p):
        reader = self.reader
        L = p[reader.length_index] if reader.length_index is not None else reader.length
        return L, reader._state(np.asarray(y, float).reshape(2 * self.n, -1), L * np.atleast_1d(sigma), p)

    def f(self, sigma, y, p):
        L, st = self.state(sigma, y, p)
        return L * self.rates.evaluate(st)["g"].reshape(-1, 2 * self.n).T

    def f_y(self, sigma, y, p):
        L, st = self.state(sigma, y, p)
        n2 = 2 * self.n
        return L * np.transpose(self.tangent.evaluate(st)["g_z"].reshape(-1, n2, n2), (1, 2, 0))

    def f_p(self, sigma, y, p, cols=None):
        """d f / d p (columns ``cols``, default all) by central differences (relative steps 1e-6)."""
        return _differences(self.f, sigma, y, p, cols)


def stress_guess(bvp: SteadyBVP, sigma: np.ndarray, y: np.ndarray, *, iterations: int = 30) -> np.ndarray:
    """Stress resultants n for a guess of (u, u_s): dH/dn(u, n) = u_s solved per point by Gauss-Newton from n = u_s.

    A constrained law (dH/dn homogeneous of degree 0 in n: an inextensible string) keeps the
    starting scale along u_s (the minimum-norm step does not change it).
    """
    n = bvp.n
    L = bvp.length if bvp.length_index is None else bvp.start[bvp.length_index]
    s = L * np.asarray(sigma, float)
    target = y[n:].copy()
    z = np.vstack([y[:n], target])
    for _ in range(iterations):
        st = bvp._state(z, s, bvp.start)
        g = bvp.system.kernels["rates"].evaluate(st, check=False)["g"].reshape(len(s), 2 * n)[:, :n]
        J = bvp.system.kernels["rates_tangent"].evaluate(st, check=False)["g_z"].reshape(len(s), 2 * n, 2 * n)
        r = g - target.T
        if not np.all(np.isfinite(r)) or np.max(np.abs(r)) < 1e-12 * (1 + np.max(np.abs(target))):
            break
        step = np.stack([np.linalg.lstsq(Ji[:n, n:], ri, rcond=1e-10)[0] for Ji, ri in zip(J, r)], axis=1)
        z[n:] -= step
    return z


def initial_guess(bvp: SteadyBVP, sigma: np.ndarray, modes: dict | None = None) -> np.ndarray:
    """Boundary values joined linearly, plus sum_j a_j sin(j pi sigma) per field (``modes``: field -> [a_1, ...])."""
    n = bvp.n
    y0 = np.zeros(2 * n)
    y1 = np.zeros(2 * n)
    # boundary values: g = y - v at the constrained entries, so v = -g(0, 0)
    with np.errstate(all="ignore"):  # the first 2n rows: the end values (a held output may follow)
        values = -bvp.problem.g(np.zeros(2 * n), np.zeros(2 * n), bvp.start)[:2 * n]
    rows_a = bvp.problem.g_ya(y0, y1, bvp.start)[:2 * n]
    rows_b = bvp.problem.g_yb(y0, y1, bvp.start)[:2 * n]
    for row, value in zip(rows_a, values):
        if row.any():
            y0[np.argmax(row)] = value
    for row, value in zip(rows_b, values):
        if row.any():
            y1[np.argmax(row)] = value
    L = bvp.start[bvp.length_index] if bvp.length_index is not None else bvp.length
    y = np.zeros((2 * n, len(sigma)))
    for i in range(n):
        y[i] = y0[i] + (y1[i] - y0[i]) * sigma
        y[n + i] = (y1[i] - y0[i]) / L
    for field, amplitudes in (modes or {}).items():
        i = bvp.fields.index(field)
        for j, a in enumerate(amplitudes, 1):
            y[i] += a * np.sin(j * np.pi * sigma)
            y[n + i] += a * j * np.pi / L * np.cos(j * np.pi * sigma)
    return stress_guess(bvp, sigma, y) if bvp.form == "hamiltonian" else y


def solve_steady(bvp: SteadyBVP, *, method: str = "collocation", guess: BVPResult | None = None, modes=None,
                 mesh: int = 200, nodes: int = 20, tol: float = 1e-10) -> BVPResult:
    """A steady state by ``method`` from a previous solution or the guess of :func:`initial_guess`."""
    if method not in METHODS:
        raise InputError(f"unknown steady method {method!r}", key="method", expected=", ".join(METHODS))
    p = bvp.start
    sigma = np.linspace(0.0, 1.0, mesh + 1)
    values = guess(sigma) if guess is not None else initial_guess(bvp, sigma, modes)
    if method == "collocation":
        return collocate(bvp.problem, sigma, values, p=p, tol=tol)
    if method == "multiple_shooting":
        return multiple_shoot(bvp.problem, sigma, values, p=p, nodes=nodes, tol=tol)
    return shoot(bvp.problem, values[:, 0], p=p, tol=tol)


def holding(bvp: SteadyBVP, output: str, at: str, value: float, free: str) -> SteadyBVP:
    """The same steady state with one more condition, ``output`` at the ``at`` end = ``value``, and the
    parameter ``free`` solved for (e.g. the eyelet tension held while the string's length adjusts).

    The condition's Jacobians (in y at that end and in p) are central differences of the outputs kernel.
    """
    if free not in bvp.params:
        raise InputError(f"hold: {free!r} is not a free parameter of the compiled kernels", key="free",
                         expected=f"one of: {', '.join(bvp.params) or 'none'}")
    base = bvp.problem
    held = _HeldOutput(bvp, output, at, value)
    problem = replace(base, g=held.g, g_ya=held.g_ya, g_yb=held.g_yb, g_p=held.g_p, unknown=(bvp.params.index(free),),
                      name=f"{base.name} with {output} at the {at} = {value:g} ({free} free)")
    return replace(bvp, problem=problem)


class _HeldOutput:
    """The boundary conditions of ``bvp`` and one more, out(y(end), p) - value = 0 with out the model's output
    ``output`` at the ``at`` end ('start' or 'end'), and their Jacobians (central differences of out)."""

    def __init__(self, bvp: SteadyBVP, output: str, at: str, value: float) -> None:
        self.bvp, self.base, self.output, self.at, self.value = bvp, bvp.problem, output, at, value
        self.sigma_end = 0.0 if at == "start" else 1.0
        self.last: dict = {}

    def out(self, y, p) -> float:
        bvp = self.bvp
        L = bvp.length_of(SimpleNamespace(p=p))
        state = bvp._state(np.asarray(y, float).reshape(-1, 1), np.array([L * self.sigma_end]), p)
        values = bvp.system.kernels["outputs"].evaluate(state, check=False)  # NaN fails Newton's own checks
        if self.output not in values:
            raise InputError(f"hold: the model has no output {self.output!r}", key="hold",
                             expected=", ".join(k for k in values if not k.startswith("bc_")))
        return float(np.ravel(values[self.output])[0])

    def d_out(self, y, p):
        """(d out/dy, d out/dp) by central differences; the last pair is kept (g_ya, g_yb, g_p ask alike)."""
        y, p = np.asarray(y, float), np.asarray(p, float)
        key = (y.tobytes(), p.tobytes())
        if key in self.last:
            return self.last[key]
        self.last.clear()
        dy, dp = np.zeros(len(y)), np.zeros(len(p))
        for vec, grad in ((y, dy), (p, dp)):
            for j in range(len(vec)):
                step = 1e-7 * max(abs(vec[j]), 1.0)
                up, down = vec.copy(), vec.copy()
                up[j] += step
                down[j] -= step
                args = (up, p) if vec is y else (y, up)
                back = (down, p) if vec is y else (y, down)
                grad[j] = (self.out(*args) - self.out(*back)) / (2 * step)
        self.last[key] = (dy, dp)
        return dy, dp

    def end_y(self, ya, yb):
        return ya if self.at == "start" else yb

    def g(self, ya, yb, p):
        return np.append(self.base.g(ya, yb, p), self.out(self.end_y(ya, yb), p) - self.value)

    def g_ya(self, ya, yb, p):
        row = self.d_out(ya, p)[0] if self.at == "start" else np.zeros(len(ya))
        return np.vstack([self.base.g_ya(ya, yb, p), row])

    def g_yb(self, ya, yb, p):
        row = self.d_out(yb, p)[0] if self.at == "end" else np.zeros(len(yb))
        return np.vstack([self.base.g_yb(ya, yb, p), row])

    def g_p(self, ya, yb, p):
        return np.vstack([self.base.g_p(ya, yb, p), self.d_out(self.end_y(ya, yb), p)[1]])
