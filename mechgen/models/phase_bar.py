"""A bar of a material with a non-convex stored energy: phase boundaries, their driving traction and kinetics.

Abeyaratne & Knowles (J. Mech. Phys. Solids 38, 1990, 345-360; "Evolution of Phase Transitions", CUP 2006,
ch. 2-3), one-dimensional and isothermal. A bar 0 <= x <= L (m) of stored energy per unit reference volume
W(gamma) (Pa) and stress sigma = W'(gamma) (Pa), ``law``:

* ``cubic``: W = mu (gamma^2/2 - beta gamma^3/3 + c gamma^4/4), sigma = mu (gamma - beta gamma^2 + c gamma^3);
  non-monotone (a rising low-strain phase 1, a falling unstable branch, a rising high-strain phase 2) when
  beta^2 > 3 c. By the cubic's symmetry about its inflection gamma_i = beta/(3 c), the Maxwell stress is
  sigma(gamma_i) = mu (beta/(3 c) - 2 beta^3/(27 c^2)) and the phase strains gamma_i -+ sqrt((beta^2 - 3 c)/(3 c^2)).
* ``trilinear``: phase 1 sigma = mu gamma for gamma <= gamma_M, phase 2 sigma = mu (gamma - gamma_T) for
  gamma >= gamma_m, joined by the straight falling branch from (gamma_M, mu gamma_M) to
  (gamma_m, mu (gamma_m - gamma_T)); W is its integral from 0 (continuous). Needs 0 < gamma_M < gamma_m and
  gamma_m - gamma_T < gamma_M (a falling middle branch). With both phases of modulus mu,
  W_2(gamma) - mu (gamma - gamma_T)^2/2 = w0 is a constant and the Maxwell stress is sigma_M = w0/gamma_T.

Across a phase boundary at x = s(t) with phase 2 on 0 < x < s (strain gamma_2) and phase 1 on s < x < L
(strain gamma), the stress sigma is continuous and the driving traction is

    f = [[W]] - sigma [[gamma]] = W(gamma) - W(gamma_2) - sigma (gamma - gamma_2)      (Pa)

([[g]] = g(s+) - g(s-)); the dissipation rate per unit area is f ds/dt >= 0 and f = 0 is Maxwell's rule of
equal areas. Kinetics (``kinetics``, :func:`kinetic_rate`): ds/dt = V = phi(f) = f/eta (``linear``, the default) or
V0 sign(f) |f/f0|^exponent (``power``). The end
x = L moves by the elongation delta(t) = rate (t_turn - |t - t_turn|) (m): a ramp up to t_turn and back to 0 at
2 t_turn, quasi-static (no inertia): s gamma_2 + (L - s) gamma = delta with sigma(gamma_2) = sigma(gamma), the
phase-2 strain gamma_2 = :func:`phase_2_strain` (gamma) in closed form (cubic: the other roots of
sigma(x) = sigma(gamma) solve a quadratic). Differentiating the constraint gives the state's law:

    dgamma/dt = (ddelta/dt - V (gamma_2 - gamma)) / (s dgamma_2/dgamma + L - s).

Modes: ``phase_1`` (s = 0, gamma = delta/L; to ``two_phase`` when sigma rises through ``sigma_nucleation``: a
boundary nucleates at x = 0), ``two_phase`` (to ``phase_2`` when s reaches L: arrival at the end, gamma reset
to the phase-2 strain; back to ``phase_1`` when s falls to 0), ``phase_2`` (s = L, gamma the phase-2 strain =
delta/L; to ``two_phase`` when sigma falls through ``sigma_reversion``: phase 1 nucleates at x = L, gamma reset
to the phase-1 strain at that stress). Each mode also has the event ``turn`` at t = t_turn (back to itself, no
reset but ``leg`` = 1, the internal variable that gives d delta/dt = rate (1 - 2 leg)), so that no integration step
straddles the kink of delta(t). Internal variables: ``s``, ``gamma`` (the strain of the phase-1 part; of the
whole bar in ``phase_2``), ``leg`` (0 up, 1 after the turn), ``work`` = int sigma ddelta/dt dt and ``dissipated`` =
int f V dt (J/m^2, per unit cross-section): work - dissipated = the stored energy E - E(0) (the dissipation check).
Outputs: ``stress`` sigma(gamma), ``energy_density`` W(gamma), ``modulus`` sigma'(gamma) (these three read the
law at the state's gamma: the ``phase_boundary`` analysis evaluates them at chosen strains), ``elongation``
delta, ``driving_traction`` f (0 without a boundary), ``velocity`` V, ``stored_energy`` E = s W(gamma_2) +
(L - s) W(gamma) (J/m^2), ``phase_fraction`` s/L; ``bar_length``, ``nucleation_stress``, ``reversion_stress``
(the parameters L, sigma_nucleation, sigma_reversion, read by the analyses whether folded or free).
"""
import sympy as sp

from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param
from mechgen.symbolic.powers import signed_power

LAWS = ("cubic", "trilinear")
KINETICS = ("linear", "power")

