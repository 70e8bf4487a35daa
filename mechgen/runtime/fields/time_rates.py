"""A compiled continuum's time rates: the first-order form dx/dt of time integration and its Jacobian.

Second order (a mass on every field): x = (q, v), dx/dt = (v, a) with M(q) a = -r(q, v, 0), M = dr/dq'';
da/d(q, v) = -M^-1 [r_q, r_v] at the current acceleration. First order (no kinetic density, M = 0): the fields
obey r(q, q', 0) = 0, D(q) q' + f(q) = 0 (js_fluid), and q' is its root by Newton on r_v. A mass on some fields
only, or a rate on some unknowns only, is an algebraic system (a DAE) and is refused.
The functions take a :class:`~mechgen.runtime.fields.continuum.FieldSystem`.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError, InputError, KernelError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.core.memory import require_dense
from mechgen.runtime.fields.conditions import reduction_key

sla = lazy_module("scipy.linalg")
sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")


#: Newton steps of a first-order continuum's rate q' (one suffices when r is linear in the rates)
FIRST_ORDER_NEWTON = 20
#: ... until |r(q, q', 0)| falls below this fraction of |r(q, 0, 0)| (a linear r: round-off, ~1e-15, at once)
FIRST_ORDER_RTOL = 1e-10
#: ... or below this many machine epsilons of the size of its terms
ROUND_OFF = 1e3 * np.finfo(float).eps


def empty_rows(A) -> int:
    """How many rows of A (dense or sparse) are entirely zero."""
    rows = np.asarray(abs(A).sum(axis=1)).ravel() if sps.issparse(A) else np.abs(np.asarray(A)).sum(axis=1)
    return int(np.count_nonzero(rows == 0.0))


def require_mass(system, M) -> None:
    """Refuse a mass matrix with zero rows: fields without kinetic energy obey first-order (or algebraic) laws,
    D(q) q' + f(q) = 0, which the second-order integration (q, v) cannot run."""
    empty = empty_rows(M)
    if empty:
        raise InputError(f"model {system.metadata.model}: {empty} of {system.n} unknowns carry no mass (fields "
                         "without a kinetic density obey first-order or algebraic laws, D(q) q' + f(q) = 0); "
                         "simulate integrates continua with a mass on every field, or on none (first-order fields)",
                         key="kind", expected="a kinetic density on every field, or on none of them")


def mass_solve(system, q, v, t: float, rhs: np.ndarray) -> np.ndarray:
    """M^-1 rhs; a state-independent M (the usual case, known from the derivation) is factorised once."""
    if system.reduction.multiplier_rows is not None:
        raise InputError("time integration with Lagrange multipliers is a DAE (singular mass)",
                         key="constraints", expected="'eliminate' or 'penalty' for simulate")
    if system.field_meta.constant_mass:
        def factor():
            M = system.tangent(np.zeros(system.n), t=t)["r_a"]
            require_mass(system, M)
            return (spla.splu(sps.csc_matrix(M)).solve if sps.issparse(M)
                    else (lambda b, f=sla.cho_factor(M): sla.cho_solve(f, b)))

        return system.memo(("mass", *reduction_key(system), system.param_key), factor)(rhs)
    M = system.tangent(q, v, t=t)["r_a"]
    require_mass(system, M)
    return spla.spsolve(sps.csc_matrix(M), rhs) if sps.issparse(M) else sla.solve(M, rhs)


def is_first_order(system) -> bool:
    """True when no unknown carries mass (no kinetic density, a constant M = 0), memoised."""
    if not system.field_meta.constant_mass or system.reduction.multiplier_rows is not None:
        return False

    def empty() -> bool:
        M = system.tangent(np.zeros(system.n))["r_a"]
        return not (M.count_nonzero() if sps.issparse(M) else np.count_nonzero(M))
    return system.memo(("first_order", *reduction_key(system), system.param_key), empty)


