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


def test_every_layout_dtype_and_sparse_format_gives_the_same_model():
    """Determinism check over the ways a matrix arrives: Fortran order, a
    strided view, float32 (converted), CSR with int64 indices, CSC, COO,
    BSR and LIL (through CSR) and the sparse arrays of scipy give the SSM
    coefficients of the C-ordered float64 input, bit for bit (float32: the
    same matrices rounded to float32 first)."""
    M, K, f3, fext = chain()
    plain = ssm.compute_ssm(ssm.from_arrays(M, K, 0.01 * K, f3=f3, fext=fext), [1], 5)
    big = np.zeros((6, 6))
    big[::2, ::2] = K
    csr64 = scipy.sparse.csr_matrix(K)
    csr64.indptr = csr64.indptr.astype(np.int64)
    csr64.indices = csr64.indices.astype(np.int64)
    variants = [
        np.asfortranarray(K),
        big[::2, ::2],
        csr64,
        scipy.sparse.csc_matrix(K),
        scipy.sparse.coo_matrix(K),
        scipy.sparse.bsr_matrix(K),
        scipy.sparse.lil_matrix(K),
        scipy.sparse.csr_array(K),
    ]
    for k in variants:
        s = ssm.compute_ssm(ssm.from_arrays(M, k, 0.01 * K, f3=f3, fext=fext), [1], 5)
        assert np.array_equal(s.w, plain.w), type(k)
    K32 = K.astype(np.float32)
    s32 = ssm.compute_ssm(ssm.from_arrays(M, K32, 0.01 * K, f3=f3, fext=fext), [1], 5)
    s64 = ssm.compute_ssm(
        ssm.from_arrays(M, K32.astype(np.float64), 0.01 * K, f3=f3, fext=fext),
        [1],
        5,
    )
    assert np.array_equal(s32.w, s64.w)


def test_a_large_sparse_model_is_read_from_scipy_buffers_without_a_copy():
    """A chain of 10^5 unit masses (CSR matrices, 3e5 entries each, 10.8 MB
    of buffers for M, K and C): the Python side allocates under 1 % of the
    matrices' bytes while the model is made (tracemalloc, which numpy
    reports its buffers to: the engine reads scipy's buffers in place and
    builds its own matrices from them; measured peak 2.8 kB against 9.6
    MB). Reference (closed form): the
    lowest eigenvalues of ``x'' + beta K x' + K x = 0`` with ``K`` the
    Dirichlet chain, ``w_k = 2 sin(k pi / (2 (n + 1)))``,
    ``lambda = -beta w^2 / 2 + i w sqrt(1 - beta^2 w^2 / 4)``, to 1e-8
    (measured 9e-10)."""
    import tracemalloc

    n, beta = 100_000, 0.01
    off = -np.ones(n - 1)
    K = scipy.sparse.diags([off, 2 * np.ones(n), off], [-1, 0, 1], format="csr")
    M = scipy.sparse.identity(n, format="csr")
    C = (beta * K).tocsr()
    nbytes = sum(a.data.nbytes + a.indices.nbytes + a.indptr.nbytes for a in (M, K, C))
    load = np.ones(n)
    tracemalloc.start()
    try:
        model = ssm.from_arrays(M, K, C, fext=load, outputs={"mid": n // 2})
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 0.01 * nbytes, (peak, nbytes)
    lam = model.spectrum(modes=6)
    lam = np.sort_complex(lam[lam.imag > 0])[::-1][:3]
    w = 2 * np.sin(np.arange(1, 4) * np.pi / (2 * (n + 1)))
    expected = -beta * w**2 / 2 + 1j * w * np.sqrt(1 - beta**2 * w**2 / 4)
    lam = lam[np.argsort(lam.imag)]
    assert np.allclose(lam, expected, rtol=1e-8, atol=0), (lam, expected)
