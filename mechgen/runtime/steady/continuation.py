"""Pseudo-arclength continuation of F(u, lam) = 0, F: R^{n+1} -> R^n, through turning points.

With x = (u, lam) and the unit tangent t (the null vector of [F_u, F_lam]), one step of
length ds from an accepted point x_i is

    predictor  x = x_i + ds t_i + ds^2/2 (t_i - t_{i-1}) / (s_i - s_{i-1})  (the curvature from the
               last two tangents; first order at the first step),
    corrector  Newton on  F(x) = 0,  t_i . (x - x_i) = ds   (the bordered system
               [[F_u, F_lam], [t_i^T]] dx = -[F, t_i . (x - x_i) - ds]),
    tangent    [[F_u, F_lam], [t_i^T]] t = (0, 1), normalised: t . t_i > 0 keeps the
               orientation, so the branch goes round a fold instead of turning back.

The corrector evaluates the residual first and the Jacobian only when it takes another
step; the tangent at the new point is solved with the last step's factorisation (the
Jacobian one quadratically small step away, and the same row t_i). A system may bring its
own linear algebra: ``evaluate(u, lam, jac)`` -> (F, J, F_lam) with J in any form, and
``bordered(J, F_lam, row)`` -> a solver of the bordered system (a collocation
:class:`DiscreteBVP` condenses and keeps its sparsity pattern); and
``arclength_weights`` W (the dot products above become t . W x: unknowns slaved to others,
such as collocation stage values, weigh 0).

The step grows (x ``grow``) after fast corrections, shrinks after slow ones, and is halved
and retried when the corrector fails or the tangent turns more than ``max_turn``; below
``ds_min`` the continuation stops with a message. A fold (turning point in lam) is a
sign change of the tangent's lam-component between two points; it is located by Brent's
method on the arclength s of the segment, with t_lam(s) from a corrected point, so the
fold's lam is accurate to the square of the location error. The branch ends at
``max_points``, where lam leaves [lam_min, lam_max] (the last point is then put exactly
on the bound), or where it comes back to its start going the same way ('closed': an isola,
a closed curve of orbits).

:func:`continue_bvp` continues a BVP (:class:`mechgen.runtime.steady.bvp.BVP`) in one of its
parameters through a collocation or multiple-shooting :class:`DiscreteBVP`;
:func:`minimize_along_branch` locates an extremum of a scalar output phi(u, lam) along a
branch as a zero of d phi/ds (exact with the output's gradient, else central differences
along the branch).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.core.budget import Progress
from mechgen.runtime.core.options import Options
from mechgen.runtime.steady.bvp import BVP, BVPResult
from mechgen.runtime.steady.collocation import DiscreteBVP


@dataclass(frozen=True)
class ParametricEquations:
    """F(u, lam) (n,), F_u(u, lam) (n, n) dense or sparse, F_lam(u, lam) (n,)."""

    F: Callable
    F_u: Callable
    F_lam: Callable
    name: str = "F"


@dataclass(frozen=True)
class Fold:
    """A turning point in lam between branch points ``index`` and ``index + 1``."""

    u: np.ndarray
    lam: float
    index: int
    tangent: np.ndarray
    located: bool = True


@dataclass(frozen=True)
class Branch:
    """Accepted points ``u`` (m, n) and ``lam`` (m,), their arclength and unit tangents
    (m, n + 1), the folds, the callback's value per point (``data``), why it stopped
    (``status``: 'max_points', 'lam_max', 'lam_min', 'min_step', 'closed' or the one ``until`` gave) and a
    message, and
    the system (to correct further points, e.g. for :func:`minimize_along_branch`)."""

    u: np.ndarray
    lam: np.ndarray
    arclength: np.ndarray
    tangents: np.ndarray
    folds: tuple
    data: tuple
    status: str
    message: str
    system: Any = field(repr=False)


@dataclass(frozen=True)
class Extremum:
    """An extremum of an output along a branch: the point, the value, 'min' or 'max', the
    segment it lies on and |d phi/ds| there (the residual of the location)."""

    u: np.ndarray
    lam: float
    value: float
    kind: str
    index: int
    slope: float


@dataclass(frozen=True)
class ContinuationOptions(Options):
    """Step control and stopping rules of :func:`continuation` (the defaults are its defaults).

    Attributes:
        ds: the first step length (arclength in the weighted norm, see the module doc).
        ds_min, ds_max: the step stays in [ds_min, ds_max]; below ds_min the branch ends ('min_step').
        direction: +1 to start towards increasing lam, -1 towards decreasing lam.
        max_points: the branch ends after this many accepted points ('max_points').
        lam_min, lam_max: the branch ends where lam leaves [lam_min, lam_max], with a last point on the bound.
        tol: the corrector's tolerance on ||F||.
        max_corrector: Newton steps per corrector (4 x as many for the start at fixed lam0).
        grow: the step's growth factor after a correction in at most 3 steps.
        max_turn: the largest angle (radians) between consecutive tangents; a step turning more is halved.
        locate_folds: locate each fold by Brent's method (else the point after the fold is recorded, located=False).
        budget: a :class:`~mechgen.runtime.core.budget.Budget` whose wall time is checked before every step
            (BudgetExceeded names the points accepted and the lam reached), or None.
        progress: draw a bar of the accepted points out of max_points on stderr (a terminal, after 2 s).

    Checked by :meth:`check`: 0 < ds_min <= ds <= ds_max, direction +1 or -1, max_points >= 1,
    lam_min < lam_max, 0 < max_turn < pi, tol > 0, grow >= 1.
    """

    ds: float = 0.05
    ds_min: float = 1e-8
    ds_max: float = 1.0
    direction: int = 1
    max_points: int = 200
    lam_min: float = -np.inf
    lam_max: float = np.inf
    tol: float = 1e-10
    max_corrector: int = 8
    grow: float = 1.5
    max_turn: float = 0.5
    locate_folds: bool = True
    budget: Any = None
    progress: bool = False

    def check(self) -> None:
        """InputError unless the options are consistent (see the class doc)."""
        ds, ds_min, ds_max, lam_min, lam_max = self.ds, self.ds_min, self.ds_max, self.lam_min, self.lam_max
        if not (0 < ds_min <= ds <= ds_max) or self.direction not in (1, -1) or self.max_points < 1 \
                or not lam_min < lam_max or not 0 < self.max_turn < math.pi or self.tol <= 0 or self.grow < 1:
            raise InputError(f"continuation: ds_min = {ds_min}, ds = {ds}, ds_max = {ds_max}, direction = "
                             f"{self.direction}, max_points = {self.max_points}, lam range [{lam_min}, {lam_max}], "
                             f"max_turn = {self.max_turn}",
                             key="options", expected="0 < ds_min <= ds <= ds_max, direction +1 or -1, max_points >= 1, "
                             "lam_min < lam_max, 0 < max_turn < pi, tol > 0, grow >= 1")


# ----------------------------------------------------------------------------- linear algebra
class _Singular(Exception):
    pass


_SOLVER_ERRORS = (np.linalg.LinAlgError, ValueError, RuntimeError, ZeroDivisionError)


def _own(system, name):
    """The system's optional method ``name`` (``evaluate``, ``bordered``) when it offers both."""
    if callable(getattr(system, "evaluate", None)) and callable(getattr(system, "bordered", None)):
        return getattr(system, name)
    return None


