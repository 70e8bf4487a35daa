"""Kinematics helpers: rotations, so(3) hat/vee, angular velocity.

All functions build sympy expressions; they know nothing of models.
"""
from __future__ import annotations

import sympy as sp


def hat(w) -> sp.Matrix:
    """so(3) hat: the skew matrix with hat(w) x = w x x."""
    w = sp.Matrix(w)
    return sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def vee(W: sp.Matrix) -> sp.Matrix:
    """Inverse of :func:`hat` (takes the skew part's axial vector)."""
    return sp.Matrix([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]]) / 2


def rot_x(angle) -> sp.Matrix:
    """Rotation by ``angle`` about x."""
    c, s = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(angle) -> sp.Matrix:
    """Rotation by ``angle`` about y."""
    c, s = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(angle) -> sp.Matrix:
    """Rotation by ``angle`` about z."""
    c, s = sp.cos(angle), sp.sin(angle)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def angular_velocity_cardan_xy(theta_x, theta_y, dtheta_x, dtheta_y, spin_rate) -> sp.Matrix:
    """Body angular velocity of R = Rx(theta_x) Ry(theta_y) Rz(phi), phi' = spin_rate.

    Components in the frame after the two tilts (where a body symmetric about
    its z axis has a constant inertia tensor diag(Id, Id, Ip)):

        omega = (theta_x' cos(theta_y), theta_y', phi' + theta_x' sin(theta_y)).
    """
    return sp.Matrix([dtheta_x * sp.cos(theta_y), dtheta_y, spin_rate + dtheta_x * sp.sin(theta_y)])


def frame_velocity(omega, position, velocity) -> sp.Matrix:
    """Inertial velocity of a point given in a frame spinning at ``omega``: v_rel + omega x r.

    All three vectors have components on the rotating axes. Squared and halved
    times a mass (density), it yields the Coriolis (gyroscopic) and centrifugal
    terms of a rotating-frame model by itself.
    """
    w, r, v = sp.Matrix(omega), sp.Matrix(position), sp.Matrix(velocity)
    return v + w.cross(r)
