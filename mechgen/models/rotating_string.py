"""Taut string spinning about its chord, seen in the co-rotating frame.

Fields v(s, t), w(s, t): displacements along the rotating axes e2, e3 normal to
the chord e1 (s in [0, L], fixed ends). A material point sits at
r = s e1 + v e2 + w e3 in a frame spinning at Omega e1, so its inertial velocity
is u_t + Omega e1 x r (mechgen.symbolic.kinematics.frame_velocity) and

    T = rhoA/2 |(0, v_t, w_t) + Omega e1 x (s, v, w)|^2
      = rhoA/2 [(v_t - Omega w)^2 + (w_t + Omega v)^2],
    V = P/2 (v_s^2 + w_s^2).

The Coriolis terms give the gyroscopic matrix and the centrifugal terms soften
the stiffness by rhoA Omega^2; the spectrum in the rotating frame is
omega = omega_n +- Omega with omega_n = (n pi / L) sqrt(P / rhoA) (the string is
isotropic, so each inertial frequency is shifted by the frame's rate).
"""
from mechgen.symbolic.field import fix
from mechgen.symbolic.kinematics import frame_velocity
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("rotating_string", doc=__doc__, file=__file__)
model.params(
    Param("P", 1.0, "N", "tension", positive=True),
    Param("rhoA", 1.0, "kg/m", "mass per unit length", positive=True),
    Param("Omega", 0.0, "rad/s", "spin rate about the chord"),
    Param("L", 1.0, "m", "length", positive=True),
)
model.field("v", "w", length="L", discretisation="sine", N=24)


@model.kinetic_density
def kinetic(u, p, s):
    vel = frame_velocity((p.Omega, 0, 0), position=(s, u.v, u.w), velocity=(0, u.v_t, u.w_t))
    return p.rhoA / 2 * (vel[0] ** 2 + vel[1] ** 2 + vel[2] ** 2)


@model.potential_density
def potential(u, p):
    return p.P / 2 * (u.v_s**2 + u.w_s**2)


@model.boundary
def boundary():
    return [fix(f, end) for f in ("v", "w") for end in ("start", "end")]