def _eval(system, u, lam, jac=True):
    """(F, F_u, F_lam) at (u, lam); (F, None, None) without ``jac`` or where F is not finite.

    A system with ``evaluate(u, lam, jac)`` and ``bordered(J, F_lam, row)`` (a
    :class:`~mechgen.runtime.steady.collocation.DiscreteBVP`) gives F_u in its own form, for its own solver."""
    evaluate = _own(system, "evaluate")
    with np.errstate(all="ignore"):
        if evaluate is not None:
            F, Fu, Fl = evaluate(u, lam, jac)
            F = np.asarray(F, float).ravel()
            if not jac or Fu is None or not np.all(np.isfinite(F)):
                return F, None, None
            return F, Fu, np.asarray(Fl, float).ravel()
        F = np.asarray(system.F(u, lam), float).ravel()
        if not jac:
            return F, None, None
        if not np.all(np.isfinite(F)):
            return F, None, None
        Fu = system.F_u(u, lam)
        Fl = np.asarray(system.F_lam(u, lam), float).ravel()
    if Fu is not None and not sps.issparse(Fu):
        Fu = np.atleast_2d(np.asarray(Fu, float))
    return F, Fu, Fl


def _factor(system, Fu, Fl, row):
    """A solver x = solve(rhs) of [[Fu, Fl], [row^T]] x = rhs: the system's own (``bordered``), or
    SuperLU when Fu is sparse, or dense LU. Raises _Singular."""
    own = _own(system, "bordered")
    if own is not None:
        return _own_factor(own, Fu, Fl, row)
    solve = _sparse_factor(Fu, Fl, row) if sps.issparse(Fu) else _dense_factor(Fu, Fl, row)

    def finite(rhs):
        x = solve(rhs)
        if not np.all(np.isfinite(x)):
            raise _Singular("the solution of the bordered system is not finite")
        return x

    return finite


