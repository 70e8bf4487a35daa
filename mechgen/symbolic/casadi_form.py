"""Declared sympy expressions -> CasADi SX graphs, sharing every repeated subexpression.

A model's energies are sympy trees in which a subexpression written once by the user (a velocity
x_k' = x_{k-1}' + l cos(theta_k) theta_k' reused by every later mass) appears many times; sympy's
derivatives then traverse each copy. :func:`to_sx` converts such a tree node by node with a memo keyed by
the (hash-consed) sympy node, so each distinct subexpression becomes one SX node and CasADi's algorithmic
differentiation (mechgen.symbolic.derive_ad) works on a graph of the size of the model.

Only smooth elementary functions and Abs/sign convert; anything else (Piecewise, Heaviside, Min/Max,
special functions) raises :class:`NotConvertible`, and the model is derived symbolically as before.
"""
from __future__ import annotations

import casadi as ca
import sympy as sp


#: sums of more terms are not built on a previous sum (each step of such a chain nests one Python call)
_MAX_CHAIN = 400


class NotConvertible(ValueError):
    """An expression holds a function the CasADi path does not convert (the reason is the message)."""


_UNARY = {sp.sin: ca.sin, sp.cos: ca.cos, sp.tan: ca.tan, sp.exp: ca.exp, sp.log: ca.log, sp.sinh: ca.sinh,
          sp.cosh: ca.cosh, sp.tanh: ca.tanh, sp.asin: ca.asin, sp.acos: ca.acos, sp.atan: ca.atan,
          sp.asinh: ca.asinh, sp.acosh: ca.acosh, sp.atanh: ca.atanh, sp.Abs: ca.fabs, sp.sign: ca.sign}


class SXForm:
    """Converter of sympy expressions in given symbols to SX, one SX node per distinct sympy node."""

    def __init__(self, symbols: dict[sp.Symbol, ca.SX]) -> None:
        self.memo: dict = dict(symbols)
        #: the SX of every sum converted so far, by the set of its terms (:meth:`_sum`)
        self.sums: dict[frozenset, ca.SX] = {}
        #: the sums of the expression being converted, by the set of their terms
        self.present: dict[frozenset, sp.Add] = {}

    def __call__(self, expr) -> ca.SX:
        """The SX of ``expr`` (a sympy expression in the symbols given at construction)."""
        expr = sp.sympify(expr)
        self.present = {frozenset(n.args): n for n in _sums(expr, self.memo)}
        return self._convert(expr)

    def _convert(self, expr) -> ca.SX:
        stack = [expr]
        while stack:  # post-order without recursion: deep user expressions do not hit Python's recursion limit
            node = stack[-1]
            if node in self.memo:
                stack.pop()
                continue
            pending = [a for a in node.args if a not in self.memo]
            if pending and not node.is_Number:
                stack.extend(pending)
                continue
            stack.pop()
            self.memo[node] = self._node(node)
        return self.memo[expr]

    def _node(self, node) -> ca.SX:
        if node.is_Number or node.is_NumberSymbol:
            return ca.SX(float(node))
        if node.is_Symbol:
            raise NotConvertible(f"symbol {node} is not a state, time or parameter symbol")
        args = [self.memo[a] for a in node.args]
        if node.is_Add:
            return self._sum(node)
        if node.is_Mul:
            return _fold(args, lambda x, y: x * y)
        if node.is_Pow:
            return _power(node, args)
        if node.func in _UNARY:
            return _UNARY[node.func](args[0])
        if node.func == sp.atan2:
            return ca.atan2(args[0], args[1])
        raise NotConvertible(f"{node.func.__name__} is not converted to CasADi")


    def _sum(self, node: sp.Add) -> ca.SX:
        """A sum, built on an earlier sum of all its terms but one where there is one.

        sympy flattens x_k' = x_{k-1}' + l cos(theta_k) theta_k' into one sum of k terms, losing the sharing the
        user wrote (a chain's velocities, each the previous one plus a link's); finding the previous sum among the
        converted ones restores it, so the graph of a chain's kinetic energy grows like n, not n^2."""
        terms = frozenset(node.args)
        if len(terms) > 2:
            for a in node.args:
                rest = terms - {a}
                if rest not in self.sums and rest in self.present and len(rest) < _MAX_CHAIN:
                    self._convert(self.present[rest])  # a chain of sums: depth up to its length
                if rest in self.sums:
                    self.sums[terms] = self.sums[rest] + self.memo[a]
                    return self.sums[terms]
        self.sums[terms] = _fold([self.memo[a] for a in node.args], lambda x, y: x + y)
        return self.sums[terms]


def _sums(expr, done: dict) -> list:
    """The sums inside ``expr`` not converted yet."""
    seen, order, stack = set(), [], [expr]
    while stack:
        node = stack.pop()
        if node in seen or node in done:
            continue
        seen.add(node)
        if node.is_Add:
            order.append(node)
        stack.extend(node.args)
    return order


def _fold(args: list, op) -> ca.SX:
    out = args[0]
    for a in args[1:]:
        out = op(out, a)
    return out


def _power(node: sp.Pow, args: list) -> ca.SX:
    """x**n: integer n as repeated products (CasADi's constpow), 1/2 as sqrt, else pow."""
    base, exp = args
    e = node.exp
    if e == sp.Rational(1, 2):
        return ca.sqrt(base)
    if e == -1:
        return 1 / base
    if e.is_Integer:
        return ca.constpow(base, float(e))
    return ca.power(base, exp)
