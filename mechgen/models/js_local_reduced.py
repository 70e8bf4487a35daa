"""Johnson-Segalman fluid under an imposed total shear stress, the seed's two-stress form (Khayat & Ashrafi, eqs. 5b-c).

The restriction of ``js_local`` (three polymer stresses) to its invariant plane W = xi tau_xx + (2 - xi) tau_yy = 0,
in the normal stress difference N = tau_xx - tau_yy and the shear stress S = tau_xy (stress in eta_p / lambda, time
in lambda):

    N' = -N + 2 g S,   S' = -S + g (1 + a N),   a = xi (xi/2 - 1),   g = (T - S) / epsilon,

the seed's local terms at an imposed total stress T. Same equilibria (the S-curve T = epsilon g + g / (1 + k g^2),
k = xi (2 - xi)) and folds as js_local; its Jacobian's eigenvalues are js_local's without the constant -1 of the
off-plane combination W. State names: N1 = N and txy = S (S is reserved). Dimensionless.
"""
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("js_local_reduced", doc=__doc__, file=__file__)
model.params(
    Param("epsilon", 0.06, "-", "solvent-to-polymer viscosity ratio eta_s / eta_p", positive=True),
    Param("xi", 0.2, "-", "slip parameter of the Gordon-Schowalter derivative", minimum=0.0, maximum=2.0),
    Param("T", 0.1, "-", "imposed total shear stress, in eta_p / lambda"),
)


def rate(z, p):
    """The shear rate g = (T - S) / epsilon."""
    return (p.T - z.txy) / p.epsilon


model.internal("N1", lambda z, p: -z.N1 + 2 * rate(z, p) * z.txy, doc="normal stress difference N = tau_xx - tau_yy")
model.internal("txy", lambda z, p: -z.txy + rate(z, p) * (1 + p.xi * (p.xi / 2 - 1) * z.N1), doc="polymer shear stress S")
model.output("shear_rate", rate, doc="shear rate g = (T - S) / epsilon, in 1 / lambda")
