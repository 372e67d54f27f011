"""Writes the model folder of a clamped-clamped beam for `matrix-model`.

Euler-Bernoulli beam, N Hermite elements (transverse w and rotation per node),
immovable ends, so the mid-plane stretches: the internal force is the
Woinowsky-Krieger cubic f(q) = E A / (2 L) (q^T G q) G q, with G the
assembled integral of N'^T N'. Units mm, kg, s (as the divider of Li, Jain &
Haller 2023). Needs numpy and scipy only. Usage: python3 write_beam.py DIR
"""

import pathlib
import sys

import numpy as np
import scipy.io
import scipy.sparse

L, b, h, E, rho, N = 500.0, 10.0, 1.0, 70e6, 2700e-9, 8
A, I, le = b * h, b * h**3 / 12, L / N
# element matrices on (w1, phi1, w2, phi2)
k = (
    E
    * I
    / le**3
    * np.array(
        [
            [12, 6 * le, -12, 6 * le],
            [6 * le, 4 * le**2, -6 * le, 2 * le**2],
            [-12, -6 * le, 12, -6 * le],
            [6 * le, 2 * le**2, -6 * le, 4 * le**2],
        ]
    )
)
m = (
    rho
    * A
    * le
    / 420
    * np.array(
        [
            [156, 22 * le, 54, -13 * le],
            [22 * le, 4 * le**2, 13 * le, -3 * le**2],
            [54, 13 * le, 156, -22 * le],
            [-13 * le, -3 * le**2, -22 * le, 4 * le**2],
        ]
    )
)
g = (
    1
    / (30 * le)
    * np.array(
        [
            [36, 3 * le, -36, 3 * le],
            [3 * le, 4 * le**2, -3 * le, -(le**2)],
            [-36, -3 * le, 36, -3 * le],
            [3 * le, -(le**2), -3 * le, 4 * le**2],
        ]
    )
)
n_all = 2 * (N + 1)
K, M, G = (np.zeros((n_all, n_all)) for _ in range(3))
for e in range(N):
    d = slice(2 * e, 2 * e + 4)
    K[d, d] += k
    M[d, d] += m
    G[d, d] += g
free = np.arange(2, n_all - 2)  # both ends clamped
K, M, G = (X[np.ix_(free, free)] for X in (K, M, G))

out = pathlib.Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
scipy.io.mmwrite(
    out / "M.mtx", scipy.sparse.coo_matrix(np.tril(M)), symmetry="symmetric"
)
scipy.io.mmwrite(
    out / "K.mtx", scipy.sparse.coo_matrix(np.tril(K)), symmetry="symmetric"
)
# f_i += c G_ij G_kl q_j q_k q_l for every pair of non-zeros of G
c = E * A / (2 * L)
rows, cols = np.nonzero(G)
with open(out / "f3.coo", "w") as f:
    f.write("% Woinowsky-Krieger stretching E A / (2 L) (q^T G q) G q\n")
    for i, j in zip(rows, cols):
        f.writelines(
            f"{i + 1} {j + 1} {p + 1} {q + 1} {float(c * G[i, j] * G[p, q])!r}\n"
            for p, q in zip(rows, cols)
        )
mid = 2 * (N // 2) - 2  # transverse dof of the middle node among the free dofs
load = np.zeros((len(free), 1))
load[mid] = 1.0
scipy.io.mmwrite(out / "fext.mtx", load)
(out / "outputs.csv").write_text(f"name,dof\nw_mid,{mid + 1}\n")
