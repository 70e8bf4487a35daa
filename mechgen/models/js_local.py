"""Johnson-Segalman fluid under an imposed total shear stress: the local (homogeneous shear) dynamics.

Seed 002 (Khayat & Ashrafi, eqs. 3-5). A fluid of polymer viscosity eta_p, relaxation time lambda and solvent
viscosity epsilon eta_p, with the Gordon-Schowalter derivative of slip parameter xi (0 Oldroyd-B, 2 Jaumann),
sheared at the rate g = du/dy. Stress in eta_p / lambda, time in lambda, rate in 1 / lambda. The polymer
stresses obey tau + lambda (Gordon-Schowalter derivative of tau) = 2 eta_p D; in simple shear:

    tau_xx' = -tau_xx + (2 - xi) g tau_xy,
    tau_yy' = -tau_yy - xi g tau_xy,
    tau_xy' = -tau_xy + g - (xi/2) g tau_xx + ((2 - xi)/2) g tau_yy,

and the imposed total shear stress T = epsilon g + tau_xy fixes g = (T - tau_xy) / epsilon (epsilon > 0).
Equilibria: tau_xy = g / (1 + k g^2), k = xi (2 - xi), so T = epsilon g + g / (1 + k g^2), the steady shear
curve, an S-curve in (T, g) for epsilon < 1/8 whose two folds are its extrema. W = xi tau_xx + (2 - xi) tau_yy
obeys W' = -W exactly: the seed's two-stress system (N = tau_xx - tau_yy, S = tau_xy:
N' = -N + 2 g S, S' = -S + g (1 + a N), a = xi (xi/2 - 1)) is the restriction to the invariant plane W = 0,
and the three-stress model carries the constant eigenvalue -1 off it. Closed forms, the extrema and the
no-Hopf verdict: mechgen.runtime.fluids.johnson_segalman. Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("js_local", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.06, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("T", 0.1, "-", "imposed total shear stress, in eta_p / lambda"),
)


def rate(z, p):
    """The shear rate g = (T - tau_xy) / epsilon."""
    return (p.T - z.txy) / p.epsilon


model.internal("txx", lambda z, p: -z.txx + (2 - p.xi) * rate(z, p) * z.txy, doc="polymer normal stress tau_xx")
model.internal("tyy", lambda z, p: -z.tyy - p.xi * rate(z, p) * z.txy, doc="polymer normal stress tau_yy")
model.internal("txy", lambda z, p: -z.txy + rate(z, p) * (1 - p.xi / 2 * z.txx + (2 - p.xi) / 2 * z.tyy),
               doc="polymer shear stress tau_xy")


@model.initial
def rest(p):
    """The fluid at rest (zero polymer stresses)."""
    return {"txx": 0, "tyy": 0, "txy": 0}


model.output("shear_rate", rate, doc="shear rate g = (T - tau_xy) / epsilon, in 1 / lambda")
model.output("normal_stress_difference", lambda z: z.txx - z.tyy, doc="N = tau_xx - tau_yy")
model.output("polymer_shear_stress", lambda z: z.txy, doc="S = tau_xy")
model.output("off_manifold", lambda z, p: p.xi * z.txx + (2 - p.xi) * z.tyy,
             doc="W = xi tau_xx + (2 - xi) tau_yy (zero on the seed's invariant plane)")
