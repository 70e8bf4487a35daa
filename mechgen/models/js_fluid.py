"""Johnson-Segalman fluid in a pressure-driven channel, declared as four fields and a weak form (issue 28 item 1).

The same flow as ``js_channel`` (seed 002, Khayat & Ashrafi), written the way a user writes a non-variational
continuum: the velocity u(s, t) along the channel and the three polymer stresses tau_xx, tau_yy, tau_xy are
fields on s in [0, width] (s = y + 1: walls at y = -1, 1, half-width 1), and the momentum balance and the
constitutive law are one weak form. Stress in eta_p / lambda, time in lambda, velocity in (half-width) / lambda;
epsilon = eta_s / eta_p, xi the slip parameter of the Gordon-Schowalter derivative, Re the Reynolds number (0: no
inertia), G the pressure gradient in stress units per half-width, diffusion a stress diffusivity (0: none). With
g = u_s,

    Re u_t = G + epsilon u_ss + (tau_xy)_s,                         u = 0 at both walls,
    tau_xx_t = -tau_xx + (2 - xi) g tau_xy                + diffusion (tau_xx)_ss,
    tau_yy_t = -tau_yy - xi g tau_xy                      + diffusion (tau_yy)_ss,
    tau_xy_t = -tau_xy + g (1 - xi/2 tau_xx + (2 - xi)/2 tau_yy) + diffusion (tau_xy)_ss,

each multiplied by its test function and integrated over the channel, the second derivatives by parts (the
momentum's boundary term vanishes with the test function at the walls; the stresses' is the no-flux condition of
the diffusion). The model has no kinetic energy: every field obeys a first-order law, so the Galerkin
linearisation is K + lambda D (D singular when Re = 0: u is then slaved to the stresses, and its infinite
eigenvalues are dropped). The generic analyses run it: ``steady`` (Newton), ``stability`` (the spectrum, checked
at twice the size), ``continuation`` in G (its first fold tends to the spurt threshold T_max of the local shear
curve as the mesh is refined, at first order in the element size: the wall element's shear rate reaches the
curve's maximum while G exceeds it by O(h)).

The combination xi tau_xx + (2 - xi) tau_yy obeys c_t = -c exactly (without diffusion): the three-stress law leaves
the invariant manifold c = 0 at rate -1, an eigenvalue of multiplicity one per stress node (``js_local`` and
``js_local_reduced`` show the same on the local law). Dimensionless.
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("js_fluid", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.06, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("Re", 1.0, "-", "Reynolds number (inertia; 0: none)", minimum=0.0),
    Param("G", 0.5, "-", "pressure gradient, in eta_p / lambda per half-width (the wall shear stress)", minimum=0.0),
    Param("diffusion", 0.0, "-", "stress diffusivity, in (half-width)^2 / lambda (0: none)", minimum=0.0),
    Param("width", 2.0, "-", "channel width (twice the half-width, the length unit)", positive=True),
)
model.field("u", "txx", "tyy", "txy", length="width", discretisation="lagrange2", N=16)


@model.weak_form
def balance(test, u, p):
    """Momentum and the three stress laws, times their test functions (second derivatives by parts)."""
    g = u.u_s
    momentum = test.u * (p.Re * u.u_t - p.G) + test.u_s * (p.epsilon * g + u.txy)
    xx = test.txx * (u.txx_t + u.txx - (2 - p.xi) * g * u.txy) + p.diffusion * test.txx_s * u.txx_s
    yy = test.tyy * (u.tyy_t + u.tyy + p.xi * g * u.txy) + p.diffusion * test.tyy_s * u.tyy_s
    xy = (test.txy * (u.txy_t + u.txy - g * (1 - p.xi / 2 * u.txx + (2 - p.xi) / 2 * u.tyy))
          + p.diffusion * test.txy_s * u.txy_s)
    return momentum + xx + yy + xy


@model.boundary
def boundary():
    """No slip at both walls."""
    return [fix("u", "start"), fix("u", "end")]


model.output("flow_rate", lambda u: u.u, integrate=True, doc="Q = integral of u across the channel")
model.output("first_normal_stress_integral", lambda u: u.txx - u.tyy, integrate=True,
             doc="integral of N1 = tau_xx - tau_yy across the channel")
