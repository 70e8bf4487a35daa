"""Closed-form plane elasticity fields: references for the plane solvers and the fracture integrals.

Everything is linear isotropic elasticity in the (x, y) plane, per unit thickness, in consistent units
(lengths m, stresses and moduli Pa, weight per unit volume N/m^3, energies J/m, forces N/m). One material
object, :class:`PlaneElastic`, carries the plane switch: Kolosov's constant

    kappa = 3 - 4 nu          (plane strain)
    kappa = (3 - nu)/(1 + nu) (plane stress, the default),

mu = E / (2 (1 + nu)), the in-plane Lame constant lambda* = mu (3 - kappa)/(kappa - 1) (lambda in plane
strain, 2 lambda mu/(lambda + 2 mu) in plane stress) and the crack modulus E' = 8 mu/(kappa + 1)
(E in plane stress, E/(1 - nu^2) in plane strain).

Fields without body force come from Kolosov-Muskhelishvili potentials phi(z), psi(z), z = x + i y,
Phi = phi', Psi = psi' (:func:`fields_from_potentials`):

    2 mu (u_x + i u_y) = kappa phi(z) - z conj(phi'(z)) - conj(psi(z))
    sigma_xx + sigma_yy = 4 Re Phi(z)
    sigma_yy - sigma_xx + 2 i sigma_xy = 2 (conj(z) Phi'(z) + Psi(z)).

Cases (each checked symbolically in tests/test_plane_closed_forms.py):

* the circular membrane under in-plane gravity (Tejeda, Lovell & Engelstad, J. Appl. Mech. 67 (2000) 837,
  Michell's solution): a disk of radius R fixed at its rim, weight rho_g per unit volume acting in -y;
* the annulus a < r < b, inner edge free, outer edge fixed, same load (Michell's n = 1 terms with the
  logarithmic force terms; derived here, not in the paper);
* the Griffith crack |x| < a, y = 0 in an infinite plate under remote sigma11, sigma22, sigma12;
* the Williams eigenfunctions at a crack tip (K_I, K_II, the T-stress, the point force at the tip and
  Bueckner's r^(-3/2) field), the auxiliary fields of the interaction and Bueckner integrals.

Arrays: points are given as x, y arrays of any common shape S; displacements come back as S + (2,),
gradients u_i,j and stresses as S + (2, 2) (index order [i, j]).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.errors import InputError

__all__ = [
    "PlaneElastic", "PlaneField", "fields_from_potentials", "membrane_field", "membrane_polar_stress",
    "membrane_strain_energy", "membrane_rim_traction", "membrane_rim_reaction", "annulus_coefficients",
    "annulus_field", "annulus_strain_energy", "annulus_rim_traction", "CrackTip", "GriffithCrack", "crack_sqrt",
    "griffith_field", "griffith_rotation_field", "griffith_sif", "williams_field", "tip_frame_field", "k_field",
    "t_field", "point_force_field", "bueckner_weight", "bueckner_field",
]


@dataclass(frozen=True)
class PlaneElastic:
    """An isotropic linear elastic material in the plane: E (Pa), nu, plane = "stress" | "strain"."""

    E: float
    nu: float
    plane: str = "stress"

    def __post_init__(self) -> None:
        if self.plane not in ("stress", "strain"):
            raise InputError(f"plane must be 'stress' or 'strain', not {self.plane!r}", key="plane",
                             expected='"stress" or "strain"')
        if not (np.isfinite(self.E) and self.E > 0):
            raise InputError(f"Young's modulus must be positive and finite, not {self.E!r}", key="E",
                             expected="E > 0")
        if not (-1.0 < self.nu < 0.5):
            raise InputError(f"Poisson's ratio must lie in (-1, 0.5), not {self.nu!r}", key="nu",
                             expected="-1 < nu < 0.5")

    @property
    def mu(self) -> float:
        """Shear modulus mu = E / (2 (1 + nu)) (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def kappa(self) -> float:
        """Kolosov's constant: 3 - 4 nu (plane strain) or (3 - nu)/(1 + nu) (plane stress)."""
        return 3.0 - 4.0 * self.nu if self.plane == "strain" else (3.0 - self.nu) / (1.0 + self.nu)

    @property
    def lam(self) -> float:
        """In-plane Lame constant lambda* = mu (3 - kappa)/(kappa - 1) (Pa)."""
        return self.mu * (3.0 - self.kappa) / (self.kappa - 1.0)

    @property
    def modulus(self) -> float:
        """Crack modulus E' = 8 mu/(kappa + 1): E (plane stress), E/(1 - nu^2) (plane strain) (Pa)."""
        return 8.0 * self.mu / (self.kappa + 1.0)


@dataclass(frozen=True)
class PlaneField:
    """Displacement u (S,2) (m), gradient grad[..., i, j] = u_i,j (S,2,2), stress (S,2,2) (Pa)."""

    u: np.ndarray
    grad: np.ndarray
    stress: np.ndarray

    @property
    def strain(self) -> np.ndarray:
        """eps_ij = (u_i,j + u_j,i)/2."""
        return 0.5 * (self.grad + np.swapaxes(self.grad, -1, -2))

    @property
    def energy_density(self) -> np.ndarray:
        """W = sigma_ij eps_ij / 2 (J/m^3; in plane stress and plane strain alike, sigma_zz eps_zz = 0)."""
        return 0.5 * np.einsum("...ij,...ij->...", self.stress, self.strain)

    def __add__(self, other: "PlaneField") -> "PlaneField":
        return PlaneField(self.u + other.u, self.grad + other.grad, self.stress + other.stress)


def _stack2(a, b):
    return np.stack([a, b], axis=-1)


def _stack22(a11, a12, a21, a22):
    return np.stack([np.stack([a11, a12], axis=-1), np.stack([a21, a22], axis=-1)], axis=-2)


def fields_from_potentials(z, phi, Phi, dPhi, psi, Psi, mat: PlaneElastic) -> PlaneField:
    """Displacement, gradient and stress from Kolosov-Muskhelishvili potentials at the points z.

    2 mu D = kappa phi - z conj(Phi) - conj(psi), D = u_x + i u_y; dD/dz = (kappa Phi - conj Phi)/(2 mu),
    dD/dzbar = -(z conj(Phi') + conj(Psi))/(2 mu); D_,x = D_z + D_zbar, D_,y = i (D_z - D_zbar).
    sigma_xx + sigma_yy = 4 Re Phi, sigma_yy - sigma_xx + 2 i sigma_xy = 2 (conj(z) Phi' + Psi).
    """
    mu, kappa = mat.mu, mat.kappa
    disp = (kappa * phi - z * np.conj(Phi) - np.conj(psi)) / (2.0 * mu)
    d_z = (kappa * Phi - np.conj(Phi)) / (2.0 * mu)
    d_zb = -(z * np.conj(dPhi) + np.conj(Psi)) / (2.0 * mu)
    d_x, d_y = d_z + d_zb, 1j * (d_z - d_zb)
    s_sum = 4.0 * Phi.real
    s_dif = 2.0 * (np.conj(z) * dPhi + Psi)
    sxx, syy, sxy = 0.5 * (s_sum - s_dif.real), 0.5 * (s_sum + s_dif.real), 0.5 * s_dif.imag
    return PlaneField(_stack2(disp.real, disp.imag), _stack22(d_x.real, d_y.real, d_x.imag, d_y.imag),
                      _stack22(sxx, sxy, sxy, syy))


# --- the circular membrane and the annulus under in-plane gravity ------------------------------------


def _gravity_particular(x, y, R, mat: PlaneElastic, rho_g) -> PlaneField:
    """u = (0, c (x^2 + y^2 - R^2)), c = rho_g (kappa - 1)/(4 mu kappa): equilibrium with f = (0, -rho_g).

    sigma_xx = rho_g (3 - kappa) y/(2 kappa), sigma_yy = rho_g (kappa + 1) y/(2 kappa),
    sigma_xy = rho_g (kappa - 1) x/(2 kappa); div sigma = (0, rho_g) balances the weight.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    kappa = mat.kappa
    c = rho_g * (kappa - 1.0) / (4.0 * mat.mu * kappa)
    zero = np.zeros_like(x + y)
    u = _stack2(zero, c * (x * x + y * y - R * R) + zero)
    grad = _stack22(zero, zero, 2.0 * c * x + zero, 2.0 * c * y + zero)
    sxx = rho_g * (3.0 - kappa) / (2.0 * kappa) * y + zero
    syy = rho_g * (kappa + 1.0) / (2.0 * kappa) * y + zero
    sxy = rho_g * (kappa - 1.0) / (2.0 * kappa) * x + zero
    return PlaneField(u, grad, _stack22(sxx, sxy, sxy, syy))


def membrane_field(x, y, R: float, mat: PlaneElastic, rho_g: float) -> PlaneField:
    """The disk r < R fixed at r = R under the weight rho_g (N/m^3) acting in -y (Tejeda et al. 2000).

    u_x = 0, u_y = c (r^2 - R^2), c = rho_g (kappa - 1)/(4 mu kappa)  (plane stress: rho_g (1 - nu^2)/(E (3 - nu)),
    the paper's eqs. 28-29 in Cartesian form); stresses (paper's eqs. 30-32, plane stress):
    sigma_xx = 2 nu rho_g y/(3 - nu), sigma_yy = 2 rho_g y/(3 - nu), sigma_xy = (1 - nu) rho_g x/(3 - nu);
    in kappa: sigma_xx = rho_g (3 - kappa) y/(2 kappa), sigma_yy = rho_g (kappa + 1) y/(2 kappa),
    sigma_xy = rho_g (kappa - 1) x/(2 kappa). Plane strain: the same with kappa = 3 - 4 nu
    (sigma_zz = nu (sigma_xx + sigma_yy) is then not in the 2 x 2 stress).
    """
    _check_positive(R=R)
    return _gravity_particular(x, y, R, mat, rho_g)


def membrane_polar_stress(r, theta, mat: PlaneElastic, rho_g: float):
    """(sigma_rr, sigma_tt, sigma_rt) of the membrane (Pa), the paper's eqs. 22-24.

    sigma_rr = rho_g r (kappa + 1) sin(theta)/(2 kappa)   (plane stress: 2 rho_g r sin(theta)/(3 - nu))
    sigma_tt = rho_g r (3 - kappa) sin(theta)/(2 kappa)   (plane stress: 2 nu rho_g r sin(theta)/(3 - nu))
    sigma_rt = rho_g r (kappa - 1) cos(theta)/(2 kappa)   (plane stress: (1 - nu) rho_g r cos(theta)/(3 - nu)).
    """
    kappa = mat.kappa
    r, theta = np.asarray(r, float), np.asarray(theta, float)
    return (rho_g * r * (kappa + 1.0) * np.sin(theta) / (2.0 * kappa),
            rho_g * r * (3.0 - kappa) * np.sin(theta) / (2.0 * kappa),
            rho_g * r * (kappa - 1.0) * np.cos(theta) / (2.0 * kappa))


def membrane_strain_energy(R: float, mat: PlaneElastic, rho_g: float) -> float:
    """U = int W dA = pi rho_g^2 (kappa - 1) R^4/(16 mu kappa) (J/m); plane stress pi rho_g^2 R^4 (1-nu^2)/(4 E (3-nu)).

    Clapeyron: U = (1/2) int f.u dA (the rim does no work); Pi = U - int f.u dA = -U.
    """
    _check_positive(R=R)
    return np.pi * rho_g ** 2 * (mat.kappa - 1.0) * R ** 4 / (16.0 * mat.mu * mat.kappa)


def membrane_rim_traction(theta, R: float, mat: PlaneElastic, rho_g: float) -> np.ndarray:
    """Force per unit rim length (N/m^2 per unit thickness) the support exerts on the disk: t = sigma . e_r at r = R.

    t = sigma_rr e_r + sigma_rt e_theta; resultant int t R dtheta = (0, pi R^2 rho_g) carries the weight.
    """
    theta = np.asarray(theta, float)
    srr, _, srt = membrane_polar_stress(R, theta, mat, rho_g)
    c, s = np.cos(theta), np.sin(theta)
    return _stack2(srr * c - srt * s, srr * s + srt * c)


def membrane_rim_reaction(R: float, rho_g: float) -> np.ndarray:
    """The rim's resultant force on the disk (N/m): (0, pi R^2 rho_g), equal and opposite to the weight."""
    return np.array([0.0, np.pi * R * R * rho_g])


def annulus_coefficients(a: float, b: float, mat: PlaneElastic, rho_g: float) -> dict:
    """The imaginary coefficients of the annulus's homogeneous potentials (derived with sympy, checked in tests).

    phi = A log(z/b) + B z^2/2,  psi = C log(z/b) + D/z^2,  C = -kappa conj(A) (single-valued u), plus the
    translation i T2; A = i A2, B = i B2, D = i D2 with
      A2 = -a^2 rho_g/(2 (kappa + 1))        (the force pi a^2 rho_g the hole's missing weight does not carry)
      B2 = a^2 rho_g (2 kappa b^2 - (kappa - 1) a^2)/(2 kappa (kappa + 1) (a^4 + kappa b^4))
      D2 = a^4 b^2 rho_g (2 a^2 + (kappa - 1) b^2)/(4 (kappa + 1) (a^4 + kappa b^4))
      T2 = -b^2 B2/(2 mu).
    """
    _check_positive(a=a, b=b)
    if not a < b:
        raise InputError(f"the annulus needs a < b, got a = {a!r}, b = {b!r}", key="a", expected="0 < a < b")
    kappa, den = mat.kappa, a ** 4 + mat.kappa * b ** 4
    A2 = -a * a * rho_g / (2.0 * (kappa + 1.0))
    B2 = a * a * rho_g * (2.0 * kappa * b * b - (kappa - 1.0) * a * a) / (2.0 * kappa * (kappa + 1.0) * den)
    D2 = a ** 4 * b * b * rho_g * (2.0 * a * a + (kappa - 1.0) * b * b) / (4.0 * (kappa + 1.0) * den)
    return {"A2": A2, "B2": B2, "D2": D2, "T2": -b * b * B2 / (2.0 * mat.mu)}


def annulus_field(x, y, a: float, b: float, mat: PlaneElastic, rho_g: float) -> PlaneField:
    """The annulus a < r < b, r = a traction-free, r = b fixed, weight rho_g (N/m^3) in -y.

    u = (0, c (r^2 - b^2)) (the membrane's field, :func:`membrane_field` with R = b) + the potentials of
    :func:`annulus_coefficients`, which cancel its traction sigma . e_r on r = a and vanish on r = b.
    No polynomial field does this: the hole's free edge needs the log z force terms and 1/z^2.
    """
    co = annulus_coefficients(a, b, mat, rho_g)
    x, y = np.asarray(x, float), np.asarray(y, float)
    z = x + 1j * y
    A, B, D = 1j * co["A2"], 1j * co["B2"], 1j * co["D2"]
    C = -mat.kappa * np.conj(A)
    logz = np.log(z / b)
    hom = fields_from_potentials(z, A * logz + B * z * z / 2.0, A / z + B * z, -A / z ** 2 + B,
                                 C * logz + D / z ** 2, C / z - 2.0 * D / z ** 3, mat)
    shift = np.zeros(z.shape + (2,))
    shift[..., 1] = co["T2"]
    hom = PlaneField(hom.u + shift, hom.grad, hom.stress)
    return _gravity_particular(x, y, b, mat, rho_g) + hom


def annulus_strain_energy(a: float, b: float, mat: PlaneElastic, rho_g: float) -> float:
    """U = -(rho_g/2) int u_y dA (Clapeyron; the free edge has no traction, the fixed edge no displacement) (J/m).

    int u_y dA = -pi c (b^2 - a^2)^2/2 + (kappa A2/mu)(-pi (b^2 - a^2)/2 - pi a^2 log(a/b))
                 + B2 pi (b^4 - a^4)/(4 mu) + T2 pi (b^2 - a^2), c = rho_g (kappa - 1)/(4 mu kappa)
    (the theta-mean of u_y: c (r^2 - b^2) + (2 kappa A2 log(r/b) + B2 r^2)/(2 mu) + T2).
    """
    co, mu, kappa = annulus_coefficients(a, b, mat, rho_g), mat.mu, mat.kappa
    c = rho_g * (kappa - 1.0) / (4.0 * mu * kappa)
    d2 = b * b - a * a
    mean = (-np.pi * c * d2 ** 2 / 2.0
            + kappa * co["A2"] / mu * (-np.pi * d2 / 2.0 - np.pi * a * a * np.log(a / b))
            + co["B2"] * np.pi * (b ** 4 - a ** 4) / (4.0 * mu) + co["T2"] * np.pi * d2)
    return -0.5 * rho_g * mean


def annulus_rim_traction(theta, a: float, b: float, mat: PlaneElastic, rho_g: float) -> np.ndarray:
    """Force per unit length the fixed rim r = b exerts on the annulus: sigma . e_r at r = b (N/m^2 per thickness).

    Resultant: (0, pi (b^2 - a^2) rho_g), the weight of the annulus.
    """
    theta = np.asarray(theta, float)
    f = annulus_field(b * np.cos(theta), b * np.sin(theta), a, b, mat, rho_g)
    return np.einsum("...ij,...j->...i", f.stress, _stack2(np.cos(theta), np.sin(theta)))


def _check_positive(**values) -> None:
    for key, v in values.items():
        if not (np.isfinite(v) and v > 0):
            raise InputError(f"{key} must be positive and finite, not {v!r}", key=key, expected=f"{key} > 0")


# --- the Griffith crack ------------------------------------------------------------------------------


def _complex(x, y) -> np.ndarray:
    """x + i y keeping the sign of a zero y (x + 1j * y would turn -0.0 into +0.0 and lose the crack face)."""
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    z = np.array(x, dtype=complex)
    z.imag = y
    return z


@dataclass(frozen=True)
class CrackTip:
    """A crack tip: its position (x, y) (m) and the angle (rad) of its crack's extension from the x axis.

    The tip's frame has x along the extension and y to its left: Q = [[cos, -sin], [sin, cos]] maps its
    components to global ones.
    """

    position: tuple
    angle: float = 0.0

    @property
    def rotation(self) -> np.ndarray:
        """Q, the rotation by angle (global = Q local)."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class GriffithCrack:
    """The slit |x| < a, y = 0 in an infinite plate under remote stresses sigma11, sigma22, sigma12 (Pa)."""

    a: float
    s11: float = 0.0
    s22: float = 0.0
    s12: float = 0.0

    def __post_init__(self) -> None:
        _check_positive(a=self.a)

    def tips(self) -> tuple:
        """The right tip (a, 0), facing +x, and the left tip (-a, 0), facing -x (angle pi)."""
        return (CrackTip((self.a, 0.0), 0.0), CrackTip((-self.a, 0.0), np.pi))


def crack_sqrt(z, a: float) -> np.ndarray:
    """X(z) = sqrt(z - a) sqrt(z + a): the branch of sqrt(z^2 - a^2) cut on [-a, a] with X ~ z at infinity.

    Principal roots: sqrt(z + a) jumps on x < -a, sqrt(z - a) on x < a; the product jumps only on |x| < a.
    On the faces X = +i sqrt(a^2 - x^2) (y = +0.0, upper) and -i sqrt(a^2 - x^2) (y = -0.0, lower).
    """
    z = np.asarray(z, complex)
    # z + a in complex arithmetic would turn a face's -0.0 into +0.0: build both factors part by part
    return np.sqrt(_complex(z.real - a, z.imag)) * np.sqrt(_complex(z.real + a, z.imag))


def griffith_field(x, y, crack: GriffithCrack, mat: PlaneElastic) -> PlaneField:
    """The Griffith crack's exact field (Muskhelishvili), at points off the slit or on a face (signed zero y).

    With s = sigma22 - i sigma12, g = (sigma11 - sigma22)/2 + i sigma12, X = :func:`crack_sqrt`:
      Phi = (s z/X + g)/2,  Phi' = -s a^2/(2 X^3),  phi = (s X + g z)/2,
      Psi = (conj(s) z/X - conj(g))/2 - Phi - z Phi',  psi = (conj(s) X - conj(g) z)/2 - z Phi.
    This is Phi + Omega = s z/X, Phi - Omega = g (Omega(z) = conj(Phi)(z) + z conj(Phi)'(z) + conj(Psi)(z)),
    so sigma_yy - i sigma_xy = Phi^+ + Omega^- = 0 on both faces; at infinity sigma -> the remote stresses.
    The displacement is fixed up to a rigid motion by phi, psi as written (u is odd in z: u(-z) = -u(z)).
    """
    z, a = _complex(x, y), crack.a
    s = crack.s22 - 1j * crack.s12
    g = 0.5 * (crack.s11 - crack.s22) + 1j * crack.s12
    X = crack_sqrt(z, a)
    Phi = 0.5 * (s * z / X + g)
    dPhi = -0.5 * s * a * a / X ** 3
    phi = 0.5 * (s * X + g * z)
    Psi = 0.5 * (np.conj(s) * z / X - np.conj(g)) - Phi - z * dPhi
    psi = 0.5 * (np.conj(s) * X - np.conj(g) * z) - z * Phi
    return fields_from_potentials(z, phi, Phi, dPhi, psi, Psi, mat)


def griffith_rotation_field(x, y, crack: GriffithCrack, mat: PlaneElastic) -> PlaneField:
    """Shi, Liu & Li's supplemental field (their eq. 4): the Griffith field's derivative in a rigid rotation.

    If u(x) solves the problem, so does Q u(Q^T x) (isotropy); d/dtheta at theta = 0 gives
    u^II = (y d/dx - x d/dy) u + (-u_y, u_x), sigma^II = (y d/dx - x d/dy) sigma + E sigma - sigma E
    (E = [[0, -1], [1, 0]]), i.e. Phi^II = -i z Phi', Psi^II = -i z Psi' - 2 i Psi,
    phi^II = i (phi - z Phi), psi^II = -i (psi + z Psi). On the faces it is NOT traction-free:
    sigma^II_xy = d(x sigma_xx)/dx, sigma^II_yy = 0 (differentiate the faces' zero traction along them).
    """
    z, a = _complex(x, y), crack.a
    s = crack.s22 - 1j * crack.s12
    g = 0.5 * (crack.s11 - crack.s22) + 1j * crack.s12
    X = crack_sqrt(z, a)
    Phi, phi = 0.5 * (s * z / X + g), 0.5 * (s * X + g * z)
    dPhi, ddPhi = -0.5 * s * a * a / X ** 3, 1.5 * s * a * a * z / X ** 5
    Psi = 0.5 * (np.conj(s) * z / X - np.conj(g)) - Phi - z * dPhi
    dPsi = -0.5 * np.conj(s) * a * a / X ** 3 - 2.0 * dPhi - z * ddPhi
    psi = 0.5 * (np.conj(s) * X - np.conj(g) * z) - z * Phi
    return fields_from_potentials(z, 1j * (phi - z * Phi), -1j * z * dPhi, -1j * (dPhi + z * ddPhi),
                                  -1j * (psi + z * Psi), -1j * (z * dPsi + 2.0 * Psi), mat)


def griffith_sif(crack: GriffithCrack) -> dict:
    """K_I = sigma22 sqrt(pi a), K_II = sigma12 sqrt(pi a) (Pa m^0.5), T = sigma11 - sigma22 (Pa), at each tip.

    Each tip in its own frame (x along the crack's extension, y to its left): the left tip's frame is the
    right tip's turned by pi, under which the Griffith field is symmetric, so both tips share the values.
    """
    root = np.sqrt(np.pi * crack.a)
    return {"K_I": crack.s22 * root, "K_II": crack.s12 * root, "T": crack.s11 - crack.s22}


# --- Williams eigenfunctions at a tip (local frame: tip at 0, crack along the negative x axis) ---------


def williams_field(x, y, n: int, A: complex, mat: PlaneElastic) -> PlaneField:
    """The n-th Williams eigenfunction of a traction-free crack along theta = +-pi, lambda = n/2.

    Phi = A z^(lambda - 1), Omega = B z^(lambda - 1) with B = A (n odd) or B = -A (n even) makes the faces
    traction-free; Psi = (conj(B) - lambda A) z^(lambda - 1), phi = A z^lambda/lambda,
    psi = (conj(B) - lambda A) z^lambda/lambda (log z in place of z^lambda/lambda for n = 0).
    Stresses ~ r^(n/2 - 1): n = 1 the K field, n = 2 the T-stress (and a rotation), n = 0 a point force at
    the tip, n = -1 Bueckner's field (r^(-3/2)). Principal powers: the cut lies on the faces.
    """
    z = _complex(x, y)
    lam = 0.5 * n
    B = A if n % 2 else -A
    cpsi = np.conj(B) - lam * A
    Phi, dPhi = A * z ** (lam - 1.0), A * (lam - 1.0) * z ** (lam - 2.0)
    Psi = cpsi * z ** (lam - 1.0)
    prim = np.log(z) if n == 0 else z ** lam / lam
    return fields_from_potentials(z, A * prim, Phi, dPhi, cpsi * prim, Psi, mat)


def k_field(x, y, K_I: float, K_II: float, mat: PlaneElastic) -> PlaneField:
    """The K field: Williams n = 1 with A = (K_I - i K_II)/(2 sqrt(2 pi)) (K in Pa m^0.5).

    Ahead of the tip (theta = 0) sigma_yy = K_I/sqrt(2 pi r), sigma_xy = K_II/sqrt(2 pi r).
    """
    return williams_field(x, y, 1, (K_I - 1j * K_II) / (2.0 * np.sqrt(2.0 * np.pi)), mat)


def t_field(x, y, T: float, mat: PlaneElastic) -> PlaneField:
    """The T-stress field: sigma_xx = T, the rest zero (Williams n = 2, A = T/4)."""
    return williams_field(x, y, 2, T / 4.0, mat)


def point_force_field(x, y, f: float, mat: PlaneElastic) -> PlaneField:
    """A point force f (N/m) at the tip in +x (Williams n = 0, A = -f/(4 pi)): sigma_rr = -f cos(theta)/(pi r).

    Flamant's radial field over the cut plane; sigma_ij = -f x_i x_j x/(pi r^4), i.e. sigma_xx = -f cos^3/(pi r)
    (Kfouri's auxiliary field for the T-stress). The material around the tip carries the force: the
    tractions on a circle about the tip sum to -f e_x on the disk inside.
    """
    return williams_field(x, y, 0, -f / (4.0 * np.pi), mat)


def bueckner_weight(mat: PlaneElastic) -> float:
    """w_B = mu/(sqrt(2 pi) (kappa + 1)) (Pa): the scale of Bueckner's field that makes his integral give K.

    For Williams coefficients A_1 (n = 1) of u and A_-1 (n = -1) of v, Betti's integral about the tip is
    B(u, v) = -(4 pi (kappa + 1)/mu) Re(A_1 conj(A_-1)) (every other pair of orders gives zero), and
    A_1 = (K_I - i K_II)/(2 sqrt(2 pi)); so A_-1 = -w_B gives B = K_I and A_-1 = i w_B gives B = K_II.
    """
    return mat.mu / (np.sqrt(2.0 * np.pi) * (mat.kappa + 1.0))


def bueckner_field(x, y, mode: str, mat: PlaneElastic) -> PlaneField:
    """Bueckner's fundamental field (Williams n = -1: u ~ r^(-1/2), stresses ~ r^(-3/2)), normalised to give K.

    mode "I": A = -w_B, mode "II": A = i w_B (:func:`bueckner_weight`), so that Bueckner's integral
    B(u, v) = oint_C (u . sigma[v] n - v . sigma[u] n) ds over a contour C about the tip (counter-clockwise
    from the lower face to the upper, n pointing away from the tip) equals K_I or K_II of u.
    """
    if mode not in ("I", "II"):
        raise InputError(f"mode must be 'I' or 'II', not {mode!r}", key="mode", expected='"I" or "II"')
    weight = bueckner_weight(mat)
    return williams_field(x, y, -1, -weight if mode == "I" else 1j * weight, mat)


def tip_frame_field(x, y, tip: CrackTip, local) -> PlaneField:
    """A field given in a tip's frame (origin at the tip, x along its angle) evaluated at global points.

    local(xl, yl) -> PlaneField in the tip frame; x_l = Q^T (x - x_tip), u = Q u_l, grad = Q grad_l Q^T,
    sigma = Q sigma_l Q^T (Q = tip.rotation). Points on the faces keep their side through a signed zero only
    when the angle is 0.
    """
    Q = tip.rotation
    dx, dy = np.asarray(x, float) - tip.position[0], np.asarray(y, float) - tip.position[1]
    f = local(Q[0, 0] * dx + Q[1, 0] * dy, Q[0, 1] * dx + Q[1, 1] * dy)
    return PlaneField(np.einsum("ij,...j->...i", Q, f.u), Q @ f.grad @ Q.T, Q @ f.stress @ Q.T)
