"""Two-point boundary-value problems: single shooting, multiple shooting, collocation.

The problem (:class:`BVP`)::

    y' = f(s, y, p),  s in [a, b],  y in R^n,  p in R^{n_p},
    g(y(a), y(b), p) = 0,           n + k residuals,

where the k entries ``p[unknown]`` are solved for (an unknown length, tension or
eigenvalue) and the other entries of ``p`` are fixed. The Jacobians f_y = df/dy (n, n),
f_p = df/dp (n, n_p), g_ya, g_yb = dg/dy(a), dg/dy(b) (n + k, n) and g_p (n + k, n_p)
are given (mechgen generates them); nothing here differentiates numerically.

* :func:`shoot` - single shooting. Unknowns x = (y(a), p_u); y is integrated
  (``solve_ivp``, DOP853 or Radau) together with its variational equations::

      Phi' = f_y Phi,  Phi(a) = I;      Psi' = f_y Psi + f_p[:, unknown],  Psi(a) = 0,

  so the Newton matrix of R(x) = g(y(a), y(b), p) is exact to the integrator's tolerance:
  dR/dx = [g_ya + g_yb Phi(b), g_yb Psi(b) + g_p[:, unknown]].
* :func:`multiple_shoot` - nodes a = s_0 < ... < s_K = b, unknowns x = (Y_0, ..., Y_K, p_u)::

      R = (phi_0(Y_0) - Y_1, ..., phi_{K-1}(Y_{K-1}) - Y_K, g(Y_0, Y_K, p)),

  phi_j the flow from s_j to s_{j+1} (with its variational equations on each interval);
  the Jacobian is block-bidiagonal plus the boundary rows, factored by SuperLU.
* :func:`collocate` - ``scipy.integrate.solve_bvp`` (3-stage Lobatto IIIA, 4th order,
  adaptive mesh) fed with the analytic ``fun_jac`` and ``bc_jac``.
* :class:`~mechgen.runtime.steady.collocation.DiscreteBVP` (which builds on this module) -
  the same residuals as a square system F(u, lam) = 0 with a sparse Jacobian, lam =
  p[lam_index] (for :mod:`mechgen.runtime.steady.continuation`): the multiple-shooting residual
  above, or collocation on a fixed mesh (Hermite-Simpson, 4th order at the nodes, or
  s-stage Gauss-Legendre, order 2s).

``f_p`` may take a keyword ``cols`` (parameter indices) and return only those columns,
(n, len(cols)[, m]); the discretisations then ask for the continuation parameter and the
unknown parameters alone.

Newton (shooting and multiple shooting) uses a backtracking line search on ||R||_2; a
trajectory that overflows (|y| > ``blowup``, NaN/Inf) or stops (``solve_ivp`` failure)
counts as an infinite residual, so a divergent shot shortens the step instead of hanging;
a whole solve may spend at most ``max_nfev`` right-hand side evaluations. Failure raises
:class:`ConvergenceError` naming the method, the iterations and
the residual; inconsistent shapes raise :class:`InputError`.
"""
from __future__ import annotations

import inspect
import warnings
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.core.options import Options

__all__ = ["BVP", "BVPResult", "IVPOptions", "IVP_METHODS", "check_jacobians", "collocate", "multiple_shoot",
           "on_unit_interval", "shoot"]

IVP_METHODS = ("DOP853", "Radau", "RK45", "BDF", "LSODA")
_IMPLICIT = ("Radau", "BDF", "LSODA")


