"""ROSS (ross-rotordynamics 2.3.0) reference data for mechgen's rotor elements.

What it computes
----------------
Three rotors are built with ROSS and analysed with ROSS's own solvers:

(a) ``example``    -- ``ross.rotor_example()`` exactly as shipped: 6 Timoshenko shaft
                      elements (L=0.25 m, solid d=0.05 m, steel), 2 disks from
                      geometry at nodes 2 and 4, 2 undamped anisotropic bearings
                      (kxx=1e6, kyy=0.8e6 N/m) at nodes 0 and 6.
(b) ``compressor`` -- a compressor-like 14-element rotor defined in this file
                      (``build_compressor_like``): solid journals, stepped hollow
                      mid-span sections, 3 impeller-like disks plus an overhung
                      coupling disk, 2 anisotropic bearings with cross-coupled
                      stiffness and (cross-coupled) damping.
(c) ``example_refined`` -- rotor (a) with each shaft element split into 8 equal
                      elements (48 elements, 49 nodes, 294 dof). Used for timing
                      ``run_campbell`` / ``run_modal``; its Campbell data are saved too.

For every rotor the JSON holds the full model definition (every shaft element with
L, idl, odl, idr, odr, E, G_s, rho, Poisson, n and ROSS's derived A, Ie, kappa, phi,
m; every disk with node, m, Ip, Id (geometry: see ``construction``); every bearing
with node and kxx, kyy, kxy, kyx, cxx, cyy, cxy, cyx) and, at spin speeds
0, 500, 1000, 2000 rad/s, the first 8 modes as returned by

* ``rotor.run_modal(speed, num_modes=16)`` (ROSS default: ARPACK shift-invert,
  sigma=1) -> wd, wn, complex eigenvalues, log_dec, damping_ratio, whirl
  ('Forward'/'Backward'/'Mixed'/None), mode_type ('Lateral'/'Axial'/'Torsional');
* ``whirl_robust``: the same per-node orbit test, ignoring roundoff-level nodes and
  calling near-straight-line orbits 'Planar' (see ``robust_whirl``); ROSS's own
  ``whirl`` is roundoff-decided for antisymmetric modes of the symmetric rotor (a)
  (node 3 has |x|,|y| ~ 1e-17) and for the planar modes of undamped (a) at speed 0;
* ``rotor.run_modal(speed, num_modes=16, sparse=False)`` (dense ``scipy.linalg.eig``)
  -> wd and eigenvalues, as a cross-check;
* ``lateral_only``: dense eig of ROSS's global matrices restricted to the lateral
  dofs (x, y, alpha, beta of every node), with ROSS's own sort (``Rotor._index``)
  and ROSS's per-node orbit whirl classification. ROSS 2.3.0 elements are 6-dof per
  node (x, y, z, alpha, beta, theta); the lateral block is exactly decoupled from
  the axial/torsional one (no axial force/torque), so this list is what a 4-dof per
  node (lateral-only) model must reproduce. The ROSS lists can contain torsional /
  axial modes (e.g. the 774.35 rad/s torsional mode of rotor (a)).

Bearing coefficients are constant here, so K(speed)/C(speed) do not depend on speed.
ROSS's state matrix is A = [[0, I], [-M^-1 K, -M^-1 (C + speed*G)]] (Rotor.A).

``element_formula_checks``: ROSS's cylindrical ShaftElement M, K, G compared with the
closed-form Timoshenko matrices in ``closed_form_shaft_matrices`` (agree to ~1e-16).

Global matrices ``rotor.M(speed)``, ``rotor.K(speed)``, ``rotor.C(speed)``,
``rotor.G()`` at speeds 0 and 1000 rad/s (plus element matrices of the first shaft
element and first disk) are written to ``<out-stem>_example_matrices.npz`` and
``<out-stem>_compressor_matrices.npz`` next to the JSON. Global dof index of
(node n, local dof j) is 6*n + j with j = 0:x, 1:y, 2:z, 3:alpha, 4:beta, 5:theta.

Timing (unless ``--no-timing``): median of ``--repeats`` (default 3) wall times of
``rotor.run_campbell(np.linspace(0, 1000, 50), frequencies=8)`` and of single
``run_modal`` calls on rotor (c). The first run_modal call in a process JIT-compiles
ROSS's numba orbit helper (several seconds); that warm-up is timed separately.
``Rotor.run_modal`` is lru-cached per rotor and per argument tuple, so the cache is
cleared before every timed call. BLAS is limited to ``--blas-threads`` (default 1)
threads during timing; the load average is recorded because the timings are only
meaningful on an otherwise idle machine.

How to run
----------
    .venv/bin/python benchmarks/ross_reference.py --out benchmarks/ross_data/ross_reference.json
    .venv/bin/python benchmarks/ross_reference.py            # JSON to stdout

ROSS comes with the project's test and bench extras (``pip install -e '.[bench]'``:
``ross-rotordynamics==2.3.0`` and ``plotly<6``); it is not a runtime dependency.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import scipy
import scipy.linalg as la


@contextlib.contextmanager
def _fd_stdout_to_stderr():
    """Send fd-level stdout to stderr (ROSS -> ccp -> CoolProp prints REFPROP noise)."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        os.dup2(2, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