def rate_solve(system, r_v, rhs: np.ndarray) -> np.ndarray:
    """r_v^-1 rhs, refusing rows without a rate (an algebraic unknown: a DAE)."""
    empty = empty_rows(r_v)
    if empty:
        raise InputError(f"model {system.metadata.model}: {empty} of {system.n} unknowns have neither mass nor a "
                         "rate (algebraic, a DAE: an inertialess field); simulate integrates ODEs",
                         key="kind", expected="a rate on every field (js_fluid: Re > 0), or steady / stability")
    A = sps.csc_matrix(r_v) if sps.issparse(r_v) else np.asarray(r_v)
    return spla.spsolve(A, rhs) if sps.issparse(r_v) else sla.solve(A, rhs)


def first_order_rate(system, t: float, q: np.ndarray) -> np.ndarray:
    """q' of a first-order continuum: the root v of r(q, v, 0) = 0 by Newton on r_v (one step when r is linear
    in the rates); a singular r_v (an unknown without a rate: Re = 0 in js_fluid) is refused, a DAE."""
    q = np.asarray(q, float)
    v = np.zeros(system.n)
    r = system.residual(q, v, None, None, t)
    start = np.linalg.norm(r)
    for _ in range(FIRST_ORDER_NEWTON):
        if not np.all(np.isfinite(r)):
            raise KernelError(f"residual of {system.metadata.model} gave NaN/Inf at t = {t}")
        tan = system.tangent(q, v, t=t)
        v = v + rate_solve(system, tan["r_v"], -r)
        r = system.residual(q, v, None, None, t)
        # converged: |r| down by 1/FIRST_ORDER_RTOL, or at the round-off of its terms (a state near steady has a
        # tiny |r(q, 0, 0)| itself), eps |terms| ~ eps (|r_q| |q| + |r_v| |v| + |r(q, 0, 0)|)
        terms = np.linalg.norm(abs(tan["r_q"]) @ np.abs(q) + abs(tan["r_v"]) @ np.abs(v)) + start
        if np.linalg.norm(r) <= max(FIRST_ORDER_RTOL * start, ROUND_OFF * terms):
            return v
    raise ConvergenceError(f"the rates of {system.metadata.model} at t = {t}: Newton on r(q, q', 0) = 0 left "
                           f"|r| = {np.linalg.norm(r):.3g} after {FIRST_ORDER_NEWTON} steps (from {start:.3g})")


def first_order_jacobian(system, t: float, q: np.ndarray):
    """d q'/dq = -r_v^-1 r_q at (q, q'(q)) (dense; a first-order continuum's implicit integration)."""
    v = first_order_rate(system, t, q)
    require_dense(system.n, 8, "the dense first-order Jacobian (implicit time integration)",
                  expected="a smaller N, or an explicit method (RK45, DOP853)")
    tan = system.tangent(q, v, t=t)
    r_q = tan["r_q"].toarray() if sps.issparse(tan["r_q"]) else np.asarray(tan["r_q"])
    return -rate_solve(system, tan["r_v"], r_q)


def rhs(system, t: float, x: np.ndarray) -> np.ndarray:
    """dx/dt = (v, -M^-1 r(q, v, 0))."""
    q, v, _ = system.split(x)
    a = mass_solve(system, q, v, t, -system.residual(q, v, None, None, t))
    out = np.concatenate([v, a])
    if not np.all(np.isfinite(out)):
        raise KernelError(f"residual of {system.metadata.model} gave NaN/Inf at t = {t}")
    return out


def jacobian(system, t: float, x: np.ndarray):
    """d(dx/dt)/dx with da/d(q, v) = -M^-1 [r_q, r_v] at the current acceleration."""
    q, v, _ = system.split(x)
    a = None if system.field_meta.constant_mass else system.rhs(t, x)[system.n:]
    require_dense(system.n, 12, "the dense first-order Jacobian (implicit time integration)",
                  expected="a smaller N, or an explicit method (RK45, DOP853) or leapfrog")
    tan = system.tangent(q, v, a, t=t)
    dense = lambda A: A.toarray() if sps.issparse(A) else A  # noqa: E731
    da = -mass_solve(system, q, v, t, np.hstack([dense(tan["r_q"]), dense(tan["r_v"])]))
    n = system.n
    return np.block([[np.zeros((n, n)), np.eye(n)], [da]])
