"""Plane Poiseuille flow between walls at y = -1 and y = 1 and its linear stability (Orr-Sommerfeld).

The base flow U(y) = 1 - y^2 (velocities in the centreline velocity U_c, lengths in the half-width h,
Re = U_c h / nu) is disturbed by a stream function psi = v(y) exp(i alpha (x - c t)); linearising the
Navier-Stokes equations gives the Orr-Sommerfeld equation

    (U - c)(v'' - alpha^2 v) - U'' v = (v'''' - 2 alpha^2 v'' + alpha^4 v) / (i alpha Re),
    v = v' = 0 at y = -1, 1   (no slip),

an eigenproblem for the complex wave speed c; the flow is unstable where Im c > 0. The model holds the
two parameters; the ``orr_sommerfeld`` analysis (mechgen.analyses.orr_sommerfeld) solves the problem by
Chebyshev collocation (mechgen.runtime.linear.orr_sommerfeld). Orszag (1971, J. Fluid Mech. 50:689):
c = 0.23752649 + 0.00373967 i at alpha = 1, Re = 10^4; the critical Re = 5772.22 at alpha = 1.02056.
Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("plane_poiseuille", doc=__doc__, file=__file__)
model.params(
    Param("alpha", 1.0, "-", "streamwise wavenumber alpha h", positive=True),
    Param("Re", 1.0e4, "-", "Reynolds number U_c h / nu (centreline velocity, half-width)", positive=True),
)
