"""Ballooning hyperelastic string between a fixed and a rotating eyelet (Sarangi, Bhattacharyya & Samantaray).

Nondimensional (lengths by the eyelet radius a, time by 1/omega, tension by
rho A0 omega^2 a^2; beta = E / (rho omega^2 a^2)). The undeformed length is
l0 = h / (1 - lambda0) (lambda0 = (l0 - h)/l0, the paper's length parameter).
Fields x, y, z(sigma, t): the position, in the frame {e1, e2, e3} spinning at unit
rate about e3, of the material point at undeformed arclength s = l0 sigma,
sigma in [0, 1] (the domain length L = 1: so that lambda0 is an ordinary parameter
that branches can follow); the mass per unit s is 1. The fixed (guide) eyelet is
at the origin, the rotating eyelet at e1 + h e3. With r = (x, y, z), stretch
lambda = |r_s| = |r_sigma| / l0 and the frame velocity e3 x r
(mechgen.symbolic.kinematics.frame_velocity), per unit sigma:

    T = l0/2 |r_t + e3 x r|^2,   V = l0 W(lambda),   R = l0 drag/2 |r_t + e3 x r|^2,

    neo-Hookean  W = beta/3 (lambda^2/2 + 1/lambda),  tension p = W'(lambda) = beta/3 (lambda - lambda^-2),
    linear       W = beta/2 (lambda - 1)^2,           p = beta (lambda - 1).

R is a linear air drag on the inertial velocity (zero by default: it then
disappears from the generated code). Steady balloons solve
(p r_s / lambda)_s + (x, y, 0) = drag e3 x r with r(0) = 0, r(l0) = (1, 0, h)
(mechgen.symbolic.steady); small motions about one obey
u_tt + 2 e3 x u_t - (A u_s)_s - diag(1, 1, 0) u = 0 with
A = (p/lambda) I + (p' - p/lambda) t t^T, t = r_s/lambda, and u = 0 at both eyelets
(Galerkin with sin(j pi sigma), N per component). Outputs: ``tension`` p,
``stretch`` lambda, ``radius`` sqrt(x^2 + y^2).
"""
import sympy as sp

from mechgen.errors import ModelError
from mechgen.symbolic.field import fix
from mechgen.symbolic.kinematics import frame_velocity
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("balloon_string", doc=__doc__, file=__file__)
model.params(
    Param("h", 10.0, "", "axial distance of the eyelets / a", positive=True),
    Param("beta", 100.0, "", "stiffness E / (rho omega^2 a^2)", positive=True),
    Param("lambda0", 0.0, "", "length parameter (l0 - h)/l0, below 1", below=1.0),
    Param("L", 1.0, "", "domain length in sigma = s / l0 (keep 1)", positive=True),
    Param("drag", 0.0, "", "linear air drag coefficient"),
    Param("law", "neo_hookean", "", "constitutive law", choices=("neo_hookean", "linear", "inextensible")),
)
model.field("x", "y", "z", length="L", discretisation="sine", N=10)


def length(p):
    """l0 = h / (1 - lambda0)."""
    return p.h / (1 - p.lambda0)


def stretch(u, p):
    """lambda = |r_s| = |r_sigma| / l0 (the jets u.x_s ... are sigma-derivatives)."""
    return sp.sqrt(u.x_s**2 + u.y_s**2 + u.z_s**2) / length(p)


def strain_energy(lam, p):
    """W(lambda) per unit undeformed length."""
    if p.law == "inextensible":
        raise ModelError("the inextensible string has no strain energy (its tension is a constraint force): its "
                         "steady balloons use the Hamiltonian form (steady form = 'hamiltonian'); for its "
                         "dynamics use law = 'linear' with a large beta", file=__file__, key="law",
                         expected="neo_hookean or linear for modes, stability and continuation with stability")
    if p.law == "neo_hookean":
        return p.beta / 3 * (lam**2 / 2 + 1 / lam)
    return p.beta / 2 * (lam - 1) ** 2


def stretch_of_tension(t, p):
    """lambda(p), the inverse of the law: neo-Hookean lambda^3 - (3p/beta) lambda^2 - 1 = 0 by Cardano's
    formula, lambda = q + cbrt(S) + cbrt(q^6 / S), q = p/beta, S = 1/2 + q^3 + sqrt(1/4 + q^3) (the second
    root written without cancellation; real for q^3 > -1/4); linear 1 + p/beta; inextensible 1."""
    if p.law == "inextensible":
        return sp.Integer(1)
    if p.law == "linear":
        return 1 + t / p.beta
    q = t / p.beta
    S = sp.Rational(1, 2) + q**3 + sp.sqrt(sp.Rational(1, 4) + q**3)
    return q + sp.cbrt(S) + sp.cbrt(q**6 / S)


def complementary_energy(t, p):
    """W*(p) = p lambda(p) - W(lambda(p)) = integral of lambda dp: per unit undeformed length, up to a constant."""
    if p.law == "inextensible":
        return t
    if p.law == "linear":
        return t + t**2 / (2 * p.beta)
    lam = stretch_of_tension(t, p)
    return t * lam - strain_energy(lam, p)


def inertial_velocity(u):
    return frame_velocity((0, 0, 1), (u.x, u.y, u.z), (u.x_t, u.y_t, u.z_t))


@model.kinetic_density
def kinetic(u, p):
    w = inertial_velocity(u)
    return length(p) / 2 * (w[0] ** 2 + w[1] ** 2 + w[2] ** 2)


@model.potential_density
def potential(u, p):
    return length(p) * strain_energy(stretch(u, p), p)


@model.complementary_density
def complementary(u, n, p):
    """C(n) = l0 W*(|n|): n = (n.x, n.y, n.z) is the tension vector p t, conjugate to r_sigma, so that
    r_sigma = dC/dn = l0 lambda(p) n / p (the tension-vector form of Zhu et al. and Hall et al.)."""
    return length(p) * complementary_energy(sp.sqrt(n.x**2 + n.y**2 + n.z**2), p)


@model.dissipation_density
def dissipation(u, p):
    w = inertial_velocity(u)
    return length(p) * p.drag / 2 * (w[0] ** 2 + w[1] ** 2 + w[2] ** 2)


@model.boundary
def boundary(p):
    return [fix("x", "start"), fix("y", "start"), fix("z", "start"),
            fix("x", "end", 1), fix("y", "end"), fix("z", "end", p.h)]


model.output("tension", lambda n: sp.sqrt(n.x**2 + n.y**2 + n.z**2), doc="p = |n| = W'(lambda)")
model.output("stretch", stretch, doc="lambda = |r_s|")
model.output("radius", lambda u: sp.sqrt(u.x**2 + u.y**2), doc="distance from the axis")
