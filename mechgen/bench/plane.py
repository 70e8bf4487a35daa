"""``mechgen bench plane``: assembly of the plane-stress elasticity stiffness, mechgen's numeric plane path against
scikit-fem on the same mesh.

The problem: K = int_Omega eps(v) : C eps(u) dA, plane stress, E = 1, nu = 0.3 (lambda* = E nu / (1 - nu^2),
mu = E / (2 (1 + nu))), on the unit square meshed by :func:`mechgen.runtime.plane.mesh.rectangle` with P1 or P2
triangles at about 10^5 and 10^6 unknowns (quick: about 2 x 10^4). scikit-fem (``MeshTri`` of the same vertices
and cells, ``ElementVector(ElementTriP1/P2)``, the same quadrature degree) assembles
``skfem.models.elasticity.linear_elasticity``; mechgen evaluates the pointwise coefficient C[e, q, a, b] of the
jets (ux_x, ux_y, uy_x, uy_y) at every quadrature point (what a generated tangent kernel hands over), forms the
element matrices (:func:`mechgen.runtime.plane.elements.jet_element_matrices`) and scatters them into CSR
(:class:`mechgen.runtime.fields.assemble.Assembler`). Both return a CSR matrix; they are checked equal to round-off
(after permuting scikit-fem's dof numbering to mechgen's) before anything is timed.

Two timings, each the median over interleaved repeats (mechgen then scikit-fem, the order swapped every repeat)
after one untimed warm-up of each, one BLAS thread for both:

* ``assemble``: on a built mesh -- mechgen's tables and CSR pattern (built once per mesh, like scikit-fem's
  ``Basis``) reused: coefficients + element matrices + scatter, against ``skfem.asm`` on a built ``Basis``
  (which converts COO to CSR every call);
* ``from scratch``: mechgen's tables + dof map + CSR pattern + the above, against ``Basis(...)`` + ``asm``.

* ``user path``: as a user runs it -- ``tangent()`` of the compiled model ``membrane_gravity`` on a disk mesh of
  the same size (the generated pointwise kernel at every point, the system's own element matrices and scatter,
  the rim's dofs removed; it returns K and M) against ``skfem.asm`` of the elasticity and mass forms and the same
  reduction ``K[free][:, free]``.

Ratios are mechgen / scikit-fem (target <= 1); the standard ratios file records peer_s / ours_s.
Measured on the project's 2-core machine (shared, load average about 3, one BLAS thread), scikit-fem 12.0.2,
median of 5 interleaved; ratio mechgen / scikit-fem:

=======  ==========  ========  ============  ===========================
element  unknowns    assemble  from scratch  user path (tangent: K and M)
=======  ==========  ========  ============  ===========================
P1       ~1.0e5      0.20      0.48          0.58 (1.2e5 unknowns)
P2       ~1.0e5      0.13      0.43          0.33
P1       ~1.0e6      0.08      0.25          1.38 (9.8 s against 7.1 s)
P2       ~1.0e6      0.04      0.16          0.63
=======  ==========  ========  ============  ===========================

The user path's P1 row at 10^6 grows faster than the cell count (0.36 s at 10^5). In a process of its own the same
``tangent()`` takes 3.0-4.1 s once warm (13 s the first call, which builds the tables and CSR patterns), which
would be about 0.5 x scikit-fem; inside the bench, beside scikit-fem's multi-GB arrays, its median is 9.8 s.
Profiled alone: element matrices ~2 s, scatter ~1.2 s, the kernel 0.8 s, point jets 0.6 s. Left to study.

Entry point: :func:`run_plane_benchmarks`.
"""
from __future__ import annotations

import statistics
import sys
from pathlib import Path

import numpy as np

from mechgen.bench.common import blas_threads, environment, interleaved_rounds, suite_report, write_json, write_text

E_MODULUS, NU = 1.0, 0.3
JETS = ((0, "x"), (0, "y"), (1, "x"), (1, "y"))
#: target unknowns
SIZES = (100_000, 1_000_000)
QUICK_SIZES = (20_000,)
ELEMENTS = ("P1", "P2")
# max |K_mechgen - K_skfem| / max |K_skfem|: round-off, amplified by x / h because both map the cells from
# coordinates ~1 differenced over cells ~1e-3 (measured 6e-16 P1, 2e-13 P2 at 10^6 unknowns)
CHECK_TOL = 1e-12


