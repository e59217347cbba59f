"""Loop-based reference versions of the paper's matrices, for teaching and for tests.

One spring at a time, written literally as the paper's sums (Liu et al. 2013, Eq. 5–6):

    L = (Σ_i k_i A_i A_iᵀ) ⊗ I3,     J = (Σ_i k_i A_i S_iᵀ) ⊗ I3,     M = diag(m) ⊗ I3.

These are dense and O(s n²): use them on small models only. The fast, vectorized versions
in :mod:`clothsim.matrices` must agree with them (tests/test_matrices.py).
"""

from __future__ import annotations

import numpy as np

from .model import Model


def incidence_vector(n: int, a: int, b: int) -> np.ndarray:
    """A_i ∈ R^n: +1 at a, −1 at b."""
    A = np.zeros(n)
    A[a] = 1.0
    A[b] = -1.0
    return A


def indicator_vector(s: int, i: int) -> np.ndarray:
    """S_i ∈ R^s: 1 at i."""
    S = np.zeros(s)
    S[i] = 1.0
    return S


def mass_matrix(model: Model) -> np.ndarray:
    """M = diag(m_1 … m_n) ⊗ I3, dense (3n, 3n)."""
    return np.kron(np.diag(model.vertex_mass), np.eye(3))


def stiffness_matrix(model: Model) -> np.ndarray:
    """L = (Σ_i k_i A_i A_iᵀ) ⊗ I3, dense (3n, 3n)."""
    n = model.vertex_count
    Ls = np.zeros((n, n))
    for (a, b), k in zip(model.springs.spring_vertices, model.springs.spring_stiffness):
        A = incidence_vector(n, a, b)
        Ls += k * np.outer(A, A)
    return np.kron(Ls, np.eye(3))


def spring_matrix(model: Model) -> np.ndarray:
    """J = (Σ_i k_i A_i S_iᵀ) ⊗ I3, dense (3n, 3s)."""
    n, s = model.vertex_count, model.spring_count
    Js = np.zeros((n, s))
    for i, ((a, b), k) in enumerate(zip(model.springs.spring_vertices,
                                        model.springs.spring_stiffness)):
        Js += k * np.outer(incidence_vector(n, a, b), indicator_vector(s, i))
    return np.kron(Js, np.eye(3))


def local_step(model: Model, x: np.ndarray) -> np.ndarray:
    """d_i = r_i (x_a − x_b) / |x_a − x_b| one spring at a time; x, d as (n, 3), (s, 3)."""
    d = np.zeros((model.spring_count, 3))
    for i, ((a, b), r) in enumerate(zip(model.springs.spring_vertices,
                                        model.springs.spring_rest_length)):
        p = x[a] - x[b]
        length = np.sqrt(p @ p)
        if length > 0:
            d[i] = r * p / length
    return d


def spring_energy(model: Model, x: np.ndarray) -> float:
    """E_springs(x) = Σ_i ½ k_i (|x_a − x_b| − r_i)², one spring at a time [J]."""
    e = 0.0
    for (a, b), k, r in zip(model.springs.spring_vertices, model.springs.spring_stiffness,
                            model.springs.spring_rest_length):
        e += 0.5 * k * (np.linalg.norm(x[a] - x[b]) - r) ** 2
    return e
