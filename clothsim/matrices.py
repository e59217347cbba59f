"""The paper's matrices M, L and J (Liu et al. 2013, Section 4).

Degree-of-freedom layout (stated once, used everywhere): a 3n vector stacks positions per
vertex, x = (x0 y0 z0 x1 y1 z1 …), so vertex i, coordinate c lives at index 3 i + c. The
3s vector d stacks the spring directions the same way. Because

    M = M_s ⊗ I3,    L = L_s ⊗ I3,    J = J_s ⊗ I3,

every 3n × 3n system splits into one n × n system with three right-hand sides (the x, y, z
columns of an (n, 3) array). The solvers use the n × n ("scalar") forms; the 3n forms
(``expand=True``) are the paper's and are kept for validation and export.

=========  ====================================  ===========================
symbol     definition                            function
=========  ====================================  ===========================
M          diag(m_1 … m_n) ⊗ I3                   :func:`mass_matrix`
L          (Σ_i k_i A_i A_iᵀ) ⊗ I3                :func:`stiffness_matrix`
J          (Σ_i k_i A_i S_iᵀ) ⊗ I3                :func:`spring_matrix`
M + h² L   the global step's system matrix        :func:`system_matrix`
=========  ====================================  ===========================

A_i ∈ R^n is spring i's incidence vector (+1 at a_i, −1 at b_i), S_i ∈ R^s its indicator.
Assembly is vectorized: triplet arrays are filled at once and converted to CSR once, scipy
summing the duplicates. :mod:`clothsim.reference` builds the same matrices one spring at a
time, literally as the sums above.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .model import Model

I3 = sp.identity(3, format="csr")


def expand3(A: sp.spmatrix) -> sp.csr_matrix:
    """A ⊗ I3: the 3-D (interleaved per vertex) form of a scalar matrix.

    Parameters
    ----------
    A : scipy.sparse matrix, shape (p, q)
        A scalar matrix (one row per vertex, one column per vertex or spring).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (3p, 3q)
        Entry (3 i + c, 3 j + c) is A[i, j] for c = 0, 1, 2; same unit as A.
    """
    return sp.kron(A, I3, format="csr")


def mass_matrix(model: Model, *, expand: bool = True) -> sp.csr_matrix:
    """The mass matrix M = diag(m_1 … m_n) ⊗ I3.

    Parameters
    ----------
    model : Model
        Supplies the vertex masses m_i [kg].
    expand : bool, default True
        True: the paper's 3n form (interleaved layout). False: the scalar n-row form.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (3n, 3n), or (n, n) with ``expand=False``
        M, or M_s = diag(m) [kg].
    """
    Ms = sp.diags(model.vertex_mass, format="csr")
    return expand3(Ms) if expand else Ms


def stiffness_matrix(model: Model, *, expand: bool = True) -> sp.csr_matrix:
    """The stiffness (graph Laplacian) matrix L = (Σ_i k_i A_i A_iᵀ) ⊗ I3.

    Each spring adds k to (a, a) and (b, b) and −k to (a, b) and (b, a). Penalty pins are
    not included (see :func:`system_matrix`).

    Parameters
    ----------
    model : Model
        Supplies the springs (a_i, b_i, k_i [N/m]).
    expand : bool, default True
        True: the paper's 3n form (interleaved layout). False: the scalar n-row form.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (3n, 3n), or (n, n) with ``expand=False``
        L, or L_s = Σ_i k_i A_i A_iᵀ [N/m].
    """
    n = model.vertex_count
    a, b = model.springs.spring_vertices.T
    k = model.springs.spring_stiffness
    # the diagonal summed first (each vertex's springs as end a, then as end b, in spring
    # order): 2s + n triplets for scipy to sort instead of 4s, 3x faster at 513²
    diag = np.bincount(np.concatenate([a, b]), np.concatenate([k, k]), n)
    v = np.arange(n)
    Ls = sp.coo_matrix((np.concatenate([-k, -k, diag]),
                        (np.concatenate([a, b, v]), np.concatenate([b, a, v]))),
                       shape=(n, n)).tocsr()
    return expand3(Ls) if expand else Ls


def spring_matrix(model: Model, *, expand: bool = True) -> sp.csr_matrix:
    """The spring matrix J = (Σ_i k_i A_i S_iᵀ) ⊗ I3.

    Column i holds +k_i at row a_i and −k_i at row b_i, so J d is the springs' pull
    toward the directions d of the local step (the h² J d term of the global step).

    Parameters
    ----------
    model : Model
        Supplies the springs (a_i, b_i, k_i [N/m]).
    expand : bool, default True
        True: the paper's 3n form (interleaved layout). False: the scalar n-row form.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (3n, 3s), or (n, s) with ``expand=False``
        J, or J_s = Σ_i k_i A_i S_iᵀ [N/m].
    """
    n, s = model.vertex_count, model.spring_count
    a, b = model.springs.spring_vertices.T
    k = model.springs.spring_stiffness
    # column i is (a_i: +k_i, b_i: −k_i): built as CSC directly (no triplets to sort), then
    # converted (rows come out with sorted column indices, as from the triplets)
    Js = sp.csc_matrix((np.stack([k, -k], axis=1).ravel(), np.stack([a, b], axis=1).ravel(),
                        np.arange(0, 2 * s + 1, 2)), shape=(n, s)).tocsr()
    return expand3(Js) if expand else Js


def system_matrix(model: Model, h: float, *, expand: bool = False,
                  anchor_vertices=None, anchor_stiffness=None) -> sp.csc_matrix:
    """The global step's matrix M + h² L (plus penalty-pin stiffness on L's diagonal).

    The global step solves (M + h² L) x = h² J d + M y + h² f_ext; the matrix depends only
    on masses, stiffnesses, topology, pins and h, so it is factored once.

    Parameters
    ----------
    model : Model
        Masses [kg] and springs.
    h : float
        Time step [s].
    expand : bool
        False (default): the n × n matrix M_s + h² L_s the solver factors. True: 3n × 3n.
    anchor_vertices, anchor_stiffness : array_like, optional
        Penalty pins: a zero-rest-length spring of stiffness k from vertex v to a fixed
        point adds k to L_s[v, v]; vertices (q,), int, and stiffness [N/m], scalar or (q,).

    Returns
    -------
    scipy.sparse.csc_matrix, shape (n, n), or (3n, 3n) with ``expand=True``
        M_s + h² L_s (symmetric positive definite when every mass is positive) [kg].
    """
    A = mass_matrix(model, expand=False) + (h * h) * stiffness_matrix(model, expand=False)
    if anchor_vertices is not None and len(anchor_vertices):
        n = model.vertex_count
        k = np.broadcast_to(np.asarray(anchor_stiffness, dtype=np.float64),
                            (len(anchor_vertices),))
        A = A + (h * h) * sp.coo_matrix((k, (anchor_vertices, anchor_vertices)),
                                        shape=(n, n)).tocsr()
    A = A.tocsc()
    return expand3(A).tocsc() if expand else A