with _fd_stdout_to_stderr():
    import warnings

    warnings.filterwarnings("ignore", message=".*REFPROP.*")
    import ross as rs
    from ross.results import Orbit

SPEEDS = [0.0, 500.0, 1000.0, 2000.0]  # rad/s
N_MODES = 8
MATRIX_SPEEDS = [0.0, 1000.0]
DOF_NAMES = ["x", "y", "z", "alpha", "beta", "theta"]
LATERAL_LOCAL = [0, 1, 3, 4]  # x, y, alpha, beta inside each node's 6 dofs


def log(*a):
    print(*a, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- models
def build_example():
    """ross.rotor_example(), unchanged."""
    return rs.rotor_example()


def example_construction_text():
    return (
        "ross.rotor_example() [ross/rotor_assembly.py, def rotor_example]: "
        "6 x ShaftElement(L=0.25, idl=0, odl=0.05, material=steel, shear_effects=True, "
        "rotary_inertia=True, gyroscopic=True) (shear_method_calc='cowper'); "
        "DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28); "
        "DiskElement.from_geometry(n=4, material=steel, width=0.07, i_d=0.05, o_d=0.28); "
        "BearingElement(0, kxx=1e6, kyy=0.8e6, cxx=0); BearingElement(6, kxx=1e6, kyy=0.8e6, cxx=0) "
        "(kxy=kyx=0, cyy=cxx=0, cxy=cyx=0, kzz=czz=0, no mass coefficients). "
        "steel = Material('Steel', rho=7810, E=211e9, G_s=81.2e9)."
    )


# (L [m], idl [m], odl [m]) for every element of rotor (b); all cylindrical, steel.
COMPRESSOR_SHAFT = [
    (0.08, 0.00, 0.06),  # 0: node 0-1 left overhang stub (bearing 0 at node 1)
    (0.08, 0.00, 0.06),  # 1: node 1-2 journal
    (0.10, 0.00, 0.08),  # 2: node 2-3 step up (solid)
    (0.10, 0.03, 0.10),  # 3: node 3-4 hollow
    (0.10, 0.03, 0.10),  # 4: node 4-5 hollow (disk A at node 4)
    (0.10, 0.04, 0.12),  # 5: node 5-6 hollow, larger bore
    (0.10, 0.04, 0.12),  # 6: node 6-7 (disk B at node 6)
    (0.10, 0.04, 0.12),  # 7: node 7-8
    (0.10, 0.04, 0.12),  # 8: node 8-9 (disk C at node 8)
    (0.10, 0.03, 0.10),  # 9: node 9-10 hollow
    (0.10, 0.00, 0.08),  # 10: node 10-11 solid step down
    (0.08, 0.00, 0.06),  # 11: node 11-12 journal (bearing 1 at node 12)
    (0.08, 0.00, 0.06),  # 12: node 12-13
    (0.06, 0.00, 0.05),  # 13: node 13-14 coupling stub (coupling disk at node 14)
]
# (node, width [m], i_d [m], o_d [m]) -> DiskElement.from_geometry(material=steel)
COMPRESSOR_DISKS = [
    (4, 0.05, 0.10, 0.40),  # impeller A
    (6, 0.06, 0.12, 0.45),  # impeller B
    (8, 0.05, 0.12, 0.40),  # impeller C
    (14, 0.04, 0.05, 0.20),  # overhung coupling hub
]
# fluid-film-like anisotropic bearings, constant (speed independent) coefficients
COMPRESSOR_BEARINGS = [
    dict(n=1, kxx=2.0e7, kyy=3.5e7, kxy=4.0e6, kyx=-2.5e6,
         cxx=3.0e3, cyy=4.5e3, cxy=3.0e2, cyx=2.0e2),
    dict(n=12, kxx=1.5e7, kyy=2.5e7, kxy=3.0e6, kyx=-2.0e6,
         cxx=2.5e3, cyy=3.5e3, cxy=2.5e2, cyx=1.5e2),
]


def build_compressor_like():
    steel = rs.materials.steel
    shaft = [
        rs.ShaftElement(L=L, idl=idl, odl=odl, material=steel,
                        shear_effects=True, rotary_inertia=True, gyroscopic=True)
        for (L, idl, odl) in COMPRESSOR_SHAFT
    ]
    disks = [
        rs.DiskElement.from_geometry(n=n, material=steel, width=w, i_d=i_d, o_d=o_d)
        for (n, w, i_d, o_d) in COMPRESSOR_DISKS
    ]
    bearings = [rs.BearingElement(**b) for b in COMPRESSOR_BEARINGS]
    return rs.Rotor(shaft, disks, bearings)


def compressor_construction_text():
    return (
        "rs.Rotor(shaft, disks, bearings) with shaft = [ShaftElement(L, idl, odl, material=steel, "
        "shear_effects=True, rotary_inertia=True, gyroscopic=True) for (L, idl, odl) in "
        f"{COMPRESSOR_SHAFT}] (idr=idl, odr=odl), disks = [DiskElement.from_geometry(n, steel, "
        f"width, i_d, o_d) for (n, width, i_d, o_d) in {COMPRESSOR_DISKS}], bearings = "
        f"[BearingElement(**b) for b in {COMPRESSOR_BEARINGS}] (kzz=czz=0, no mass terms, "
        "constant coefficients)."
    )


def build_refined_example(nsub=8):
    """rotor_example() with each of its 6 shaft elements split into nsub equal elements."""
    steel = rs.materials.steel
    shaft = [
        rs.ShaftElement(0.25 / nsub, 0.0, 0.05, material=steel,
                        shear_effects=True, rotary_inertia=True, gyroscopic=True)
        for _ in range(6 * nsub)
    ]
    disks = [
        rs.DiskElement.from_geometry(n=2 * nsub, material=steel, width=0.07, i_d=0.05, o_d=0.28),
        rs.DiskElement.from_geometry(n=4 * nsub, material=steel, width=0.07, i_d=0.05, o_d=0.28),
    ]
    bearings = [
        rs.BearingElement(0, kxx=1e6, kyy=0.8e6, cxx=0),
        rs.BearingElement(6 * nsub, kxx=1e6, kyy=0.8e6, cxx=0),
    ]
    return rs.Rotor(shaft, disks, bearings)


# ---------------------------------------------------------------------- extraction
def _f(x):
    return float(np.real(x))


def model_definition(rotor, speed_for_bearings=0.0):
    shafts = []
    for sh in rotor.shaft_elements:
        mat = sh.material
        shafts.append(dict(
            n=int(sh.n), L=sh.L, idl=sh.idl, odl=sh.odl, idr=sh.idr, odr=sh.odr,
            E=mat.E, G_s=mat.G_s, rho=mat.rho, Poisson=mat.Poisson, material=mat.name,
            shear_effects=bool(sh.shear_effects), rotary_inertia=bool(sh.rotary_inertia),
            gyroscopic=bool(sh.gyroscopic), shear_method_calc=sh.shear_method_calc,
            A=_f(sh.A), Ie=_f(sh.Ie), kappa=_f(getattr(sh, "kappa", np.nan)), phi=_f(sh.phi),
            m=_f(sh.m),
        ))
    disks = [dict(node=int(d.n), m=d.m, Ip=d.Ip, Id=d.Id) for d in rotor.disk_elements]
    bearings = []
    for b in rotor.bearing_elements:
        K = b.K(speed_for_bearings)
        C = b.C(speed_for_bearings)
        Mb = b.M(speed_for_bearings)
        bearings.append(dict(
            node=int(b.n), kxx=_f(K[0, 0]), kyy=_f(K[1, 1]), kxy=_f(K[0, 1]), kyx=_f(K[1, 0]),
            kzz=_f(K[2, 2]), cxx=_f(C[0, 0]), cyy=_f(C[1, 1]), cxy=_f(C[0, 1]), cyx=_f(C[1, 0]),
            czz=_f(C[2, 2]), mxx=_f(Mb[0, 0]), myy=_f(Mb[1, 1]), speed_dependent=b.frequency is not None,
        ))
    return dict(
        n_nodes=len(rotor.nodes), nodes_pos=[_f(p) for p in rotor.nodes_pos],
        ndof=int(rotor.ndof), dof_per_node=int(rotor.number_dof), dof_order=DOF_NAMES,
        shaft_elements=shafts, disks=disks, bearings=bearings,
        total_mass=_f(rotor.m),
    )


def _cplx(z):
    return [float(np.real(z)), float(np.imag(z))]


def robust_whirl(ru, rv, rel_amp=1e-6, planar=1e-6):
    """Whirl label that ignores roundoff-level nodes.

    ROSS labels a mode 'Forward'/'Backward' only if *every* node's orbit agrees
    (else 'Mixed'); a node sitting exactly on a nodal point (e.g. mid-span node 3 of
    the symmetric rotor (a) in antisymmetric modes, |x|,|y| ~ 1e-17) or a planar orbit
    (undamped anisotropic rotor at speed 0) is then decided by roundoff. Here nodes
    with orbit major axis < rel_amp * max are ignored and |kappa| < planar counts as
    'Planar' (roundoff gives |kappa| ~ 1e-8 for a truly planar orbit). Returns 'Forward', 'Backward', 'Mixed' or 'Planar'.
    """
    orbits = [Orbit(node=i, node_pos=0.0, ru_e=u, rv_e=w) for i, (u, w) in enumerate(zip(ru, rv))]
    amax = max(o.major_axis for o in orbits)
    labels = set()
    for o in orbits:
        if o.major_axis < rel_amp * amax:
            continue
        labels.add("Planar" if abs(o.kappa) < planar else ("Forward" if o.kappa > 0 else "Backward"))
    if labels == {"Planar"}:
        return "Planar"
    labels.discard("Planar")
    return labels.pop() if len(labels) == 1 else "Mixed"


def ross_modal(rotor, speed, n=N_MODES):
    """ROSS's run_modal (ARPACK default) + dense cross-check, first n modes."""
    m = rotor.run_modal(speed, num_modes=2 * n)
    whirl = m.whirl_direction()
    out = dict(
        wd=[_f(v) for v in m.wd[:n]],
        wn=[_f(v) for v in m.wn[:n]],
        eigenvalues=[_cplx(v) for v in m.evalues[:n]],
        log_dec=[_f(v) for v in m.log_dec[:n]],
        damping_ratio=[_f(v) for v in m.damping_ratio[:n]],
        whirl=[None if w is None or str(w) == "None" else str(w) for w in whirl[:n]],
        mode_type=[s.mode_type for s in m.shapes[:n]],
    )
    nd = rotor.number_dof
    out["whirl_robust"] = [
        robust_whirl(m.evectors[0:rotor.ndof:nd, k], m.evectors[1:rotor.ndof:nd, k])
        if t == "Lateral" else None
        for k, t in enumerate(out["mode_type"])
    ]
    md = rotor.run_modal(speed, num_modes=2 * n, sparse=False)
    out["dense_wd"] = [_f(v) for v in md.wd[:n]]
    out["dense_eigenvalues"] = [_cplx(v) for v in md.evalues[:n]]
    return out


def lateral_dofs(rotor):
    nd = rotor.number_dof
    return np.array([nd * k + j for k in range(len(rotor.nodes)) for j in LATERAL_LOCAL])


def lateral_only_modal(rotor, speed, n=N_MODES):
    """Dense eig of the lateral (x, y, alpha, beta) block of ROSS's matrices."""
    idx = lateral_dofs(rotor)
    ix = np.ix_(idx, idx)
    M = rotor.M(speed)[ix]
    K = rotor.K(speed)[ix]
    C = rotor.C(speed)[ix]
    G = rotor.G()[ix]
    N = len(idx)
    A = np.block([[np.zeros((N, N)), np.eye(N)],
                  [la.solve(-M, K), la.solve(-M, C + speed * G)]])
    ev, vec = la.eig(A)
    keep = np.abs(ev) > 1e-1  # same rigid-mode filter as Rotor._eigen
    ev, vec = ev[keep], vec[:, keep]
    order = rotor._index(ev)  # ROSS sort: Im>0 first, ascending Im, then |lam|
    ev, vec = ev[order][:n], vec[:, order][:, :n]
    zeta = -ev.real / np.abs(ev)
    with np.errstate(invalid="ignore", divide="ignore"):
        logdec = 2 * np.pi * zeta / np.sqrt(1 - zeta**2)
    whirls = []
    for k in range(ev.size):
        # same normalisation as ross.results.Shape (normalize=True): divide by the
        # largest x or y entry; it matters for near-planar orbits (kappa == 0 ->
        # ROSS calls the node 'Backward').
        v = vec[:N, k].copy()
        vx, vy = v[0::4], v[1::4]
        ix, iy = np.argmax(np.abs(vx)), np.argmax(np.abs(vy))
        v /= vy[iy] if np.abs(vy[iy]) > np.abs(vx[ix]) else vx[ix]
        per_node = [Orbit(node=i, node_pos=0.0, ru_e=v[4 * i], rv_e=v[4 * i + 1]).whirl
                    for i in range(len(rotor.nodes))]
        if all(w == "Forward" for w in per_node):
            whirls.append("Forward")
        elif all(w == "Backward" for w in per_node):
            whirls.append("Backward")
        else:
            whirls.append("Mixed")
    return dict(
        wd=[_f(v) for v in ev.imag], wn=[_f(v) for v in np.abs(ev)],
        eigenvalues=[_cplx(v) for v in ev], log_dec=[_f(v) for v in logdec],
        damping_ratio=[_f(v) for v in zeta], whirl=whirls,
        whirl_robust=[robust_whirl(vec[0:N:4, k], vec[1:N:4, k]) for k in range(ev.size)],
    )


def analyse(rotor, speeds=SPEEDS):
    rotor.run_modal.cache_clear()
    res = {}
    for s in speeds:
        res[repr(float(s))] = dict(
            speed=float(s),
            ross=ross_modal(rotor, s),
            lateral_only=lateral_only_modal(rotor, s),
        )
    return res


def dump_matrices(rotor, path, speeds=MATRIX_SPEEDS):
    arrays = {}
    for s in speeds:
        tag = f"{int(s)}"
        arrays[f"M_{tag}"] = rotor.M(s)
        arrays[f"K_{tag}"] = rotor.K(s)
        arrays[f"C_{tag}"] = rotor.C(s)
    arrays["G"] = rotor.G()
    arrays["speeds"] = np.array(speeds, dtype=float)
    arrays["lateral_dofs"] = lateral_dofs(rotor)
    arrays["dof_names"] = np.array([f"{d}_{k}" for k in range(len(rotor.nodes)) for d in DOF_NAMES])
    sh = rotor.shaft_elements[0]
    arrays["shaft0_M"], arrays["shaft0_K"], arrays["shaft0_G"] = sh.M(), sh.K(), sh.G()
    d = rotor.disk_elements[0]
    arrays["disk0_M"], arrays["disk0_G"] = d.M(), d.G()
    np.savez(path, **arrays)
    return sorted(arrays)


# ------------------------------------------------------------- closed-form checks
def closed_form_shaft_matrices(L, idl, odl, mat):
    """Cylindrical ShaftElement matrices from closed forms (12x12, ROSS dof order).

    Lateral part: Timoshenko beam, interdependent cubic/quadratic shape functions
    (Friswell et al. 2010, ch. 5), applied in the x-z plane with dofs (x, beta=dx/dz)
    and in the y-z plane with (y, -alpha=dy/dz). G[x-plane, y-plane] = 2*Mr, skew.
    Axial/torsional: linear bars (rho A L/6 [2 1;1 2], E A/L, rho J L/6, G_s J/L, J=2I).
    """
    E, Gs, rho, nu = mat.E, mat.G_s, mat.rho, mat.Poisson
    A = np.pi * (odl**2 - idl**2) / 4
    I = np.pi * (odl**4 - idl**4) / 64
    r2 = (idl / odl) ** 2
    kappa = 6 * (1 + nu) * (1 + r2) ** 2 / ((7 + 6 * nu) * (1 + r2) ** 2 + (20 + 12 * nu) * r2)  # Cowper
    p = 12 * E * I / (kappa * Gs * A * L**2)
    sym = lambda X: np.triu(X) + np.triu(X, 1).T
    Mt = sym(rho * A * L / (840 * (1 + p) ** 2) * np.array([
        [312 + 588 * p + 280 * p**2, (44 + 77 * p + 35 * p**2) * L, 108 + 252 * p + 140 * p**2, -(26 + 63 * p + 35 * p**2) * L],
        [0, (8 + 14 * p + 7 * p**2) * L**2, (26 + 63 * p + 35 * p**2) * L, -(6 + 14 * p + 7 * p**2) * L**2],
        [0, 0, 312 + 588 * p + 280 * p**2, -(44 + 77 * p + 35 * p**2) * L],
        [0, 0, 0, (8 + 14 * p + 7 * p**2) * L**2]]))
    Mr = sym(rho * I / (30 * L * (1 + p) ** 2) * np.array([
        [36, (3 - 15 * p) * L, -36, (3 - 15 * p) * L],
        [0, (4 + 5 * p + 10 * p**2) * L**2, -(3 - 15 * p) * L, (-1 - 5 * p + 5 * p**2) * L**2],
        [0, 0, 36, -(3 - 15 * p) * L],
        [0, 0, 0, (4 + 5 * p + 10 * p**2) * L**2]]))
    Kb = sym(E * I / (L**3 * (1 + p)) * np.array([
        [12, 6 * L, -12, 6 * L], [0, (4 + p) * L**2, -6 * L, (2 - p) * L**2],
        [0, 0, 12, -6 * L], [0, 0, 0, (4 + p) * L**2]]))
    ix, iy, Ty = [0, 4, 6, 10], [1, 3, 7, 9], np.diag([1.0, -1.0, 1.0, -1.0])
    M, K, G = (np.zeros((12, 12)) for _ in range(3))
    for idx, T in ((ix, np.eye(4)), (iy, Ty)):
        M[np.ix_(idx, idx)] += T @ (Mt + Mr) @ T
        K[np.ix_(idx, idx)] += T @ Kb @ T
    G[np.ix_(ix, iy)] = 2 * Mr @ Ty
    G[np.ix_(iy, ix)] = -(2 * Mr @ Ty).T
    J, bar = 2 * I, np.array([[2.0, 1.0], [1.0, 2.0]])
    M[np.ix_([2, 8], [2, 8])] += rho * A * L / 6 * bar
    M[np.ix_([5, 11], [5, 11])] += rho * J * L / 6 * bar
    K[np.ix_([2, 8], [2, 8])] += E * A / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[np.ix_([5, 11], [5, 11])] += Gs * J / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return dict(M=M, K=K, G=G, kappa=kappa, phi=p)


def check_element_formulas():
    """Max relative deviation of ROSS element matrices from the closed forms above."""
    out = []
    for (L, idl, odl) in [(0.25, 0.0, 0.05), (0.1, 0.04, 0.12), (0.03125, 0.0, 0.05)]:
        el = rs.ShaftElement(L, idl, odl, material=rs.materials.steel)
        cf = closed_form_shaft_matrices(L, idl, odl, rs.materials.steel)
        rel = {k: float(np.abs(cf[k] - getattr(el, k)()).max() / np.abs(getattr(el, k)()).max())
               for k in ("M", "K", "G")}
        out.append(dict(L=L, idl=idl, odl=odl, kappa=float(el.kappa), phi=float(el.phi),
                        kappa_rel_err=abs(cf["kappa"] / el.kappa - 1), phi_rel_err=abs(cf["phi"] / el.phi - 1),
                        max_rel_err=rel))
    return out


# --------------------------------------------------------------------------- timing
# NB: Rotor.run_modal is wrapped in methodtools.lru_cache (rotor_assembly.py line 805),
# so repeated calls with the same arguments return the cached ModalResults in ~20 us,
# and run_campbell reorders those cached objects in place (MAC tracking). Every timed
# call therefore starts from rotor.run_modal.cache_clear().
def _median_time(fn, repeats, rotor):
    ts = []
    for _ in range(repeats):
        rotor.run_modal.cache_clear()
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    rotor.run_modal.cache_clear()
    return float(np.median(ts)), ts


def timing(rotor, repeats, blas_threads):
    try:
        from threadpoolctl import threadpool_info, threadpool_limits
    except ImportError:  # pragma: no cover
        threadpool_limits = None
    limiter = (threadpool_limits(limits=blas_threads) if (threadpool_limits and blas_threads)
               else contextlib.nullcontext())
    with limiter:
        blas = [dict(api=i.get("internal_api"), num_threads=i.get("num_threads"))
                for i in (threadpool_info() if threadpool_limits else [])]
        load_before = os.getloadavg()
        speed_range = np.linspace(0, 1000, 50)
        rotor.run_modal.cache_clear()
        t0 = time.perf_counter()
        rotor.run_modal(0.0)  # warm-up (numba JIT of ross.results._init_orbit if first in process)
        warm = time.perf_counter() - t0
        camp_med, camp_all = _median_time(
            lambda: rotor.run_campbell(speed_range=speed_range, frequencies=8), repeats, rotor)
        r5 = max(repeats, 5)
        modal12_med, modal12_all = _median_time(lambda: rotor.run_modal(500.0), r5, rotor)
        modal20_med, modal20_all = _median_time(lambda: rotor.run_modal(500.0, num_modes=20), r5, rotor)
        dense_med, dense_all = _median_time(
            lambda: rotor.run_modal(500.0, num_modes=20, sparse=False), r5, rotor)
        A = rotor.A(500.0)
        a_med, a_all = _median_time(lambda: rotor.A(500.0), r5, rotor)
        eig_med, eig_all = _median_time(lambda: la.eig(A), r5, rotor)
        load_after = os.getloadavg()
    return dict(
        ndof=int(rotor.ndof), state_dim=int(2 * rotor.ndof), n_elements=len(rotor.shaft_elements),
        blas=blas, loadavg_before=list(load_before), loadavg_after=list(load_after),
        note="run_modal lru_cache cleared before every timed call",
        first_run_modal_s=warm,
        run_campbell=dict(call="rotor.run_campbell(speed_range=np.linspace(0, 1000, 50), frequencies=8)",
                          median_s=camp_med, all_s=camp_all,
                          note="internally run_modal(speed, num_modes=2*(8+2)=20) per speed + MAC mode tracking"),
        run_modal_default=dict(call="rotor.run_modal(500.0)  # num_modes=12, ARPACK k=24",
                               median_s=modal12_med, all_s=modal12_all),
        run_modal_num_modes_20=dict(call="rotor.run_modal(500.0, num_modes=20)  # ARPACK k=40",
                                    median_s=modal20_med, all_s=modal20_all),
        run_modal_dense=dict(call="rotor.run_modal(500.0, num_modes=20, sparse=False)",
                             median_s=dense_med, all_s=dense_all),
        rotor_A=dict(call="rotor.A(500.0)  # state matrix incl. 2 dense solves", median_s=a_med, all_s=a_all),
        scipy_eig_of_A=dict(call="scipy.linalg.eig(A)  # A = rotor.A(500.0)", median_s=eig_med, all_s=eig_all),
    )


def campbell_data(rotor, speed_range, frequencies=8):
    rotor.run_modal.cache_clear()
    camp = rotor.run_campbell(speed_range=speed_range, frequencies=frequencies)
    rotor.run_modal.cache_clear()  # run_campbell reorders cached ModalResults in place
    return dict(
        call=f"rotor.run_campbell(speed_range=np.linspace({speed_range[0]!r}, {speed_range[-1]!r}, "
             f"{len(speed_range)}), frequencies={frequencies})",
        note="columns are MAC-tracked modes (order of the first speed), not re-sorted per speed; "
             "whirl_values: 0 Forward, 0.5 Mixed, 1 Backward, NaN non-lateral",
        speed_range=[float(s) for s in speed_range],
        wd=np.asarray(camp.wd).tolist(),
        log_dec=np.asarray(camp.log_dec).tolist(),
        whirl_values=[[None if np.isnan(v) else float(v) for v in row] for row in np.asarray(camp.whirl_values)],
    )


# ----------------------------------------------------------------------------- main
def _print_table(name, res):
    log(f"--- {name}: first {N_MODES} damped natural frequencies wd [rad/s] (ROSS run_modal)")
    for key, r in res.items():
        ro = r["ross"]
        cells = [f"{w:.6f}{'' if t == 'Lateral' else '(' + t[0] + ')'}"
                 for w, t in zip(ro["wd"], ro["mode_type"])]
        log(f"  speed {r['speed']:7.1f}: " + "  ".join(cells))
        log(f"    lateral-only     : " + "  ".join(f"{w:.6f}" for w in r["lateral_only"]["wd"]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=None,
                    help="write JSON here (npz files go next to it); default: JSON to stdout")
    ap.add_argument("--repeats", type=int, default=3, help="timing repeats (median reported)")
    ap.add_argument("--no-timing", action="store_true", help="skip the run_campbell timing of rotor (c)")
    ap.add_argument("--blas-threads", type=int, default=1,
                    help="BLAS threads during timing (threadpoolctl); 0 = leave as is")
    args = ap.parse_args(argv)

    data = dict(
        generator="benchmarks/ross_reference.py",
        environment=dict(python=platform.python_version(), ross=rs.__version__,
                         numpy=np.__version__, scipy=scipy.__version__,
                         cpu_count=os.cpu_count(), machine=platform.machine()),
        conventions=dict(
            dof_per_node=DOF_NAMES,
            global_dof_index="6*node + local (x=0, y=1, z=2, alpha=3, beta=4, theta=5)",
            rotations="alpha = -dy/dz (rotation about x), beta = +dx/dz (rotation about y)",
            equation="M q'' + (C + speed*G) q' + K q = f ; bearings evaluated at frequency=speed",
            eigen="run_modal: scipy.sparse.linalg.eigs(A, k=min(2*num_modes, max(num_modes, 2*ndof-2)), "
                  "sigma=1, which='LM', v0=ones); drop |lambda|<=0.1; sort Im>0 first by Im then |lambda|; "
                  "wd=Im(lambda)[:num_modes//2], wn=|lambda|, zeta=-Re/|lambda|, log_dec=2*pi*zeta/sqrt(1-zeta^2)",
            speeds_rad_s=SPEEDS,
        ),
        rotors={},
    )
    data["element_formula_checks"] = check_element_formulas()
    log("closed-form vs ROSS element matrices (max rel. err): "
        + "; ".join(f"L={c['L']}, id={c['idl']}, od={c['odl']}: " + ", ".join(f"{k}={v:.1e}" for k, v in c["max_rel_err"].items())
                    for c in data["element_formula_checks"]))

    stem = args.out.with_suffix("") if args.out else None
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)

    for name, builder, text in [
        ("example", build_example, example_construction_text()),
        ("compressor", build_compressor_like, compressor_construction_text()),
    ]:
        rotor = builder()
        log(f"building/analysing {name}: {len(rotor.shaft_elements)} shaft elements, "
            f"{len(rotor.disk_elements)} disks, {len(rotor.bearing_elements)} bearings, ndof={rotor.ndof}")
        entry = dict(construction=text, model=model_definition(rotor), modal=analyse(rotor))
        if stem is not None:
            npz = Path(f"{stem}_{name}_matrices.npz")
            entry["matrices_npz"] = npz.name
            entry["matrices_keys"] = dump_matrices(rotor, npz)
            log(f"  wrote {npz}")
        data["rotors"][name] = entry
        _print_table(name, entry["modal"])

    refined = build_refined_example(8)
    log(f"building/analysing example_refined: {len(refined.shaft_elements)} elements, ndof={refined.ndof}")
    entry = dict(
        construction="rotor_example() with each 0.25 m element split into 8 elements of 0.03125 m "
                     "(48 ShaftElement(0.03125, 0, 0.05, steel)); disks at nodes 16 and 32; "
                     "bearings (kxx=1e6, kyy=0.8e6, cxx=0) at nodes 0 and 48",
        model=model_definition(refined),
        modal=analyse(refined),
    )
    if not args.no_timing:
        entry["timing"] = timing(refined, args.repeats, args.blas_threads)
        t = entry["timing"]
        log(f"  run_campbell(linspace(0,1000,50), frequencies=8): median {t['run_campbell']['median_s']:.3f} s "
            f"(all {', '.join(f'{v:.3f}' for v in t['run_campbell']['all_s'])})")
        log(f"  run_modal(500) default: {t['run_modal_default']['median_s'] * 1e3:.1f} ms; "
            f"num_modes=20: {t['run_modal_num_modes_20']['median_s'] * 1e3:.1f} ms; "
            f"dense: {t['run_modal_dense']['median_s'] * 1e3:.1f} ms; "
            f"A(): {t['rotor_A']['median_s'] * 1e3:.1f} ms; eig(A): {t['scipy_eig_of_A']['median_s'] * 1e3:.1f} ms; "
            f"loadavg {t['loadavg_before'][0]:.2f}->{t['loadavg_after'][0]:.2f}")
    entry["campbell"] = campbell_data(refined, np.linspace(0.0, 1000.0, 50), 8)
    data["rotors"]["example_refined"] = entry
    _print_table("example_refined", entry["modal"])

    text = json.dumps(data, indent=1)
    if args.out:
        args.out.write_text(text + "\n")
        log(f"wrote {args.out}")
    else:
        sys.stdout.write(text + "\n")


if __name__ == "__main__":
    main()