def _own_factor(own, Fu, Fl, row):
    """The system's own bordered solver ``own(Fu, Fl, row)``, its solver errors raised as _Singular."""
    try:
        solve = own(Fu, Fl, row)
    except _SOLVER_ERRORS as exc:
        raise _Singular(str(exc)) from exc

    def checked(rhs):
        try:
            return solve(rhs)
        except _SOLVER_ERRORS as exc:
            raise _Singular(str(exc)) from exc

    return checked


def _sparse_factor(Fu, Fl, row):
    """SuperLU's solve of the bordered matrix with a sparse Fu. Raises _Singular."""
    n = Fl.size
    A = sps.vstack([sps.hstack([Fu, sps.csc_matrix(Fl.reshape(n, 1))]),
                    sps.csr_matrix(row.reshape(1, n + 1))], format="csc")
    if not np.all(np.isfinite(A.data)):
        raise _Singular("the Jacobian is not finite")
    try:
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")  # banded blocks + border: 8x less fill than COLAMD
    except RuntimeError as exc:
        raise _Singular(str(exc)) from exc
    return lu.solve


def _dense_factor(Fu, Fl, row):
    """Dense LU's solve of the bordered matrix. Raises _Singular (also at a pivot below 1e-14 max |A|)."""
    A = np.vstack([np.hstack([Fu, Fl[:, None]]), row[None, :]])
    if not np.all(np.isfinite(A)):
        raise _Singular("the Jacobian is not finite")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", sla.LinAlgWarning)
            lu = sla.lu_factor(A, check_finite=False)
    except (np.linalg.LinAlgError, ValueError, sla.LinAlgWarning) as exc:
        raise _Singular(str(exc)) from exc
    if np.min(np.abs(np.diag(lu[0]))) <= 1e-14 * max(np.abs(A).max(), 1e-300):
        raise _Singular("a zero pivot")

    def solve(rhs):
        return sla.lu_solve(lu, rhs, check_finite=False)

    return solve


class _Linearisation:
    """F_u and F_lam at a point, with the bordered system's factorisation for ``row`` made on first use."""

    def __init__(self, system, Fu, Fl, row):
        self.system, self.Fu, self.Fl, self.row = system, Fu, Fl, row
        self._solve = None

    def solve(self, rhs, row=None):
        if row is not None and row is not self.row and not np.array_equal(row, self.row):
            return _factor(self.system, self.Fu, self.Fl, row)(rhs)
        if self._solve is None:
            self._solve = _factor(self.system, self.Fu, self.Fl, self.row)
        return self._solve(rhs)


def _linearise(system, x, row):
    """The linearisation at x, where F is known to be finite (None when F_u cannot be evaluated there)."""
    n = x.size - 1
    if _own(system, "evaluate") is not None:
        _, Fu, Fl = _eval(system, x[:n], x[n])
    else:
        with np.errstate(all="ignore"):
            Fu = system.F_u(x[:n], x[n])
            Fl = np.asarray(system.F_lam(x[:n], x[n]), float).ravel()
        if Fu is not None and not sps.issparse(Fu):
            Fu = np.atleast_2d(np.asarray(Fu, float))
    return None if Fu is None else _Linearisation(system, Fu, Fl, row)


def _weights(system, size: int):
    """Weights of the arclength inner product (None: all 1): a discretisation's slaved unknowns weigh 0."""
    w = getattr(system, "arclength_weights", None)
    if w is None:
        return None
    w = np.asarray(w, float)
    if w.shape != (size,) or np.any(w < 0) or not np.any(w > 0):
        raise InputError(f"continuation: arclength weights of shape {w.shape}", key="arclength_weights",
                         expected=f"{size} non-negative weights, not all zero")
    return w


def _row(w, t):
    """The pseudo-arclength row W t."""
    return t if w is None else w * t


def _norm(w, x) -> float:
    return float(np.sqrt(x @ _row(w, x)))


def _tangent(lin, ref, w=None):
    """Unit null vector (in the W-norm) of [F_u, F_lam] with t . ref > 0 (ref: the corrector's row W t_i)."""
    rhs = np.zeros(lin.Fl.size + 1)
    rhs[-1] = 1.0
    t = lin.solve(rhs, row=ref)
    return t / _norm(w, t)


