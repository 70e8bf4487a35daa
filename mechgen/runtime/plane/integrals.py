"""Path-independent integrals of plane elasticity, in domain (q-function) and contour form.

The integrals work on arrays at quadrature points, so they plug into any finite element code: points
x (e, q, 2) (m), weights w (e, q) including |det J| (m^2), the displacement u (e, q, 2) (m), its gradient
grad_u[..., i, j] = u_i,j, the stress (e, q, 2, 2) (Pa), the strain energy density W (e, q) (J/m^3; computed
as sigma_ij u_i,j / 2 when omitted), and the weight function q (e, q) with its gradient grad_q (e, q, 2)
(1/m), interpolated by the caller from nodal values (q = 1 on the inner boundary of the ring, 0 on the
outer). Any common leading shape works; only the last axes are fixed. Units, per unit thickness: J_k in
N/m (= J/m^2), M and L in N (= J/m), K and Bueckner's normalised integral in Pa m^0.5, T in Pa.

Every integral is the flux of a divergence-free tensor F through a closed contour C, I = oint_C F_l n_l ds,
n the normal pointing away from what C encloses. Its domain form over a ring A between C (q = 1) and an
outer contour (q = 0) is

    I = - int_A F_l q_,l dA        (div F = 0 in A; the crack faces in A add nothing when F_l n_l = 0 on them)

(:func:`domain_integral`); the contour form is :func:`contour_integral` with the nodes of
:func:`circle_contour` or :func:`polygon_contour`. The fluxes (no body force, no crack-face traction):

* J_k (Eshelby; Rice's J = J_1 in the tip's frame): F_kl = W delta_kl - sigma_il u_i,k. J_1 is path
  independent around one tip; J_2 is not (the faces carry W n_2: J_2 on a ring misses
  -int q [[W]] dx along the faces, :func:`j2_face_term`); around the whole crack both are.
  Write P_kl for this flux (Eshelby's tensor).
* M (Budiansky-Rice, about an origin x0): F_l = (x_k - x0_k) P_kl; around the whole crack.
* L (Knowles-Sternberg, the rotational integral, about x0): F_l = e_3ij ((x_j - x0_j) P_il + sigma_il u_j),
  i.e. L = oint e_3ij (W x_j n_i + T_i u_j - T_k u_k,i x_j) ds; around the whole crack.
* Bueckner's work-conjugate integral of u with an auxiliary field v:
  F_l = u_i sigma[v]_il - v_i sigma[u]_il (Betti); path independent when both fields are traction-free
  on the faces inside the ring.
* the interaction integral (the cross term of J_1 in the tip frame) of u with v:
  F_l = sigma[u]_ij eps[v]_ij delta_1l - sigma[u]_il v_i,1 - sigma[v]_il u_i,1.

The domain forms take a :class:`Sample` (the arrays above) and, for a tip's integrals, a
:class:`closed_forms.CrackTip`: its position (m) and the angle (rad) of its crack's extension from the x
axis; its frame has x along the extension and y to its left (the left tip of a crack on y = 0 has angle pi).
A body force enters J_k only (- int q b_i u_i,k dA); the other integrals refuse a sample that has one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechgen.errors import InputError
from mechgen.runtime.plane import closed_forms as cf

__all__ = [
    "energy_density", "eshelby_flux", "m_flux", "l_flux", "bueckner_flux", "interaction_flux",
    "domain_integral", "contour_integral", "circle_contour", "polygon_contour", "to_tip_frame", "Sample",
    "j_vector", "j2_face_term", "m_integral", "l_integral", "work_conjugate_integral", "bueckner_integral",
    "interaction_integral",
    "stress_intensity", "t_stress",
]

_EPS = np.array([[0.0, 1.0], [-1.0, 0.0]])   # e_3ij in the plane


def energy_density(grad_u, stress) -> np.ndarray:
    """W = sigma_ij u_i,j / 2 (J/m^3; the skew part of grad u does no work on a symmetric stress)."""
    return 0.5 * np.einsum("...ij,...ij->...", stress, grad_u)


def eshelby_flux(grad_u, stress, W=None) -> np.ndarray:
    """Eshelby's energy-momentum tensor P_kl = W delta_kl - sigma_il u_i,k (Pa); J_k = oint P_kl n_l ds."""
    W = energy_density(grad_u, stress) if W is None else np.asarray(W)
    return W[..., None, None] * np.eye(2) - np.einsum("...il,...ik->...kl", stress, grad_u)


