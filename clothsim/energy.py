"""Energies, the implicit Euler objective g(x), its gradient and Hessian (vectorized).

Liu et al. 2013, Section 3–4. With x, y as (n, 3) arrays and p_i = x_{a_i} − x_{b_i}:

    E(x)    = Σ_i ½ k_i (|p_i| − r_i)²  +  Σ_anchors ½ k (|x_v − q_v|)²  −  Σ_v x_v · f_v
    g(x)    = ½ (x − y)ᵀ M (x − y) + h² E(x)                                   (Eq. 4)
    ĝ(x, d) = ½ (x − y)ᵀ M (x − y) + h² [Σ_i ½ k_i |p_i − d_i|² + anchors − xᵀ f]

Because (|p| − r)² = min_{|d| = r} |p − d|², g(x) = min_{d ∈ U} ĝ(x, d): the local step
minimizes ĝ over d, the global step over x, and neither can increase it. ĝ expands to
½ xᵀ(M + h²L)x − h² xᵀ J d − xᵀ(M y + h² f) + const, the paper's Eq. 9.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .model import Model


def spring_vectors(model: Model, x: np.ndarray) -> np.ndarray:
    """Spring vectors p_i = x_{a_i} − x_{b_i}.

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]) and masses.
    x : ndarray, shape (n, 3)
        Positions [m].

    Returns
    -------
    ndarray, shape (s, 3)
        p_i for every spring [m].
    """
    a, b = model.springs.spring_vertices.T
    return x[a] - x[b]


def spring_lengths(model: Model, x: np.ndarray) -> np.ndarray:
    """Spring lengths |p_i|.

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]) and masses.
    x : ndarray, shape (n, 3)
        Positions [m].

    Returns
    -------
    ndarray, shape (s,)
        Current lengths [m].
    """
    return np.linalg.norm(spring_vectors(model, x), axis=1)


def spring_strain(model: Model, x: np.ndarray) -> np.ndarray:
    """Spring strains ε_i = |p_i| / r_i − 1.

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]) and masses.
    x : ndarray, shape (n, 3)
        Positions [m].

    Returns
    -------
    ndarray, shape (s,)
        Strain (dimensionless; positive when stretched, 0 where r_i = 0).
    """
    r = model.springs.spring_rest_length
    length = spring_lengths(model, x)
    return np.divide(length, r, out=np.ones_like(length), where=r > 0) - 1.0


def spring_energy(model: Model, x: np.ndarray) -> float:
    """Spring part of the potential energy, E_s(x) = Σ_i ½ k_i (|p_i| − r_i)².

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]) and masses.
    x : ndarray, shape (n, 3)
        Positions [m].

    Returns
    -------
    float
        E_s(x) [J].
    """
    k, r = model.springs.spring_stiffness, model.springs.spring_rest_length
    return float(0.5 * np.sum(k * (spring_lengths(model, x) - r) ** 2))


def spring_gradient(model: Model, x: np.ndarray) -> np.ndarray:
    """Gradient of :func:`spring_energy`: ∇E_s(x) = Σ_i A_i ⊗ k_i (1 − r_i/|p_i|) p_i.

    Each spring adds k_i (1 − r_i/|p_i|) p_i at a_i and subtracts it at b_i; a spring of
    zero length contributes 0 (a subgradient). Equals L x − J d(x) with the local step's
    d(x): the 3n form of the paper.

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]) and masses.
    x : ndarray, shape (n, 3)
        Positions [m].

    Returns
    -------
    ndarray, shape (n, 3)
        ∇E_s(x) [N], i.e. minus the spring forces.
    """
    p = spring_vectors(model, x)
    length = np.linalg.norm(p, axis=1)
    k, r = model.springs.spring_stiffness, model.springs.spring_rest_length
    # k (1 − r/l) p, with the limit 0·p where l = 0 (any direction is a subgradient)
    coef = np.where(length > 0, k * (1.0 - r / np.where(length > 0, length, 1.0)), 0.0)
    f = coef[:, None] * p
    return _scatter(model, f)


def _scatter(model: Model, per_spring: np.ndarray) -> np.ndarray:
    """Σ_i A_i ⊗ v_i: +v_i at a_i, −v_i at b_i, shape (n, 3)."""
    n = model.vertex_count
    a, b = model.springs.spring_vertices.T
    out = np.zeros((n, 3))
    for c in range(3):
        out[:, c] = (np.bincount(a, per_spring[:, c], minlength=n)
                     - np.bincount(b, per_spring[:, c], minlength=n))
    return out


def spring_hessian_blocks(model: Model, x: np.ndarray, *, definite: bool = True) -> np.ndarray:
    """Each spring's 3 × 3 Hessian block H_i of :func:`spring_energy` (see
    :func:`spring_hessian`, which places ±H_i; :class:`clothsim.solvers.hessian.FreeHessian`
    does too, in its fixed pattern).

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]).
    x : ndarray, shape (n, 3)
        Positions [m].
    definite : bool, default True
        Clamp compressed springs' transverse factor 1 − r/l at 0.

    Returns
    -------
    ndarray, shape (s, 3, 3)
        H_i = k_i [u uᵀ + (1 − r_i/l_i)(I − u uᵀ)] [N/m]; k_i I where l_i = 0.
    """
    a, b = model.springs.spring_vertices.T
    k, r = model.springs.spring_stiffness, model.springs.spring_rest_length
    p = x[a] - x[b]
    length = np.sqrt(np.einsum("ij,ij->i", p, p))
    safe = np.where(length > 0, length, 1.0)
    u = p / safe[:, None]
    c = np.where(length > 0, 1.0 - r / safe, 1.0)
    if definite:
        c = np.maximum(c, 0.0)
    uu = u[:, :, None] * u[:, None, :]
    H = k[:, None, None] * (uu + c[:, None, None] * (np.eye(3)[None] - uu))
    H[length == 0] = k[length == 0, None, None] * np.eye(3)   # r/l undefined: use k I
    return H


def spring_hessian(model: Model, x: np.ndarray, *, definite: bool = True) -> sp.csr_matrix:
    """Hessian of :func:`spring_energy`, shape (3n, 3n), interleaved layout.

    Spring i contributes ±H_i to blocks (a,a), (b,b), −H_i to (a,b), (b,a), with
    H_i = k_i [u uᵀ + (1 − r_i/l_i)(I − u uᵀ)], u = p_i / l_i. With ``definite=True`` the
    factor (1 − r/l) is clamped at 0 for compressed springs (l < r), which makes every H_i
    positive semidefinite (the usual fix; Choi and Ko 2002).

    Parameters
    ----------
    model : Model
        Springs (a_i, b_i, k_i [N/m], r_i [m]) and masses.
    x : ndarray, shape (n, 3)
        Positions [m].
    definite : bool, default True
        Clamp compressed springs' transverse stiffness at 0 (positive semidefinite).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (3n, 3n)
        ∇²E_s(x) [N/m]; row 3 i + c is coordinate c of vertex i.
    """
    n = model.vertex_count
    a, b = model.springs.spring_vertices.T
    H = spring_hessian_blocks(model, x, definite=definite)
    ri, ci = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    blocks = [(a, a, H), (b, b, H), (a, b, -H), (b, a, -H)]
    rows = np.concatenate([(3 * i[:, None, None] + ri).ravel() for i, _, _ in blocks])
    cols = np.concatenate([(3 * j[:, None, None] + ci).ravel() for _, j, _ in blocks])
    vals = np.concatenate([v.ravel() for _, _, v in blocks])
    return sp.coo_matrix((vals, (rows, cols)), shape=(3 * n, 3 * n)).tocsr()


def kinetic_energy(model: Model, v: np.ndarray) -> float:
    """Kinetic energy ½ Σ_i m_i |v_i|² = ½ vᵀ M v.

    Parameters
    ----------
    model : Model
        Supplies the masses m_i [kg].
    v : ndarray, shape (n, 3)
        Velocities [m/s].

    Returns
    -------
    float
        Kinetic energy [J].
    """
    return float(0.5 * np.sum(model.vertex_mass[:, None] * v * v))


def gravity_energy(model: Model, x: np.ndarray, acceleration) -> float:
    """Gravitational potential energy −Σ_i m_i g · x_i of a uniform field g.

    Parameters
    ----------
    model : Model
        Supplies the masses m_i [kg].
    x : ndarray, shape (n, 3)
        Positions [m].
    acceleration : array_like, shape (3,)
        Gravitational acceleration g [m/s²], e.g. (0, −9.81, 0).

    Returns
    -------
    float
        Potential energy [J] (zero at the origin).
    """
    g = np.asarray(acceleration, dtype=np.float64)
    return float(-np.sum(model.vertex_mass * (x @ g)))
