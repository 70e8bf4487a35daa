"""Damped gyroscopic modes, whirl, Campbell tracking and critical speeds against closed forms.

Laval (Jeffcott) rotor tilt dofs q = (theta_x, theta_y) of a disk (transverse inertia Id, polar Ip) on
a shaft of tilt stiffness k_r spinning at Omega about +z. Euler's equations for small tilt
(H = Ip Omega n + Id omega_perp, disk normal n = (theta_y, -theta_x, 1)) give

    Id theta_x'' + Ip Omega theta_y' + k_r theta_x = 0,    Id theta_y'' - Ip Omega theta_x' + k_r theta_y = 0,

so G = Ip Omega [[0, 1], [-1, 0]]; Friswell, Penny, Garvey, Lees, "Dynamics of Rotating Machines"
(CUP 2010), sect. 3.5 (eq. 3.53-3.61), and Genta, "Dynamics of Rotating Systems" (Springer 2005), ch. 4.
The map (theta_x, theta_y) -> n_perp = (theta_y, -theta_x) is a rotation by -90 degrees, so a
counter-clockwise orbit of (theta_x, theta_y) is a counter-clockwise whirl of the disk normal: forward.
Whirl frequencies (same references): Id w^2 -+ Ip Omega w - k_r = 0,

    omega_f,b = (+-Ip Omega + sqrt(Ip^2 Omega^2 + 4 Id k_r)) / (2 Id),   '+' forward.
"""
import warnings

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sps
from scipy.optimize import brentq

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.linear.campbell import (SpeedPolynomial, campbell, critical_speeds, fit_speed_polynomial,
                                      mac_matrix)
from mechgen.runtime.linear.damped import damped_modes, orbit_kappa, whirl, whirl_sign


def laval(Id, Ip, k, speed, sign=1.0):
    """M, G, K of the Laval tilt rotor (module docstring)."""
    M = np.diag([Id, Id])
    G = sign * Ip * speed * np.array([[0.0, 1.0], [-1.0, 0.0]])
    return M, G, k * np.eye(2)


def omega_fb(Id, Ip, k, speed):
    """Closed-form forward and backward whirl frequencies (Friswell et al. 2010, sect. 3.5)."""
    root = np.sqrt(Ip**2 * speed**2 + 4 * Id * k)
    return (Ip * speed + root) / (2 * Id), (-Ip * speed + root) / (2 * Id)


# ------------------------------------------------------------------------------------------- whirl sign


def test_whirl_sign_of_elementary_orbits():
    # x = cos(wt) = Re(1 e^{iwt}), y = sin(wt) = Re(-i e^{iwt}): counter-clockwise, Im(X conj Y) = +1.
    t = np.linspace(0.0, 2 * np.pi, 401)
    X, Y = 1.0 + 0j, -1j
    x, y = np.real(X * np.exp(1j * t)), np.real(Y * np.exp(1j * t))
    assert np.allclose(x, np.cos(t)) and np.allclose(y, np.sin(t))
    area = 0.5 * np.trapezoid(x * np.gradient(y, t) - y * np.gradient(x, t), t)  # > 0: counter-clockwise
    assert area > 0 and np.imag(X * np.conj(Y)) > 0
    shapes = np.array([[1.0, 1.0, 1.0, 1.0], [-1j, 1j, 0.5, -0.3j]])  # ccw, cw, straight line, ccw ellipse
    # a straight line has no whirl direction: 'linear' (issue 25; the rule before it, forward, on request)
    assert whirl(shapes, 0, 1) == ["forward", "backward", "linear", "forward"]
    assert whirl(shapes, 0, 1, planar="backward")[2] == "backward"
    assert whirl(shapes, 0, 1, planar="forward")[2] == "forward"
    assert np.allclose(orbit_kappa(shapes, 0, 1), [1.0, -1.0, 0.0, 0.3])
    # the station with the largest orbit decides; a straight line there defers to the weighted sum
    two = np.array([[0.1, 1.0], [0.1j, 0.0], [1.0, 0.2], [-0.5j, 0.05j]])  # rows: x0, y0, x1, y1
    assert whirl(two, [0, 2], [1, 3]) == ["forward", "backward"]
    assert list(whirl_sign(two, [0, 2], [1, 3])) == [1, -1]


# ------------------------------------------------------------------------------------------- Laval rotor