def m_flux(x, grad_u, stress, W=None, origin=(0.0, 0.0)) -> np.ndarray:
    """M's flux F_l = (x_k - x0_k) P_kl (N/m); M = oint (W x.n - T_k u_k,i x_i) ds."""
    r = np.asarray(x, float) - np.asarray(origin, float)
    return np.einsum("...k,...kl->...l", r, eshelby_flux(grad_u, stress, W))


def l_flux(x, u, grad_u, stress, W=None, origin=(0.0, 0.0)) -> np.ndarray:
    """L's flux F_l = e_3ij ((x_j - x0_j) P_il + sigma_il u_j) (N/m), e_312 = 1 = -e_321."""
    r = np.asarray(x, float) - np.asarray(origin, float)
    P = eshelby_flux(grad_u, stress, W)
    return (np.einsum("ij,...j,...il->...l", _EPS, r, P)
            + np.einsum("ij,...il,...j->...l", _EPS, stress, np.asarray(u, float)))


def bueckner_flux(u, stress, u_aux, stress_aux) -> np.ndarray:
    """Betti's flux F_l = u_i sigma^aux_il - u^aux_i sigma_il (units of u times stress)."""
    return np.einsum("...i,...il->...l", u, stress_aux) - np.einsum("...i,...il->...l", u_aux, stress)


def interaction_flux(grad_u, stress, grad_aux, stress_aux) -> np.ndarray:
    """J_1's cross term F_l = sigma_ij eps^aux_ij delta_1l - sigma_il v_i,1 - sigma^aux_il u_i,1 (frame of the tip)."""
    w12 = np.einsum("...ij,...ij->...", stress, 0.5 * (grad_aux + np.swapaxes(grad_aux, -1, -2)))
    F = -np.einsum("...il,...i->...l", stress, grad_aux[..., :, 0])
    F = F - np.einsum("...il,...i->...l", stress_aux, grad_u[..., :, 0])
    F[..., 0] += w12
    return F


def domain_integral(flux, w, grad_q) -> np.ndarray:
    """I = - sum w F_l q_,l over all points (the domain form of oint F_l n_l ds); flux (..., [k,] 2)."""
    w, grad_q = np.asarray(w, float), np.asarray(grad_q, float)
    lead = w.ndim
    F = np.asarray(flux, float)
    extra = F.shape[lead:-1]
    Fq = np.einsum("...l,...l->...", F.reshape(w.shape + (-1, 2)), grad_q[..., None, :]).reshape(w.shape + extra)
    return -np.tensordot(w, Fq, axes=(tuple(range(lead)), tuple(range(lead))))


def contour_integral(flux, normals, weights) -> np.ndarray:
    """I = sum ds F_l n_l over the contour's nodes; flux (m, [k,] 2), normals (m, 2), weights ds (m,)."""
    F = np.asarray(flux, float)
    n = np.asarray(normals, float).reshape((len(weights),) + (1,) * (F.ndim - 2) + (2,))
    return np.tensordot(np.asarray(weights, float), (F * n).sum(-1), axes=(0, 0))


def circle_contour(center, radius: float, n: int, start: float = -np.pi):
    """Gauss-Legendre nodes on the circle |x - center| = radius, theta in (start, start + 2 pi).

    Returns points (n, 2), outward normals (n, 2), arc-length weights (n,). Around a tip, start = angle - pi
    puts the ends on the crack faces, where the integrand jumps (no node lies on them).
    """
    if radius <= 0 or n < 1:
        raise InputError(f"a circle needs radius > 0 and n >= 1 nodes, got {radius!r}, {n!r}", key="contour",
                         expected="radius > 0, n >= 1")
    t, wt = np.polynomial.legendre.leggauss(n)
    theta = start + np.pi * (t + 1.0)
    nrm = np.stack([np.cos(theta), np.sin(theta)], -1)
    return np.asarray(center, float) + radius * nrm, nrm, np.pi * radius * wt


def polygon_contour(vertices, n_per_edge: int):
    """Gauss-Legendre nodes on each edge of a counter-clockwise polygon: points, outward normals, weights."""
    V = np.asarray(vertices, float)
    t, wt = np.polynomial.legendre.leggauss(n_per_edge)
    pts, nrms, ws = [], [], []
    for p, q in zip(V, np.roll(V, -1, axis=0)):
        d = q - p
        length = float(np.hypot(*d))
        pts.append(p + np.outer(0.5 * (t + 1.0), d))
        nrms.append(np.tile([d[1] / length, -d[0] / length], (n_per_edge, 1)))
        ws.append(0.5 * length * wt)
    Vn = np.roll(V, -1, axis=0)
    if np.sum(V[:, 0] * Vn[:, 1] - V[:, 1] * Vn[:, 0]) <= 0:          # twice the signed area
        raise InputError("the polygon's vertices must run counter-clockwise", key="contour",
                         expected="counter-clockwise vertices")
    return np.concatenate(pts), np.concatenate(nrms), np.concatenate(ws)