def _correct(system, x_pred, row, target, *, tol, max_iter, polish=False):
    """Newton on F(x) = 0, row . x = target from x_pred. Returns (x, iterations, linearisation) or None.

    The residual is evaluated first and the Jacobian only when another step is needed; the
    returned linearisation is the last step's (its factorisation, with ``row``, serves the
    tangent: the Jacobian one quadratically small step before x), or the one at x when the
    predictor was already converged. With ``polish`` one more Newton step follows convergence
    (for folds, extrema and end points, whose lam should be exact to rounding rather than to
    tol / |F_lam|)."""
    x = np.array(x_pred, float)
    n = x.size - 1
    prev = np.inf
    done = False
    lin = None
    for it in range(max_iter + 2):
        F = _eval(system, x[:n], x[n], jac=False)[0]
        norm = float(np.linalg.norm(F))
        if not np.isfinite(norm) or norm > 1e3 * prev + 1e3 * tol:
            return None
        converged = norm <= tol and abs(row @ x - target) <= tol * max(1.0, abs(target))
        if done or (converged and not polish):
            if not (converged or norm <= 1e3 * tol):
                return None
            lin = lin or _linearise(system, x, row)
            return None if lin is None else (x, it, lin)
        if converged:
            done = True
        elif it >= max_iter:
            return None
        lin = _linearise(system, x, row)
        if lin is None:
            return None
        try:
            dx = lin.solve(-np.append(F, row @ x - target))
        except _Singular:
            return None
        x = x + dx
        prev = max(norm, tol)
    return None


def _bordered_solve(Fu, Fl, row, rhs):
    """Solve [[Fu, Fl], [row^T]] x = rhs (dense LU, or sparse LU when Fu is sparse)."""
    return _factor(None, Fu, Fl, row)(rhs)


# ----------------------------------------------------------------------------- driver
def _check_system(system, u, lam):
    for name in ("F", "F_u", "F_lam"):
        if not callable(getattr(system, name, None)):
            raise InputError(f"continuation: the system has no callable {name}", key=name,
                             expected="F(u, lam), F_u(u, lam) and F_lam(u, lam)")
    u = np.asarray(u, float).ravel()
    if not (np.all(np.isfinite(u)) and np.isfinite(lam)):
        raise InputError("continuation: the starting point is not finite", key="u0", expected="finite values")
    n = u.size
    F, Fu, Fl = _eval(system, u, float(lam))
    if F.shape != (n,):
        raise InputError(f"continuation: F returned {F.size} values for {n} unknowns", key="F",
                         expected=f"{n} values (F: R^(n+1) -> R^n)")
    if _own(system, "evaluate") is not None:  # the discretisation's own Jacobian and solver
        if Fu is None:
            raise InputError("continuation: the Jacobian at the starting point cannot be evaluated", key="u0",
                             expected="a start where F, F_u and F_lam are finite")
        return u
    shape = Fu.shape if Fu is not None else None
    if shape != (n, n):
        raise InputError(f"continuation: F_u has shape {shape}", key="F_u", expected=f"({n}, {n})")
    if Fl.shape != (n,):
        raise InputError(f"continuation: F_lam has shape {Fl.shape}", key="F_lam", expected=f"({n},)")
    return u


def continuation(system, u0, lam0: float, options: ContinuationOptions | None = None, *,
                 callback: Callable | None = None, start_tangent: np.ndarray | None = None,
                 until: Callable | None = None, **overrides) -> Branch:
    """Continue F(u, lam) = 0 from (u0, lam0) in the direction of increasing lam
    (``direction=+1``) or decreasing lam (-1).

    ``system`` has F, F_u, F_lam (a :class:`ParametricEquations`, a :class:`DiscreteBVP`, ...). The
    start is first corrected at fixed lam0 (Newton). ``options`` (a :class:`ContinuationOptions`,
    its defaults when None) set the steps and the stopping rules; keyword ``overrides`` replace
    single options (``continuation(F, u0, lam0, ds=0.1, lam_max=2.0)``). ``callback(u, lam)`` is
    called at every accepted point and its values are kept in ``Branch.data``. ``start_tangent``: a start
    already on the branch (a branch point, mechgen.runtime.steady.special_points) and the direction of the first
    step, used as given (no correction at fixed lam, no orientation by ``direction``). ``until(u, lam)``, called
    at each corrected point before it is accepted, may end the branch there: it returns None, or (status, message),
    and the point is not kept (a branch of orbits that shrink to an equilibrium ends at its smallest orbit).
    """
    opts = ContinuationOptions.of(options, **overrides)
    opts.check()
    lam0 = float(lam0)
    u = _check_system(system, u0, lam0)
    if not opts.lam_min <= lam0 <= opts.lam_max:
        raise InputError(f"continuation: lam0 = {lam0} lies outside [{opts.lam_min}, {opts.lam_max}]", key="lam0",
                         expected="a start inside the lam range")
    w = _weights(system, u.size + 1)
    if start_tangent is not None:
        return _run(system, np.append(u, lam0), _unit(w, start_tangent), callback, opts, until)
    x, lin = _corrected_start(system, u, lam0, opts)
    t = _start_tangent(lin, w)
    if t[-1] * opts.direction < 0:
        t = -t
    return _run(system, x, t, callback, opts, until)