@pytest.mark.parametrize("speed", [0.5, 2.0, 7.0])
def test_laval_frequencies_and_whirl_dense(speed):
    Id, Ip, k = 1.3, 0.7, 5.0
    res = damped_modes(*laval(Id, Ip, k, speed))
    wf, wb = omega_fb(Id, Ip, k, speed)
    assert np.allclose(res.wd, [wb, wf], rtol=1e-12)
    assert np.allclose(res.eigenvalues.real, 0.0, atol=1e-12 * wf)
    assert whirl(res.shapes, 0, 1) == ["backward", "forward"]
    assert np.allclose(np.abs(res.shapes).max(axis=0), 1.0)
    # opposite spin (G transposed): the stiffened (higher) mode now whirls clockwise about +z
    rev = damped_modes(*laval(Id, Ip, k, speed, sign=-1.0))
    assert np.allclose(rev.wd, [wb, wf], rtol=1e-12)
    assert whirl(rev.shapes, 0, 1) == ["forward", "backward"]


def test_laval_sparse_path():
    # five decoupled Laval rotors (n = 10); the sparse path finds the lowest 4 whirl modes
    Id, Ip, speed = 1.0, 0.6, 3.0
    ks = [2.0, 3.0, 5.0, 7.0, 11.0]
    parts = [laval(Id, Ip, k, speed) for k in ks]
    M, C, K = (sps.block_diag([p[i] for p in parts], format="csr") for i in range(3))
    res = damped_modes(M, C, K, 4)
    ref = np.sort(np.concatenate([omega_fb(Id, Ip, k, speed) for k in ks]))[:4]
    assert np.allclose(res.wd, ref, rtol=1e-10)
    expect = []
    for w in res.wd:  # label each by which closed-form branch it is
        expect.append("forward" if any(np.isclose(w, omega_fb(Id, Ip, k, speed)[0]) for k in ks) else "backward")
    assert whirl(res.shapes, [0, 2, 4, 6, 8], [1, 3, 5, 7, 9]) == expect
    dense = damped_modes(M, C, K, 4, sparse=False)
    assert np.allclose(dense.wd, res.wd, rtol=1e-12)


# ------------------------------------------------------------------------------------------- damping


def test_damped_pair_log_decrement():
    # m x'' + c x' + k x = 0 in x and y: s = -zeta wn +- i wn sqrt(1 - zeta^2), zeta = c / (2 sqrt(k m)),
    # log decrement delta = ln(x_n / x_{n+1}) = 2 pi zeta / sqrt(1 - zeta^2)
    # (Inman, "Engineering Vibration", 4th ed., sect. 1.6, eq. 1.87; Rao, "Mechanical Vibrations", eq. 2.84)
    m, k, c = 2.0, 800.0, 6.0
    res = damped_modes(m * np.eye(2), c * np.eye(2), k * np.eye(2))
    wn, zeta = np.sqrt(k / m), c / (2 * np.sqrt(k * m))
    assert np.allclose(res.wn, wn, rtol=1e-12)
    assert np.allclose(res.damping_ratio, zeta, rtol=1e-10)
    assert np.allclose(res.wd, wn * np.sqrt(1 - zeta**2), rtol=1e-12)
    assert np.allclose(res.log_dec, 2 * np.pi * zeta / np.sqrt(1 - zeta**2), rtol=1e-10)
    # the decrement is the ratio of successive peaks of the free response x(t) = e^{-zeta wn t} cos(wd t)
    wd = res.wd[0]
    assert np.isclose(np.log(1.0 / np.exp(-zeta * wn * 2 * np.pi / wd)), res.log_dec[0])


def test_overdamped_and_rigid_are_real():
    # c^2 > 4 k m: s = (-c +- sqrt(c^2 - 4 k m)) / (2 m), each twice; no oscillatory mode
    m, k, c = 1.0, 1.0, 5.0
    res = damped_modes(m * np.eye(2), c * np.eye(2), k * np.eye(2))
    assert res.wd.size == 0 and res.shapes.shape == (2, 0)
    roots = np.sort([(-c + np.sqrt(c * c - 4 * k * m)) / (2 * m), (-c - np.sqrt(c * c - 4 * k * m)) / (2 * m)])
    assert np.allclose(np.sort(res.real_eigenvalues), np.repeat(roots, 2)[[0, 1, 2, 3]])
    # free mass plus a spring-mass: one rigid (s = 0, double) pair, one oscillatory mode sqrt(k/m)
    res = damped_modes(np.eye(2), np.zeros((2, 2)), np.diag([0.0, 9.0]))
    assert np.allclose(res.wd, [3.0]) and np.allclose(res.real_eigenvalues, 0.0, atol=1e-12)


