"""Johnson-Segalman channel flow reduced to a low-order dynamical system by Galerkin projection (seed 002).

Khayat & Ashrafi reduce the one-dimensional plane-Poiseuille flow of the Johnson-Segalman fluid to a nonlinear
dynamical system by Galerkin projection, but do not state their truncation (Chandrasekhar-function modes chosen
by "a judicious selection process"). This model is the most natural lowest truncation, rebuilt from the PDEs
(velocity in d / lambda, time in lambda, stress in eta_p / lambda, y in [-1/2, 1/2] across the gap d):

    Re u_t = We + S_y + epsilon u_yy,   N_t = -N + 2 S u_y,   S_t = -S + u_y (1 + a N),   a = xi (xi/2 - 1),

u(+-1/2) = 0; We is the dimensionless driving pressure gradient (steady total shear stress S + epsilon u_y = -We y),
N the normal stress difference, S the polymer shear stress, Re = rho d^2 / (eta_p lambda). One mode per field:

    u = A(t) phi,  S = B(t) phi',  N = C(t) phi'^2,   phi = 1 - 4 y^2   (the lowest no-slip polynomial),

each equation projected on its own mode over the gap (the integrals are redone with sympy in
tests/test_js_galerkin.py). The N equation is exact in this basis; the S equation's N u_y term ~ y^3 is projected
on y with <y^4> / <y^2> = 3/20, giving the factor 64 * 3/20 = 48/5:

    A' = 5 (We - 8 B - 8 epsilon A) / (4 Re),   B' = -B + A + (48/5) a A C,   C' = -C + 2 A B.

Steady states: B = A / (1 + (48/5) k A^2), C = 2 A B, k = xi (2 - xi), and

    We = 8 epsilon A + 8 A / (1 + (48/5) k A^2) = (8 / c) T(c A),   c = sqrt(48/5),

with T(g) = epsilon g + g / (1 + k g^2) the homogeneous shear curve: the steady branch in We has folds exactly at
We = (8 / c) T_max and (8 / c) T_min (for epsilon < 1/8), the middle branch a saddle; no Hopf point for any
epsilon, xi, Re > 0 (the Routh-Hurwitz quantity a1 a2 - a3 of the branch's Jacobian is a ratio of polynomials with
positive coefficients). No steady state has N(0) != 0 here (phi'(0) = 0), unlike the seed's Fig. 2 departures; see the README for the comparison of critical
Weissenberg numbers. State names: u1 = A, txy1 = B, N1 = C (S is reserved). Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

#: the projection coefficient <phi'^3, phi'> / <phi', phi'> = 64 <y^4> / <y^2> of the S equation's N u_y term
NU_COUPLING = 48 / 5

model = Model("js_galerkin", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.08, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("Re", 1.0, "-", "Reynolds number rho d^2 / (eta_p lambda)", positive=True),
    Param("We", 1.0, "-", "Weissenberg number, the dimensionless driving pressure gradient"),
)


def velocity_rate(z, p):
    """A' = 5 (We - 8 B - 8 epsilon A) / (4 Re): momentum projected on phi (<phi, phi> = 8/15, <phi, 1> = 2/3)."""
    return 5 * (p.We - 8 * z.txy1 - 8 * p.epsilon * z.u1) / (4 * p.Re)


def shear_rate_of_change(z, p):
    """B' = -B + A + (48/5) a A C, a = xi (xi/2 - 1): the shear-stress law projected on phi' = -8 y."""
    return -z.txy1 + z.u1 + NU_COUPLING * p.xi * (p.xi / 2 - 1) * z.u1 * z.N1


model.internal("u1", velocity_rate, doc="velocity amplitude A: u = A (1 - 4 y^2), A the centre velocity")
model.internal("txy1", shear_rate_of_change, doc="shear stress amplitude B: S = -8 B y")
model.internal("N1", lambda z, p: -z.N1 + 2 * z.u1 * z.txy1, doc="normal stress amplitude C: N = 64 C y^2")
model.output("wall_shear_rate", lambda z: 4 * z.u1, doc="|u_y| at the walls, 4 A, in 1 / lambda")
model.output("wall_normal_stress", lambda z: 16 * z.N1, doc="N at the walls, 16 C, in eta_p / lambda")
model.output("flow_rate", lambda z: 2 * z.u1 / 3, doc="flow rate per unit width, (2/3) A, in d^2 / lambda")
