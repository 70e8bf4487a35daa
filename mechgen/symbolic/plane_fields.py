"""Declared analytic fields of plane elasticity, as sympy expressions of the position (x, y): the exact stresses
of closed-form solutions, for tractions a model applies on its boundary (the cracked plate loaded by the
Griffith solution's own tractions, so that the finite plate carries the infinite plate's field exactly).

The Griffith crack |x| < a, y = 0 in an infinite plate under remote sigma11, sigma22, sigma12 (Westergaard's
functions Z = c z / X, c = sigma22 (mode I) or sigma12 (mode II), X = sqrt(z - a) sqrt(z + a) the branch cut
on the crack with X ~ z at infinity):

    mode I:  s_xx = Re Z - y Im Z',  s_yy = Re Z + y Im Z',  s_xy = -y Re Z',
    mode II: s_xx = 2 Im Z + y Re Z',  s_yy = -y Re Z',  s_xy = Re Z - y Im Z',
    plus the uniform s_xx = sigma11 - sigma22 (the T-stress), Z' = -c a^2 / X^3.

In real arithmetic X = rho e^{i phi} with rho = sqrt(r1 r2), phi = (atan2(y, x - a) + atan2(y, x + a))/2
(principal arguments: the sum jumps by 4 pi on x < -a, so phi is continuous there, and by 2 pi on the crack,
where X changes sign: the cut). Checked against mechgen.runtime.plane.closed_forms.griffith_field (Muskhelishvili's
potentials, an independent construction) in tests/test_plane_cracked.py.
"""
from __future__ import annotations

import sympy as sp


def _westergaard(x, y, a):
    """(Re, Im) of z/X and of 1/X^3 for the crack |x| < a."""
    rho = sp.sqrt(sp.sqrt((x - a) ** 2 + y**2) * sp.sqrt((x + a) ** 2 + y**2))
    phi = (sp.atan2(y, x - a) + sp.atan2(y, x + a)) / 2
    c, s = sp.cos(phi), sp.sin(phi)
    A = ((x * c + y * s) / rho, (y * c - x * s) / rho)
    B = (sp.cos(3 * phi) / rho**3, -sp.sin(3 * phi) / rho**3)
    return A, B


def griffith_stress(x, y, a, sigma11, sigma22, sigma12) -> sp.Matrix:
    """The Griffith crack's exact stress [[s_xx, s_xy], [s_xy, s_yy]] at (x, y) (Pa), per the module doc."""
    (reA, imA), (reB, imB) = _westergaard(x, y, a)
    # mode I: Z = s22 z/X, Z' = -s22 a^2 / X^3
    reZ1, reD1, imD1 = sigma22 * reA, -sigma22 * a**2 * reB, -sigma22 * a**2 * imB
    # mode II: Z = s12 z/X
    reZ2, imZ2, reD2, imD2 = sigma12 * reA, sigma12 * imA, -sigma12 * a**2 * reB, -sigma12 * a**2 * imB
    sxx = reZ1 - y * imD1 + 2 * imZ2 + y * reD2 + (sigma11 - sigma22)
    syy = reZ1 + y * imD1 - y * reD2
    sxy = -y * reD1 + reZ2 - y * imD2
    return sp.Matrix([[sxx, sxy], [sxy, syy]])