# ----------------------------------------------------------------------------- problem
@dataclass(frozen=True)
class BVP:
    """y' = f(s, y, p) on ``interval``, g(y(a), y(b), p) = 0, ``p[unknown]`` solved for.

    Args:
        f, f_y: right-hand side (n,) and its Jacobian (n, n). With ``vectorized`` they take
            s of shape (m,) and y of shape (n, m) and return (n, m) and (n, n, m).
        g, g_ya, g_yb: boundary residual (n + k,) and its Jacobians (n + k, n).
        interval: (a, b) with a < b.
        n: state dimension.
        n_p: number of parameters (fixed and unknown together).
        f_p, g_p: Jacobians in p, (n, n_p) [(n, n_p, m) vectorized] and (n + k, n_p);
            required when n_p > 0 (pass zeros where there is no dependence).
        unknown: indices into p that are solved for (k of them).
        vectorized: whether f, f_y and f_p evaluate many points at once.
        name: used in error messages.
    """

    f: Callable
    f_y: Callable
    g: Callable
    g_ya: Callable
    g_yb: Callable
    interval: tuple
    n: int
    n_p: int = 0
    f_p: Callable | None = None
    g_p: Callable | None = None
    unknown: tuple = ()
    vectorized: bool = False
    name: str = "bvp"

    def __post_init__(self):
        if not (isinstance(self.n, (int, np.integer)) and self.n >= 1):
            raise InputError(f"{self.name}: the state dimension n is {self.n!r}", key="n",
                             expected="a positive integer")
        if not (isinstance(self.n_p, (int, np.integer)) and self.n_p >= 0):
            raise InputError(f"{self.name}: the parameter count n_p is {self.n_p!r}", key="n_p",
                             expected="a non-negative integer")
        try:
            a, b = (float(v) for v in self.interval)
        except (TypeError, ValueError):
            raise InputError(f"{self.name}: the interval is {self.interval!r}", key="interval",
                             expected="a pair (a, b) of numbers") from None
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise InputError(f"{self.name}: the interval ({a}, {b}) is empty or not finite", key="interval",
                             expected="finite a < b")
        object.__setattr__(self, "interval", (a, b))
        unknown = tuple(int(i) for i in self.unknown)
        if len(set(unknown)) != len(unknown) or any(not 0 <= i < self.n_p for i in unknown):
            raise InputError(f"{self.name}: unknown parameter indices {list(unknown)} with n_p = {self.n_p}",
                             key="unknown", expected=f"distinct indices in 0..{self.n_p - 1}")
        object.__setattr__(self, "unknown", unknown)
        try:
            takes = self.f_p is not None and "cols" in inspect.signature(self.f_p).parameters
        except (TypeError, ValueError):
            takes = False
        object.__setattr__(self, "_f_p_takes_cols", takes)
        for name in ("f", "f_y", "g", "g_ya", "g_yb"):
            if not callable(getattr(self, name)):
                raise InputError(f"{self.name}: {name} is not callable", key=name, expected="a function")
        if self.n_p > 0:
            for name in ("f_p", "g_p"):
                if not callable(getattr(self, name)):
                    raise InputError(f"{self.name}: {name} is required when the problem has parameters (n_p = "
                                     f"{self.n_p})", key=name, expected="a function (zeros where there is no "
                                     "dependence)")

    @property
    def k(self) -> int:
        """Number of unknown parameters."""
        return len(self.unknown)

    # point-wise and vectorised evaluations with shape checks ---------------------------
    def _call(self, name, *args):
        with np.errstate(all="ignore"):
            return np.asarray(getattr(self, name)(*args), dtype=float)

    def f1(self, s, y, p):
        """f at one point, shape (n,)."""
        if self.vectorized:
            return self._call("f", np.array([s]), y[:, None], p)[:, 0]
        return self._call("f", s, y, p)

    def f_y1(self, s, y, p):
        if self.vectorized:
            return self._call("f_y", np.array([s]), y[:, None], p)[:, :, 0]
        return self._call("f_y", s, y, p)

    def f_p1(self, s, y, p):
        if self.n_p == 0:
            return np.zeros((self.n, 0))
        if self.vectorized:
            return self._call("f_p", np.array([s]), y[:, None], p)[:, :, 0]
        return self._call("f_p", s, y, p)

    def fv(self, s, Y, p):
        """f at many points: s (m,), Y (n, m) -> (n, m)."""
        if self.vectorized:
            return self._call("f", s, Y, p).reshape(self.n, len(s))
        return np.stack([self._call("f", s[j], Y[:, j], p) for j in range(len(s))], axis=1)

    def f_yv(self, s, Y, p):
        if self.vectorized:
            return self._call("f_y", s, Y, p).reshape(self.n, self.n, len(s))
        return np.stack([self._call("f_y", s[j], Y[:, j], p) for j in range(len(s))], axis=2)

    def f_pv(self, s, Y, p, cols=None):
        """d f / d p at many points: (n, n_p, m), or (n, len(cols), m) for the columns ``cols`` (an
        f_p that takes a keyword ``cols`` computes only those)."""
        if self.n_p == 0 or (cols is not None and not len(cols)):
            return np.zeros((self.n, 0 if cols is None else len(cols), len(s)))
        if cols is not None and self._f_p_takes_cols:
            with np.errstate(all="ignore"):
                out = np.asarray(self.f_p(s, Y, p, cols=list(cols)), dtype=float)
            return out.reshape(self.n, len(cols), len(s))
        if self.vectorized:
            out = self._call("f_p", s, Y, p).reshape(self.n, self.n_p, len(s))
        else:
            out = np.stack([self._call("f_p", s[j], Y[:, j], p) for j in range(len(s))], axis=2)
        return out if cols is None else out[:, list(cols)]


    def bc(self, ya, yb, p):
        return self._call("g", ya, yb, p)

    def bc_jac(self, ya, yb, p):
        """(g_ya, g_yb, g_p)."""
        gp = self._call("g_p", ya, yb, p) if self.n_p else np.zeros((self.n + self.k, 0))
        return self._call("g_ya", ya, yb, p), self._call("g_yb", ya, yb, p), gp

    def check(self, y, p) -> None:
        """Evaluate every function once at (a, y, p) and raise InputError on a wrong shape."""
        n, m, npar = self.n, self.n + self.k, self.n_p
        y = np.asarray(y, float)
        a = self.interval[0]
        if self.vectorized:
            Y, s = np.stack([y, y], axis=1), np.array([a, a])
            checks = [("f", (n, 2), (s, Y, p)), ("f_y", (n, n, 2), (s, Y, p))]
            if npar:
                checks.append(("f_p", (n, npar, 2), (s, Y, p)))
        else:
            checks = [("f", (n,), (a, y, p)), ("f_y", (n, n), (a, y, p))]
            if npar:
                checks.append(("f_p", (n, npar), (a, y, p)))
        checks += [("g", (m,), (y, y, p)), ("g_ya", (m, n), (y, y, p)), ("g_yb", (m, n), (y, y, p))]
        if npar:
            checks.append(("g_p", (m, npar), (y, y, p)))
        for name, shape, args in checks:
            try:
                out = self._call(name, *args)
            except (ValueError, TypeError, IndexError) as exc:
                raise InputError(f"{self.name}: calling {name} failed ({exc})", key=name,
                                 expected=f"a function returning an array of shape {shape}") from exc
            if out.shape != shape:
                hint = " (n + number of unknown parameters boundary conditions)" if name == "g" else ""
                raise InputError(f"{self.name}: {name} returned shape {out.shape}{hint}", key=name,
                                 expected=f"shape {shape}")


