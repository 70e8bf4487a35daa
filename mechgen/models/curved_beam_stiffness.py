"""Cross-section stiffness of a curved beam: a circular arc of radius r with a square section of side b.

Seed 001 (Grazioso, "Modeling of a soft link", slides 20-25): the reference curve is the arc
u0(s) = (r cos(s/r), r sin(s/r), 0), so kappa0 = 1/r, tau0 = 0 and f0 = (e1, e3/r); the section's
stiffness is K = int_A D^T C D da2 da3 over the square |a2|, |a3| <= b/2 from the isotropic law with
Lame constants lam, mu (mechgen.symbolic.cross_section, transverse stresses condensed:
E = mu (3 lam + 2 mu)/(lam + mu)). With beta = kappa0 b = b/r:

    c1 = 4/(4 - beta^2),   c2 = 12/beta^3 (2 ln((2 - beta)/(2 + beta)) + (1 + c1) beta),
    c3 = 1/beta^2 (ln((2 - beta)/(2 + beta)) + c1 beta),
    K_uu = c1 diag(E b^2, mu b^2, mu b^2),   K_ww = diag(mu b^4 (c1 + c2)/12, c1 E b^4/12, c2 E b^4/12),
    K_uw: K[u1, w3] = -c3 E b^3, K[u3, w1] = c3 mu b^3 (all other couplings zero).

Defined for beta < 2 (the section short of the centre of curvature). SI units: K_uu in N, K_uw in N m,
K_ww in N m^2. The ``cross_section`` analysis reports K.
"""
from mechgen.symbolic.cross_section import Square, cross_section_stiffness
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("curved_beam_stiffness", doc=__doc__, file=__file__)
model.params(
    Param("r", 0.5, "m", "radius of the arc (the reference curve)", positive=True),
    Param("b", 0.1, "m", "side of the square section", positive=True),
    Param("lam", 2.0e6, "Pa", "Lame's first constant"),
    Param("mu", 1.0e6, "Pa", "shear modulus (Lame's second constant)", positive=True),
)


@model.section_stiffness
def stiffness(p):
    return cross_section_stiffness(p.lam, p.mu, Square(p.b), kappa0=1 / p.r)
