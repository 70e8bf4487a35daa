"""The path-independent integrals (mechgen/runtime/plane/integrals.py) on the Griffith crack's exact field.

References (closed forms, derived in docs/plane_fracture_notes.md and checked here):
  J_1 = G = (kappa + 1)(K_I^2 + K_II^2)/(8 mu) at each tip, J_2 -> -(kappa + 1) K_I K_II/(4 mu) (Cherepanov,
  Hellen-Blackburn), K_I = sigma22 sqrt(pi a), K_II = sigma12 sqrt(pi a), T = sigma11 - sigma22 (Griffith);
  around the whole crack J = 0, M = (kappa + 1) pi a^2 (sigma22^2 + sigma12^2)/(4 mu) (= a (G_L + G_R)),
  L = (kappa + 1) pi a^2 sigma12 (sigma11 + sigma22)/(4 mu) (tips a (kappa + 1)(K_I K_II)_L,R/(4 mu) plus the
  faces' (kappa + 1) pi a^2 sigma12 T/(4 mu)); Bueckner's integral with the rotation field of Shi, Liu & Li
  (J. Appl. Mech. 67 (2000) 828) = 2 L.

Contour forms: Gauss-Legendre nodes on circles and polygons; the integrand is analytic on each arc or edge
(the ends sit on the faces, where it jumps), so 200-400 nodes give ~1e-13: tolerance 1e-10.
Domain forms: the exact field sampled at the quadrature points of ring meshes built here with scikit-fem
(tests only). The identity I = -int F.grad q dA is exact for any piecewise polynomial q that is 1 on the
inner and 0 on the outer edge of the ring (div F = 0); what remains is the quadrature error of a smooth
field on each element, measured below (the tables) and bounded by the stated tolerances.
"""
from __future__ import annotations

import numpy as np
import pytest

from mechgen.errors import InputError
from mechgen.runtime.plane import closed_forms as cf
from mechgen.runtime.plane import integrals as ig

skfem = pytest.importorskip("skfem", reason="scikit-fem is in the 'test' extra")

MAT = cf.PlaneElastic(E=2.0, nu=0.3, plane="strain")
LOADS = [cf.GriffithCrack(a=1.0, s11=0.3, s22=1.0, s12=0.4),     # T = -0.7 != 0
         cf.GriffithCrack(a=1.0, s11=1.0, s22=1.0, s12=0.4),     # T = 0
         cf.GriffithCrack(a=2.0, s11=-0.5, s22=0.2, s12=-0.6)]


def closed(crack, mat=MAT):
    """The closed forms of the module docstring."""
    k, mu, a = mat.kappa, mat.mu, crack.a
    s = cf.griffith_sif(crack)
    return {"G": (k + 1) * (s["K_I"]**2 + s["K_II"]**2) / (8 * mu), "J2": -(k + 1) * s["K_I"] * s["K_II"] / (4 * mu),
            "M": (k + 1) * np.pi * a * a * (crack.s22**2 + crack.s12**2) / (4 * mu),
            "L": (k + 1) * np.pi * a * a * crack.s12 * (crack.s11 + crack.s22) / (4 * mu),
            "L_paper": (k + 1) * a * 2 * s["K_I"] * s["K_II"] / (4 * mu), **s}


def local_to_global(tip, pts):
    """Global points of points given in a tip's frame: x = tip + Q x_l."""
    return np.asarray(tip.position) + pts @ tip.rotation.T


def field_at(crack, pts):
    return cf.griffith_field(pts[..., 0], pts[..., 1], crack, MAT)


# --- contour forms ---------------------------------------------------------------------------------------

