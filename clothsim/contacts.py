"""Held contacts: vertices kept on contact planes during a step (the arithmetic).

An obstacle in the default contact mode (``"hold"``, :mod:`clothsim.effects.obstacles`)
hands the next step the vertices it pushes: vertex v_c stays on the plane
n_c · x = o_c (n_c a unit outward normal, o_c [m]) and slides freely in it. The step's
problem (:class:`~clothsim.problem.StepProblem`) carries these planes; its feasible set is
affine, so

- :func:`hold` moves points onto it (the initial guess; explicit methods);
- :func:`tangential` removes the normal part of a gradient at held vertices: the gradient
  on the feasible set, zero at the step's solution;
- :func:`contact_basis` gives each held vertex an orthonormal basis of its constrained
  directions (a vertex on a box's side and on the floor has two).

A vertex held by two planes is moved onto both in turn: exact when their normals are
orthogonal (axis-aligned faces), the only way two obstacles' faces meet in the built-in
scenes.
"""

from __future__ import annotations

import numpy as np


def occurrences(v: np.ndarray) -> list[np.ndarray]:
    """Rows of ``v`` grouped by rank: the first occurrence of each value, the second, …

    Parameters
    ----------
    v : ndarray, shape (c,), int

    Returns
    -------
    list of ndarray of int
        Row indices into ``v``; within one group every value appears once.
    """
    if not len(v):
        return []
    order = np.argsort(v, kind="stable")
    sv = v[order]
    start = np.r_[0, np.flatnonzero(np.diff(sv)) + 1]
    rank = np.arange(len(v)) - np.repeat(start, np.diff(np.r_[start, len(v)]))
    return [order[rank == r] for r in range(int(rank.max()) + 1)]


def hold(x: np.ndarray, vertices: np.ndarray, normals: np.ndarray,
         offsets: np.ndarray) -> np.ndarray:
    """Move each listed vertex onto its plane, in place: x_v += (o − n·x_v) n.

    Parameters
    ----------
    x : ndarray, shape (n, 3)
        Positions [m], changed in place.
    vertices : ndarray, shape (c,), int
    normals : ndarray, shape (c, 3)
        Unit normals.
    offsets : ndarray, shape (c,)
        Plane offsets o [m].

    Returns
    -------
    x : ndarray, shape (n, 3), the same array
    """
    for rows in occurrences(vertices):
        v, n = vertices[rows], normals[rows]
        gap = offsets[rows] - np.einsum("ij,ij->i", x[v], n)
        x[v] += gap[:, None] * n
    return x


def contact_basis(vertices: np.ndarray, normals: np.ndarray) -> list[tuple[np.ndarray,
                                                                           np.ndarray]]:
    """Orthonormal constrained directions of the held vertices, one layer per rank.

    Parameters
    ----------
    vertices : ndarray, shape (c,), int
    normals : ndarray, shape (c, 3), unit normals

    Returns
    -------
    list of (ndarray (u,) of int, ndarray (u, 3))
        Layer r holds the r-th normal of each vertex that has one (vertices sorted),
        orthogonalized against that vertex's directions in earlier layers (Gram–Schmidt);
        a normal parallel to an earlier one is dropped.
    """
    layers: list[tuple[np.ndarray, np.ndarray]] = []
    for rows in occurrences(vertices):
        verts, n = vertices[rows], normals[rows].astype(np.float64)
        for earlier_v, earlier in layers:
            pos = np.minimum(np.searchsorted(earlier_v, verts), len(earlier_v) - 1)
            hit = earlier_v[pos] == verts
            e = earlier[pos[hit]]
            n[hit] -= np.einsum("ij,ij->i", n[hit], e)[:, None] * e
        length = np.linalg.norm(n, axis=1)
        keep = length > 1e-6
        if not np.any(keep):     # every normal parallel to an earlier one: no new layer
            continue
        order = np.argsort(verts[keep])
        layers.append((verts[keep][order], (n[keep] / length[keep, None])[order]))
    return layers


def tangential(g: np.ndarray, basis) -> np.ndarray:
    """A copy of ``g`` without its components along the held directions.

    Parameters
    ----------
    g : ndarray, shape (n, 3)
    basis : list
        :func:`contact_basis`.

    Returns
    -------
    ndarray, shape (n, 3)
    """
    g = np.array(g, dtype=np.float64)
    for v, b in basis:
        g[v] -= np.einsum("ij,ij->i", g[v], b)[:, None] * b
    return g


def projector(n: int, basis):
    """The block-diagonal projector P = I − Σ b bᵀ onto the feasible directions, (3n, 3n).

    Parameters
    ----------
    n : int
        Vertex count.
    basis : list
        :func:`contact_basis`.

    Returns
    -------
    (P, D) : csr_matrix, csr_matrix
        P as above, and D = Σ b bᵀ (the constrained directions), both interleaved
        (x, y, z of vertex 0, then vertex 1, …).
    """
    import scipy.sparse as sp

    rows, cols, vals = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)], [np.zeros(0)]
    for v, b in basis:
        r = np.broadcast_to((3 * v)[:, None, None] + np.arange(3)[None, :, None], (len(v), 3, 3))
        c = np.broadcast_to((3 * v)[:, None, None] + np.arange(3)[None, None, :], (len(v), 3, 3))
        rows.append(r.ravel())
        cols.append(c.ravel())
        vals.append((b[:, :, None] * b[:, None, :]).ravel())
    D = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(3 * n, 3 * n))
    return sp.identity(3 * n, format="csr") - D, D





class ContactSet:
    """The contacts one obstacle holds during a step (what its ``hold_contacts`` returns).

    Parameters
    ----------
    vertices : ndarray, shape (c,), int
    normals : ndarray, shape (c, 3)
        Unit outward normals of the contact planes.
    offsets : ndarray, shape (c,)
        Plane offsets o = n · x [m].

    Attributes
    ----------
    forces : ndarray, shape (c,) or None
        The normal force [N] the plane exerted on each vertex in the step just solved
        (n · ∇g / h² at the answer, before any correction; > 0 pushes), set by the
        simulation after the solve; None before.
    noise : float
        The root mean square of the solve's unbalanced force per vertex [N] (the part of
        ∇g / h² the iterations left), set with ``forces``: the uncertainty of each force.
    """

    def __init__(self, vertices=None, normals=None, offsets=None):
        self.vertices = np.zeros(0, np.int64) if vertices is None else np.asarray(vertices,
                                                                                  np.int64)
        self.normals = np.zeros((0, 3)) if normals is None else np.asarray(normals, np.float64)
        self.offsets = np.zeros(0) if offsets is None else np.asarray(offsets, np.float64)
        self.forces: np.ndarray | None = None
        self.noise = 0.0

    def __len__(self) -> int:
        return len(self.vertices)

    @staticmethod
    def merge(parts: list[ContactSet]) -> ContactSet:
        """One set holding every contact of ``parts``, in order.

        Parameters
        ----------
        parts : list of ContactSet

        Returns
        -------
        ContactSet
        """
        if len(parts) == 1:
            return parts[0]
        cat = np.concatenate
        return ContactSet(cat([np.zeros(0, np.int64)] + [p.vertices for p in parts]),
                          cat([np.zeros((0, 3))] + [p.normals for p in parts]),
                          cat([np.zeros(0)] + [p.offsets for p in parts]))
__all__ = ["ContactSet", "occurrences", "hold", "contact_basis", "tangential", "projector"]