def test_singular_mass_drops_infinite_eigenvalues():
    # q1 = q2 enforced by a massless Lagrange multiplier: (m1 + m2) q'' + (k1 + k2) q = 0
    M = np.diag([1.0, 2.0, 0.0])
    K = np.array([[3.0, 0.0, 1.0], [0.0, 5.0, -1.0], [1.0, -1.0, 0.0]])
    res = damped_modes(M, np.zeros((3, 3)), K)
    assert np.allclose(res.wd, [np.sqrt(8.0 / 3.0)], rtol=1e-12)
    assert np.allclose(res.shapes[0], res.shapes[1])


# ------------------------------------------------------------------------------------------- anisotropy


def test_anisotropic_jeffcott_planar_modes_at_rest():
    # Jeffcott disk on bearings kxx != kyy, zero speed: x and y decouple, w = sqrt(kxx/m), sqrt(kyy/m)
    # (Friswell et al. 2010, sect. 3.6.1, eq. 3.74), each a straight-line orbit
    m, kxx, kyy = 3.0, 300.0, 480.0
    res = damped_modes(m * np.eye(2), np.zeros((2, 2)), np.diag([kxx, kyy]))
    assert np.allclose(res.wd, [np.sqrt(kxx / m), np.sqrt(kyy / m)], rtol=1e-12)
    assert np.allclose(orbit_kappa(res.shapes, 0, 1), 0.0, atol=1e-12)
    assert np.allclose(np.abs(res.shapes), np.eye(2), atol=1e-12)
    assert whirl(res.shapes, 0, 1) == ["linear", "linear"]  # a straight line has no whirl direction (issue 25)
    assert list(whirl_sign(res.shapes, 0, 1)) == [0, 0]


def test_anisotropic_laval_spinning():
    # tilt stiffnesses kx != ky with gyroscopics: det = (kx - Id w^2)(ky - Id w^2) - Ip^2 Omega^2 w^2 = 0
    # (Friswell et al. 2010, sect. 3.6.2); the lower mode whirls backward, the upper forward
    Id, Ip, kx, ky, speed = 1.0, 0.8, 4.0, 6.0, 2.5
    M, G, _ = laval(Id, Ip, 1.0, speed)
    res = damped_modes(M, G, np.diag([kx, ky]))
    b = Id * (kx + ky) + Ip**2 * speed**2
    w2 = np.sort(np.roots([Id**2, -b, kx * ky]).real)
    assert np.allclose(res.wd, np.sqrt(w2), rtol=1e-12)
    assert whirl(res.shapes, 0, 1) == ["backward", "forward"]
    kappa = orbit_kappa(res.shapes, 0, 1)
    assert kappa[0] < 0 < kappa[1] and np.all(np.abs(kappa) < 1)  # elliptical, not circular


# ------------------------------------------------------------------------------------------- Campbell


def two_rotors(speed, A=(1.0, 0.5, 1.0), B=(1.0, 0.5, 4.0)):
    """Two decoupled Laval tilt rotors, dofs (theta_xA, theta_yA, theta_xB, theta_yB)."""
    pa, pb = laval(*A, speed), laval(*B, speed)
    return {name: sla.block_diag(pa[i], pb[i]) for i, name in enumerate("MCK")}


