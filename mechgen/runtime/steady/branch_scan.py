"""Scanning a branch of steady states: both ways from a start, output bounds, crossings, switches of a label.

:func:`follow` continues a BVP in one parameter (mechgen.runtime.steady.continuation.continue_bvp)
in one direction or both ways from the start, and ends the branch where ``inside(u, lam)``
turns false (an output leaves its bounds): it then runs in chunks of ``chunk`` points, each
restarted from the last accepted point in the direction of its tangent, and drops the first
point outside. Two half-branches are joined in the order of the branch (the one in the
decreasing direction reversed, its tangents negated).

Between two consecutive branch points x_a, x_b (x = (u, lam)) the branch is parametrised by
theta in [0, 1]: the point x(theta) solves

    F(u, lam) = 0,   d . (x - x_a) = theta |x_b - x_a|,   d = (x_b - x_a) / |x_b - x_a|

(Newton on the bordered system [[F_u, F_lam], [d^T]] from the chord point, as the
continuation's corrector). :func:`crossing` finds where a scalar g(x) changes sign (Brent's
method in theta; g an output minus its target value) and :func:`switch` where a discrete
label (the stability verdict) changes (bisection in theta down to ``tol``).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.steady.continuation import Branch, ContinuationOptions, continue_bvp

sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")

DIRECTIONS = ("increasing", "decreasing", "both")


# ----------------------------------------------------------------------------- following a branch
def _sign(t_lam: float, default: int) -> int:
    return default if t_lam == 0 else (1 if t_lam > 0 else -1)


def _join(pieces: list[Branch], status: str, message: str) -> Branch:
    """One branch from consecutive pieces (each starting at the previous one's last point)."""
    first = pieces[0]
    u, lam, arc, tan, data, folds = [first.u], [first.lam], [first.arclength], [first.tangents], list(first.data), \
        list(first.folds)
    offset, shift = len(first.lam) - 1, first.arclength[-1]
    for piece in pieces[1:]:
        u.append(piece.u[1:])
        lam.append(piece.lam[1:])
        arc.append(piece.arclength[1:] + shift)
        tan.append(piece.tangents[1:])
        data += list(piece.data[1:])
        folds += [replace(f, index=f.index + offset) for f in piece.folds]
        offset += len(piece.lam) - 1
        shift += piece.arclength[-1]
    return replace(first, u=np.vstack(u), lam=np.concatenate(lam), arclength=np.concatenate(arc),
                   tangents=np.vstack(tan), folds=tuple(folds), data=tuple(data), status=status, message=message)


def _truncate(branch: Branch, keep: int) -> Branch:
    """The first ``keep`` points of a branch (and the folds among them)."""
    return replace(branch, u=branch.u[:keep], lam=branch.lam[:keep], arclength=branch.arclength[:keep],
                   tangents=branch.tangents[:keep], data=branch.data[:keep],
                   folds=tuple(f for f in branch.folds if f.index + 1 < keep))


def _one_way(problem, guess, index, direction: int, inside, *, chunk: int, max_points: int, mesh,
             options: ContinuationOptions, **discretisation):
    """The branch from ``guess`` in one direction, ended where ``inside`` fails (then in chunks)."""
    if inside is None:
        return continue_bvp(problem, guess, index, mesh=mesh, options=replace(options, direction=direction,
                                                                              max_points=max_points),
                            **discretisation)
    pieces, total, start = [], 1, guess
    while True:
        size = min(chunk, max_points - total + 1)
        piece = continue_bvp(problem, start, index, mesh=mesh,
                             options=replace(options, direction=direction, max_points=size), **discretisation)
        outside = next((j for j in range(1, len(piece.lam)) if not inside(piece.u[j], piece.lam[j], piece.system)),
                       None)
        if outside is not None:
            pieces.append(_truncate(piece, outside))
            return _join(pieces, "bounds", f"an output left its bounds after lam = {piece.lam[outside - 1]:.10g}")
        pieces.append(piece)
        total += len(piece.lam) - 1
        if piece.status != "max_points" or total >= max_points or len(piece.lam) < 2:
            return _join(pieces, piece.status, piece.message)
        start = piece.system.to_result(piece.u[-1], piece.lam[-1])
        direction = _sign(piece.tangents[-1][-1], direction)
        options = replace(options, ds=float(piece.arclength[-1] - piece.arclength[-2]))


def _reverse(branch: Branch) -> Branch:
    m = len(branch.lam)
    return replace(branch, u=branch.u[::-1], lam=branch.lam[::-1],
                   arclength=branch.arclength[-1] - branch.arclength[::-1], tangents=-branch.tangents[::-1],
                   data=branch.data[::-1],
                   folds=tuple(replace(f, index=m - 2 - f.index, tangent=-f.tangent) for f in branch.folds[::-1]))


def follow(problem, guess, index: int, *, direction: str = "increasing", inside=None, chunk: int = 20,
           max_points: int = 200, mesh=100, options: ContinuationOptions | None = None, **extra) -> Branch:
    """The branch of ``problem`` through ``guess`` (a BVPResult) in the parameter p[index].

    ``direction``: 'increasing' or 'decreasing' (the parameter's direction at the start) or
    'both' (the two half-branches, ``max_points`` each, joined: the start is then an inner point).
    ``inside(u, lam, system) -> bool`` ends the branch where it turns false (status 'bounds').
    ``options`` (:class:`~mechgen.runtime.steady.continuation.ContinuationOptions`: ds, lam_min,
    lam_max ...; direction and max_points are set here) go to the continuation; in ``extra``,
    single options override them and the rest (method, stages, ...) go to
    :func:`~mechgen.runtime.steady.continuation.continue_bvp`.
    """
    if direction not in DIRECTIONS:
        raise InputError(f"unknown branch direction {direction!r}", key="direction", expected=", ".join(DIRECTIONS))
    names = ContinuationOptions.names()
    options = ContinuationOptions.of(options, **{k: v for k, v in extra.items() if k in names})
    discretisation = {k: v for k, v in extra.items() if k not in names}
    ways = {"increasing": (1,), "decreasing": (-1,), "both": (-1, 1)}[direction]
    halves = [_one_way(problem, guess, index, d, inside, chunk=chunk, max_points=max_points, mesh=mesh,
                       options=options, **discretisation) for d in ways]
    if len(halves) == 1:
        return halves[0]
    down, up = halves
    status = down.status if down.status == up.status else f"{down.status} (decreasing), {up.status} (increasing)"
    return _join([_reverse(down), up], status, f"decreasing: {down.message}; increasing: {up.message}")


# ----------------------------------------------------------------------------- points between branch points
def _solver(system, x):
    """x -> (F, solve) at x: the residual and a solver of [[F_u, F_lam], [row^T]] dx = rhs for a given row."""
    n = x.size - 1
    if callable(getattr(system, "evaluate", None)) and callable(getattr(system, "bordered", None)):
        F, J, Fl = system.evaluate(x[:n], x[n], True)
        return np.asarray(F, float).ravel(), lambda row: system.bordered(J, np.asarray(Fl, float).ravel(), row)
    F = np.asarray(system.F(x[:n], x[n]), float).ravel()
    Fu, Fl = system.F_u(x[:n], x[n]), np.asarray(system.F_lam(x[:n], x[n]), float).ravel()

    def factor(row):
        A = sps.vstack([sps.hstack([sps.csc_matrix(Fu), sps.csc_matrix(Fl.reshape(-1, 1))]),
                        sps.csr_matrix(row.reshape(1, -1))], format="csc")
        return spla.splu(A).solve

    return F, factor


def point_between(system, xa, xb, theta: float, *, tol: float = 1e-10, max_iter: int = 25,
                  start: np.ndarray | None = None) -> np.ndarray:
    """The branch point x(theta) between the branch points xa and xb (see the module doc); Newton starts from
    ``start`` (default: the chord's point xa + theta (xb - xa))."""
    xa, xb = np.asarray(xa, float), np.asarray(xb, float)
    chord = xb - xa
    length = float(np.linalg.norm(chord))
    if theta == 0.0 or length == 0.0:
        return xa.copy()
    row = chord / length
    target = float(row @ xa) + theta * length
    x = xa + theta * chord if start is None else np.array(start, float)
    done = False
    for _ in range(max_iter):
        try:
            F, factor = _solver(system, x)
            converged = np.all(np.isfinite(F)) and np.linalg.norm(F) <= tol
            if done:
                return x
            dx = factor(row)(-np.append(F, row @ x - target))
        except (np.linalg.LinAlgError, RuntimeError, ValueError, ZeroDivisionError) as exc:
            raise ConvergenceError(f"no branch point at theta = {theta:.6g} between lam = {xa[-1]:.8g} and "
                                   f"{xb[-1]:.8g}: {exc}") from None
        if not np.all(np.isfinite(dx)):
            break
        x = x + dx
        done = converged  # one more (polishing) step after convergence
    if done:
        return x
    raise ConvergenceError(f"no branch point at theta = {theta:.6g} between lam = {xa[-1]:.8g} and {xb[-1]:.8g} "
                           f"(Newton did not converge in {max_iter} steps)")


def crossing(system, xa, xb, g, *, xtol: float = 1e-12) -> np.ndarray:
    """The branch point between xa and xb where g(x) = 0 (g changes sign from xa to xb)."""
    cache = {}

    def value(theta):
        x = point_between(system, xa, xb, theta)
        cache[theta] = x
        return float(g(x))

    from scipy.optimize import brentq  # loaded on use (startup)

    theta = brentq(value, 0.0, 1.0, xtol=xtol, maxiter=100)
    return cache[theta] if theta in cache else point_between(system, xa, xb, theta)


def switch(system, xa, xb, label, label_a, *, tol: float = 1e-9) -> np.ndarray:
    """The branch point between xa and xb where label(x) stops being ``label_a`` (bisection in theta to ``tol``;
    returns the point at the middle of the last bracket). Each bisection point's Newton starts from the middle
    of its bracket's two branch points (the chord's point is farther from the branch: more iterations)."""
    xa, xb = np.asarray(xa, float), np.asarray(xb, float)
    lo, hi, x_lo, x_hi = 0.0, 1.0, xa, xb
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        x = point_between(system, xa, xb, mid, start=0.5 * (x_lo + x_hi))
        if label(x) == label_a:
            lo, x_lo = mid, x
        else:
            hi, x_hi = mid, x
    return point_between(system, xa, xb, 0.5 * (lo + hi), start=0.5 * (x_lo + x_hi))