def full_parameters(problem: BVP, p) -> np.ndarray:
    """A copy of the parameter vector p as ``(n_p,)`` finite floats (empty when n_p = 0); InputError otherwise."""
    if problem.n_p == 0:
        if p is not None and np.size(p) != 0:
            raise InputError(f"{problem.name}: parameters given but the problem has n_p = 0", key="p",
                             expected="no parameters")
        return np.zeros(0)
    if p is None:
        raise InputError(f"{problem.name}: the parameter vector p is missing", key="p",
                         expected=f"{problem.n_p} values (initial guesses for the unknown ones)")
    p = np.asarray(p, float).ravel()
    if p.shape != (problem.n_p,) or not np.all(np.isfinite(p)):
        raise InputError(f"{problem.name}: p has {p.size} entries or is not finite", key="p",
                         expected=f"{problem.n_p} finite values")
    return p.copy()


def _state(problem: BVP, y, what: str) -> np.ndarray:
    y = np.asarray(y, float)
    if y.shape != (problem.n,) or not np.all(np.isfinite(y)):
        raise InputError(f"{problem.name}: {what} has shape {y.shape} or is not finite", key=what,
                         expected=f"{problem.n} finite values")
    return y


# ----------------------------------------------------------------------------- result
@dataclass(frozen=True)
class BVPResult:
    """Solution of a BVP: mesh ``s`` (m,), values ``y`` (n, m), full parameter vector ``p``.

    ``residual_norm`` is the final Newton residual (boundary conditions for shooting,
    continuity plus boundary conditions for multiple shooting, the largest relative
    collocation residual or boundary residual for collocation); ``iterations`` counts
    Newton iterations; ``sol(s)`` (or calling the result) is the dense output, (n,) for a
    scalar s and (n, len(s)) for an array.
    """

    s: np.ndarray
    y: np.ndarray
    p: np.ndarray
    residual_norm: float
    iterations: int
    method: str
    sol: Callable = field(repr=False)

    def __call__(self, s):
        return self.sol(s)


class _PiecewiseDense:
    """Dense output glued from the intervals [s_j, s_{j+1}] of multiple shooting."""

    def __init__(self, nodes, pieces, n):
        self.nodes, self.pieces, self.n = np.asarray(nodes), pieces, n

    def __call__(self, s):
        s_arr = np.atleast_1d(np.asarray(s, float))
        idx = np.clip(np.searchsorted(self.nodes, s_arr, side="right") - 1, 0, len(self.pieces) - 1)
        out = np.empty((self.n, s_arr.size))
        for j in np.unique(idx):
            mask = idx == j
            out[:, mask] = np.asarray(self.pieces[j](s_arr[mask])).reshape(-1, mask.sum())[: self.n]
        return out[:, 0] if np.ndim(s) == 0 else out


# ----------------------------------------------------------------------------- integration
class IVPFailure(Exception):
    """The residual cannot be evaluated (an initial value problem blew up or stopped)."""


class BudgetSpent(Exception):
    """The solve used up its right-hand side evaluations (``max_nfev``)."""


class _Budget:
    """Right-hand side evaluations used and allowed, shared by every integration of a solve."""

    def __init__(self, limit: int):
        self.limit, self.used = int(limit), 0


def _flow(problem: BVP, span, y0, p, cols, opts: dict, dense=False):
    """Integrate y from s0 to s1 (``span``), with the variational equations for the columns ``cols``
    (None: none; else a list of parameter indices for Psi), as the options ``opts`` of :func:`ivp_options`
    say. Returns (y1, Phi, Psi, sol)."""
    system = _FlowRhs(problem, p, cols, opts["budget"], opts["blowup"])
    kwargs = {"jac": system.jac} if opts["method"] in _IMPLICIT else {}
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            from scipy.integrate import solve_ivp  # loaded on use (startup)

            sol = solve_ivp(system.rhs, span, system.start(y0), method=opts["method"], rtol=opts["rtol"],
                            atol=opts["atol"], dense_output=dense, **kwargs)
    except (ValueError, np.linalg.LinAlgError, ZeroDivisionError, OverflowError) as exc:
        raise IVPFailure(f"the integrator failed ({exc})") from exc
    if sol.status != 0:
        raise IVPFailure(f"the integrator stopped at s = {sol.t[-1]:.6g} ({sol.message})")
    z1 = sol.y[:, -1]
    if not np.all(np.isfinite(z1)):
        raise IVPFailure("the trajectory is not finite")
    return (*system.end(z1), sol)


def _point_functions(problem: BVP, p):
    """(f, f_y, f_p) at one point (s, y) with the parameters p: shapes (n,), (n, n), (n, n_p)."""
    f, f_y, f_p = problem.f, problem.f_y, problem.f_p
    if problem.vectorized:
        def f1(s, y):
            return np.asarray(f(np.array([s]), y[:, None], p), float)[:, 0]

        def fy1(s, y):
            return np.asarray(f_y(np.array([s]), y[:, None], p), float)[:, :, 0]

        def fp1(s, y):
            return np.asarray(f_p(np.array([s]), y[:, None], p), float)[:, :, 0]
    else:
        def f1(s, y):
            return np.asarray(f(s, y, p), float)

        def fy1(s, y):
            return np.asarray(f_y(s, y, p), float)

        def fp1(s, y):
            return np.asarray(f_p(s, y, p), float)
    return f1, fy1, fp1


