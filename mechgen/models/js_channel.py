"""Johnson-Segalman fluid in a pressure-driven channel (seed 002, Khayat & Ashrafi; issue 28 item 3).

Walls at y = -1, 1 (half-width 1), stress in eta_p / lambda, time in lambda, velocity in (half-width) / lambda;
epsilon = eta_s / eta_p, xi the slip parameter, Re the Reynolds number, G the pressure gradient in stress units
per half-width. The flow u(y, t) along the channel and the polymer stresses obey

    Re u_t = G + epsilon u_yy + (tau_xy)_y,
    tau_xx_t = -tau_xx + (2 - xi) u_y tau_xy,   tau_yy_t = -tau_yy - xi u_y tau_xy,
    tau_xy_t = -tau_xy + u_y - (xi/2) u_y tau_xx + ((2 - xi)/2) u_y tau_yy,

with u = 0 at the walls. In a steady state the total shear stress is T = epsilon u_y + tau_xy = -G y, so the
shear rate at each y is a root of the local law's curve T(g) (mechgen.runtime.fluids.johnson_segalman): the
classical (low-rate) solution exists while the wall stress G stays below the curve's maximum (the spurt
threshold), and above it the rate jumps to the high branch at a position fixed by a selection rule (top- or
bottom-jumping). The model holds the parameters; the ``channel_flow`` analysis (mechgen.analyses.channel_flow)
computes the spurt threshold and the flow curve from the local law in closed form. Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("js_channel", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.06, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("Re", 0.0, "-", "Reynolds number (inertia; 0: none)", minimum=0.0),
    Param("G", 0.5, "-", "pressure gradient, in eta_p / lambda per half-width (the wall shear stress)", minimum=0.0),
)