def test_campbell_tracks_through_a_crossing():
    A, B = (1.0, 0.5, 1.0), (1.0, 0.5, 4.0)
    # rotor A's forward mode rises through rotor B's backward mode; put the crossing on a grid speed too
    cross = brentq(lambda w: omega_fb(*A, w)[0] - omega_fb(*B, w)[1], 0.1, 20.0)
    speeds = np.sort(np.r_[np.linspace(0.0, 8.0, 33), cross])
    res = campbell(two_rotors, speeds, 4, x_index=[0, 2], y_index=[1, 3])
    ref = np.array([[omega_fb(*A, w)[1], omega_fb(*A, w)[0], omega_fb(*B, w)[1], omega_fb(*B, w)[0]]
                    for w in speeds])
    # curve order at speed 0: A (1, 1) then B (2, 2), each pair backward before forward
    assert np.allclose(res.frequencies, ref, rtol=1e-9)
    assert all(row == ["backward", "forward", "backward", "forward"] for row in res.whirl)
    d = np.diff(res.frequencies, axis=0)
    assert np.all(d[:, [0, 2]] < 0) and np.all(d[:, [1, 3]] > 0)  # monotone: no swap
    assert res.frequencies[-1, 1] > res.frequencies[-1, 2]  # the curves did cross (sorting would swap them)
    assert res.mac.min() > 0.99
    assert np.allclose(res.log_dec, 0.0, atol=1e-9)
    # a coarse grid whose first step jumps across the crossing: frequency proximity alone would swap
    # A-forward (1 -> 2.0) with B-backward (2 -> 1.39); the mode shapes (MAC) keep them apart
    coarse = campbell(two_rotors, [0.0, 3.0, 6.0], 4, x_index=[0, 2], y_index=[1, 3])
    ref = np.array([[omega_fb(*A, w)[1], omega_fb(*A, w)[0], omega_fb(*B, w)[1], omega_fb(*B, w)[0]]
                    for w in coarse.speeds])
    assert np.allclose(coarse.frequencies, ref, rtol=1e-9)
    assert all(row == ["backward", "forward", "backward", "forward"] for row in coarse.whirl)


def test_campbell_sparse_path_with_spare_modes():
    # four decoupled Laval rotors (n = 8), ARPACK at every speed; rotor A's forward curve climbs past
    # the backward curves of B, C and D and is followed through the spare modes
    rotors = [(1.0, 0.5, k) for k in (1.0, 4.0, 9.0, 16.0)]

    def mats(speed):
        parts = [laval(*r, speed) for r in rotors]
        return {name: sps.block_diag([p[i] for p in parts], format="csr") for i, name in enumerate("MCK")}

    speeds = np.linspace(0.0, 8.0, 41)
    res = campbell(mats, speeds, 4, x_index=[0, 2, 4, 6], y_index=[1, 3, 5, 7], sparse=True)
    A, B = rotors[0], rotors[1]
    ref = np.array([[omega_fb(*A, w)[1], omega_fb(*A, w)[0], omega_fb(*B, w)[1], omega_fb(*B, w)[0]]
                    for w in speeds])
    assert res.candidates == 6
    assert np.allclose(res.frequencies, ref, rtol=1e-8)
    assert all(row == ["backward", "forward", "backward", "forward"] for row in res.whirl)


def test_campbell_anisotropic_start_is_linear_then_whirls():
    # at Omega = 0 the anisotropic rotor's modes are x-only and y-only (straight lines: 'linear', issue 25);
    # the gyroscopic coupling makes them ellipses, backward (lower) and forward (upper), at every speed > 0
    def mats(speed):
        M, G, _ = laval(1.0, 0.8, 1.0, speed)
        return {"M": M, "C": G, "K": np.diag([4.0, 6.0])}

    res = campbell(mats, np.linspace(0.0, 4.0, 9), 2, x_index=0, y_index=1)
    assert np.allclose(res.frequencies[0], [2.0, np.sqrt(6.0)])
    assert res.whirl[0] == ["linear", "linear"]
    assert all(row == ["backward", "forward"] for row in res.whirl[1:])


def laval_mats(Id, Ip, k, D=0.0):
    def mats(speed):
        M, G, K = laval(Id, Ip, k, speed)
        return {"M": M, "C": G + D * np.eye(2), "K": K}
    return mats


def test_critical_speeds_when_id_exceeds_ip():
    # synchronous crossing w = Omega of Id w^2 -+ Ip Omega w - k = 0: Omega_f = sqrt(k / (Id - Ip)),
    # Omega_b = sqrt(k / (Id + Ip)) (Friswell et al. 2010, sect. 3.5, eq. 3.62)
    Id, Ip, k = 1.0, 0.5, 1.0
    mats = laval_mats(Id, Ip, k)
    res = campbell(mats, np.linspace(0.0, 3.0, 61), 2, x_index=0, y_index=1)
    assert res.whirl[0] == ["backward", "forward"]  # degenerate start resolved
    crit = critical_speeds(res)
    assert [(c["mode"], c["whirl"]) for c in crit] == [(0, "backward"), (1, "forward")]
    assert np.isclose(crit[0]["speed"], np.sqrt(k / (Id + Ip)), rtol=2e-3)
    assert np.isclose(crit[1]["speed"], np.sqrt(k / (Id - Ip)), rtol=2e-3)
    fine = critical_speeds(res, refine=mats)
    assert np.isclose(fine[0]["speed"], np.sqrt(k / (Id + Ip)), rtol=1e-10)
    assert np.isclose(fine[1]["speed"], np.sqrt(k / (Id - Ip)), rtol=1e-10)
    assert np.isclose(fine[1]["frequency"], fine[1]["speed"])
    # twice the spin speed: w = 2 Omega gives 4 Id -+ 2 Ip: Omega = sqrt(k / (4 Id -+ 2 Ip))
    two = critical_speeds(res, multiples=(2.0,), refine=mats)
    assert np.allclose([c["speed"] for c in two], [np.sqrt(k / (4 * Id + 2 * Ip)), np.sqrt(k / (4 * Id - 2 * Ip))],
                       rtol=1e-10)


