"""Laval (Jeffcott) rotor: rigid disk on a massless elastic shaft, spinning at Omega.

Coordinates: disk-centre translations x, y (m) and tilts theta_x, theta_y (rad)
about the fixed x and y axes; the disk spins at the imposed rate Omega (rad/s)
about its own symmetry axis. The disk orientation is R = Rx(theta_x) Ry(theta_y) Rz(Omega t),
so its angular velocity in the tilted frame is
omega = (theta_x' cos(theta_y), theta_y', Omega + theta_x' sin(theta_y)) and

    T = m/2 (x'^2 + y'^2) + Id/2 (omega_1^2 + omega_2^2) + Ip/2 omega_3^2
    V = k_t/2 (x^2 + y^2) + k_t3/4 (x^2 + y^2)^2 + k_r/2 (theta_x^2 + theta_y^2)
    R = c/2 (x'^2 + y'^2) + c_r/2 (theta_x'^2 + theta_y'^2)   (non-rotating damping)
        + c_i/2 ((x' + Omega y)^2 + (y' - Omega x)^2)             (internal damping, in the rotating frame)

Linearised about rest: translations vibrate at sqrt(k_t/m); the tilts whirl at
omega_f,b = (+-Ip Omega + sqrt(Ip^2 Omega^2 + 4 Id k_r)) / (2 Id), forward and
backward, so omega_f - omega_b = Ip Omega / Id (the gyroscopic moment Ip Omega).
Internal (rotating) damping c_i acts on the centre's velocity seen from the shaft, r' - Omega x r: it drives the
forward whirl of the translations unstable above the onset speed Omega = sqrt(k_t/m) (1 + c/c_i) (Crandall;
Genta, Dynamics of Rotating Systems, sec. 8.3), a Hopf point of the rest state in Omega. A hardening shaft
(k_t3 > 0) bounds the whirl beyond it: the circular orbit r = R exp(i w t) with w = c_i Omega / (c + c_i) (the
damping forces balance) and m w^2 = k_t + k_t3 R^2 (the elastic force balances the centripetal one).
Whirl is judged at two stations, the centre's (x, y) and the tilts (theta_x, theta_y): the disk normal is
n = (theta_y, -theta_x, 1), a rotation of (theta_x, theta_y) by -90 degrees, so a counter-clockwise tilt
orbit is a counter-clockwise (forward) whirl of the normal.
Frequencies in rad/s. SI units.
"""
import sympy as sp

from mechgen.symbolic.kinematics import angular_velocity_cardan_xy
from mechgen.symbolic.model import Model
from mechgen.symbolic.params import Param

model = Model("laval_rotor", doc=__doc__, file=__file__)
model.params(
    Param("m", 10.0, "kg", "disk mass", positive=True),
    Param("Ip", 0.2, "kg m^2", "polar moment of inertia", positive=True),
    Param("Id", 0.1, "kg m^2", "diametral moment of inertia", positive=True),
    Param("k_t", 4.0e5, "N/m", "translational shaft stiffness"),
    Param("k_r", 2.0e4, "N m/rad", "rotational (tilt) shaft stiffness"),
    Param("Omega", 0.0, "rad/s", "spin speed"),
    Param("c", 0.0, "N s/m", "translational damping"),
    Param("c_r", 0.0, "N m s/rad", "tilt damping"),
    Param("c_i", 0.0, "N s/m", "internal (rotating) damping of the translations"),
    Param("k_t3", 0.0, "N/m^3", "cubic (hardening) translational shaft stiffness"),
)
model.coordinates("x", "y", "theta_x", "theta_y")
model.whirl_pair("x", "y")
model.whirl_pair("theta_x", "theta_y")  # the tilt modes whirl here (x, y stay at rest in them)


@model.kinetic
def kinetic(q, v, p):
    w = angular_velocity_cardan_xy(q.theta_x, q.theta_y, v.theta_x, v.theta_y, p.Omega)
    return p.m / 2 * (v.x**2 + v.y**2) + p.Id / 2 * (w[0] ** 2 + w[1] ** 2) + p.Ip / 2 * w[2] ** 2


@model.potential
def potential(q, p):
    return (p.k_t / 2 * (q.x**2 + q.y**2) + p.k_t3 / 4 * (q.x**2 + q.y**2) ** 2
            + p.k_r / 2 * (q.theta_x**2 + q.theta_y**2))


@model.dissipation
def dissipation(q, v, p):
    return (p.c / 2 * (v.x**2 + v.y**2) + p.c_r / 2 * (v.theta_x**2 + v.theta_y**2)
            + p.c_i / 2 * ((v.x + p.Omega * q.y) ** 2 + (v.y - p.Omega * q.x) ** 2))


model.output("orbit_radius", lambda q: sp.sqrt(q.x**2 + q.y**2), unit="m", doc="disk-centre orbit radius")
