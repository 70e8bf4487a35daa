"""mechgen's Hermite beam against scikit-fem, an independent finite-element assembler.

Reference: scikit-fem (Gustafsson & McBain, JOSS 5(52) 2020; checked with 12.0.2),
``MeshLine`` + ``ElementLineHermite`` + ``Basis`` and the bilinear forms
``rhoA u v`` and ``EI dd(u)[0,0] dd(v)[0,0]`` (its docs/examples/ex34.py), assembled
with ``asm``. Both number the dofs (w, w_s) per node in node order, so the
unconstrained matrices compare entry by entry.

Tolerances are measured, not guessed: scikit-fem's ElementLineHermite builds its
shape functions by inverting a Vandermonde matrix in global coordinates on each
element, so its entries carry round-off that grows as the elements shrink (2.5e-13
of the largest entry at 8 elements on [0, 1], 1e-5 at 2 000; mechgen matches the
closed-form element matrices to 1e-15). At 8 elements the matrices agree to 1e-11
of the largest entry and the first five clamped-free frequencies to 1e-8 (measured
1e-10); both also sit at the known cubic-Hermite error against the exact roots of
cos(x) cosh(x) = -1 (5.8e-3 at 8 elements, tests/test_field_beam.py).
"""
import numpy as np
import pytest
import scipy.linalg as sla

from mechgen import models
from mechgen.pipeline import compile_model
from mechgen.runtime.linear.modes import modes
from mechgen.symbolic.specialize import specialize

skfem = pytest.importorskip("skfem", reason="scikit-fem is not installed (it is in the 'test' extra: "
                                            "pip install -e '.[test]')")

N, EI, RHOA, L = 8, 2.0, 3.0, 1.5


def skfem_matrices(elements: int, length: float, ei: float, rhoa: float):
    """Unconstrained M and K (CSR) of scikit-fem's Hermite beam."""
    from skfem.helpers import dd

    basis = skfem.Basis(skfem.MeshLine(np.linspace(0.0, length, elements + 1)), skfem.ElementLineHermite())
    mass = skfem.BilinearForm(lambda u, v, w: rhoa * u * v)
    stiffness = skfem.BilinearForm(lambda u, v, w: ei * dd(u)[0, 0] * dd(v)[0, 0])
    return skfem.asm(mass, basis), skfem.asm(stiffness, basis)


def mechgen_matrices(bc: str):
    model = models.get("euler_bernoulli_beam")
    spec = specialize(model, {"bc": bc, "discretisation": "hermite", "N": N, "EI": EI, "rhoA": RHOA, "L": L})
    system, _ = compile_model(model, spec, kernels={"linear"})
    mats = system.linear()
    return mats["M"], mats["K"]


def test_unconstrained_matrices_match_skfem():
    M, K = mechgen_matrices("free-free")
    Ms, Ks = skfem_matrices(N, L, EI, RHOA)
    assert M.shape == Ms.shape == (2 * N + 2, 2 * N + 2)
    for ours, theirs in ((M, Ms), (K, Ks)):
        ours, theirs = ours.toarray(), theirs.toarray()
        assert np.abs(ours - theirs).max() <= 1e-11 * np.abs(theirs).max()


def test_clamped_free_frequencies_match_skfem():
    M, K = mechgen_matrices("clamped-free")
    ours = modes(M, K, count=5).frequencies
    Ms, Ks = skfem_matrices(N, L, EI, RHOA)
    free = np.arange(2, 2 * N + 2)  # w and w_s at s = 0 removed
    lam = sla.eigh(Ks.toarray()[np.ix_(free, free)], Ms.toarray()[np.ix_(free, free)], eigvals_only=True,
                   subset_by_index=[0, 4])
    theirs = np.sqrt(lam)
    assert np.abs(ours / theirs - 1).max() < 1e-8
    # and both are the Hermite approximation of the exact beam (beta L from cos cosh = -1)
    exact = np.array([1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349, 14.1371683910]) ** 2
    exact = exact * np.sqrt(EI / (RHOA * L**4))
    assert np.abs(theirs / exact - 1).max() < 1e-2