def test_no_forward_critical_speed_when_ip_exceeds_id():
    # thin disk, Ip = 2 Id: w_f > Omega at every speed, only the backward crossing sqrt(k / (Id + Ip)) remains
    Id, Ip, k = 0.5, 1.0, 1.0
    mats = laval_mats(Id, Ip, k, D=0.01)
    res = campbell(mats, np.linspace(0.0, 50.0, 101), 2, x_index=0, y_index=1)
    assert all(row == ["backward", "forward"] for row in res.whirl)
    assert np.all(res.frequencies[:, 1] > res.speeds)
    assert np.all(res.log_dec > 0)
    crit = critical_speeds(res, refine=mats)
    assert [(c["mode"], c["whirl"]) for c in crit] == [(0, "backward")]
    # light damping shifts the crossing only slightly from the undamped closed form
    assert np.isclose(crit[0]["speed"], np.sqrt(k / (Id + Ip)), rtol=1e-3)


# ------------------------------------------------------------------------------------------- sparse chain


def chain(n_masses, speed=3.0, damping=True):
    """n_masses lumped masses, lateral dofs (x_i, y_i) interleaved, anisotropic springs to neighbours and
    to ground at the ends, gyroscopic coupling g_i Omega between x_i and y_i, proportional damping
    (none with ``damping=False``: a conservative gyroscopic system)."""
    i = np.arange(n_masses)
    m = 1.0 + 0.3 * np.sin(i)

    def lap(k):
        d = np.zeros(n_masses)
        d[:-1] += k[:-1]
        d[1:] += k[:-1]
        d[[0, -1]] += k[-1]
        return sps.diags([d, -k[:-1], -k[:-1]], [0, 1, -1])

    kx = 1e4 * (1.0 + 0.2 * np.cos(0.7 * i))
    perm = np.empty(2 * n_masses, int)
    perm[0::2], perm[1::2] = i, n_masses + i
    K = sps.block_diag([lap(kx), lap(1.3 * kx)]).tocsr()[perm][:, perm]
    M = sps.diags(np.repeat(m, 2)).tocsr()
    g = 0.2 * m * speed
    G = sps.csr_matrix((np.r_[g, -g], (np.r_[2 * i, 2 * i + 1], np.r_[2 * i + 1, 2 * i])), shape=K.shape)
    return M, ((1e-4 * K + 0.01 * M + G) if damping else G).tocsr(), K


def test_sparse_chain_agrees_with_dense():
    M, C, K = chain(100)  # 100 masses x (x, y) = 200 dofs, a 400 x 400 pencil
    sp = damped_modes(M, C, K, 8)
    de = damped_modes(M.toarray(), C.toarray(), K.toarray(), 8)
    assert np.allclose(sp.eigenvalues, de.eigenvalues, rtol=1e-8, atol=0)
    assert np.allclose(sp.log_dec, de.log_dec, rtol=1e-6)
    assert np.all(np.diag(mac_matrix(sp.shapes, de.shapes)) > 1 - 1e-8)
    xs, ys = np.arange(0, 200, 2), np.arange(1, 200, 2)
    assert whirl(sp.shapes, xs, ys) == whirl(de.shapes, xs, ys)


def test_dense_path_matches_the_qz_pencil():
    # an independent reference for the dense path: QZ on A x = s B x as written (no Cholesky, no scaling)
    M, C, K = chain(15)
    n = M.shape[0]
    de = damped_modes(M.toarray(), C.toarray(), K.toarray())
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K.toarray(), -C.toarray()]])
    B = sla.block_diag(np.eye(n), M.toarray())
    s = sla.eigvals(A, B)
    s = s[s.imag > 0]
    assert np.allclose(de.eigenvalues, s[np.argsort(s.imag)], rtol=1e-9)
    assert de.eigenvalues.size == n