def lame_plane_stress(E: float = E_MODULUS, nu: float = NU) -> tuple[float, float]:
    """(lambda*, mu) = (E nu / (1 - nu^2), E / (2 (1 + nu))): plane stress, sigma_zz = 0 condensed [Pa]."""
    return E * nu / (1 - nu * nu), E / (2 * (1 + nu))


def coefficient(shape: tuple, lam: float, mu: float) -> np.ndarray:
    """C[..., a, b] = d2W/dg_a dg_b, W = lam/2 (tr eps)^2 + mu eps:eps, g = (ux_x, ux_y, uy_x, uy_y) [Pa]."""
    C = np.zeros(shape + (4, 4))
    C[..., 0, 0] = C[..., 3, 3] = lam + 2 * mu
    C[..., 0, 3] = C[..., 3, 0] = lam
    C[..., 1, 1] = C[..., 1, 2] = C[..., 2, 1] = C[..., 2, 2] = mu
    return C


def square_mesh(unknowns: int, element: str):
    """The unit square with about ``unknowns`` dofs (2 per node) of ``element``."""
    from mechgen.runtime.plane.mesh import rectangle

    per_side = max(1, int(round((np.sqrt(unknowns / 2) - 1) / (1 if element == "P1" else 2))))
    return rectangle(0.0, 1.0, 0.0, 1.0, 1.0 / per_side, element)


class Ours:
    """mechgen's path: tables and CSR pattern (``build``), then coefficients + element matrices + scatter."""

    def __init__(self, mesh) -> None:
        self.mesh = mesh
        self.lam, self.mu = lame_plane_stress()
        self.build()

    def build(self) -> None:
        """Tables, dof map and CSR pattern of the mesh."""
        from mechgen.runtime.fields.assemble import Assembler
        from mechgen.runtime.plane.elements import element_dofs, tables

        self.tab = tables(self.mesh)
        self.assembler = Assembler(element_dofs(self.mesh, 2), 2 * self.mesh.n_nodes, False)

    def assemble(self):
        """K (CSR) on the built tables and pattern."""
        from mechgen.runtime.plane.elements import jet_element_matrices

        C = coefficient(self.tab.w.shape, self.lam, self.mu)
        return self.assembler.matrix(jet_element_matrices(self.tab, 2, JETS, C))

    def scratch(self):
        """K (CSR) from the mesh alone."""
        self.build()
        return self.assemble()


class Theirs:
    """scikit-fem's path on the same vertices and cells (``MeshTri``; P2 midsides are its own facet dofs)."""

    def __init__(self, mesh) -> None:
        import skfem
        from skfem.models.elasticity import linear_elasticity

        from mechgen.runtime.plane.elements import DEFAULT_DEGREE

        self.skfem = skfem
        self.mesh = mesh
        verts = np.unique(mesh.vertices)
        self.verts = verts
        self.vid = np.full(mesh.n_nodes, -1)
        self.vid[verts] = np.arange(len(verts))
        self.sk_mesh = skfem.MeshTri(np.ascontiguousarray(mesh.points[verts].T),
                                     np.ascontiguousarray(self.vid[mesh.vertices].T))
        self.degree = DEFAULT_DEGREE[mesh.element]
        self.form = linear_elasticity(*lame_plane_stress())
        self.basis = self.make_basis()

    def make_basis(self):
        element = self.skfem.ElementTriP1() if self.mesh.element == "P1" else self.skfem.ElementTriP2()
        return self.skfem.Basis(self.sk_mesh, self.skfem.ElementVector(element), intorder=self.degree)

    def assemble(self):
        return self.skfem.asm(self.form, self.basis)

    def scratch(self):
        return self.skfem.asm(self.form, self.make_basis())

    def permutation(self) -> np.ndarray:
        """perm[mechgen dof] = scikit-fem dof (vertex dofs by vertex, P2 midside dofs by the facet's vertices)."""
        from mechgen.runtime.plane.mesh import cell_edges

        perm = np.empty(2 * self.mesh.n_nodes, np.int64)
        for c in range(2):
            perm[2 * self.verts + c] = self.basis.nodal_dofs[c]
        if self.mesh.element == "P2":
            f = np.sort(self.sk_mesh.facets, axis=0).astype(np.int64)  # keys f0 * nv + f1 overflow int32
            nv = len(self.verts)
            order = np.argsort(f[0] * nv + f[1])
            edges = cell_edges(self.mesh.cells, "P2").reshape(-1, 3)
            a, b = np.sort(self.vid[edges[:, :2]], axis=1).T
            index = order[np.searchsorted((f[0] * nv + f[1])[order], a * nv + b)]
            for c in range(2):
                perm[2 * edges[:, 2] + c] = self.basis.facet_dofs[c][index]
        return perm


