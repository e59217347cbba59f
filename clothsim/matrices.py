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
    """A ⊗ I3: the 3-D (interleaved per vertex) form of a scalar matrix."""
    return sp.kron(A, I3, format="csr")


def mass_matrix(model: Model, *, expand: bool = True) -> sp.csr_matrix:
    """M = diag(m) ⊗ I3, shape (3n, 3n) [kg]; with ``expand=False`` M_s, shape (n, n)."""
    Ms = sp.diags(model.vertex_mass, format="csr")
    return expand3(Ms) if expand else Ms


def stiffness_matrix(model: Model, *, expand: bool = True) -> sp.csr_matrix:
    """L = (Σ_i k_i A_i A_iᵀ) ⊗ I3, shape (3n, 3n) [N/m]; ``expand=False``: L_s (n, n).

    Each spring adds k to (a, a) and (b, b) and −k to (a, b) and (b, a).
    """
    n = model.vertex_count
    a, b = model.springs.spring_vertices.T
    k = model.springs.spring_stiffness
    rows = np.concatenate([a, b, a, b])
    cols = np.concatenate([a, b, b, a])
    vals = np.concatenate([k, k, -k, -k])
    Ls = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
    return expand3(Ls) if expand else Ls


def spring_matrix(model: Model, *, expand: bool = True) -> sp.csr_matrix:
    """J = (Σ_i k_i A_i S_iᵀ) ⊗ I3, shape (3n, 3s) [N/m]; ``expand=False``: J_s (n, s).

    Column i holds +k_i at row a_i and −k_i at row b_i.
    """
    n, s = model.vertex_count, model.spring_count
    a, b = model.springs.spring_vertices.T
    k = model.springs.spring_stiffness
    cols = np.arange(s)
    Js = sp.coo_matrix(
        (np.concatenate([k, -k]), (np.concatenate([a, b]), np.concatenate([cols, cols]))),
        shape=(n, s),
    ).tocsr()
    return expand3(Js) if expand else Js


def system_matrix(model: Model, h: float, *, expand: bool = False,
                  anchor_vertices=None, anchor_stiffness=None) -> sp.csc_matrix:
    """The global step's matrix M + h² L (plus penalty-pin stiffness on L's diagonal).

    Parameters
    ----------
    h : float
        Time step [s].
    expand : bool
        False (default): the n × n matrix M_s + h² L_s the solver factors. True: 3n × 3n.
    anchor_vertices, anchor_stiffness : array_like, optional
        Penalty pins: a zero-rest-length spring of stiffness k from vertex v to a fixed
        point adds k to L_s[v, v].
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
