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

(the string laws of mechgen.symbolic.materials with stiffness beta).

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
keep t . u_s = 0, A = p I, mechgen.runtime.steady.constrained; with ``strain = "projected"`` the
extensible laws' axial stiffness p' t t^T is seen through cos(k pi sigma) as well, the
strain measure being g = (lambda^2 - 1)/2: N = 10 then converges about ten times better).
Outputs: ``tension`` p,
``stretch`` lambda, ``radius`` sqrt(x^2 + y^2); the shape output ``loops`` with its starting guesses
(``shape = { loops = 2 }``) comes from mechgen.runtime.steady.guesses.
"""
import sympy as sp

from mechgen.runtime.steady import guesses
from mechgen.symbolic.field import fix
from mechgen.symbolic.kinematics import frame_velocity
from mechgen.symbolic.materials import green_strain, string_law
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


def law(p):
    """The string's constitutive law, by the scene's ``law`` (mechgen.symbolic.materials), stiffness beta."""
    return string_law(p.law, stiffness=p.beta)


def strain_energy(lam, p):
    """W(lambda) per unit undeformed length (0 for the inextensible law: its tension is the constraint's
    multiplier)."""
    return law(p).energy(lam)


def stretch_of_tension(t, p):
    """lambda(p), the inverse of the law (neo-Hookean by Cardano's formula)."""
    return law(p).stretch(t)


def complementary_energy(t, p):
    """W*(p) = p lambda(p) - W(lambda(p)) = integral of lambda dp: per unit undeformed length, up to a constant."""
    return law(p).complementary(t)


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
    return law(p).constraint(stretch(u, p))


@model.strain_density
def axial_strain(u, p):
    """g = (lambda^2 - 1)/2, the strain measure of the extensible laws (for strain = "projected")."""
    return 0 if law(p).inextensible else green_strain(stretch(u, p))


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


# Loop count and starting guesses for a balloon with a given loop count: numeric, in mechgen.runtime.steady.guesses.
loop_count = guesses.loop_count

#: the tension levels (p_e scale) of the starting guesses tried, in order
START_TENSIONS = (2.0, 5.0, 10.0)


def loop_start(value, s, p):
    """Starting guesses for a balloon with ``value`` loops (mechgen.runtime.steady.guesses.sine_loop_guesses: the
    string from the guide eyelet to (1, 0, h), undeformed length l0, one guess per level of START_TENSIONS)."""
    return guesses.sine_loop_guesses(value, s, height=p.h, length=length(p), domain=p.L, stiffness=p.beta,
                                     tensions=START_TENSIONS)


model.shape_output("loops", loop_count, start=loop_start,
                   doc="loop label: 1 + sign changes of x, less 1/2 when the last bulge is incomplete")