# ------------------------------------------------------------------------------------------- reduced basis


def chain_at(n_masses, damping=True):
    def mats(speed):
        M, C, K = chain(n_masses, speed, damping)
        return {"M": M, "C": C, "K": K}
    return mats


CHAIN_STATIONS = {"x_index": np.arange(0, 120, 2), "y_index": np.arange(1, 120, 2)}


def test_speed_polynomial_detection_and_fallback():
    K0, K2, G1 = (sps.random(30, 30, density=0.2, random_state=k, format="csr") for k in range(3))
    M = sps.identity(30, format="csr")
    lin = fit_speed_polynomial(lambda w: {"M": M, "G": w * G1}, 0.0, 100.0)
    assert isinstance(lin, SpeedPolynomial) and lin.degree == 1 and len(lin.terms["M"]) == 1  # M constant
    quad = fit_speed_polynomial(lambda w: {"M": M, "K": K0 - w**2 * K2, "G": w * G1}, 10.0, 60.0)
    assert quad.degree == 2
    for w in (10.0, 23.7, 60.0, 45.0):
        at = quad(w)
        assert abs(at["K"] - (K0 - w**2 * K2)).max() <= 1e-12 * abs(K0 - w**2 * K2).max()
        assert abs(at["G"] - w * G1).max() <= 1e-12 * abs(w * G1).max()
    both = quad.combined({"C": ("G",), "KM": ("K", "M")})
    assert abs(both(30.0)["KM"] - (K0 - 900.0 * K2 + M)).max() < 1e-9
    # not polynomial (or cubic): no fit, the caller assembles at every speed
    assert fit_speed_polynomial(lambda w: {"M": M, "G": np.sin(w / 50.0) * G1}, 0.0, 100.0) is None
    assert fit_speed_polynomial(lambda w: {"M": M, "K": K0 + (w / 10.0) ** 3 * K2}, 0.0, 100.0) is None
    assert fit_speed_polynomial(lambda w: {"M": M}, 5.0, 5.0) is None


@pytest.mark.parametrize("damping", [True, False])
def test_reduced_campbell_equals_exact(damping):
    # 60 masses (120 dofs): modes solved at full size at the ends only, the rest on the reduced basis
    mats = chain_at(60, damping)
    speeds = np.linspace(0.0, 30.0, 25)
    poly = fit_speed_polynomial(mats, speeds[0], speeds[-1])
    assert poly is not None and poly.degree == 1
    red = campbell(poly, speeds, 6, **CHAIN_STATIONS, sparse=True)
    ex = campbell(mats, speeds, 6, **CHAIN_STATIONS, sparse=True)
    assert red.method == "reduced" and ex.method == "exact" and ex.exact_solves == 25
    assert red.exact_solves < 8 and 0 < red.basis_size < 120
    assert np.allclose(red.frequencies, ex.frequencies, rtol=1e-8, atol=0)
    assert red.whirl == ex.whirl
    assert np.allclose(red.log_dec, ex.log_dec, rtol=1e-5, atol=1e-12)
    assert np.all(np.abs(np.sum(red.shapes.conj() * ex.shapes, axis=1)) ** 2
                  / (np.sum(np.abs(red.shapes) ** 2, axis=1) * np.sum(np.abs(ex.shapes) ** 2, axis=1)) > 1 - 1e-8)
    forced = campbell(poly, speeds, 6, **CHAIN_STATIONS, sparse=True, method="exact")
    assert forced.method == "exact" and np.allclose(forced.frequencies, ex.frequencies, rtol=1e-12)
    # critical speeds: secant on the reduced model, one exact solve, equal to the exact path's
    cr, ce = critical_speeds(red, refine=poly, sparse=True), critical_speeds(ex, refine=mats, sparse=True)
    assert len(cr) == len(ce) > 0
    assert [(c["mode"], c["whirl"]) for c in cr] == [(c["mode"], c["whirl"]) for c in ce]
    assert np.allclose([c["speed"] for c in cr], [c["speed"] for c in ce], rtol=1e-10)
    for c in cr:  # each is a fixed point: some mode at that speed has wd = speed
        wd = damped_modes(**mats(c["speed"]), count=8, sparse=True).wd
        assert np.min(np.abs(wd - c["speed"])) <= 1e-9 * c["speed"]


