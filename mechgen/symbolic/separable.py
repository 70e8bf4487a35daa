"""Is H = T(v) + V(q) separable with a constant diagonal mass? The fact the splitting methods rest on.

The leapfrog and the other splittings (mechgen.runtime.core.splitting) integrate

    q'' = M^-1 f(q),   f = -dV/dq,   M = diag(m_1 .. m_n) constant,

i.e. Lagrange's equations of L = sum_i m_i v_i^2 / 2 - V(q) with no dissipation and no other force. A
model is fit for them only when its derived equations are exactly these: T = v^T M v / 2 with M = d2T/dv2
free of q, v, t and of the internal variables, diagonal, and the residual r = M a + dV/dq (nothing else:
no Rayleigh dissipation, no generalised force, no gyroscopic term), V free of t, v and z (the force kernel is
evaluated at t = 0). :func:`separable_obstacle` decides this symbolically on the specialised equations (a
sum that is zero only by a trigonometric identity is taken as nonzero: a refusal, never a wrong run) and
returns why not, or None.
"""
from __future__ import annotations

import sympy as sp


def _depends(expr: sp.Expr, symbols) -> list[str]:
    """Names of ``symbols`` that ``expr`` (expanded) depends on."""
    free = sp.expand(expr).free_symbols if expr != 0 else set()
    return [s.name for s in symbols if s in free]


def _zero(expr: sp.Expr) -> bool:
    """True when ``expr`` expands to exactly zero (no identity beyond polynomial expansion is tried)."""
    return expr == 0 or sp.expand(expr) == 0


def diagonal_masses(T: sp.Expr, v) -> list | None:
    """The m_i of T = sum_i m_i v_i^2 / 2, read off T as a polynomial in v (no Hessian is formed: a 200-coordinate
    lattice's took 34 s), or None where T is not of that form in v (not a polynomial, a cross term v_i v_j, a
    term of other degree). The m_i may still depend on q, t or z: the caller checks."""
    try:
        poly = sp.Poly(T, *v)
    except sp.PolynomialError:
        return None
    masses = [sp.Integer(0)] * len(v)
    for monom, coef in poly.terms():
        if sum(monom) != 2 or max(monom) != 2:
            return None
        masses[monom.index(2)] = 2 * coef
    return masses


def mass_obstacle(T: sp.Expr, q, v, others, coordinates) -> str | None:
    """Why T is not v^T M v / 2 with a constant diagonal M (``others``: t and the internal variables), or None.
    The form is read off T's polynomial in v where it has it (:func:`diagonal_masses`); the Hessian is taken
    only to name what breaks it."""
    masses = diagonal_masses(T, v) if v else None
    if masses is not None and not any(_depends(m, (*q, *others)) for m in masses):
        return None
    M = sp.hessian(T, list(v)) if v else sp.zeros(0, 0)
    moving = sorted({name for e in M for name in _depends(e, (*q, *v, *others))})
    if moving:
        return f"its mass matrix d2T/dv2 depends on {', '.join(moving)}"
    for i in range(len(v)):
        for j in range(i):
            if not _zero(M[i, j]):
                return (f"its mass matrix is not diagonal (the entry of {coordinates[i]} and {coordinates[j]} is "
                        f"{M[i, j]})")
    quad = sum((M[i, i] * v[i] ** 2 for i in range(len(v))), sp.Integer(0)) / 2
    if not _zero(T - quad):
        return "its kinetic energy is not a quadratic form v^T M v / 2 (it has terms of other order in v)"
    return None


def separable_obstacle(T: sp.Expr, V: sp.Expr, residual: sp.Matrix, q, v, a, others, coordinates) -> str | None:
    """Why Lagrange's equations ``residual`` of T, V are not q'' = M^-1 (-dV/dq) with constant diagonal M.

    None when r = M a + dV/dq exactly, M = d2T/dv2 constant and diagonal, T = v^T M v / 2 and V free of v, t and
    the internal variables; else a clause naming what breaks it (the mass, the potential, or the terms of
    dissipation, forces or gyroscopic coupling that the splittings' force -dV/dq leaves out).
    """
    why = mass_obstacle(T, q, v, others, coordinates)
    if why:
        return why
    names = _depends(V, (*v, *others))
    if names:
        return f"its potential energy depends on {', '.join(names)} (the force -dV/dq is evaluated at t = 0)"
    M = sp.hessian(T, list(v)) if v else sp.zeros(0, 0)
    grad = sp.Matrix([sp.diff(V, s) for s in q])
    extra = residual - M * sp.Matrix(a) - grad
    for i, e in enumerate(extra):
        if not _zero(e):
            return (f"its equation of {coordinates[i]} has terms besides M a + dV/dq (dissipation, a generalised "
                    "force or gyroscopic coupling) that the splitting's force -dV/dq leaves out")
    return None


def declared_obstacle(T: sp.Expr, V: sp.Expr, R: sp.Expr, Q: list, q, v, others, coordinates) -> str | None:
    """:func:`separable_obstacle` decided on the declared pieces (T, V, Rayleigh's R, the forces Q) instead of the
    derived residual, for a model derived by algorithmic differentiation (mechgen.symbolic.derive_ad): a kinetic
    energy that names a coordinate, t or an internal variable is refused before its Hessian is taken (the mass
    matrix of a large multibody model is never formed symbolically); then r = M a + dV/dq exactly when R = 0
    and Q = 0 (M constant: Lagrange's velocity terms vanish)."""
    moving = sorted(s.name for s in T.free_symbols & {*q, *others})
    if moving:
        return f"its kinetic energy depends on {', '.join(moving)} (its mass matrix is not constant)"
    why = mass_obstacle(T, q, v, others, coordinates)
    if why:
        return why
    names = _depends(V, (*v, *others))
    if names:
        return f"its potential energy depends on {', '.join(names)} (the force -dV/dq is evaluated at t = 0)"
    for i, extra in enumerate(Q):
        if not _zero(extra) or not _zero(sp.diff(R, v[i])):
            return (f"its equation of {coordinates[i]} has terms besides M a + dV/dq (dissipation, a generalised "
                    "force or gyroscopic coupling) that the splitting's force -dV/dq leaves out")
    return None


def lattice_obstacle(T: sp.Expr, site_V: sp.Expr, bond_V: sp.Expr, q: sp.Symbol, v: sp.Symbol,
                     coordinate: str) -> str | None:
    """Why a chain's site kinetic energy T_s(u, u') is not m u'^2 / 2 with a constant m, or its site or bond
    potential depends on a velocity (a chain has no other term, and its mass matrix is diagonal), or None."""
    why = mass_obstacle(T, (q,), (v,), (), (coordinate,))
    if why:
        return "its site " + why.removeprefix("its ")
    # the bond's velocity symbols as mechgen.symbolic.lattice.derive_lattice names them
    velocities = (v, *(sp.Symbol(f"{coordinate}_{end}_dot", real=True) for end in ("a", "b")))
    for what, expr in (("site", site_V), ("bond", bond_V)):
        names = _depends(expr, velocities)
        if names:
            return f"its {what} potential depends on {', '.join(names)}"
    return None
