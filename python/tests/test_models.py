"""Models from arrays: the same model as its folder of files, and dense and
sparse inputs alike."""

import numpy as np
import scipy.io
import scipy.sparse
import ssm


def chain():
    """Three masses in a chain with cubic springs to the ground, Rayleigh
    damping and a load on the last mass."""
    M = np.diag([1.0, 2.0, 1.5])
    K = np.array([[3.0, -1.0, 0.0], [-1.0, 2.5, -1.2], [0.0, -1.2, 1.9]])
    idx = np.array([[0, 0, 0, 0], [1, 1, 1, 1], [2, 2, 2, 2], [0, 0, 0, 1]])
    vals = np.array([0.4, 0.3, 0.5, -0.1])
    fext = np.array([0.0, 0.0, 1.0])
    return M, K, (idx, vals), fext


def write_folder(path, M, K, f3, fext):
    """The chain as model files (Matrix Market, 1-based tensor rows)."""
    scipy.io.mmwrite(path / "M.mtx", scipy.sparse.coo_matrix(M))
    scipy.io.mmwrite(path / "K.mtx", scipy.sparse.coo_matrix(K))
    idx, vals = f3
    with open(path / "f3.coo", "w") as f:
        f.writelines(
            " ".join(str(i + 1) for i in row) + f" {float(v)!r}\n"
            for row, v in zip(idx, vals)
        )
    scipy.io.mmwrite(path / "fext.mtx", fext.reshape(-1, 1))
    (path / "outputs.csv").write_text("name,dof\ntip,3\n")


def test_arrays_and_files_give_the_same_spectrum_and_ssm(tmp_path):
    """Reference: the model folder read by the engine (`matrix-model`'s
    path). The spectra and the coefficients of W at O(7) agree to 1e-12
    relative."""
    M, K, f3, fext = chain()
    write_folder(tmp_path, M, K, f3, fext)
    from_files = ssm.from_files(tmp_path, rayleigh=(0.01, 0.002))
    from_arrays = ssm.from_arrays(
        M, K, rayleigh=(0.01, 0.002), f3=f3, fext=fext, outputs={"tip": 2}
    )
    a, b = from_arrays.spectrum(), from_files.spectrum()
    assert np.allclose(a, b, rtol=1e-12, atol=0.0)
    sa = ssm.compute_ssm(from_arrays, [1], 7)
    sb = ssm.compute_ssm(from_files, [1], 7)
    scale = np.abs(sb.w).max()
    assert np.abs(sa.w - sb.w).max() <= 1e-12 * scale


def test_dense_and_sparse_inputs_give_the_same_model():
    """Determinism check: scipy.sparse (CSR, COO) and dense arrays of the
    same matrices give identical SSM coefficients."""
    M, K, f3, fext = chain()
    dense = ssm.compute_ssm(ssm.from_arrays(M, K, 0.01 * M, f3=f3, fext=fext), [1], 5)
    sparse = ssm.compute_ssm(
        ssm.from_arrays(
            scipy.sparse.csr_matrix(M),
            scipy.sparse.coo_matrix(K),
            scipy.sparse.csc_matrix(0.01 * M),
            f3=f3,
            fext=fext,
        ),
        [1],
        5,
    )
    assert np.array_equal(dense.w, sparse.w)