def _corrected_start(system, u, lam0: float, opts: ContinuationOptions):
    """(x, linearisation) of the start corrected onto the branch by Newton at fixed lam0 (4 x max_corrector
    steps); ConvergenceError when it fails."""
    e_lam = np.zeros(u.size + 1)
    e_lam[-1] = 1.0
    got = _correct(system, np.append(u, lam0), e_lam, lam0, tol=opts.tol, max_iter=4 * opts.max_corrector)
    if got is None:
        F = _eval(system, u, lam0, jac=False)[0]
        raise ConvergenceError(f"continuation of {getattr(system, 'name', 'F')}: the start (lam = {lam0:.6g}, "
                               f"||F|| = {np.linalg.norm(F):.3g}) could not be corrected onto the branch (Newton at "
                               "fixed lam failed: a bad start or a fold exactly at the start)")
    x, _, lin = got
    return x, lin


def _start_tangent(lin, w):
    """The unit tangent at the start, with the bordering row e_lam (or, where that is singular, a fixed random
    row); ConvergenceError at a branch point ([F_u, F_lam] rank deficient)."""
    size = lin.Fl.size + 1
    e_lam = np.zeros(size)
    e_lam[-1] = 1.0
    for ref in (e_lam, np.random.default_rng(0).standard_normal(size)):
        try:
            return _tangent(lin, ref, w)
        except _Singular:
            continue
    raise ConvergenceError("continuation: no tangent at the start ([F_u, F_lam] is rank deficient: a "
                           "branch point)")


def closes(w, xs: list, ts: list, step: float) -> bool:
    """Whether the newest point has come back to the branch's start, going the same way (a closed branch, an
    isola): the segment to it passes within half a step of the start, with the start's tangent direction, after
    the branch has been at least 4 steps away from it."""
    if len(xs) < 6:
        return False
    start, last, new = xs[0], xs[-2], xs[-1]
    chord = new - last
    length = _norm(w, chord)
    if length == 0.0 or ts[-1] @ _row(w, ts[0]) <= 0:
        return False
    theta = float(np.clip((start - last) @ _row(w, chord) / length**2, 0.0, 1.0))
    near = _norm(w, last + theta * chord - start) < 0.5 * step
    went_away = max(_norm(w, x - start) for x in xs[1:-1]) > 4 * step
    return bool(near and went_away)


def _unit(w, t) -> np.ndarray:
    t = np.asarray(t, float)
    return t / _norm(w, t)


def _run(system, x, t, callback, opts: ContinuationOptions, until: Callable | None = None) -> Branch:
    """The steps of :func:`continuation` from the point x on the branch with the unit tangent t."""
    walk = _Walk(system, x, t, callback, opts)
    n = walk.n
    status, message = "max_points", f"reached max_points = {opts.max_points}"
    step = opts.ds
    bar = Progress(opts.max_points, desc="continuation", unit="point", enabled=opts.progress)
    while len(walk.xs) < opts.max_points:
        x_i = walk.xs[-1]
        bar.to(len(walk.xs))
        if opts.budget is not None:
            opts.budget.check_time(lambda: f"{len(walk.xs)} branch points, lam = {x_i[n]:.10g}")
        row = _row(walk.w, walk.ts[-1])
        got = walk.advance(step, row)
        if got is None:
            step *= 0.5
            if step < opts.ds_min:
                status, message = "min_step", _min_step_message(opts.ds_min, x_i[n])
                break
            continue
        x_new, iters, t_new = got
        ended = until(x_new[:n].copy(), float(x_new[n])) if until is not None else None
        if ended is not None:
            status, message = ended
            break
        walk.note_fold(step, x_new, t_new)
        if not opts.lam_min <= x_new[n] <= opts.lam_max:
            status, message = walk.end_at_bound(x_new, t_new, row)
            break
        walk.keep(x_new, t_new, step)
        if closes(walk.w, walk.xs, walk.ts, step):
            status = "closed"
            message = (f"the branch closed on itself after {len(walk.xs) - 1} points (back at its start, lam = "
                       f"{walk.xs[0][n]:.10g}, going the same way: an isola)")
            break
        step = _next_step(step, iters, opts)
    bar.close()
    return walk.branch(status, message)


def _min_step_message(ds_min: float, lam: float) -> str:
    return (f"the step fell below ds_min = {ds_min:.3g} at lam = {lam:.10g} (the corrector fails or the branch "
            "turns too sharply: a singular point, or tol below the residual's noise)")


def _next_step(step: float, iters: int, opts: ContinuationOptions) -> float:
    """The step after a correction in ``iters`` Newton steps: x grow (to ds_max) after at most 3, x 0.7 (to
    ds_min) after max(4, max_corrector - 2) or more, else unchanged."""
    if iters <= 3:
        return min(step * opts.grow, opts.ds_max)
    if iters >= max(4, opts.max_corrector - 2):
        return max(0.7 * step, opts.ds_min)
    return step