def interleaved(ours, theirs, repeats: int) -> tuple[list, list]:
    """Per-call seconds of ``repeats`` rounds, ours then theirs, the order swapped every round (warm-ups excluded:
    mechgen.bench.common.interleaved_rounds)."""
    rounds = interleaved_rounds({"ours": ours, "theirs": theirs}, repeats)
    return rounds["ours"][0], rounds["theirs"][0]


def compare(unknowns: int, element: str, repeats: int) -> dict:
    """Check then time one size and element: both paths' medians and the ratios mechgen / scikit-fem."""
    mesh = square_mesh(unknowns, element)
    ours, theirs = Ours(mesh), Theirs(mesh)
    K, Ks = ours.assemble(), theirs.assemble()
    perm = theirs.permutation()
    Ks = Ks[perm][:, perm]
    error = float(abs(K - Ks).max() / abs(Ks).max())
    if error > CHECK_TOL or K.shape != Ks.shape:
        raise AssertionError(f"{element} at {K.shape[0]} unknowns: mechgen and scikit-fem differ ({error:.2e})")
    # scikit-fem drops entries that sum to exactly zero; mechgen keeps the element pattern (stored zeros)
    row = {"element": element, "unknowns": int(K.shape[0]), "cells": mesh.n_cells, "nnz": int(K.nnz),
           "nnz_skfem": int(Ks.nnz),
           "max_rel_difference": error, "repeats": repeats}
    for what in ("assemble", "scratch"):
        a, b = interleaved(getattr(ours, what), getattr(theirs, what), repeats)
        row[f"{what}_mechgen_s"], row[f"{what}_skfem_s"] = statistics.median(a), statistics.median(b)
        row[f"{what}_ratio"] = row[f"{what}_mechgen_s"] / row[f"{what}_skfem_s"]
    return row


def disk_mesh(unknowns: int, element: str):
    """The unit disk (straight-sided cells: scikit-fem's MeshTri maps them the same way) with about ``unknowns``
    dofs of ``element``."""
    from mechgen.runtime.plane.mesh import disk

    cells_a_quarter = max(2.0, (np.sqrt(unknowns / 2 / (2.2 if element == "P1" else 8.8))))
    return disk(1.0, np.pi / 2 / (cells_a_quarter - 0.5), element, curved=False)


def user_path(unknowns: int, element: str, repeats: int) -> dict:
    """As a user runs it: ``tangent()`` of the compiled model ``membrane_gravity`` (plane stress, E = 1, nu = 0.3,
    rho = 1; the generated pointwise kernel at every point, element matrices, scatter, the rim's dofs removed: r_q = K,
    r_a = M, r_v = 0) on a disk mesh, against scikit-fem's ``asm`` of linear_elasticity and of rho u.v with the same
    reduction (``K[free][:, free]``)."""
    import mechgen
    from skfem import BilinearForm
    from skfem.helpers import dot

    mesh = disk_mesh(unknowns, element)
    system = mechgen.compile("membrane_gravity", {"E": E_MODULUS, "nu": NU, "rho_g": 1.0, "rho": 1.0, "R": 1.0},
                             kernels=("tangent",)).with_mesh(mesh)
    theirs = Theirs(mesh)
    keep = theirs.permutation()[system.disc.free]
    mass = BilinearForm(lambda u, v, w: dot(u, v))
    ours = lambda: system.tangent(np.zeros(system.n))  # noqa: E731
    peer = lambda: {"r_q": theirs.assemble()[keep][:, keep],  # noqa: E731
                    "r_a": theirs.skfem.asm(mass, theirs.basis)[keep][:, keep]}
    mats, ref = ours(), peer()
    error = max(float(abs(mats[k] - ref[k]).max() / abs(ref[k]).max()) for k in ref)
    if error > CHECK_TOL or mats["r_v"].nnz and abs(mats["r_v"]).max() > 0:
        raise AssertionError(f"membrane_gravity's tangent and scikit-fem differ ({error:.2e}) on {element}")
    a, b = interleaved(ours, peer, repeats)
    return {"element": element, "unknowns": int(2 * mesh.n_nodes), "free": int(ref["r_q"].shape[0]),
            "max_rel_difference": error, "mechgen_s": statistics.median(a), "skfem_s": statistics.median(b),
            "ratio": statistics.median(a) / statistics.median(b), "repeats": repeats}