def to_tip_frame(tip: cf.CrackTip, x=None, vec=None, tensor=None):
    """Components in a tip's frame: x_l = Q^T (x - tip), v_l = Q^T v, A_l = Q^T A Q (Q = tip.rotation)."""
    Q = tip.rotation
    out = []
    if x is not None:
        out.append(np.einsum("ji,...j->...i", Q, np.asarray(x, float) - np.asarray(tip.position, float)))
    if vec is not None:
        out.append(np.einsum("ji,...j->...i", Q, np.asarray(vec, float)))
    if tensor is not None:
        out.append(Q.T @ np.asarray(tensor, float) @ Q)
    return out[0] if len(out) == 1 else tuple(out)


@dataclass(frozen=True)
class Sample:
    """A field sampled at quadrature points (leading shape S, e.g. (elements, points)), for the domain forms.

    x (S, 2) points (m); w (S,) weights including |det J| (m^2); grad_q (S, 2) the weight function's gradient
    (1/m); grad_u (S, 2, 2) with grad_u[..., i, j] = u_i,j; stress (S, 2, 2) (Pa); optional: u (S, 2) (m; L and
    Bueckner's integral need it), W (S,) (J/m^3; else sigma_ij u_i,j/2), q (S,) and body (S, 2) the body force
    per unit volume (N/m^3; J_k's term - int q b_i u_i,k dA needs both).
    """

    x: np.ndarray
    w: np.ndarray
    grad_q: np.ndarray
    grad_u: np.ndarray
    stress: np.ndarray
    u: np.ndarray | None = None
    W: np.ndarray | None = None
    q: np.ndarray | None = None
    body: np.ndarray | None = None

    def __post_init__(self) -> None:
        S = np.shape(self.w)
        want = {"x": S + (2,), "grad_q": S + (2,), "grad_u": S + (2, 2), "stress": S + (2, 2), "u": S + (2,),
                "W": S, "q": S, "body": S + (2,)}
        for key, shape in want.items():
            value = getattr(self, key)
            if value is not None and np.shape(value) != shape:
                raise InputError(f"the sample's {key} has shape {np.shape(value)}, the weights {S}", key=key,
                                 expected=f"shape {shape}")
        if self.body is not None and self.q is None:
            raise InputError("a body force needs q at the points (the term - int q b_i u_i,k dA)", key="q",
                             expected="q with the weights' shape")

    @property
    def energy(self) -> np.ndarray:
        """W, given or sigma_ij u_i,j/2."""
        return energy_density(self.grad_u, self.stress) if self.W is None else np.asarray(self.W)

    def require(self, key: str, what: str) -> np.ndarray:
        """The optional array key, or an InputError saying that what needs it."""
        value = getattr(self, key)
        if value is None:
            raise InputError(f"{what} needs the sample's {key}", key=key, expected="an array at the points")
        return np.asarray(value)

    def refuse_body(self, what: str) -> None:
        """M, L, Bueckner's and the interaction integrals here hold without body force only."""
        if self.body is not None:
            raise InputError(f"{what} is implemented without body force; the sample has one", key="body",
                             expected="no body force (or use J_k, which takes it)")


def j_vector(s: Sample, tip: cf.CrackTip | None = None) -> np.ndarray:
    """(J_1, J_2) (N/m): J_k = - int P_kl q_,l dA - int q b_i u_i,k dA, in the tip's frame if a tip is given.

    div P_k = b_i u_i,k with a body force b, whence its term. J_1 = G = (K_I^2 + K_II^2)/E' around one tip;
    J_2 -> -2 K_I K_II/E' needs :func:`j2_face_term` added when the ring crosses the faces.
    """
    J = domain_integral(eshelby_flux(s.grad_u, s.stress, s.energy), s.w, s.grad_q)
    if s.body is not None:
        bu = np.einsum("...i,...ik->...k", np.asarray(s.body, float), s.grad_u)
        J = J - ((np.asarray(s.w, float) * np.asarray(s.q, float))[..., None] * bu).reshape(-1, 2).sum(0)
    return J if tip is None else to_tip_frame(tip, vec=J)


def j2_face_term(w_face, W_upper, W_lower, q_face) -> float:
    """The crack faces' share of J_2 at a tip: - int q (W^+ - W^-) dx over the faces (N/m).

    J_2(tip) = - int_A P_2l q_,l dA - int_faces q (W^+ - W^-) dx, with W^+ on the face to the tip frame's
    left (y > 0), x along the faces (weights w_face in m), q at the face nodes; from div P = 0 in the ring
    and P_2l m_l = W m_2 on a traction-free face.
    """
    return -float(np.sum(np.asarray(w_face) * np.asarray(q_face) * (np.asarray(W_upper) - np.asarray(W_lower))))