class _Walk:
    """The growing branch of :func:`_run`: accepted points ``xs`` = (u, lam), their unit tangents ``ts``,
    arclengths ``arc``, callback values ``data`` and the folds found so far; ``w`` the arclength weights."""

    def __init__(self, system, x, t, callback, opts: ContinuationOptions) -> None:
        self.system, self.callback, self.opts = system, callback, opts
        self.n = n = x.size - 1
        self.w = _weights(system, n + 1)
        self.xs, self.ts, self.arc = [x], [t], [0.0]
        self.data = [callback(x[:n].copy(), x[n]) if callback else None]
        self.folds: list = []

    def keep(self, x, t, length: float) -> None:
        """Accept the point x with tangent t, ``length`` (arclength) after the last."""
        n = self.n
        self.xs.append(x)
        self.ts.append(t)
        self.arc.append(self.arc[-1] + length)
        self.data.append(self.callback(x[:n].copy(), x[n]) if self.callback else None)

    def advance(self, step: float, row):
        """(x_new, corrector iterations, t_new) a ``step`` on from the last point (predictor with the
        curvature of the last two tangents, corrector on the row W t_i), or None when the corrector or the
        tangent fails or the tangent turns by more than max_turn."""
        x_i, t_i, opts = self.xs[-1], self.ts[-1], self.opts
        pred = x_i + step * t_i
        if len(self.xs) > 1 and self.arc[-1] > self.arc[-2]:  # second order: x'' ~ (t_i - t_{i-1}) / (s_i - s_{i-1})
            pred += 0.5 * step ** 2 / (self.arc[-1] - self.arc[-2]) * (t_i - self.ts[-2])
        got = _correct(self.system, pred, row, row @ x_i + step, tol=opts.tol, max_iter=opts.max_corrector)
        if got is None:
            return None
        x_new, iters, lin = got
        try:
            t_new = _tangent(lin, row, self.w)
        except _Singular:
            return None
        return (x_new, iters, t_new) if t_new @ row >= math.cos(opts.max_turn) else None

    def note_fold(self, step: float, x_new, t_new) -> None:
        """Record the fold between the last point and x_new when t_lam changes sign there (located by
        :func:`_locate_fold` when asked and possible, else at the extreme lam of the two points)."""
        x_i, t_i, n, opts = self.xs[-1], self.ts[-1], self.n, self.opts
        if not (opts.locate_folds and t_i[n] * t_new[n] < 0):
            return
        fold = _locate_fold(self.system, x_i, t_i, step, tol=opts.tol, max_corrector=opts.max_corrector, w=self.w)
        if fold is None:
            lam_f = max(x_i[n], x_new[n]) if t_i[n] > 0 else min(x_i[n], x_new[n])
            fold = Fold(x_new[:n].copy(), float(lam_f), len(self.xs) - 1, t_new, located=False)
        else:
            fold = Fold(fold[0][:n].copy(), float(fold[0][n]), len(self.xs) - 1, fold[1], True)
        if opts.lam_min <= fold.lam <= opts.lam_max:
            self.folds.append(fold)

    def end_at_bound(self, x_new, t_new, row) -> tuple[str, str]:
        """(status, message) where x_new has left [lam_min, lam_max]: the last point is put on the bound
        (corrected at fixed lam, polished) unless that fails or a fold lies between."""
        x_i, t_i, n, opts = self.xs[-1], self.ts[-1], self.n, self.opts
        bound = opts.lam_max if x_new[n] > opts.lam_max else opts.lam_min
        status = "lam_max" if bound == opts.lam_max else "lam_min"
        message = f"lam left [{opts.lam_min}, {opts.lam_max}] after lam = {x_i[n]:.10g}"
        theta = (bound - x_i[n]) / (x_new[n] - x_i[n])
        e_lam = np.zeros(n + 1)
        e_lam[-1] = 1.0
        end = _correct(self.system, x_i + theta * (x_new - x_i), e_lam, bound, tol=opts.tol,
                       max_iter=opts.max_corrector, polish=True)
        if end is not None and (t_i[n] * t_new[n] > 0):
            x_end, _, lin = end
            try:
                t_end = _tangent(lin, row, self.w)
            except _Singular:
                t_end = t_new
            self.keep(x_end, t_end, _norm(self.w, x_end - x_i))
            message = f"lam reached the bound {bound:.10g}"
        return status, message

    def branch(self, status: str, message: str) -> Branch:
        X, T = np.array(self.xs), np.array(self.ts)
        n = self.n
        return Branch(X[:, :n], X[:, n], np.array(self.arc), T, tuple(self.folds), tuple(self.data), status, message,
                      self.system)