class _FlowRhs:
    """The right-hand side of y' = f(s, y, p) for solve_ivp, with the variational equations
    Phi' = f_y Phi, Psi' = f_y Psi + f_p[:, cols] when ``cols`` is not None (z = (y, Phi, Psi) column-major,
    Phi(s0) = I, Psi(s0) = 0); every evaluation counts against ``budget``, and a state beyond ``blowup`` or a
    value that is not finite raises IVPFailure."""

    def __init__(self, problem: BVP, p, cols, budget, blowup) -> None:
        self.n = n = problem.n
        self.var = cols is not None
        self.ncol = 1 + (n + len(cols) if self.var else 0)
        self.cols = list(cols) if self.var else None
        self.f1, self.fy1, self.fp1 = _point_functions(problem, p)
        self.budget, self.blowup = budget, blowup

    def guard(self, out):
        budget = self.budget
        budget.used += 1
        if budget.used > budget.limit:
            raise BudgetSpent()
        if not np.isfinite(out).all():
            raise IVPFailure("the right-hand side overflowed (NaN or Inf)")
        return out

    def start(self, y0):
        """z(s0)."""
        if not self.var:
            return np.asarray(y0, float)
        n = self.n
        Z0 = np.zeros((n, self.ncol))
        Z0[:, 0] = y0
        Z0[:, 1:1 + n] = np.eye(n)
        return Z0.ravel(order="F")

    def rhs(self, s, z):
        if not self.var:
            if np.abs(z).max() > self.blowup:
                raise IVPFailure("the trajectory overflowed (|y| beyond %.0e)" % self.blowup)
            return self.guard(self.f1(s, z))
        n = self.n
        Z = z.reshape(n, self.ncol, order="F")
        y = Z[:, 0]
        if np.abs(y).max() > self.blowup:
            raise IVPFailure("the trajectory overflowed (|y| beyond %.0e)" % self.blowup)
        fy = self.fy1(s, y)
        out = np.empty_like(Z)
        out[:, 0] = self.f1(s, y)
        out[:, 1:] = fy @ Z[:, 1:]
        if self.cols:
            out[:, 1 + n:] += self.fp1(s, y)[:, self.cols]
        return self.guard(out.ravel(order="F"))

    def jac(self, s, z):
        if not self.var:
            return self.fy1(s, z)
        # block-diagonal, without the second derivatives of f: enough for Newton inside Radau/BDF
        n, ncol = self.n, self.ncol
        fy = self.fy1(s, z[:n])
        return np.kron(np.eye(ncol), fy) if n * ncol <= 120 else sps.kron(sps.identity(ncol), fy, format="csc")

    def end(self, z1):
        """(y1, Phi, Psi) from z(s1) (Phi, Psi None without the variational equations)."""
        if not self.var:
            return z1, None, None
        n = self.n
        Z1 = z1.reshape(n, self.ncol, order="F")
        return Z1[:, 0], Z1[:, 1:1 + n], Z1[:, 1 + n:]


@dataclass(frozen=True)
class IVPOptions(Options):
    """How every flow of a shooting solve is integrated (``scipy.integrate.solve_ivp``); the defaults are
    those of :func:`shoot` and :func:`multiple_shoot`.

    Attributes:
        rtol_ivp: the relative tolerance, 0 < rtol_ivp < 1.
        atol_ivp: the absolute tolerance (None: rtol_ivp / 100).
        ivp_method: the integrator, one of IVP_METHODS.
        max_nfev: right-hand side evaluations allowed for the whole solve (>= 1).
        blowup: a trajectory with |y| beyond this has blown up (> 0).
    """

    rtol_ivp: float = 1e-11
    atol_ivp: float | None = None
    ivp_method: str = "DOP853"
    max_nfev: int = 200_000
    blowup: float = 1e12


def ivp_options(problem, options: IVPOptions) -> dict:
    """The checked keyword options of every flow of one solve (rtol, atol = rtol_ivp / 100 unless given,
    method, a shared budget of ``max_nfev`` right-hand side evaluations, blowup); InputError when bad."""
    rtol_ivp, atol_ivp, ivp_method = options.rtol_ivp, options.atol_ivp, options.ivp_method
    max_nfev, blowup = options.max_nfev, options.blowup
    if ivp_method not in IVP_METHODS:
        raise InputError(f"{problem.name}: unknown integrator {ivp_method!r}", key="ivp_method",
                         expected=f"one of {IVP_METHODS}")
    if not (0 < rtol_ivp < 1):
        raise InputError(f"{problem.name}: rtol_ivp = {rtol_ivp}", key="rtol_ivp", expected="0 < rtol_ivp < 1")
    atol = rtol_ivp * 1e-2 if atol_ivp is None else float(atol_ivp)
    if not max_nfev >= 1 or not blowup > 0:
        raise InputError(f"{problem.name}: max_nfev = {max_nfev}, blowup = {blowup}", key="max_nfev",
                         expected="max_nfev >= 1 and blowup > 0")
    return dict(rtol=float(rtol_ivp), atol=atol, method=ivp_method, budget=_Budget(max_nfev), blowup=float(blowup))


# ----------------------------------------------------------------------------- Newton
def _dense_solve(J, r):
    """Solve J dx = -r after scaling the rows of J to unit max-norm; a condition number
    above 1e14 (after scaling) counts as singular."""
    if not np.all(np.isfinite(J)):
        raise _Singular("the Newton matrix is not finite")
    scale = np.max(np.abs(J), axis=1)
    if np.any(scale == 0):
        raise _Singular("a zero row")
    Js = J / scale[:, None]
    cond = np.linalg.cond(Js)
    if not cond < 1e14:
        raise _Singular(f"condition number {cond:.1e} after row scaling")
    return np.linalg.solve(Js, -r / scale)


