"""Johnson-Segalman fluid in a pressure-driven channel (seed 002, Khayat & Ashrafi; issue 28 items 3, 4).

Walls at y = -1, 1 (half-width 1), stress in eta_p / lambda, time in lambda, velocity in (half-width) / lambda;
epsilon = eta_s / eta_p, xi the slip parameter, Re the Reynolds number, G the pressure gradient in stress units
per half-width. The flow u(y, t) along the channel and the polymer stresses obey

    Re u_t = G + epsilon u_yy + (tau_xy)_y,                        u = 0 at y = -1, 1,
    tau_xx_t = -tau_xx + (2 - xi) g tau_xy,   tau_yy_t = -tau_yy - xi g tau_xy,
    tau_xy_t = -tau_xy + g - (xi/2) g tau_xx + ((2 - xi)/2) g tau_yy,       g = u_y.

The model declares the local piece: the three stress laws at one point, at the imposed shear rate
``shear_rate`` (g); the analyses repeat it over the channel (``channel_spectrum``: its Jacobian at each
collocation point, the momentum balance assembled by Chebyshev collocation). In a steady state the total shear
stress is epsilon g + tau_xy = -G y, so the shear rate at each y is a root of the local shear curve
T(g) = epsilon g + g / (1 + xi (2 - xi) g^2) (mechgen.runtime.fluids.johnson_segalman): the classical solution
exists while the wall stress G stays below its maximum (the spurt threshold); ``channel_flow`` gives it and the
flow curve. Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("js_channel", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.06, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("Re", 0.0, "-", "Reynolds number (inertia; 0: none)", minimum=0.0),
    Param("G", 0.5, "-", "pressure gradient, in eta_p / lambda per half-width (the wall shear stress)", minimum=0.0),
    Param("shear_rate", 0.0, "-", "the local shear rate g = u_y at which the stress laws are evaluated"),
)

model.internal("txx", lambda z, p: -z.txx + (2 - p.xi) * p.shear_rate * z.txy, doc="polymer normal stress tau_xx")
model.internal("tyy", lambda z, p: -z.tyy - p.xi * p.shear_rate * z.txy, doc="polymer normal stress tau_yy")
model.internal("txy", lambda z, p: -z.txy + p.shear_rate * (1 - p.xi / 2 * z.txx + (2 - p.xi) / 2 * z.tyy),
               doc="polymer shear stress tau_xy")
model.output("normal_stress_difference", lambda z: z.txx - z.tyy, doc="N = tau_xx - tau_yy")