def _segment_point(system, x_i, t_i, sigma, *, tol, max_corrector, w=None):
    """The corrected point at arclength parameter sigma on the segment from x_i, and its tangent."""
    row = _row(w, t_i)
    got = _correct(system, x_i + sigma * t_i, row, row @ x_i + sigma, tol=tol, max_iter=2 * max_corrector,
                   polish=True)
    if got is None:
        raise _Singular(f"no corrected point at sigma = {sigma:.6g}")
    x, _, lin = got
    return x, _tangent(lin, row, w)


def _locate_fold(system, x_i, t_i, step, *, tol, max_corrector, w=None):
    """Zero of t_lam(sigma) on [0, step] (Brent); None when it cannot be bracketed."""
    cache = {}

    def tlam(sigma):
        if sigma == 0.0:
            return t_i[-1]
        x, t = _segment_point(system, x_i, t_i, sigma, tol=tol, max_corrector=max_corrector, w=w)
        cache[sigma] = (x, t)
        return t[-1]

    try:
        a, b = 0.0, step
        fa, fb = t_i[-1], tlam(b)
        if fa * fb > 0:
            return None
        from scipy.optimize import brentq  # loaded on use (startup)

        sigma = brentq(tlam, a, b, xtol=1e-14 * max(1.0, step), maxiter=100)
        return cache[sigma] if sigma in cache else _segment_point(system, x_i, t_i, sigma, tol=tol,
                                                                  max_corrector=max_corrector, w=w)
    except (_Singular, ValueError, RuntimeError):
        return None


# ----------------------------------------------------------------------------- BVP continuation
def continue_bvp(problem: BVP, guess: BVPResult, lam_index: int, *, method: str = "collocation", mesh=100,
                 stages: int | None = None, rtol_ivp: float = 1e-10, ivp_method: str = "DOP853",
                 options: ContinuationOptions | None = None, **overrides) -> Branch:
    """Continue a BVP in the fixed parameter p[lam_index], starting from ``guess`` (a
    BVPResult, e.g. from :func:`~mechgen.runtime.steady.bvp.collocate`).

    ``method`` is 'collocation' (Hermite-Simpson on a fixed mesh; ``mesh`` an interval count or
    nodes), 'gauss' (``stages``-point Gauss-Legendre collocation, default 4: order 8) or
    'multiple_shooting' (``mesh`` the shooting nodes); ``options`` and the keyword ``overrides``
    (``callback`` and single options) go to :func:`continuation`. ``branch.system`` is the
    :class:`DiscreteBVP`; its ``to_result(u, lam)`` turns a branch point into a BVPResult.
    """
    if not isinstance(guess, BVPResult):
        raise InputError(f"{problem.name}: continue_bvp needs a BVPResult to start from, got "
                         f"{type(guess).__name__}", key="guess", expected="a BVPResult")
    disc = DiscreteBVP(problem, lam_index, guess.p, mesh, method=method, stages=stages, rtol_ivp=rtol_ivp,
                       ivp_method=ivp_method)
    u0, lam0 = disc.start(guess)
    return continuation(disc, u0, lam0, options, **overrides)


def point_at(branch: Branch, lam: float, *, tol: float = 1e-10) -> np.ndarray:
    """The branch's u at the parameter value ``lam``: the point of the first segment whose lam-range holds it,
    interpolated linearly and corrected by Newton at fixed lam (polished). Raises ConvergenceError
    when no segment holds lam or the correction fails."""
    lam = float(lam)
    system = branch.system
    n = branch.u.shape[1]
    e_lam = np.zeros(n + 1)
    e_lam[-1] = 1.0
    for i in range(len(branch.lam) - 1):
        a, b = branch.lam[i], branch.lam[i + 1]
        if min(a, b) <= lam <= max(a, b) and a != b:
            theta = (lam - a) / (b - a)
            guess = np.append(branch.u[i] + theta * (branch.u[i + 1] - branch.u[i]), lam)
            got = _correct(system, guess, e_lam, lam, tol=tol, max_iter=20, polish=True)
            if got is not None:
                return got[0][:n]
            raise ConvergenceError(f"point_at: Newton at lam = {lam:.10g} failed on segment {i}")
    raise ConvergenceError(f"point_at: lam = {lam:.10g} is not on the branch ([{branch.lam.min():.6g}, "
                           f"{branch.lam.max():.6g}])")