model = Model("phase_bar", doc=__doc__)
model.params(
    Param("law", "cubic", "", "stored energy W(gamma)", choices=LAWS),
    Param("mu", 1.0, "Pa", "modulus (the phases' modulus for the trilinear law)", positive=True),
    Param("beta", 3.0, "", "cubic law: quadratic coefficient of sigma/mu"),
    Param("c", 2.2, "", "cubic law: cubic coefficient of sigma/mu", positive=True),
    Param("gamma_M", 0.02, "", "trilinear law: end of phase 1 (stress peak)", positive=True),
    Param("gamma_m", 0.06, "", "trilinear law: start of phase 2 (stress valley)", positive=True),
    Param("gamma_T", 0.05, "", "trilinear law: transformation strain (phase 2: sigma = mu (gamma - gamma_T))",
          positive=True),
    Param("L", 1.0, "m", "bar length", positive=True),
    Param("kinetics", "linear", "", "kinetic law V = phi(f)", choices=KINETICS),
    Param("eta", 1.0, "Pa s/m", "linear kinetics: viscosity, V = f/eta", positive=True),
    Param("V0", 1.0, "m/s", "power kinetics: the speed at f = f0", positive=True),
    Param("f0", 1.0, "Pa", "power kinetics: the reference driving traction", positive=True),
    Param("exponent", 3.0, "", "power kinetics: V = V0 sign(f) |f/f0|^exponent", positive=True),
    Param("rate", 0.01, "m/s", "elongation rate of the ramp", positive=True),
    Param("t_turn", 10.0, "s", "time the ramp turns back", positive=True),
    Param("sigma_nucleation", 0.05, "Pa", "stress at which phase 2 nucleates at x = 0"),
    Param("sigma_reversion", 0.0, "Pa", "stress at which phase 1 nucleates at x = L"),
)


def law_stress(g, p):
    """sigma(gamma) (Pa) of ``law``."""
    if p.law == "cubic":
        return p.mu * (g - p.beta * g**2 + p.c * g**3)
    falling = p.mu * (p.gamma_M + ((p.gamma_m - p.gamma_T) - p.gamma_M) * (g - p.gamma_M) / (p.gamma_m - p.gamma_M))
    return sp.Piecewise((p.mu * g, g <= p.gamma_M), (falling, g < p.gamma_m), (p.mu * (g - p.gamma_T), True))


def law_energy(g, p):
    """W(gamma) (Pa): int_0^gamma sigma, continuous."""
    if p.law == "cubic":
        return p.mu * (g**2 / 2 - p.beta * g**3 / 3 + p.c * g**4 / 4)
    slope = p.mu * ((p.gamma_m - p.gamma_T) - p.gamma_M) / (p.gamma_m - p.gamma_M)
    at_peak = p.mu * p.gamma_M**2 / 2

    def middle_at(x):
        return at_peak + p.mu * p.gamma_M * (x - p.gamma_M) + slope * (x - p.gamma_M)**2 / 2

    middle, at_valley = middle_at(g), middle_at(p.gamma_m)
    phase_2 = at_valley + p.mu * ((g - p.gamma_T)**2 - (p.gamma_m - p.gamma_T)**2) / 2
    return sp.Piecewise((p.mu * g**2 / 2, g <= p.gamma_M), (middle, g < p.gamma_m), (phase_2, True))


def _other_roots(g, p, sign):
    """The roots x != gamma of sigma(x) = sigma(gamma) (cubic): c x^2 + (c gamma - beta) x + c gamma^2 - beta gamma
    + 1 = 0; ``sign`` +1 the larger (phase 2), -1 the smaller (phase 1)."""
    disc = -3 * p.c**2 * g**2 + 2 * p.beta * p.c * g + p.beta**2 - 4 * p.c
    return (p.beta - p.c * g + sign * sp.sqrt(disc)) / (2 * p.c)


def phase_2_strain(g, p):
    """gamma_2: the phase-2 strain at the stress sigma(gamma) of a phase-1 strain gamma."""
    return _other_roots(g, p, 1) if p.law == "cubic" else law_stress(g, p) / p.mu + p.gamma_T


def phase_1_strain(g, p):
    """The phase-1 strain at the stress sigma(gamma) of a phase-2 strain gamma."""
    return _other_roots(g, p, -1) if p.law == "cubic" else law_stress(g, p) / p.mu


def law_modulus(g, p):
    """d sigma/d gamma (Pa)."""
    x = sp.Dummy("x")
    return sp.diff(law_stress(x, p), x).subs(x, g)


def elongation(p, t):
    """delta(t) = rate (t_turn - |t - t_turn|) (m)."""
    return p.rate * (p.t_turn - sp.Abs(t - p.t_turn))


def elongation_rate(z, p):
    """d delta/dt (m/s): rate on the way up (leg = 0), -rate after the turn (leg = 1)."""
    return p.rate * (1 - 2 * z.leg)


def driving_traction(z, p):
    """f = W(gamma) - W(gamma_2) - sigma(gamma) (gamma - gamma_2) (Pa), phase 2 on the left."""
    g, g2 = z.gamma, phase_2_strain(z.gamma, p)
    return law_energy(g, p) - law_energy(g2, p) - law_stress(g, p) * (g - g2)


