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

    inextensible lambda = 1: no W; the constraint g = (lambda^2 - 1)/2 = 0 (model.constraint_density)
                 with multiplier mu = l0 p.

The complementary energy C(n) = l0 W*(|n|), W*(p) = integral of lambda(p) dp, of the
tension vector n = p t (conjugate to r_sigma) gives the steady balloons in the
tension-vector form r_sigma = l0 lambda(p) n / p, n_sigma = -l0 (x, y, 0) (steady
``form = "hamiltonian"``; the only form for the inextensible law; lambda(p) of the
neo-Hookean law by Cardano's formula). R is a linear air drag on the inertial
velocity (zero by default: it then disappears from the generated code). Steady balloons solve
(p r_s / lambda)_s + (x, y, 0) = drag e3 x r with r(0) = 0, r(l0) = (1, 0, h)
(mechgen.symbolic.steady); small motions about one obey
u_tt + 2 e3 x u_t - (A u_s)_s - diag(1, 1, 0) u = 0 with
A = (p/lambda) I + (p' - p/lambda) t t^T, t = r_s/lambda, and u = 0 at both eyelets
(Galerkin with sin(j pi sigma), N per component; the inextensible string's motions
keep t . u_s = 0, A = p I, mechgen.runtime.constrained; with ``strain = "projected"`` the
extensible laws' axial stiffness p' t t^T is seen through cos(k pi sigma) as well, the
strain measure being g = (lambda^2 - 1)/2: N = 10 then converges about ten times better).
Outputs: ``tension`` p,
``stretch`` lambda, ``radius`` sqrt(x^2 + y^2).
"""
import sympy as sp

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
    Param("strain", "pointwise", "", "axial stiffness in the Galerkin stability: pointwise, or projected on "
          "cos(k pi sigma) (mixed; converges faster in N)", choices=("pointwise", "projected"), runtime=True),
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
    if p.law == "inextensible":  # no strain energy: the tension is the multiplier of the constraint below
        return sp.Integer(0)
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


@model.constraint_density
def inextensible(u, p):
    """g = (lambda^2 - 1)/2 = 0 for the inextensible law (none otherwise); its multiplier is mu = l0 p."""
    return (stretch(u, p) ** 2 - 1) / 2 if p.law == "inextensible" else 0


@model.strain_density
def axial_strain(u, p):
    """g = (lambda^2 - 1)/2, the strain measure of the extensible laws (for strain = "projected")."""
    return (stretch(u, p) ** 2 - 1) / 2 if p.law != "inextensible" else 0


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


# ---------------------------------------------------------------------------------------------------------------
# Loop count: a number measured on a sampled steady balloon (numeric; the scene code stays generic), and starting
# guesses for a balloon with a given loop count.
def loop_count(u):
    """The balloon's loop label (Sarangi et al.: single 1, one-and-a-half 1.5, double 2 ...), for planar balloons.

    n_c = the sign changes of x(s) between the eyelets; loops = 1 if n_c = 0, else n_c + 1 when the last bulge
    is complete (x_s < 0 at the rotating eyelet, i.e. the tension vector's Q(l0) < 0: |x| peaked before the
    eyelet, since x(l0) = 1 > 0) and n_c + 1/2 otherwise (benchmarks/balloon_notes.md, section 4)."""
    import numpy as np

    x = np.asarray(u.x, float)[1:-1]
    signs = np.sign(x[x != 0.0])
    crossings = int(np.count_nonzero(signs[1:] != signs[:-1]))
    if crossings == 0:
        return 1.0
    return crossings + (1.0 if float(np.asarray(u.x_s)[-1]) < 0.0 else 0.5)


#: the tension levels (p_e scale) of the starting guesses tried, in order
START_TENSIONS = (2.0, 5.0, 10.0)


def loop_start(value, s, p):
    """Starting guesses for a balloon with ``value`` loops: n_c = round(value + 1/2) - 1 axis crossings.

    Each guess is the graph x(z) = z/h + a sin(k pi z/h), k = n_c + 1 (the sign of a makes the last bulge
    positive), with a chosen so that the curve's length is l0 lambda_g: a uniformly stretched string at the
    tension level p_g (lambda_g = 1 + p_g/beta), material points spaced evenly along it, and the tension
    vector n = p_g t along its tangent t. One guess per p_g in START_TENSIONS."""
    import numpy as np
    from scipy.integrate import cumulative_trapezoid
    from scipy.optimize import brentq

    k = max(int(np.floor(float(value) + 0.5)), 1)
    h, l0 = float(p.h), float(p.h) / (1.0 - float(p.lambda0))
    sigma = np.asarray(s, float) / float(p.L)
    zeta = np.linspace(0.0, 1.0, 4001)
    cos = np.cos(k * np.pi * zeta)
    for tension in START_TENSIONS:
        target = l0 * (1.0 + tension / float(p.beta))

        def excess(a):
            return h * np.trapezoid(np.sqrt(1.0 + ((1.0 + a * k * np.pi * cos) / h) ** 2), zeta) - target

        a = 0.0
        if excess(0.0) < 0.0:
            top = 1.0
            while excess(top) < 0.0:
                top *= 2.0
            a = brentq(excess, 0.0, top, xtol=1e-12)
        a *= (-1.0) ** (k - 1)
        slope = (1.0 + a * k * np.pi * cos) / h  # dx/dz
        arc = cumulative_trapezoid(h * np.sqrt(1.0 + slope**2), zeta, initial=0.0)
        at = arc / arc[-1]
        x = np.interp(sigma, at, zeta + a * np.sin(k * np.pi * zeta))
        z = np.interp(sigma, at, h * zeta)
        norm = np.sqrt(1.0 + slope**2)
        tx, tz = np.interp(sigma, at, slope / norm), np.interp(sigma, at, 1.0 / norm)
        stretch_ = arc[-1] / float(p.L)
        zero = np.zeros_like(sigma)
        yield {"u": {"x": x, "y": zero, "z": z}, "u_s": {"x": stretch_ * tx, "y": zero, "z": stretch_ * tz},
               "n": {"x": tension * tx, "y": zero, "z": tension * tz}}


model.shape_output("loops", loop_count, start=loop_start,
                   doc="loop label: 1 + sign changes of x, less 1/2 when the last bulge is incomplete")