# ----------------------------------------------------------------------------- extrema
def minimize_along_branch(branch: Branch, output: Callable, *, gradient: Callable | None = None, kind: str = "min",
                          fd_step: float | None = None, tol: float | None = None) -> Extremum:
    """The interior minimum (``kind='min'``) or maximum of phi = output(u, lam) along a branch.

    The sampled extremum at point j brackets a sign change of d phi/ds on the segments
    j-1 -> j -> j+1; Brent's method finds the zero on that segment (arclength parameter
    sigma, corrected points). d phi/ds = grad phi . t with ``gradient(u, lam) ->
    (d phi/du, d phi/dlam)``, else a central difference of phi between the corrected
    points at sigma +- ``fd_step``. Raises ConvergenceError when the extremum is at an end
    of the branch (continue further).
    """
    if kind not in ("min", "max"):
        raise InputError(f"minimize_along_branch: kind = {kind!r}", key="kind", expected="'min' or 'max'")
    m = branch.u.shape[0]
    if m < 3:
        raise InputError(f"minimize_along_branch: the branch has {m} points", key="branch",
                         expected="at least 3 points")
    j = _sampled_extremum(branch, output, kind)
    h = fd_step if fd_step is not None else 1e-5 * max(float(np.min(np.diff(branch.arclength)[j - 1:j + 1])), 1e-8)
    slope = _BranchSlope(branch, output, gradient, h, 1e-10 if tol is None else tol)
    for i in (j - 1, j):
        found = slope.extremum(i, kind)
        if found is not None:
            return found
    raise ConvergenceError(f"minimize_along_branch: d phi/ds does not change sign around the sampled {kind}imum at "
                           f"lam = {branch.lam[j]:.6g} (a kink, or the branch is too coarse there)")


def _sampled_extremum(branch: Branch, output: Callable, kind: str) -> int:
    """The index of the branch point with the smallest (kind 'min') or largest output; ConvergenceError at an end."""
    m = branch.u.shape[0]
    sign = 1.0 if kind == "min" else -1.0
    vals = np.array([float(output(branch.u[j], branch.lam[j])) for j in range(m)])
    j = int(np.argmin(sign * vals))
    if j == 0 or j == m - 1:
        raise ConvergenceError(f"minimize_along_branch: the {kind}imum of the sampled output ({vals[j]:.6g}) is at "
                               f"an end of the branch (lam = {branch.lam[j]:.6g}); continue the branch further")
    return j


class _BranchSlope:
    """d phi/ds at the corrected point at arclength parameter sigma on the branch's segment i: grad phi . t
    with ``gradient``, else the central difference of phi = output(u, lam) over sigma +- h."""

    def __init__(self, branch: Branch, output: Callable, gradient: Callable | None, h: float, tol: float) -> None:
        self.system, self.output, self.gradient, self.h, self.tol = branch.system, output, gradient, h, tol
        self.n = n = branch.u.shape[1]
        self.w = _weights(branch.system, n + 1)
        self.X = np.hstack([branch.u, branch.lam[:, None]])
        self.T = branch.tangents

    def point(self, i: int, sigma: float):
        """(x, t) at sigma on segment i (the branch point itself at sigma = 0)."""
        if sigma == 0.0:
            return self.X[i], self.T[i]
        return _segment_point(self.system, self.X[i], self.T[i], sigma, tol=self.tol, max_corrector=10, w=self.w)

    def __call__(self, i: int, sigma: float) -> float:
        n, h, output = self.n, self.h, self.output
        if self.gradient is not None:
            x, t = self.point(i, sigma)
            gu, gl = self.gradient(x[:n], x[n])
            return float(np.dot(np.asarray(gu, float).ravel(), t[:n]) + gl * t[n])
        xp, _ = self.point(i, sigma + h)
        xm, _ = self.point(i, sigma - h) if sigma - h != 0.0 else (self.X[i], None)
        return (float(output(xp[:n], xp[n])) - float(output(xm[:n], xm[n]))) / (2 * h)

    def extremum(self, i: int, kind: str) -> Extremum | None:
        """The zero of d phi/ds on segment i (Brent), None without a sign change; ConvergenceError when
        correcting points fails."""
        n, X = self.n, self.X
        length = float(_row(self.w, self.T[i]) @ (X[i + 1] - X[i]))
        try:
            a, b = self(i, 0.0), self(i, length)
            if a * b > 0:
                return None
            from scipy.optimize import brentq  # loaded on use (startup)

            sigma = brentq(lambda s: self(i, s), 0.0, length, xtol=1e-13 * max(1.0, length), maxiter=100)
            x, _ = self.point(i, sigma)
            return Extremum(x[:n].copy(), float(x[n]), float(self.output(x[:n], x[n])), kind, i, abs(self(i, sigma)))
        except (_Singular, ValueError, RuntimeError) as exc:
            raise ConvergenceError(f"minimize_along_branch: correcting points near lam = {X[i][n]:.6g} failed "
                                   f"({exc})") from None
