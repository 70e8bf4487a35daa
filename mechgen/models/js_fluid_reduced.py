"""Johnson-Segalman channel as fields, the seed's two-stress form (Khayat & Ashrafi, eqs. 5; issue 28 item 1).

``js_fluid`` restricted to its invariant manifold W = xi tau_xx + (2 - xi) tau_yy = 0, in the normal stress
difference N = tau_xx - tau_yy (field ``N1``) and the shear stress S = tau_xy (field ``txy``), as the seed writes
it (stress in eta_p / lambda, time in lambda, s = y + 1 across the channel of half-width 1, g = u_s):

    Re u_t = G + epsilon u_ss + S_s,                 u = 0 at both walls,
    N_t = -N + 2 g S            + diffusion N_ss,
    S_t = -S + g (1 + a N)      + diffusion S_ss,    a = xi (xi/2 - 1),

as one weak form (second derivatives by parts). Its steady states are js_fluid's, and its spectrum is js_fluid's
without the eigenvalue -1 of W at every stress node (tests/test_js_fluid.py). Dimensionless.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("js_fluid_reduced", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.06, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("Re", 1.0, "-", "Reynolds number (inertia; 0: none)", minimum=0.0),
    Param("G", 0.5, "-", "pressure gradient, in eta_p / lambda per half-width (the wall shear stress)", minimum=0.0),
    Param("diffusion", 0.0, "-", "stress diffusivity, in (half-width)^2 / lambda (0: none)", minimum=0.0),
    Param("width", 2.0, "-", "channel width (twice the half-width, the length unit)", positive=True),
)
model.field("u", "N1", "txy", length="width", discretisation="lagrange2", N=16)


@model.weak_form
def balance(test, u, p):
    """Momentum and the seed's two stress laws, times their test functions (second derivatives by parts)."""
    g = u.u_s
    momentum = test.u * (p.Re * u.u_t - p.G) + test.u_s * (p.epsilon * g + u.txy)
    normal = test.N1 * (u.N1_t + u.N1 - 2 * g * u.txy) + p.diffusion * test.N1_s * u.N1_s
    shear = (test.txy * (u.txy_t + u.txy - g * (1 + p.xi * (p.xi / 2 - 1) * u.N1))
             + p.diffusion * test.txy_s * u.txy_s)
    return momentum + normal + shear


@model.boundary
def boundary():
    """No slip at both walls."""
    return [fix("u", "start"), fix("u", "end")]


model.output("flow_rate", lambda u: u.u, integrate=True, doc="Q = integral of u across the channel")
model.output("first_normal_stress_integral", lambda u: u.N1, integrate=True,
             doc="integral of N1 = tau_xx - tau_yy across the channel")
