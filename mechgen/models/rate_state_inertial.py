"""Spring-slider with inertia and rate-and-state friction (aging or slip law): stick-slip limit cycles.

The quasi-static slider of ``rate_state_slider`` with a mass m per unit area (kg/m^2): a block under normal
stress sigma (Pa), pulled through a spring k (Pa/m) whose far end moves at V2 (m/s) from t = 0,

    m dV/dt = F - sigma mu,   dF/dt = k (V2 - V),   mu = mu0 + a ln(V/V_ref) + b ln(V_ref theta/D_c),

with the state theta (s) of ``law``: ``aging`` dtheta/dt = 1 - V theta/D_c, ``slip`` dtheta/dt =
-(V theta/D_c) ln(V theta/D_c) (Dieterich 1979; Ruina 1983). Internal variables, all dimensionless:
phi = ln(V/V_ref), psi = ln(V_ref theta/D_c), f = F/sigma - mu0, so that

    phi' = sigma (f - a phi - b psi)/(m V_ref exp(phi)),   f' = k (V2 - V_ref exp(phi))/sigma,
    aging: psi' = (V_ref/D_c)(exp(-psi) - exp(phi)),   slip: psi' = -(V_ref/D_c) exp(phi) (phi + psi).

The run starts (declared initial state) in steady sliding at V1 with the spring at its steady force
(f = (a - b) ln(V1/V_ref)). Linearised about steady sliding at V2 (both laws; tests/test_rate_state.py):
s^3 M + s^2 (M w0 + a) + s (kappa - (b - a) w0) + kappa w0 = 0 with M = m V2/sigma, w0 = V2/D_c,
kappa = k V2/sigma, hence the critical stiffness k_c = sigma (b - a)/D_c (1 + m V2^2/(sigma a D_c))
(Rice & Ruina 1983, J. Appl. Mech. 50, 343) and the neutral frequency (V2/D_c) sqrt((b - a)/a), as without
inertia; m -> 0 is the quasi-static slider. Below k_c the inertia bounds the slip velocity: the slider
settles on a stick-slip limit cycle (without inertia it runs away). Outputs: ``mu``, ``velocity`` V (m/s),
``theta`` (s), ``spring_stress`` F (Pa).
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

LAWS = ("aging", "slip")

model = Model("rate_state_inertial", doc=__doc__)
model.params(
    Param("a", 0.01, "", "direct-effect coefficient", positive=True),
    Param("b", 0.015, "", "evolution-effect coefficient", minimum=0.0),
    Param("D_c", 1e-5, "m", "characteristic slip distance", positive=True),
    Param("k", 4e9, "Pa/m", "spring stiffness per unit area", positive=True),
    Param("sigma", 1e7, "Pa", "normal stress", positive=True),
    Param("mu0", 0.6, "", "steady friction at V_ref"),
    Param("V1", 1e-6, "m/s", "load-point velocity before the step (t < 0)", positive=True),
    Param("V2", 1e-5, "m/s", "load-point velocity after the step (t > 0)", positive=True),
    Param("V_ref", 1e-6, "m/s", "reference velocity V* of mu0", positive=True),
    Param("m", 1e8, "kg/m^2", "slider mass per unit area", positive=True),
    Param("law", "aging", "", "state evolution law", choices=LAWS),
)


def state_rate(z, p):
    """psi' = theta'/theta (1/s) of the law."""
    if p.law == "aging":
        return p.V_ref / p.D_c * (sp.exp(-z.psi) - sp.exp(z.phi))
    return -p.V_ref / p.D_c * sp.exp(z.phi) * (z.phi + z.psi)


model.internal("phi", lambda z, p: p.sigma * (z.f - p.a * z.phi - p.b * z.psi) / (p.m * p.V_ref * sp.exp(z.phi)),
               doc="ln(V/V_ref), the log slip velocity")
model.internal("psi", state_rate, doc="ln(V_ref theta/D_c), the log state")
model.internal("f", lambda z, p: p.k * (p.V2 - p.V_ref * sp.exp(z.phi)) / p.sigma,
               doc="F/sigma - mu0, the spring's stress over sigma less mu0")


@model.initial
def after_step(p):
    """Steady sliding at V1 when the load point's velocity steps to V2."""
    before = sp.log(p.V1 / p.V_ref)
    return {"phi": before, "psi": -before, "f": (p.a - p.b) * before}


model.output("mu", lambda z, p: p.mu0 + p.a * z.phi + p.b * z.psi, doc="friction coefficient")
model.output("velocity", lambda z, p: p.V_ref * sp.exp(z.phi), unit="m/s", doc="slip velocity V")
model.output("theta", lambda z, p: p.D_c / p.V_ref * sp.exp(z.psi), unit="s", doc="state theta")
model.output("spring_stress", lambda z, p: p.sigma * (z.f + p.mu0), unit="Pa", doc="spring stress F")
