"""Rewrites of one block's write expressions ahead of CSE (part of the ``lower`` stage).

Input: the write expressions of a block, in gathered locals ``g0, g1, ...``.
Output (:func:`optimise`): CSE'd assignments ``t0, t1, ...`` and the reduced
write expressions, where

* a write equal to an earlier one, or to its negation, reuses it: the two ends of
  a bond get dV/du_a and dV/du_b = -dV/du_a, and the Hessian entries of a bond
  agree up to sign, so each is computed once into a temporary ``t`` and written
  as ``t`` or ``-t`` (sympy's CSE alone misses ``a - b`` against ``b - a``);
* an expression that is a polynomial in one linear form L = c_0 + sum_i c_i g_i
  of the locals (a bond strain u_b - u_a, or a single local) is put in Horner
  form in L when that needs fewer operations after CSE:
  gamma r + alpha r^2 + beta r^3 -> r*(gamma + r*(alpha + r*beta)) with r = u_b - u_a.
  Only the polynomial in L is re-associated; L itself is evaluated once, as
  written, so no cancellation between the locals is introduced.

Deterministic: candidates are tried in sympy's default sort order and the
temporaries are numbered in order of creation.
"""
from __future__ import annotations

import sympy as sp

from mechgen.stage_clock import timed_stage

#: Expressions larger than this (sympy's count_ops) are compared and rewritten as they stand.
MAX_OPS = 200
#: Operations (count_ops) of the expressions of one block offered to the Horner rewrite; the rest stay as
#: derived. Each offer costs a CSE per candidate form, so without a budget the rewrite dominates the build of a
#: large kernel (an n-link pendulum's tangent); the built-in models' blocks offer at most ~740.
HORNER_BUDGET = 1000


def _key(expr: sp.Expr) -> sp.Expr:
    """A canonical form for comparing writes: the expansion of small expressions."""
    return sp.expand(expr) if sp.count_ops(expr) <= MAX_OPS else expr


def share_writes(exprs: list[sp.Expr]) -> tuple[list[sp.Expr], list[tuple[int, int]]]:
    """Distinct expressions up to sign, and for each write (index into them, sign +1 or -1)."""
    reps: list[sp.Expr] = []
    refs: list[tuple[int, int]] = []
    seen: dict = {}
    for expr in exprs:
        key = _key(expr)
        if key in seen:
            refs.append((seen[key], 1))
        elif -key in seen:
            refs.append((seen[-key], -1))
        else:
            seen[key] = len(reps)
            refs.append((len(reps), 1))
            reps.append(expr)
    return reps, refs


def _linear_forms(expr: sp.Expr, local: set) -> list[tuple[sp.Expr, sp.Symbol]]:
    """Linear forms of the locals inside ``expr``, then the locals alone, as (form, its last local).

    A form c_0 + sum_i c_i g_i (numbers c) is scaled so that its last local has coefficient 1.
    """
    forms = {}
    for node in sp.preorder_traversal(expr):
        if not node.is_Add:
            continue
        terms = [t.as_coeff_Mul() for t in node.args]
        syms = {s: c for c, s in terms if s in local}
        if not syms or len(syms) + sum(1 for _, s in terms if s == 1) != len(terms):
            continue
        last = max(syms, key=sp.default_sort_key)
        scale = syms[last]
        form = sp.Add(last, *[(c / scale) * s for c, s in terms if s != last])
        forms.setdefault(form, last)
    singles = sorted(expr.free_symbols & local, key=sp.default_sort_key)
    return sorted(forms.items(), key=lambda f: sp.default_sort_key(f[0])) + [(s, s) for s in singles]