def markdown(rows: list[dict], versions: dict) -> str:
    """The comparison as a markdown table."""
    lines = [f"# Plane-stress elasticity assembly: mechgen against scikit-fem {versions.get('skfem')}", "",
             "Unit square, E = 1, nu = 0.3, the same triangles and quadrature; CSR out on both sides, checked equal. "
             "Median over interleaved repeats after a warm-up, one BLAS thread. assemble: tables / Basis built; "
             "from scratch: including them. Ratio = mechgen / scikit-fem (target <= 1).", "",
             "| element | unknowns | assemble mechgen s | scikit-fem s | ratio | from scratch mechgen s | scikit-fem s "
             "| ratio | max rel. difference |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['element']} | {r['unknowns']} | {r['assemble_mechgen_s']:.4f} | {r['assemble_skfem_s']:.4f} "
                     f"| {r['assemble_ratio']:.2f} | {r['scratch_mechgen_s']:.4f} | {r['scratch_skfem_s']:.4f} | "
                     f"{r['scratch_ratio']:.2f} | {r['max_rel_difference']:.1e} |")
    return "\n".join(lines) + "\n"


def user_markdown(rows: list[dict]) -> str:
    """The user-path comparison as a markdown table."""
    lines = ["## As a user runs it: membrane_gravity's tangent() (K and M) against scikit-fem asm of both + the same reduction", "",
             "| element | unknowns | free | mechgen s | scikit-fem s | ratio | max rel. difference |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    lines += [f"| {r['element']} | {r['unknowns']} | {r['free']} | {r['mechgen_s']:.4f} | {r['skfem_s']:.4f} | "
              f"{r['ratio']:.2f} | {r['max_rel_difference']:.1e} |" for r in rows]
    return "\n".join(lines) + "\n"


def run_plane_benchmarks(out: Path, quick: bool = False, sizes=None) -> dict:
    """Write ``out/plane_assembly.{json,md}`` and the standard plane reports; print the table; return the rows."""
    import skfem

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = tuple(sizes or (QUICK_SIZES if quick else SIZES))
    env = environment(skfem=skfem.__version__)
    rows = []
    with blas_threads(1):
        for n in sizes:
            for element in ELEMENTS:
                rows.append(compare(n, element, repeats=3 if quick else 5))
                r = rows[-1]
                print(f"[plane] {element} {r['unknowns']} unknowns: assemble {r['assemble_ratio']:.2f}, from scratch "
                      f"{r['scratch_ratio']:.2f} x scikit-fem", file=sys.stderr, flush=True)
        users = [user_path(n, element, repeats=3 if quick else 5) for n in sizes for element in ELEMENTS]
    text = markdown(rows, {"skfem": skfem.__version__}) + "\n" + user_markdown(users)
    files = [write_json(out / "plane_assembly.json", {"rows": rows, "user_path": users, "environment": env}),
             write_text(out / "plane_assembly.md", text)]
    points = [{"series": f"{r['element']} {what}", "setting": f"{r['unknowns']} unknowns",
               "seconds": r[f"{what}_mechgen_s"], "error": r["max_rel_difference"], "unknowns": r["unknowns"],
               "skfem_s": r[f"{what}_skfem_s"]} for r in rows for what in ("assemble", "scratch")]
    ratios = [{"peer": f"scikit-fem {skfem.__version__} {'asm on a built Basis' if what == 'assemble' else 'Basis + asm'}",
               "ours_s": r[f"{what}_mechgen_s"], "peer_s": r[f"{what}_skfem_s"],
               "condition": f"{r['element']} plane-stress stiffness, {r['unknowns']} unknowns, same mesh and "
                            f"quadrature, CSR equal to {r['max_rel_difference']:.0e}"}
              for r in rows for what in ("assemble", "scratch")]
    files += suite_report(out, "plane", points, reference="scikit-fem's linear_elasticity matrix on the same mesh",
                          error="max |K - K_skfem| / max |K_skfem|", time="mechgen assembly wall time [s]",
                          title="Plane-stress stiffness assembly", ratios=ratios)
    print(text)
    return {"rows": rows, "user_path": users, "files": [str(f) for f in files]}
