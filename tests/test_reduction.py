"""mechgen.runtime.fields.constrain.Reduction's column selection (boundary conditions that eliminate dofs): the
one-pass sparse reduction and the indexed vector reduction equal scipy's A[keep][:, keep] and Z^T r bit for bit."""
import numpy as np
import pytest
import scipy.sparse as sps

from mechgen.runtime.fields.constrain import Reduction


def selection(n: int, keep: np.ndarray) -> Reduction:
    Z = sps.csr_matrix((np.ones(len(keep)), (keep, np.arange(len(keep)))), shape=(n, len(keep)))
    return Reduction(n, Z, keep=keep)


@pytest.mark.parametrize("n, dropped", [(5, 1), (40, 3), (200, 10)])
def test_kept_equals_scipys_fancy_indexing(n, dropped):
    rng = np.random.default_rng(n)
    keep = np.sort(rng.choice(n, n - dropped, replace=False))
    red = selection(n, keep)
    A = sps.random(n, n, density=0.2, random_state=rng, format="csr")
    A.data -= 0.5  # both signs
    for given in (A, A.tocsc(), A.tocoo()):
        B, C = red.matrix(given), A[keep][:, keep]
        assert B.format == "csr" and B.shape == C.shape
        np.testing.assert_array_equal(B.indptr, C.indptr)
        np.testing.assert_array_equal(B.indices, C.indices)
        np.testing.assert_array_equal(B.data, C.data)
    r = rng.standard_normal(n)
    np.testing.assert_array_equal(red.vector(r), red.Z.T @ r)
    R = rng.standard_normal((n, 3))
    np.testing.assert_array_equal(red.vector(R), red.Z.T @ R)


def test_a_dense_matrix_is_indexed():
    keep = np.array([0, 2, 3])
    A = np.arange(16.0).reshape(4, 4)
    np.testing.assert_array_equal(selection(4, keep).matrix(A), A[np.ix_(keep, keep)])