def _horner_in(expr: sp.Expr, form: sp.Expr, last: sp.Symbol, z: sp.Symbol) -> sp.Expr | None:
    """``expr`` as a Horner polynomial in ``z`` = the linear form ``form``, or None if it is not one."""
    others = form.free_symbols - {z}
    in_z = expr.xreplace({last: z - (form - last)})
    if in_z.free_symbols & others:
        in_z = sp.expand(in_z)
    if in_z.free_symbols & others or not in_z.is_polynomial(z):
        return None
    # coefficients that are not polynomials themselves (roots, quotients of parameters) stay plain
    # expressions: sympy's composite-domain construction for them costs minutes on a rational density
    exact = in_z.is_polynomial(*in_z.free_symbols)
    coeffs = (sp.Poly(in_z, z) if exact else sp.Poly(in_z, z, domain="EX")).all_coeffs()
    if len(coeffs) < 2:
        return None
    low = 0
    while coeffs[-1 - low] == 0:
        low += 1
    horner = coeffs[0]
    for c in coeffs[1:len(coeffs) - low]:
        horner = c + z * horner
    return z**low * horner


def operation_count(expr: sp.Expr) -> int:
    """Floating-point operations of ``expr`` as the printers write it (x**3 is x*x*x)."""
    if expr.is_Atom:
        return 0
    if expr.is_Pow and expr.exp.is_Integer and 1 < abs(int(expr.exp)) <= 8:
        exp = int(expr.exp)
        return abs(exp) - 1 + (exp < 0) + operation_count(expr.base)
    own = len(expr.args) - 1 if expr.is_Add or expr.is_Mul else 1
    return own + sum(operation_count(a) for a in expr.args)


def _cost(expr: sp.Expr) -> int:
    """Operations of ``expr`` after CSE."""
    subs, (reduced,) = sp.cse([expr])
    return sum(operation_count(e) for _, e in subs) + operation_count(reduced)


def horner(expr: sp.Expr, local: set, forms: dict) -> sp.Expr:
    """``expr`` in Horner form in the first linear form of the locals for which that is cheaper.

    The form enters as a symbol: ``forms`` maps each form used to its symbol (new ones are added).
    """
    if sp.count_ops(expr) > MAX_OPS or not expr.free_symbols & local:
        return expr
    cost = None
    for form, last in _linear_forms(expr, local):
        z = form if form.is_Symbol else forms.get(form, sp.Symbol(f"L{len(forms)}", real=True))
        rewritten = _horner_in(expr, form, last, z)
        if rewritten is None:
            continue
        cost = _cost(expr) if cost is None else cost
        if _cost(rewritten) + operation_count(form) < cost:
            if not form.is_Symbol:
                forms.setdefault(form, z)
            return rewritten
    return expr


def horner_within_budget(exprs: list[sp.Expr], local: set, forms: dict) -> list[sp.Expr]:
    """:func:`horner` on the expressions in order until they have offered :data:`HORNER_BUDGET` operations."""
    spent, out = 0, []
    for expr in exprs:
        ops = sp.count_ops(expr) if spent <= HORNER_BUDGET else MAX_OPS + 1
        offered = ops <= MAX_OPS and spent + ops <= HORNER_BUDGET
        spent += ops if offered else 0
        out.append(horner(expr, local, forms) if offered else expr)
    return out


def optimise(exprs: list[sp.Expr], local: set) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """Assignments and reduced expressions for ``exprs``: shared up to sign, Horner, CSE.

    Temporaries are ``t0, t1, ...``: the linear forms of the Horner rewrites first,
    then sympy's CSE (canonical order), then shared writes.
    """
    reps, refs = share_writes(exprs)
    forms: dict = {}
    with timed_stage("rewrite"):
        reps = horner_within_budget(reps, local, forms)
    with timed_stage("cse"):
        subs, reduced = sp.cse(reps, symbols=sp.numbered_symbols("c", real=True), order="canonical")
    assignments = [(z, form) for form, z in forms.items()] + list(subs)
    uses = [sum(1 for r, _ in refs if r == i) for i in range(len(reps))]
    for i, expr in enumerate(reduced):
        if uses[i] > 1 and not (expr.is_Atom or (-expr).is_Atom):
            temp = sp.Symbol(f"s{i}", real=True)
            assignments.append((temp, expr))
            reduced[i] = temp
    rename = {s: sp.Symbol(f"t{k}", real=True) for k, (s, _) in enumerate(assignments)}
    assignments = [(rename[s], e.xreplace(rename)) for s, e in assignments]
    return assignments, [sign * reduced[r].xreplace(rename) for r, sign in refs]