def test_reduced_campbell_enriches_where_the_basis_fails():
    # a wide range (the gyroscopic terms dominate at the top): the ends' modes do not span the middle's,
    # the safeguard solves there at full size and enriches the basis; the result equals the exact path
    mats = chain_at(60)
    speeds = np.linspace(0.0, 400.0, 30)
    poly = fit_speed_polynomial(mats, speeds[0], speeds[-1])
    red = campbell(poly, speeds, 6, **CHAIN_STATIONS, sparse=True)
    ex = campbell(mats, speeds, 6, **CHAIN_STATIONS, sparse=True)
    assert red.method == "reduced" and red.exact_solves > 2
    assert np.allclose(red.frequencies, ex.frequencies, rtol=1e-8, atol=0)
    assert red.whirl == ex.whirl


def test_reduced_campbell_through_a_crossing_and_degenerate_start():
    # the two Laval rotors (isotropic: a double eigenvalue at rest) as a 'reduced' problem: the degenerate
    # start and the crossing are handled as on the exact path
    speeds = np.linspace(0.0, 8.0, 33)
    poly = fit_speed_polynomial(two_rotors, speeds[0], speeds[-1])
    red = campbell(poly, speeds, 4, x_index=[0, 2], y_index=[1, 3], method="reduced")
    ex = campbell(two_rotors, speeds, 4, x_index=[0, 2], y_index=[1, 3])
    assert red.method == "reduced"
    assert np.allclose(red.frequencies, ex.frequencies, rtol=1e-9)
    assert red.whirl == ex.whirl == [["backward", "forward", "backward", "forward"]] * 33


# ------------------------------------------------------------------------------------------- bad input


def test_bad_input():
    M, G, K = laval(1.0, 0.5, 1.0, 1.0)
    with pytest.raises(InputError, match="count 3 is larger"):
        damped_modes(M, G, K, 3)
    with pytest.raises(InputError, match="C has shape"):
        damped_modes(M, np.zeros((3, 3)), K)
    with pytest.raises(InputError, match="K has shape"):
        damped_modes(sps.identity(4), sps.identity(4), sps.identity(3), 1)
    with pytest.raises(InputError, match="square"):
        damped_modes(np.ones((2, 3)), G, K)
    with pytest.raises(InputError, match="NaN"):
        damped_modes(M, G, K * np.nan)
    with pytest.raises(InputError, match="count"):
        damped_modes(M, G, K, 0)
    with pytest.raises(InputError, match="x_index"):
        whirl(np.ones((2, 1)), [0, 1], [1])
    with pytest.raises(InputError, match="out of range"):
        whirl(np.ones((2, 1)), 0, 5)
    mats = laval_mats(1.0, 0.5, 1.0)
    with pytest.raises(InputError, match="count 3 is larger"):
        campbell(mats, [0.0, 1.0], 3, x_index=0, y_index=1)
    with pytest.raises(InputError, match="increasing"):
        campbell(mats, [1.0, 0.0], 1, x_index=0, y_index=1)
    with pytest.raises(InputError, match="matrices_at"):
        campbell(lambda w: (M, G, K), [0.0], 1, x_index=0, y_index=1)
    with pytest.raises(InputError, match="oscillatory"):  # overdamped: no whirl mode to track
        campbell(lambda w: {"M": np.eye(2), "C": 5 * np.eye(2), "K": np.eye(2)}, [0.0], 1, x_index=0, y_index=1)
    with pytest.raises(InputError, match="SpeedPolynomial"):  # the reduced basis needs the speed polynomial
        campbell(mats, [0.0, 1.0], 1, x_index=0, y_index=1, method="reduced")
    with pytest.raises(InputError, match="method"):
        campbell(mats, [0.0, 1.0], 1, x_index=0, y_index=1, method="fast")
    with pytest.raises(InputError, match="needs a mode count"):
        damped_modes(M, G, K, sparse=True)
    # a shift exactly on an eigenvalue (negative stiffness -4: s = 2) makes A - sigma B singular
    Kneg = np.diag([-4.0, 1.0, 2.0, 3.0, 5.0])
    with pytest.raises(ConvergenceError, match="sigma"):
        damped_modes(sps.identity(5), sps.csr_matrix((5, 5)), sps.csr_matrix(Kneg), 1, sigma=2.0, sparse=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        damped_modes(M, G, K, 2)