def _sparse_solve(J, r):
    try:
        dx = spla.splu(sps.csc_matrix(J), permc_spec="MMD_AT_PLUS_A").solve(-r)
    except RuntimeError as exc:
        raise _Singular(str(exc)) from exc
    if not np.all(np.isfinite(dx)):
        raise _Singular("the solution of the Newton system is not finite")
    return dx


class _Singular(Exception):
    pass


def _damped_newton(evaluate, x0, *, solve, tol, max_iter, method):
    """Newton with backtracking on ||R||_2; ``evaluate(x)`` returns (R, J) or raises IVPFailure."""
    try:
        return _newton_loop(evaluate, x0, solve=solve, tol=tol, max_iter=max_iter, method=method)
    except BudgetSpent:
        raise ConvergenceError(f"{method}: the budget of right-hand side evaluations (max_nfev) is spent; the "
                               "integrations are too costly (stiff? try ivp_method='Radau') or diverge") from None


def _newton_loop(evaluate, x0, *, solve, tol, max_iter, method):
    x = np.array(x0, float)
    try:
        r, J = evaluate(x)
    except IVPFailure as exc:
        raise ConvergenceError(f"{method}: the residual cannot be evaluated at the initial guess: {exc}. "
                               "A better guess, or multiple shooting / collocation, is needed") from None
    norm = float(np.linalg.norm(r))
    history = [norm]
    it = 0
    while norm > tol:
        if it >= max_iter:
            tail = ", ".join(f"{h:.3g}" for h in history[-5:])
            raise ConvergenceError(f"{method}: no convergence in {max_iter} Newton iterations; residual norm "
                                   f"{norm:.3g} > tol {tol:.1e} (last norms: {tail})")
        it += 1
        try:
            dx = solve(J, r)
        except _Singular as exc:
            raise ConvergenceError(f"{method}: singular or ill-conditioned Newton matrix at iteration {it} ({exc}); "
                                   f"residual norm {norm:.3g}. The solution is not isolated (a fold, or a free "
                                   "parameter without a boundary condition), the guess is degenerate, or the "
                                   "problem is too ill-conditioned for this method (use more shooting nodes or "
                                   "collocation)") from None
        x, r, J, norm = _line_search(evaluate, (x, dx, norm), tol, it, method)
        history.append(norm)
    return x, it, norm, J


def _line_search(evaluate, step: tuple, tol: float, it: int, method: str) -> tuple:
    """Backtracking from x along the Newton step dx (``step`` = (x, dx, ||R(x)||)) until ||R|| decreases by
    the Armijo factor 1 - 1e-4 alpha: (x + alpha dx, R, J, ||R||) there; ConvergenceError below alpha = 2^-24."""
    x, dx, norm = step
    alpha, why = 1.0, ""
    while True:
        trial = x + alpha * dx
        try:
            r_t, J_t = evaluate(trial)
            n_t = float(np.linalg.norm(r_t))
        except IVPFailure as exc:
            n_t, why = np.inf, str(exc)
        if n_t <= (1.0 - 1e-4 * alpha) * norm:
            return trial, r_t, J_t, n_t
        alpha *= 0.5
        if alpha < 2.0 ** -24:
            extra = f"; the trial trajectories fail: {why}" if why and not np.isfinite(n_t) else ""
            raise ConvergenceError(f"{method}: the line search found no decrease of the residual at "
                                   f"iteration {it}; residual norm {norm:.3g} > tol {tol:.1e}{extra}. The "
                                   "problem is too ill-conditioned for this method or the tolerance is "
                                   "below the integration error")


# ----------------------------------------------------------------------------- single shooting
def shoot(problem: BVP, guess, *, p=None, tol: float = 1e-10, max_iter: int = 40, ivp: IVPOptions | None = None,
          **overrides) -> BVPResult:
    """Single shooting from the guess y(a) = ``guess`` (n,) and ``p`` (all n_p parameters; the
    unknown ones are initial guesses). ``guess`` may also be a :class:`BVPResult`. The flows are
    integrated as ``ivp`` (:class:`IVPOptions`, its defaults when None) says, with keyword
    ``overrides`` of single options (``rtol_ivp=1e-9``).

    Newton (with line search) on (y(a), p[unknown]) until ||g||_2 <= tol; the Jacobian
    comes from the variational equations. Raises ConvergenceError when it fails (including
    a shot that blows up before s = b from the guess), InputError on bad shapes.
    """
    if isinstance(guess, BVPResult):
        p = guess.p if p is None else p
        guess = guess.y[:, 0]
    options = IVPOptions.of(ivp, **overrides)
    p = full_parameters(problem, p)
    y0 = _state(problem, guess, "guess")
    problem.check(y0, p)
    shot = _SingleShot(problem, p, ivp_options(problem, options))
    x0 = np.concatenate([y0, p[shot.unk]])
    x, it, norm, _ = _damped_newton(shot.evaluate, x0, solve=_dense_solve, tol=tol, max_iter=max_iter,
                                    method="single shooting")
    return shot.result(x, it, norm)


