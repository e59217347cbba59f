"""The held global step in tangent coordinates: a small system that decouples on axis faces.

The held global step (:mod:`.held`) minimizes ĝ over displacements u = x − y − z whose
held vertices move only in their contact planes (pins not at all). Write such a u with an
orthonormal basis T of those directions, u = T w: each free vertex contributes one column
per direction it may move in,

- e_x, e_y, e_z for a vertex not held (three columns),
- the axes its planes leave free for a vertex held on axis-aligned planes (a box face, the
  floor: two columns, or one on an edge),
- an orthonormal basis of its tangent plane otherwise (a sphere: two columns),
- nothing for a vertex held in all three directions (static friction) or on three planes.

The step is then (Tᵀ A T) w = Tᵀ r with A = (M_s + h² L_s) ⊗ I3, the same constrained
minimum as (P A P + α D) u = P r over the free degrees of freedom (T Tᵀ = P; the α D
rows only pin the constrained components at 0), and the entry of Tᵀ A T for columns t_i
of vertex v and t_j of vertex w is a_vw (t_i · t_j). Two axis columns of different
coordinates are orthogonal, so the system couples x, y and z only through vertices held
on oblique planes: on a box it is three principal submatrices of M_s + h² L_s (one per
coordinate, the vertices held in that coordinate removed), on a sphere the coupling is
confined to the sliding vertices. CHOLMOD's ordering finds that structure, and the factor
has about the nonzeros of three scalar factors instead of the nine times as many of
P A P + α D, whose pattern is that of (M_s + h² L_s) ⊗ ones(3, 3).

benchmarks/held_factor.py measures both systems (assembly with factorization, one solve)
on one frame of the built-in obstacle scenes, and whole runs against post-solve mode
(docs/data/held-factor.md, shown in docs/math.md).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

#: An entry of a held vertex's constraint block Σ b bᵀ within this of 0 or 1, off the
#: diagonal within this of 0, counts as axis-aligned (its free directions are exact axes).
AXIS_TOLERANCE = 1e-14


def vertex_directions(n: int, free: np.ndarray,
                      basis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each free vertex's orthonormal directions of motion (the columns of T), by slot.

    Parameters
    ----------
    n : int
        Vertex count.
    free : ndarray, shape (f,), int
        The free vertices (not pinned), increasing.
    basis : list
        :func:`clothsim.contacts.contact_basis` of the held contacts.

    Returns
    -------
    dof : ndarray, shape (n, 3), int
        dof[v, s] is the index of vertex v's s-th column of T, −1 where it has none (pinned
        vertices, constrained directions). Columns are numbered vertex by vertex.
    vectors : ndarray, shape (n, 3, 3)
        vectors[v, s] is that column's unit direction (zero where dof is −1). Slot s of a
        vertex not held or held on axis-aligned planes is the axis e_s.
    oblique : ndarray, shape (o,), int
        The held vertices whose columns are not axes (held on an oblique plane), increasing.
    """
    D = np.zeros((n, 3, 3))
    for v, b in basis:
        D[v] += b[:, :, None] * b[:, None, :]
    vectors = np.zeros((n, 3, 3))
    present = np.zeros((n, 3), bool)
    vectors[free] = np.eye(3)
    present[free] = True
    held = np.zeros(n, bool)
    held[free] = np.abs(D[free]).max(axis=(1, 2)) > 0
    diag = np.diagonal(D, axis1=1, axis2=2)
    axis = (held & (np.abs(D - diag[:, :, None] * np.eye(3)).max(axis=(1, 2)) <= AXIS_TOLERANCE)
            & (np.minimum(np.abs(diag), np.abs(diag - 1)).max(axis=1) <= AXIS_TOLERANCE))
    present[axis] = diag[axis] < 0.5
    oblique = np.flatnonzero(held & ~axis)
    if len(oblique):   # eigenvectors of P_v = I − D_v with eigenvalue 1 (ascending order)
        values, vecs = np.linalg.eigh(np.eye(3) - D[oblique])
        keep = values > 0.5
        vectors[oblique] = np.swapaxes(vecs, 1, 2) * keep[:, :, None]
        present[oblique] = keep
    vectors[~present] = 0.0
    dof = np.full((n, 3), -1, np.int64)
    dof[present] = np.arange(int(present.sum()))
    return dof, vectors, oblique


def tangent_matrix(As: sp.csr_matrix, dof: np.ndarray, vectors: np.ndarray,
                   oblique: np.ndarray) -> sp.csc_matrix:
    """Tᵀ ((M_s + h² L_s) ⊗ I3) T over the columns of :func:`vertex_directions`.

    Parameters
    ----------
    As : csr_matrix, shape (n, n)
        M_s + h² L_s (with the anchors) [kg].
    dof, vectors, oblique : ndarray
        :func:`vertex_directions`.

    Returns
    -------
    csc_matrix, shape (m, m)
        Symmetric positive definite. Between two vertices whose columns are axes only the
        entries of equal axes are stored (the others are exactly zero); a vertex on an
        oblique plane stores its full blocks a_vw Tᵥᵀ T_w.
    """
    m = int(dof.max()) + 1 if dof.size else 0
    coo = As.tocoo()
    r, c, a = coo.row, coo.col, coo.data
    is_oblique = np.zeros(len(dof), bool)
    is_oblique[oblique] = True
    full = is_oblique[r] | is_oblique[c]
    # axes against axes: slot s of one vertex meets slot s of the other, value a_vw
    ra, ca, aa = r[~full], c[~full], a[~full]
    rows, cols = dof[ra].T, dof[ca].T                         # (3, e): slot by slot
    stored = (rows >= 0) & (cols >= 0)
    vals = [np.broadcast_to(aa, rows.shape)[stored]]
    rows, cols = [rows[stored]], [cols[stored]]
    if full.any():   # a vertex on an oblique plane: the 3 x 3 Gram block of the columns
        rf, cf = r[full], c[full]
        gram = np.einsum("esi,eti->est", vectors[rf], vectors[cf]) * a[full][:, None, None]
        rg = np.broadcast_to(dof[rf][:, :, None], gram.shape)
        cg = np.broadcast_to(dof[cf][:, None, :], gram.shape)
        stored = (rg >= 0) & (cg >= 0)
        vals.append(gram[stored])
        rows.append(rg[stored])
        cols.append(cg[stored])
    return sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(m, m))


__all__ = ["AXIS_TOLERANCE", "tangent_matrix", "vertex_directions"]
