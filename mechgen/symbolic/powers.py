"""Powers of a signed quantity with derivatives that stay finite at zero (contact laws, Hertz, Hunt-Crossley).

    signed_power(x, n) = sign(x) |x|^n,     d/dx = n abs_power(x, n - 1),
    abs_power(x, n)    = |x|^n,             d/dx = n signed_power(x, n - 1).

Written with sympy's Abs and sign, the derivative of |x|^n comes out as n |x|^n sign(x) / |x|, which is
0/0 at x = 0 (a contact starts there); these functions carry the simplified derivative instead, so the
stiffness n |x|^(n-1) of a contact force sign(x) |x|^n is 0 at first touch for n > 1. The printers
(mechgen.codegen.printing) write them as ``copysign(pow(fabs(x), n), x)`` and ``pow(fabs(x), n)``.
"""
from __future__ import annotations

import sympy as sp


class signed_power(sp.Function):  # noqa: N801 - printed by name
    """sign(x) |x|^n (odd extension of x^n)."""

    nargs = 2

    def fdiff(self, argindex=1):
        x, n = self.args
        if argindex == 1:
            return n * abs_power(x, n - 1)
        return sp.log(sp.Abs(x)) * self  # d/dn

    @classmethod
    def eval(cls, x, n):
        if n == 1:
            return x
        if x.is_number and n.is_number:
            return sp.sign(x) * sp.Abs(x) ** n


class abs_power(sp.Function):  # noqa: N801 - printed by name
    """|x|^n (even extension of x^n)."""

    nargs = 2

    def fdiff(self, argindex=1):
        x, n = self.args
        if argindex == 1:
            return n * signed_power(x, n - 1)
        return sp.log(sp.Abs(x)) * self

    @classmethod
    def eval(cls, x, n):
        if n == 0:
            return sp.Integer(1)
        if x.is_number and n.is_number:
            return sp.Abs(x) ** n