class _SingleShot:
    """Single shooting's residual g(y(a), y(b), p) with y(b) the flow of x = (y(a), p[unknown]) and its
    Jacobian [G_a + G_b Phi, G_b Psi + G_p] (the variational equations); ``opts`` as :func:`ivp_options`'s."""

    def __init__(self, problem: BVP, p, opts: dict) -> None:
        self.problem, self.p, self.opts = problem, p, opts
        self.unk = list(problem.unknown)

    def unpack(self, x):
        n = self.problem.n
        q = self.p.copy()
        q[self.unk] = x[n:]
        return x[:n], q

    def evaluate(self, x):
        problem, unk = self.problem, self.unk
        ya, q = self.unpack(x)
        yb, Phi, Psi, _ = _flow(problem, problem.interval, ya, q, unk, self.opts)
        R = problem.bc(ya, yb, q)
        Ga, Gb, Gp = problem.bc_jac(ya, yb, q)
        J = np.hstack([Ga + Gb @ Phi, Gb @ Psi + Gp[:, unk]])
        if not (np.all(np.isfinite(R)) and np.all(np.isfinite(J))):
            raise IVPFailure("the boundary residual or its Jacobian is not finite")
        return R, J

    def result(self, x, it: int, norm: float) -> BVPResult:
        """The BVPResult of the converged x: its trajectory integrated again with dense output."""
        ya, q = self.unpack(x)
        self.opts["budget"].used = 0
        try:
            _, _, _, sol = _flow(self.problem, self.problem.interval, ya, q, None, self.opts, dense=True)
        except (IVPFailure, BudgetSpent) as exc:  # pragma: no cover - the same trajectory just succeeded
            raise ConvergenceError(f"single shooting: the final trajectory failed: {exc}") from None
        return BVPResult(sol.t, sol.y, q, norm, it, "single shooting", sol.sol)


# ----------------------------------------------------------------------------- multiple shooting
def mesh_nodes(problem: BVP, nodes) -> np.ndarray:
    """Nodes a = s_0 < ... < s_K = b from an interval count (uniform) or increasing nodes (ends snapped to a, b)."""
    a, b = problem.interval
    if isinstance(nodes, (int, np.integer)):
        if nodes < 1:
            raise InputError(f"{problem.name}: nodes = {nodes}", key="nodes", expected="at least 1 interval")
        return np.linspace(a, b, int(nodes) + 1)
    s = np.asarray(nodes, float).ravel()
    if s.size < 2 or not np.all(np.diff(s) > 0) or abs(s[0] - a) > 1e-12 * max(1, abs(a)) \
            or abs(s[-1] - b) > 1e-12 * max(1, abs(b)):
        raise InputError(f"{problem.name}: the nodes are not increasing from a = {a} to b = {b}", key="nodes",
                         expected="an interval count or increasing nodes a = s_0 < ... < s_K = b")
    s = s.copy()
    s[0], s[-1] = a, b
    return s


def _interp_guess(problem: BVP, mesh, values, at) -> np.ndarray:
    mesh = np.asarray(mesh, float).ravel()
    values = np.asarray(values, float)
    if values.ndim == 1 and problem.n == 1:
        values = values[None, :]
    if values.shape != (problem.n, mesh.size) or mesh.size < 2 or not np.all(np.diff(mesh) > 0):
        raise InputError(f"{problem.name}: the guess has mesh of size {mesh.size} and values of shape "
                         f"{values.shape}", key="guess",
                         expected=f"an increasing mesh (m,) and values ({problem.n}, m)")
    if not np.all(np.isfinite(values)):
        raise InputError(f"{problem.name}: the guess is not finite", key="guess", expected="finite values")
    return np.stack([np.interp(at, mesh, values[i]) for i in range(problem.n)])


class ShootingResidual:
    """R(x) and its sparse Jacobian for x = (Y_0, ..., Y_K, p[unknown]) (rows: continuity, then g)."""

    def __init__(self, problem: BVP, nodes, opts):
        self.problem, self.nodes, self.opts = problem, nodes, opts
        n, K, k = problem.n, len(nodes) - 1, problem.k
        self.size = n * (K + 1) + k
        # sparsity: continuity block j: columns of Y_j (Phi), Y_{j+1} (-I), p_u (Psi)
        rows, cols = [], []
        rr, cc = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        for j in range(K):
            rows += [j * n + rr.ravel(), j * n + rr.ravel()]
            cols += [j * n + cc.ravel(), (j + 1) * n + cc.ravel()]
            if k:
                pr, pc = np.meshgrid(np.arange(n), np.arange(k), indexing="ij")
                rows.append(j * n + pr.ravel())
                cols.append(n * (K + 1) + pc.ravel())
        self._rows, self._cols = np.concatenate(rows), np.concatenate(cols)

    def split(self, x, p):
        n, K = self.problem.n, len(self.nodes) - 1
        Y = x[: n * (K + 1)].reshape(K + 1, n).T
        q = p.copy()
        q[list(self.problem.unknown)] = x[n * (K + 1):]
        return Y, q

    def evaluate(self, x, p, extra_cols=(), jac=True):
        """R, J (csc) and dR/dp[extra_cols] (size, len(extra_cols)) at x."""
        prob, nodes, n, K = self.problem, self.nodes, self.problem.n, len(self.nodes) - 1
        unk = list(prob.unknown)
        cols = unk + list(extra_cols)
        Y, q = self.split(x, p)
        R = np.empty(self.size)
        vals, dpar = [], np.zeros((self.size, len(cols)))
        for j in range(K):
            y1, Phi, Psi, _ = _flow(prob, (nodes[j], nodes[j + 1]), Y[:, j], q, cols if jac else None, self.opts)
            R[j * n:(j + 1) * n] = y1 - Y[:, j + 1]
            if jac:
                vals += [Phi.ravel(), -np.eye(n).ravel()]
                dpar[j * n:(j + 1) * n] = Psi
        R[K * n:] = prob.bc(Y[:, 0], Y[:, K], q)
        if not np.all(np.isfinite(R)):
            raise IVPFailure("the boundary residual is not finite")
        if not jac:
            return R, None, None
        k = len(unk)
        if k:
            for j in range(K):
                vals.insert(3 * j + 2, dpar[j * n:(j + 1) * n, :k].ravel())
        Ga, Gb, Gp = prob.bc_jac(Y[:, 0], Y[:, K], q)
        m = n + k
        br, bc_ = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")
        rows = [self._rows, K * n + br.ravel(), K * n + br.ravel()]
        colz = [self._cols, bc_.ravel(), K * n + bc_.ravel()]
        data = [np.concatenate(vals) if vals else np.zeros(0), Ga.ravel(), Gb.ravel()]
        if k:
            pr, pc = np.meshgrid(np.arange(m), np.arange(k), indexing="ij")
            rows.append(K * n + pr.ravel())
            colz.append(n * (K + 1) + pc.ravel())
            data.append(Gp[:, unk].ravel())
        J = sps.csc_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(colz))),
                           shape=(self.size, self.size))
        if not np.all(np.isfinite(J.data)):
            raise IVPFailure("the Jacobian is not finite")
        dpar[K * n:] = Gp[:, cols]
        return R, J, dpar[:, k:]

    def dense(self, x, p):
        """Mesh, values and dense output of the trajectory through the node values in x."""
        prob, nodes, K = self.problem, self.nodes, len(self.nodes) - 1
        Y, q = self.split(x, p)
        ss, ys, pieces = [], [], []
        for j in range(K):
            _, _, _, sol = _flow(prob, (nodes[j], nodes[j + 1]), Y[:, j], q, None, self.opts, dense=True)
            ss.append(sol.t if j == 0 else sol.t[1:])
            ys.append(sol.y if j == 0 else sol.y[:, 1:])
            pieces.append(sol.sol)
        return np.concatenate(ss), np.hstack(ys), _PiecewiseDense(nodes, pieces, prob.n), q