def tip_contours(tip, sizes, n=400):
    """Circles of the given radii and squares of half-side h, both about a tip, ends on the faces."""
    out = []
    for rho in sizes:
        p, nrm, w = ig.circle_contour(tip.position, rho, n, start=tip.angle - np.pi)
        out.append((f"circle r={rho}", p, nrm, w))
        h = rho
        V = np.array([[-h, 0.0], [-h, -h], [h, -h], [h, h], [-h, h]])
        p, nrm, w = ig.polygon_contour(V, n // 5)
        out.append((f"square h={rho}", local_to_global(tip, p), nrm @ tip.rotation.T, w))
    return out


def face_term_j2(crack, tip, rho, n=20):
    """-int_{-rho}^0 (W^+ - W^-) dx' along the faces behind the tip (x' = -s^2 removes the r^-1/2 singularity).

    20 nodes: 3e-12 of J_2; more nodes lie so near the tip that x = a - s^2, rounded, loses digits of s^2
    (60 nodes: 7e-11, 240: 7e-8)."""
    t, wt = np.polynomial.legendre.leggauss(n)
    s = np.sqrt(rho) * (t + 1) / 2
    w = wt * np.sqrt(rho) / 2 * 2 * s                       # dx' = 2 s ds
    pts = local_to_global(tip, np.stack([-s * s, np.zeros_like(s)], -1))
    up = cf.griffith_field(pts[:, 0], np.zeros_like(s), crack, MAT)         # y = +0.0: the upper face
    lo = cf.griffith_field(pts[:, 0], -np.zeros_like(s), crack, MAT)        # y = -0.0: the lower face
    Wp, Wm = (up.energy_density, lo.energy_density) if tip.angle == 0.0 else (lo.energy_density, up.energy_density)
    return ig.j2_face_term(w, Wp, Wm, np.ones_like(s))


@pytest.mark.parametrize("crack", LOADS)
def test_tip_contours_path_independent(crack):
    """J_1 = G, J_2 + faces = -(kappa+1) K_I K_II/(4 mu), Bueckner = K_I, K_II on circles and squares of four
    sizes about each tip (the largest reaching 3/4 of the way to the other tip)."""
    ref = closed(crack)
    for tip in crack.tips():
        for name, p, nrm, w in tip_contours(tip, [0.05 * crack.a, 0.3 * crack.a, 0.8 * crack.a, 1.5 * crack.a]):
            f = field_at(crack, p)
            J = ig.to_tip_frame(tip, vec=ig.contour_integral(ig.eshelby_flux(f.grad, f.stress), nrm, w))
            assert J[0] == pytest.approx(ref["G"], rel=1e-10), name
            for mode, key in (("I", "K_I"), ("II", "K_II")):
                aux = cf.tip_frame_field(p[:, 0], p[:, 1], tip, lambda a, b: cf.bueckner_field(a, b, mode, MAT))
                B = ig.contour_integral(ig.bueckner_flux(f.u, f.stress, aux.u, aux.stress), nrm, w)
                assert B == pytest.approx(ref[key], rel=1e-10, abs=1e-12), (name, mode)
        rho = 0.8 * crack.a
        p, nrm, w = ig.circle_contour(tip.position, rho, 400, start=tip.angle - np.pi)
        f = field_at(crack, p)
        J = ig.to_tip_frame(tip, vec=ig.contour_integral(ig.eshelby_flux(f.grad, f.stress), nrm, w))
        assert J[1] + face_term_j2(crack, tip, rho) == pytest.approx(ref["J2"], rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("crack", LOADS)
def test_whole_crack_contours(crack):
    """M, L, J = 0 and the paper's I = 2 L (Bueckner's integral with the rotation field) on circles and
    rectangles around the whole crack, against the closed forms."""
    ref = closed(crack)
    a = crack.a
    contours = [ig.circle_contour((0, 0), rho * a, 400) for rho in (1.2, 2.0, 5.0)]
    contours += [ig.polygon_contour(np.array([[-1.3, -0.4], [1.3, -0.4], [1.3, 0.6], [-1.3, 0.6]]) * a, 200)]
    for p, nrm, w in contours:
        f = field_at(crack, p)
        rot = cf.griffith_rotation_field(p[:, 0], p[:, 1], crack, MAT)
        assert ig.contour_integral(ig.m_flux(p, f.grad, f.stress), nrm, w) == pytest.approx(ref["M"], rel=1e-10)
        L = ig.contour_integral(ig.l_flux(p, f.u, f.grad, f.stress), nrm, w)
        assert L == pytest.approx(ref["L"], rel=1e-10)
        np.testing.assert_allclose(ig.contour_integral(ig.eshelby_flux(f.grad, f.stress), nrm, w), 0.0,
                                   atol=1e-10 * ref["M"] / a)
        I = ig.contour_integral(ig.bueckner_flux(f.u, f.stress, rot.u, rot.stress), nrm, w)
        assert I == pytest.approx(2 * L, rel=1e-10)
        # M and L do not depend on the origin (J = 0 around the whole crack)
        assert ig.contour_integral(ig.l_flux(p, f.u, f.grad, f.stress, origin=(0.3, -1.1)), nrm, w) == \
            pytest.approx(L, rel=1e-10)


def tip_bueckner_rotation_sum(crack, rho, n=400):
    """I_CL + I_CR: Bueckner's integral with the rotation field on circles of radius rho about each tip."""
    tot = 0.0
    for tip in crack.tips():
        p, nrm, w = ig.circle_contour(tip.position, rho, n, start=tip.angle - np.pi)
        f, rot = field_at(crack, p), cf.griffith_rotation_field(p[:, 0], p[:, 1], crack, MAT)
        tot += ig.contour_integral(ig.bueckner_flux(f.u, f.stress, rot.u, rot.stress), nrm, w)
    return tot


def faces_bueckner_rotation(crack, rho, n=200):
    """The faces' share of Bueckner's integral with the rotation field between the tip circles of radius rho:
    int (u_x^+ sigma^II_xy^+ - u_x^- sigma^II_xy^-) dx over |x| < a - rho (sigma.n = 0 for u on the faces, and
    sigma^II_yy = 0 there). Gauss-Legendre: the integrand is analytic on the interval, its singularities a
    distance rho beyond the ends (200 nodes: 1e-13 at rho = 0.1)."""
    t, wt = np.polynomial.legendre.leggauss(n)
    x = (crack.a - rho) * t
    up, lo = cf.griffith_field(x, np.zeros(n), crack, MAT), cf.griffith_field(x, -np.zeros(n), crack, MAT)
    ru = cf.griffith_rotation_field(x, np.zeros(n), crack, MAT)
    rl = cf.griffith_rotation_field(x, -np.zeros(n), crack, MAT)
    return np.sum((crack.a - rho) * wt * (up.u[:, 0] * ru.stress[:, 0, 1] - lo.u[:, 0] * rl.stress[:, 0, 1]))


def test_paper_relation_needs_zero_t_stress():
    """Shi, Liu & Li's eq. 8, L = (kappa + 1) a (K_I^L K_II^L + K_I^R K_II^R)/(4 mu), rests on I = I_CL + I_CR,
    i.e. on the rotation field being traction-free on the faces. It is not: sigma^II_xy = d(x sigma_xx)/dx there.
    With T = 0 the tips' integrals do not depend on the radius and eq. 8 holds; with T != 0 (and K_II != 0)
    they change with the radius, and L differs from eq. 8 by (kappa + 1) pi a^2 sigma12 T/(4 mu)."""
    t0, t1 = LOADS[1], LOADS[0]
    sums0 = [tip_bueckner_rotation_sum(t0, rho) for rho in (0.5, 0.1, 0.01)]
    np.testing.assert_allclose(sums0, 2 * closed(t0)["L_paper"], rtol=1e-9)
    assert closed(t0)["L"] == pytest.approx(closed(t0)["L_paper"], rel=1e-14)
    sums1 = [tip_bueckner_rotation_sum(t1, rho) for rho in (0.5, 0.1, 0.01)]
    assert np.ptp(sums1) > 0.5 * abs(closed(t1)["L"])          # path dependent: no limit to take
    for rho, tips in zip((0.5, 0.1), sums1):                     # the faces carry the difference
        assert tips + faces_bueckner_rotation(t1, rho) == pytest.approx(2 * closed(t1)["L"], rel=1e-10)
    ref = closed(t1)
    gap = (MAT.kappa + 1) * np.pi * t1.a**2 * t1.s12 * (t1.s11 - t1.s22) / (4 * MAT.mu)
    assert ref["L"] - ref["L_paper"] == pytest.approx(gap, rel=1e-13)
    assert abs(gap) > 0.3 * abs(ref["L"])
    # the face traction of the rotation field, against d(x sigma_xx)/dx by a central difference (h = 1e-5:
    # truncation 1e-10, round-off 1e-11)
    xs, h = np.array([-0.6, 0.2, 0.7]), 1e-5
    rot = cf.griffith_rotation_field(xs, np.zeros(3), t1, MAT)
    sxx = lambda xx: cf.griffith_field(xx, np.zeros(3), t1, MAT).stress[:, 0, 0]
    np.testing.assert_allclose(rot.stress[:, 0, 1], ((xs + h) * sxx(xs + h) - (xs - h) * sxx(xs - h)) / (2 * h),
                               rtol=1e-7)
    np.testing.assert_allclose(rot.stress[:, 1, 1], 0.0, atol=1e-13)


# --- domain forms on scikit-fem ring meshes ----------------------------------------------------------------

def ring_mesh(frame, r0, r1, n_r, n_t, slit):
    """A ring r0 < rho < r1 about a tip (or any CrackTip as a frame); with slit the seam at theta = +-pi is
    cut (duplicate nodes: the crack faces), otherwise periodic. Returns the mesh and each node's logical
    radial coordinate s in [0, 1] (0 on the inner edge)."""
    m_t = n_t + 1 if slit else n_t
    rho = np.linspace(r0, r1, n_r + 1)
    th = -np.pi + 2 * np.pi * np.arange(m_t) / n_t
    R_, T_ = np.meshgrid(rho, th, indexing="ij")
    loc = np.stack([R_ * np.cos(T_), R_ * np.sin(T_)], -1).reshape(-1, 2)
    p = local_to_global(frame, loc)
    idx = np.arange((n_r + 1) * m_t).reshape(n_r + 1, m_t)
    tris = []
    for i in range(n_r):
        for j in range(n_t):
            jn = j + 1 if slit else (j + 1) % n_t
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, jn], idx[i, jn]
            tris += [[a, b, c], [a, c, d]]
    mesh = skfem.MeshTri(p.T.copy(), np.array(tris).T.copy())
    s = np.repeat(np.arange(n_r + 1) / n_r, m_t)
    return mesh, s


def ring_data(crack, frame, r0, r1, q_order, slit, n_r=6, n_t=72, intorder=10, rot=False):
    """The exact field sampled on a ring mesh (an integrals.Sample) and, with rot, the rotation field there.

    q and grad q from P1 (linear in s) or P2 (the smooth step 1 - 3 s^2 + 2 s^3 at the P2 nodes, s at an edge
    node the mean of its ends')."""
    mesh, s = ring_mesh(frame, r0, r1, n_r, n_t, slit)
    elem = skfem.ElementTriP1() if q_order == 1 else skfem.ElementTriP2()
    basis = skfem.Basis(mesh, elem, intorder=intorder)
    if q_order == 1:
        qn = 1.0 - s
    else:
        s_edge = 0.5 * (s[mesh.facets[0]] + s[mesh.facets[1]])
        sd = np.concatenate([s, s_edge])
        qn = 1.0 - 3 * sd**2 + 2 * sd**3
    qf = basis.interpolate(qn)
    x = np.moveaxis(basis.mapping.F(basis.X), 0, -1)
    f = cf.griffith_field(x[..., 0], x[..., 1], crack, MAT)
    g = cf.griffith_rotation_field(x[..., 0], x[..., 1], crack, MAT) if rot else None
    sample = ig.Sample(x=x, w=np.asarray(basis.dx), grad_q=np.moveaxis(np.asarray(qf.grad), 0, -1), grad_u=f.grad,
                       stress=f.stress, u=f.u, q=np.asarray(qf))
    return sample, g


TIP_RINGS = [(0.05, 0.2), (0.2, 0.6), (0.5, 1.2)]      # radii / a: inner, outer
CRACK_RINGS = [(1.3, 2.0), (2.0, 4.0), (4.0, 10.0)]


def tip_table(crack, q_order):
    """Per tip and ring: J_1, J_2 + faces, K_I, K_II (interaction), T (point force), K_I, K_II (Bueckner)."""
    rows = []
    for tip in crack.tips():
        for r0, r1 in TIP_RINGS:
            r0_, r1_ = r0 * crack.a, r1 * crack.a
            smp, _ = ring_data(crack, tip, r0_, r1_, q_order, slit=True)
            J = ig.j_vector(smp, tip)
            J2 = J[1] + face_term_j2(crack, tip, r0_) + ring_face_term(crack, tip, r0_, r1_, q_order)
            K = ig.stress_intensity(smp, tip, MAT)
            T = ig.t_stress(smp, tip, MAT)
            B = [ig.bueckner_integral(smp, tip, MAT, m) for m in ("I", "II")]
            rows.append((tip.position[0], r0, r1, J[0], J2, K[0], K[1], T, B[0], B[1]))
    return np.array(rows)


def ring_face_term(crack, tip, r0, r1, q_order, n_r=6, n=12):
    """-int q (W^+ - W^-) dx' over the faces inside the ring, element by element along the seam (q is the
    mesh's: linear in s for P1, the P2 interpolant of the smooth step for P2), n Gauss points per element."""
    t, wt = np.polynomial.legendre.leggauss(n)
    xi = (t + 1) / 2
    g = (lambda v: 1.0 - v) if q_order == 1 else (lambda v: 1 - 3 * v**2 + 2 * v**3)
    total = 0.0
    for i in range(n_r):
        s0, s1 = i / n_r, (i + 1) / n_r
        if q_order == 1:
            q = g(s0) * (1 - xi) + g(s1) * xi
        else:
            q = g(s0) * (1 - xi) * (1 - 2 * xi) + g(0.5 * (s0 + s1)) * 4 * xi * (1 - xi) + g(s1) * xi * (2 * xi - 1)
        rho = r0 + (r1 - r0) * (s0 + (s1 - s0) * xi)
        pts = local_to_global(tip, np.stack([-rho, np.zeros_like(rho)], -1))
        up = cf.griffith_field(pts[:, 0], np.zeros_like(rho), crack, MAT)
        lo = cf.griffith_field(pts[:, 0], -np.zeros_like(rho), crack, MAT)
        Wp, Wm = (up.energy_density, lo.energy_density) if tip.angle == 0.0 else (lo.energy_density, up.energy_density)
        total += ig.j2_face_term(wt * (r1 - r0) * (s1 - s0) / 2, Wp, Wm, q)
    return total


@pytest.mark.parametrize("q_order", [1, 2])
@pytest.mark.parametrize("crack", [LOADS[0], LOADS[2]])
def test_tip_domain_integrals(crack, q_order):
    """Three rings (radii 0.05-0.2, 0.2-0.6, 0.5-1.2 a) about each tip, 6 x 72 x 2 triangles, degree-10
    quadrature: J_1, J_2 (with the faces' term), K_I, K_II, T and Bueckner's K within 1e-10 of the closed forms.
    What is left is the quadrature error of the analytic field on elements no larger than half their distance
    to the tip (measured 2e-12 at most, in the innermost ring for Bueckner's r^-3/2 field; 1e-15 in the
    outer rings) and, for J_2, the faces' 1D quadrature (1.5e-11): 7x to 50x below the tolerance."""
    ref = closed(crack)
    tab = tip_table(crack, q_order)
    scaleJ, scaleK = ref["G"], np.hypot(ref["K_I"], ref["K_II"])
    want = [ref["G"], ref["J2"], ref["K_I"], ref["K_II"], ref["T"], ref["K_I"], ref["K_II"]]
    scale = [scaleJ, scaleJ, scaleK, scaleK, max(abs(ref["T"]), scaleK / np.sqrt(crack.a)), scaleK, scaleK]
    err = np.abs(tab[:, 3:] - np.array(want)) / np.array(scale)
    assert err.max() < 1e-10, err


@pytest.mark.parametrize("q_order", [1, 2])
def test_whole_crack_domain_integrals(q_order):
    """M, L, J and the paper's I = 2 L on three periodic rings around the whole crack (T != 0 and K_II != 0);
    the field is analytic on the rings (measured errors 1e-15): tolerance 1e-12."""
    crack = LOADS[0]
    ref = closed(crack)
    for r0, r1 in CRACK_RINGS:
        smp, rot = ring_data(crack, cf.CrackTip((0.0, 0.0)), r0 * crack.a, r1 * crack.a, q_order, slit=False,
                             n_r=6, n_t=96, rot=True)
        assert ig.m_integral(smp) == pytest.approx(ref["M"], rel=1e-12)
        L = ig.l_integral(smp)
        assert L == pytest.approx(ref["L"], rel=1e-12)
        np.testing.assert_allclose(ig.j_vector(smp), 0.0, atol=1e-12 * ref["G"])
        I = ig.work_conjugate_integral(smp, rot)
        assert I == pytest.approx(2 * ref["L"], rel=1e-12)
        assert abs(L - ref["L_paper"]) > 0.3 * abs(ref["L"])     # eq. 8 misses the T-stress's face term


def test_domain_inputs_any_leading_shape():
    """The same points flattened to (n,) give the same integral as (e, q)."""
    crack = LOADS[0]
    smp, _ = ring_data(crack, crack.tips()[0], 0.2, 0.6, 1, slit=True, n_r=3, n_t=24, intorder=4)
    flat = ig.Sample(x=smp.x.reshape(-1, 2), w=smp.w.reshape(-1), grad_q=smp.grad_q.reshape(-1, 2),
                     grad_u=smp.grad_u.reshape(-1, 2, 2), stress=smp.stress.reshape(-1, 2, 2))
    np.testing.assert_allclose(ig.j_vector(smp), ig.j_vector(flat), rtol=1e-14)


def test_j_with_body_force_on_the_membrane():
    """J_k with the body-force term vanishes over a defect-free disk for any q that is 0 on the rim: the
    membrane's exact field (quadratic u, linear stress) on scikit-fem's init_circle mesh with a P2 q; the
    integrand is a polynomial of degree 3 on straight triangles, so degree-4 quadrature is exact (round-off
    1e-16 of the terms). Without the term J_2 is the (non-zero) int q b_i u_i,2 dA."""
    mat, rho_g, R = cf.PlaneElastic(E=2.0, nu=0.3, plane="stress"), 1.5, 1.0
    mesh = skfem.MeshTri.init_circle(3)
    basis = skfem.Basis(mesh, skfem.ElementTriP2(), intorder=4)
    xd, yd = basis.doflocs
    bnd = basis.get_dofs().all()
    qn = (1.0 - (xd**2 + yd**2) / np.max(xd**2 + yd**2)) * (1.0 + 0.5 * xd + 0.3 * yd)   # lopsided: the
    # membrane's field is symmetric, and a symmetric q would make the body-force term vanish by itself
    qn[bnd] = 0.0                                      # q = 0 on every boundary edge (vertices and midpoints)
    qf = basis.interpolate(qn)
    x = np.moveaxis(basis.mapping.F(basis.X), 0, -1)
    f = cf.membrane_field(x[..., 0], x[..., 1], R, mat, rho_g)
    body = np.broadcast_to([0.0, -rho_g], x.shape)
    common = dict(x=x, w=np.asarray(basis.dx), grad_q=np.moveaxis(np.asarray(qf.grad), 0, -1), grad_u=f.grad,
                  stress=f.stress, q=np.asarray(qf))
    J = ig.j_vector(ig.Sample(**common, body=body))
    without = ig.j_vector(ig.Sample(**common))
    scale = abs(without[1])
    assert scale > 1e-3
    np.testing.assert_allclose(J, 0.0, atol=1e-13 * scale)
    with pytest.raises(InputError):
        ig.m_integral(ig.Sample(**common, body=body))


def test_bad_samples_are_refused():
    w = np.ones((2, 3))
    with pytest.raises(InputError):
        ig.Sample(x=np.zeros((2, 3, 2)), w=w, grad_q=np.zeros((2, 3)), grad_u=np.zeros((2, 3, 2, 2)),
                  stress=np.zeros((2, 3, 2, 2)))
    smp = ig.Sample(x=np.zeros((2, 3, 2)), w=w, grad_q=np.zeros((2, 3, 2)), grad_u=np.zeros((2, 3, 2, 2)),
                    stress=np.zeros((2, 3, 2, 2)))
    with pytest.raises(InputError):
        ig.l_integral(smp)                       # L needs u
    with pytest.raises(InputError):
        ig.polygon_contour([[0, 0], [0, 1], [1, 1], [1, 0]], 4)     # clockwise