def kinetic_rate(f, p):
    """V = phi(f) (m/s), ``kinetics``: linear f/eta, or power V0 sign(f) |f/f0|^exponent (both odd, so f V >= 0)."""
    if p.kinetics == "power":
        return p.V0 * signed_power(f / p.f0, p.exponent)
    return f / p.eta


def strain_rate(z, p, t):
    """dgamma/dt in ``two_phase``: the derivative of s gamma_2 + (L - s) gamma = delta, solved for dgamma/dt."""
    g = sp.Dummy("g")
    g2 = phase_2_strain(z.gamma, p)
    dg2 = sp.diff(phase_2_strain(g, p), g).subs(g, z.gamma)
    V = kinetic_rate(driving_traction(z, p), p)
    return (elongation_rate(z, p) - V * (g2 - z.gamma)) / (z.s * dg2 + p.L - z.s)


phase_1 = model.mode("phase_1", initial=True)
two_phase = model.mode("two_phase")
phase_2 = model.mode("phase_2")

for _scope in (phase_1, phase_2):
    _scope.internal("s", lambda: 0, doc="phase-boundary position (m); phase 2 on 0 < x < s")
    _scope.internal("gamma", lambda z, p: elongation_rate(z, p) / p.L, doc="strain of the phase-1 part")
    _scope.internal("work", lambda z, p, t: law_stress(z.gamma, p) * elongation_rate(z, p),
                    doc="work done on the bar per unit area (J/m^2)")
    _scope.internal("dissipated", lambda: 0, doc="int f V dt (J/m^2)")
for _scope in (phase_1, two_phase, phase_2):
    _scope.internal("leg", lambda: 0, doc="0 while the ramp goes up, 1 after the turn")
two_phase.internal("s", lambda z, p: kinetic_rate(driving_traction(z, p), p))
two_phase.internal("gamma", strain_rate)
two_phase.internal("work", lambda z, p, t: law_stress(z.gamma, p) * elongation_rate(z, p))
two_phase.internal("dissipated", lambda z, p: driving_traction(z, p) * kinetic_rate(driving_traction(z, p), p))


@phase_1.guard(to="two_phase", direction="rising")
def nucleation(z, p):
    return law_stress(z.gamma, p) - p.sigma_nucleation


@two_phase.guard(to="phase_2", direction="rising", reset=lambda z, p: {"s": p.L, "gamma": phase_2_strain(z.gamma, p)})
def arrival(z, p):
    return z.s - p.L


@two_phase.guard(to="phase_1", direction="falling", reset=lambda: {"s": 0})
def retreat(z):
    return z.s


@phase_2.guard(to="two_phase", direction="rising", reset=lambda z, p: {"s": p.L, "gamma": phase_1_strain(z.gamma, p)})
def reversion(z, p):
    return p.sigma_reversion - law_stress(z.gamma, p)


def turn(z, p, t):
    """(1 - 2 leg)(t - t_turn) - leg t_turn (s): rises through 0 at t_turn on the way up (leg = 0); after the
    turn (leg = 1) it is -t < 0, so it never fires again."""
    return (1 - 2 * z.leg) * (t - p.t_turn) - z.leg * p.t_turn


for _scope in (phase_1, two_phase, phase_2):
    _scope.guard(to=_scope.name, direction="rising", reset=lambda: {"leg": 1})(turn)


model.output("stress", lambda z, p: law_stress(z.gamma, p), unit="Pa", doc="sigma(gamma), the bar's stress")
model.output("energy_density", lambda z, p: law_energy(z.gamma, p), unit="Pa", doc="W(gamma)")
model.output("modulus", lambda z, p: law_modulus(z.gamma, p), unit="Pa", doc="d sigma/d gamma at gamma")
model.output("elongation", lambda p, t: elongation(p, t), unit="m", doc="delta(t), the end's displacement")
model.output("driving_traction", driving_traction, unit="Pa", doc="f = [[W]] - sigma [[gamma]] (0 without a boundary)")
model.output("velocity", lambda z, p: kinetic_rate(driving_traction(z, p), p), unit="m/s", doc="V = ds/dt")
model.output("stored_energy", lambda z, p: z.s * law_energy(phase_2_strain(z.gamma, p), p)
             + (p.L - z.s) * law_energy(z.gamma, p), unit="J/m^2", doc="E = int_0^L W dx per unit area")
model.output("phase_fraction", lambda z, p: z.s / p.L, doc="s/L, the phase-2 fraction")
model.output("bar_length", lambda p: p.L, unit="m", doc="L (the analyses read it here, folded or free)")
model.output("nucleation_stress", lambda p: p.sigma_nucleation, unit="Pa", doc="sigma_nucleation")
model.output("reversion_stress", lambda p: p.sigma_reversion, unit="Pa", doc="sigma_reversion")
for _scope in (phase_1, phase_2):
    _scope.output("driving_traction", lambda: 0)
    _scope.output("velocity", lambda: 0)
    _scope.output("stored_energy", lambda z, p: p.L * law_energy(z.gamma, p))