def multiple_shoot(problem: BVP, guess_mesh, guess_values, *, p=None, nodes=10, tol: float = 1e-10,
                   max_iter: int = 40, ivp: IVPOptions | None = None, **overrides) -> BVPResult:
    """Multiple shooting on ``nodes`` (an interval count, uniform, or the node positions).

    The guess is given on any mesh (``guess_values`` (n, m) at ``guess_mesh`` (m,)) and
    interpolated linearly to the nodes; ``p``, ``ivp`` and the ``overrides`` as for :func:`shoot`.
    Newton with line search on the node values and unknown parameters until ||R||_2 <= tol.
    """
    options = IVPOptions.of(ivp, **overrides)
    p = full_parameters(problem, p)
    s_nodes = mesh_nodes(problem, nodes)
    Y0 = _interp_guess(problem, guess_mesh, guess_values, s_nodes)
    problem.check(Y0[:, 0], p)
    opts = ivp_options(problem, options)
    ms = ShootingResidual(problem, s_nodes, opts)
    x0 = np.concatenate([Y0.T.ravel(), p[list(problem.unknown)]])

    def evaluate(x):
        R, J, _ = ms.evaluate(x, p)
        return R, J

    method = f"multiple shooting ({len(s_nodes) - 1} intervals)"
    x, it, norm, _ = _damped_newton(evaluate, x0, solve=_sparse_solve, tol=tol, max_iter=max_iter, method=method)
    opts["budget"].used = 0
    try:
        s, y, dense, q = ms.dense(x, p)
    except (IVPFailure, BudgetSpent) as exc:  # pragma: no cover
        raise ConvergenceError(f"{method}: the final trajectory failed: {exc}") from None
    return BVPResult(s, y, q, norm, it, "multiple shooting", dense)


# ----------------------------------------------------------------------------- collocation
def collocate(problem: BVP, mesh, guess, *, p=None, tol: float = 1e-8, bc_tol: float | None = None,
              max_nodes: int = 100_000) -> BVPResult:
    """``scipy.integrate.solve_bvp`` with the analytic Jacobians.

    ``mesh`` (m,) and ``guess`` (n, m) are the initial mesh and values; ``tol`` is
    solve_bvp's relative collocation-residual tolerance (it refines the mesh until met),
    ``bc_tol`` the boundary-residual tolerance (default ``tol``).
    """
    p = full_parameters(problem, p)
    mesh = np.asarray(mesh, float).ravel()
    a, b = problem.interval
    Y = _interp_guess(problem, mesh, guess, mesh)
    if abs(mesh[0] - a) > 1e-12 * max(1, abs(a)) or abs(mesh[-1] - b) > 1e-12 * max(1, abs(b)):
        raise InputError(f"{problem.name}: the mesh runs from {mesh[0]} to {mesh[-1]}, not over the interval "
                         f"({a}, {b})", key="mesh", expected="a mesh from a to b")
    problem.check(Y[:, 0], p)
    funs = _SolveBVPFunctions(problem, p)
    kwargs = {"p": p[funs.unk]} if funs.k else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            from scipy.integrate import solve_bvp  # loaded on use (startup)

            sol = solve_bvp(funs.fun, funs.bc, mesh, Y, fun_jac=funs.fun_jac, bc_jac=funs.bc_jac, tol=tol,
                            bc_tol=tol if bc_tol is None else bc_tol, max_nodes=max_nodes, **kwargs)
        except (ValueError, np.linalg.LinAlgError) as exc:
            raise ConvergenceError(f"collocation (solve_bvp) failed: {exc}") from None
    q = funs.full(sol.p) if funs.k else p.copy()
    return _collocation_result(problem, sol, q, tol)


