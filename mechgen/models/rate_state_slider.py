"""Quasi-static spring-slider with rate-and-state friction (Dieterich aging law or Ruina slip law).

A block slides at velocity V (m/s) on a surface under normal stress sigma (Pa); its friction coefficient is

    mu = mu0 + a ln(V/V_ref) + b ln(V_ref theta/D_c)                        (Dieterich 1979; Ruina 1983)

with the state theta (s) obeying ``law``:

* ``aging`` (Dieterich): dtheta/dt = 1 - V theta/D_c,
* ``slip`` (Ruina):      dtheta/dt = -(V theta/D_c) ln(V theta/D_c).

Both have the steady state theta_ss = D_c/V, mu_ss = mu0 + (a - b) ln(V/V_ref). Velocity and state
span many decades, so the state is their logarithms, two internal variables and no coordinate:

    phi = ln(V/V_ref),   psi = ln(V_ref theta/D_c),   mu = mu0 + a phi + b psi,
    aging: psi' = (V_ref/D_c)(exp(-psi) - exp(phi)),   slip: psi' = -(V_ref/D_c) exp(phi) (phi + psi).

``loading``:

* ``spring`` (the classic setting of Ruina 1983 and Rice & Ruina 1983): a spring of stiffness k (Pa/m,
  force per unit area per unit slip) pulled at the load-point velocity V2 from t = 0, with no inertia:
  k (V2 t - x) + tau_0 = sigma mu. Its time derivative k (V2 - V) = sigma (a phi' + b psi') gives
  phi' = (k (V2 - V)/sigma - b psi')/a. Steady sliding is V = V2; its linearisation, the same for both
  laws, is stable for k > k_c = sigma (b - a)/D_c and oscillates at k = k_c with
  omega = (V2/D_c) sqrt((b - a)/a) (rad/s) (tests/test_rate_state.py derives both).
* ``imposed`` (infinite stiffness): V = V2 from t = 0, phi' = 0; only the state evolves.

The run starts (declared initial state) in steady sliding at V1 (psi = -ln(V1/V_ref)) just after the load
point's velocity steps from V1 to V2: phi = ln(V1/V_ref) with the spring (V is continuous), ln(V2/V_ref)
when imposed. Outputs: ``mu``, ``velocity`` V (m/s), ``theta`` (s), ``slip_rate_ratio`` V theta/D_c.
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

LAWS = ("aging", "slip")
LOADINGS = ("spring", "imposed")

model = Model("rate_state_slider", doc=__doc__)
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
    Param("law", "aging", "", "state evolution law", choices=LAWS),
    Param("loading", "spring", "", "spring-driven slider, or the slider's velocity imposed", choices=LOADINGS),
)


def state_rate(z, p):
    """psi' = theta'/theta (1/s) of the law."""
    if p.law == "aging":
        return p.V_ref / p.D_c * (sp.exp(-z.psi) - sp.exp(z.phi))
    return -p.V_ref / p.D_c * sp.exp(z.phi) * (z.phi + z.psi)


def velocity_rate(z, p):
    """phi' = V'/V (1/s): from the time derivative of the spring's balance, or 0 when V is imposed."""
    if p.loading == "imposed":
        return 0
    return (p.k * (p.V2 - p.V_ref * sp.exp(z.phi)) / p.sigma - p.b * state_rate(z, p)) / p.a


model.internal("phi", velocity_rate, doc="ln(V/V_ref), the log slip velocity")
model.internal("psi", state_rate, doc="ln(V_ref theta/D_c), the log state")


@model.initial
def after_step(p):
    """Steady sliding at V1 when the load point's velocity steps to V2."""
    before = sp.log(p.V1 / p.V_ref)
    return {"phi": sp.log(p.V2 / p.V_ref) if p.loading == "imposed" else before, "psi": -before}


model.output("mu", lambda z, p: p.mu0 + p.a * z.phi + p.b * z.psi, doc="friction coefficient")
model.output("velocity", lambda z, p: p.V_ref * sp.exp(z.phi), unit="m/s", doc="slip velocity V")
model.output("theta", lambda z, p: p.D_c / p.V_ref * sp.exp(z.psi), unit="s", doc="state theta")
model.output("slip_rate_ratio", lambda z: sp.exp(z.phi + z.psi), doc="V theta/D_c (1 in steady sliding)")