def m_integral(s: Sample, origin=(0.0, 0.0)) -> float:
    """M = oint (W x_i n_i - T_k u_k,i x_i) ds about origin, as - int F_l q_,l dA (N)."""
    s.refuse_body("M")
    return float(domain_integral(m_flux(s.x, s.grad_u, s.stress, s.energy, origin), s.w, s.grad_q))


def l_integral(s: Sample, origin=(0.0, 0.0)) -> float:
    """L = oint e_3ij (W x_j n_i + T_i u_j - T_k u_k,i x_j) ds about origin, as - int F_l q_,l dA (N)."""
    s.refuse_body("L")
    u = s.require("u", "L")
    return float(domain_integral(l_flux(s.x, u, s.grad_u, s.stress, s.energy, origin), s.w, s.grad_q))


def work_conjugate_integral(s: Sample, aux: cf.PlaneField) -> float:
    """Betti's (Bueckner's) integral of the sampled u with any auxiliary field given at the same points.

    I = oint (u_i sigma^aux_ij - u^aux_i sigma_ij) n_j ds = - int F_l q_,l dA (units of u times stress);
    path independent where both fields are traction-free on the faces the ring crosses. With
    closed_forms.griffith_rotation_field around the whole crack it is 2 L (Shi, Liu & Li's eq. 7).
    """
    s.refuse_body("Bueckner's integral")
    u = s.require("u", "Bueckner's integral")
    return float(domain_integral(bueckner_flux(u, s.stress, aux.u, aux.stress), s.w, s.grad_q))


def bueckner_integral(s: Sample, tip: cf.CrackTip, mat: cf.PlaneElastic, mode: str = "I") -> float:
    """Bueckner's work-conjugate integral with his r^(-3/2) field (:func:`closed_forms.bueckner_field`).

    B = oint (u_i sigma^B_ij - u^B_i sigma_ij) n_j ds = - int F_l q_,l dA around one tip; normalised so that
    B = K_I (mode "I") or K_II (mode "II") of u (Pa m^0.5). Path independent: both fields are traction-free
    on the faces; rigid motions of u add nothing (the field B carries no force nor moment).
    """
    aux = cf.tip_frame_field(s.x[..., 0], s.x[..., 1], tip, lambda xl, yl: cf.bueckner_field(xl, yl, mode, mat))
    return work_conjugate_integral(s, aux)


def interaction_integral(s: Sample, tip: cf.CrackTip, aux) -> float:
    """The interaction integral of u with an auxiliary tip field (N/m), all in the tip's frame.

    I = - int (sigma_ij eps^aux_ij delta_1l - sigma_il v_i,1 - sigma^aux_il u_i,1) q_,l dA, where
    aux(xl, yl) -> closed_forms.PlaneField gives the auxiliary field in the tip's frame.
    """
    s.refuse_body("the interaction integral")
    xl = to_tip_frame(tip, x=s.x)
    gl, sl = to_tip_frame(tip, tensor=s.grad_u), to_tip_frame(tip, tensor=s.stress)
    v = aux(xl[..., 0], xl[..., 1])
    return float(domain_integral(interaction_flux(gl, sl, v.grad, v.stress), s.w, to_tip_frame(tip, vec=s.grad_q)))


def stress_intensity(s: Sample, tip: cf.CrackTip, mat: cf.PlaneElastic) -> tuple:
    """(K_I, K_II) at a tip (Pa m^0.5): I(u, K field with unit K_I or K_II) = 2 K/E', E' = 8 mu/(kappa + 1)."""
    out = []
    for kI, kII in ((1.0, 0.0), (0.0, 1.0)):
        I = interaction_integral(s, tip, lambda xl, yl: cf.k_field(xl, yl, kI, kII, mat))
        out.append(0.5 * mat.modulus * I)
    return tuple(out)


def t_stress(s: Sample, tip: cf.CrackTip, mat: cf.PlaneElastic, f: float = 1.0) -> float:
    """T-stress at a tip (Pa) by Kfouri's point-force field: T = E' I(u, point force f at the tip)/f.

    The pairing picks the Williams n = 2 term (the T term) of u against the n = 0 field (stress ~ 1/r).
    """
    I = interaction_integral(s, tip, lambda xl, yl: cf.point_force_field(xl, yl, f, mat))
    return mat.modulus * I / f