class _SolveBVPFunctions:
    """The problem's f, f_y, g and Jacobians in solve_bvp's form: the unknown parameters p[unknown] passed
    separately (as ``pu``; none when the problem has no unknown parameters), the others fixed at p."""

    def __init__(self, problem: BVP, p) -> None:
        self.problem, self.p = problem, p
        self.unk, self.k = list(problem.unknown), problem.k

    def full(self, pu):
        q = self.p.copy()
        q[self.unk] = pu
        return q

    def fun(self, s, y, pu=()):
        return self.problem.fv(s, y, self.full(pu))

    def fun_jac(self, s, y, pu=()):
        q = self.full(pu)
        Jy = self.problem.f_yv(s, y, q)
        return (Jy, self.problem.f_pv(s, y, q)[:, self.unk, :]) if self.k else Jy

    def bc(self, ya, yb, pu=()):
        return self.problem.bc(ya, yb, self.full(pu))

    def bc_jac(self, ya, yb, pu=()):
        Ga, Gb, Gp = self.problem.bc_jac(ya, yb, self.full(pu))
        return (Ga, Gb, Gp[:, self.unk]) if self.k else (Ga, Gb)


def _collocation_result(problem: BVP, sol, q, tol: float) -> BVPResult:
    """The BVPResult of solve_bvp's solution with parameters q: residual = max(largest relative collocation
    residual, largest |g|); ConvergenceError when solve_bvp failed or the residual is not finite."""
    rms = float(np.max(sol.rms_residuals)) if sol.rms_residuals.size else np.inf
    bc_res = float(np.max(np.abs(problem.bc(sol.y[:, 0], sol.y[:, -1], q))))
    res = max(rms, bc_res)
    if sol.status != 0 or not np.isfinite(res):
        raise ConvergenceError(f"collocation (solve_bvp): {sol.message} after {sol.niter} iterations; largest "
                               f"relative collocation residual {rms:.3g}, boundary residual {bc_res:.3g} "
                               f"(tol {tol:.1e}, {sol.x.size} nodes)")
    return BVPResult(sol.x, sol.y, q, res, int(sol.niter), "collocation", sol.sol)


# ----------------------------------------------------------------------------- helpers
def on_unit_interval(problem: BVP, length_index: int, *, autonomous: bool = False, f_s=None) -> BVP:
    """The same BVP with a free length L = p[length_index]: s = a + L sigma, sigma in [0, 1].

    y_sigma = L f(a + L sigma, y, p); the p-Jacobian gains the column f + L sigma f_s
    for L. The original interval's end b is ignored. Needs ``autonomous=True`` (f
    independent of s) or ``f_s`` (df/ds, (n,) non-vectorized or (n, m) vectorized).
    """
    if not (isinstance(length_index, (int, np.integer)) and 0 <= length_index < problem.n_p):
        raise InputError(f"{problem.name}: length_index = {length_index!r} with n_p = {problem.n_p}",
                         key="length_index", expected=f"an index in 0..{problem.n_p - 1}")
    if not autonomous and f_s is None:
        raise InputError(f"{problem.name}: a free length of a non-autonomous problem needs df/ds", key="f_s",
                         expected="f_s, or autonomous=True")
    a, L_i, vec = problem.interval[0], int(length_index), problem.vectorized

    def f(t, y, p):
        return p[L_i] * np.asarray(problem.f(a + p[L_i] * t, y, p), float)

    def f_y(t, y, p):
        return p[L_i] * np.asarray(problem.f_y(a + p[L_i] * t, y, p), float)

    def f_p(t, y, p):
        L, s = p[L_i], a + p[L_i] * t
        out = L * np.array(problem.f_p(s, y, p), float)
        col = np.asarray(problem.f(s, y, p), float)
        if f_s is not None:
            col = col + L * t * np.asarray(f_s(s, y, p), float)
        out[:, L_i] += col
        return out

    return BVP(f, f_y, problem.g, problem.g_ya, problem.g_yb, (0.0, 1.0), problem.n, problem.n_p, f_p,
               problem.g_p, problem.unknown, vec, f"{problem.name} on [0, 1]")


def check_jacobians(problem: BVP, s: float, y, p=None, *, ya=None, yb=None, h: float = 1e-6) -> dict:
    """Largest relative error of each supplied Jacobian against central differences at one
    point (a debugging aid for generated kernels; the solvers never difference)."""
    p = full_parameters(problem, p)
    y = _state(problem, y, "y")
    ya = y if ya is None else _state(problem, ya, "ya")
    yb = y if yb is None else _state(problem, yb, "yb")
    problem.check(y, p)

    def fd(fun, x):
        cols = []
        for j in range(x.size):
            e = np.zeros_like(x)
            e[j] = h * max(1.0, abs(x[j]))
            cols.append((fun(x + e) - fun(x - e)) / (2 * e[j]))
        return np.stack(cols, axis=-1) if cols else np.zeros((0, 0))

    def rel(A, B):
        A, B = np.asarray(A, float), np.asarray(B, float)
        return float(np.max(np.abs(A - B)) / max(np.max(np.abs(B)) if B.size else 0.0, 1.0)) if B.size else 0.0

    out = {"f_y": rel(problem.f_y1(s, y, p), fd(lambda v: problem.f1(s, v, p), y))}
    Ga, Gb, Gp = problem.bc_jac(ya, yb, p)
    out["g_ya"] = rel(Ga, fd(lambda v: problem.bc(v, yb, p), ya))
    out["g_yb"] = rel(Gb, fd(lambda v: problem.bc(ya, v, p), yb))
    if problem.n_p:
        out["f_p"] = rel(problem.f_p1(s, y, p), fd(lambda v: problem.f1(s, y, v), p))
        out["g_p"] = rel(Gp, fd(lambda v: problem.bc(ya, yb, v), p))
    return out

