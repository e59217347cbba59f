"""Matrix Market and text vectors: clothsim.io.matrices."""


import numpy as np
import scipy.sparse

from clothsim import io


def test_matrix_and_vector_round_trip_exact(tmp_path):
    rng = np.random.default_rng(3)
    A = scipy.sparse.random(30, 20, density=0.2, random_state=rng, format="csr")
    A.data = A.data / 3 + np.pi * 1e-300
    io.write_matrix(tmp_path / "A.mtx", A)
    B = io.read_matrix(tmp_path / "A.mtx")
    assert scipy.sparse.issparse(B) and B.shape == (30, 20)
    assert (B != A).nnz == 0
    assert np.array_equal(B.toarray(), A.toarray())
    D = rng.standard_normal((4, 5)) / 7
    io.write_matrix(tmp_path / "D.mtx", D)
    assert np.array_equal(io.read_matrix(tmp_path / "D.mtx"), D)
    v = rng.standard_normal(12) * 1e10 / 3
    io.write_vector(tmp_path / "v.txt", v)
    assert np.array_equal(io.read_vector(tmp_path / "v.txt"), v)
    assert len((tmp_path / "v.txt").read_text().splitlines()) == 12
