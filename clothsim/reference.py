"""Loop-based reference versions of the paper's matrices, for teaching and for tests.

One spring at a time, written literally as the paper's sums (Liu et al. 2013, Eq. 5–6):

    L = (Σ_i k_i A_i A_iᵀ) ⊗ I3,     J = (Σ_i k_i A_i S_iᵀ) ⊗ I3,     M = diag(m) ⊗ I3.

It also holds one local/global iteration written literally in the paper's 3n form
(:func:`local_step`, :func:`global_step`, :func:`iteration`) and the spring gradient one
spring at a time (:func:`spring_gradient`).

These are dense and O(s n²): use them on small models only. The fast, vectorized versions
(:mod:`clothsim.matrices`, :class:`clothsim.solvers.LocalGlobalSolver`,
:mod:`clothsim.energy`) must agree with them; the tests check that they do.
"""

from __future__ import annotations

import numpy as np

from .model import Model


def incidence_vector(n: int, a: int, b: int) -> np.ndarray:
    """The spring's incidence vector A_i ∈ R^n: +1 at a, −1 at b (paper, Sec. 3).

    Parameters
    ----------
    n : int
        Number of vertices.
    a, b : int
        The spring's two vertices, in ``range(n)``.

    Returns
    -------
    ndarray, shape (n,)
        A_i (dimensionless).
    """
    A = np.zeros(n)
    A[a] = 1.0
    A[b] = -1.0
    return A


def indicator_vector(s: int, i: int) -> np.ndarray:
    """The spring's indicator vector S_i ∈ R^s: 1 at i, 0 elsewhere (paper, Sec. 3).

    Parameters
    ----------
    s : int
        Number of springs.
    i : int
        The spring's index, in ``range(s)``.

    Returns
    -------
    ndarray, shape (s,)
        S_i (dimensionless).
    """
    S = np.zeros(s)
    S[i] = 1.0
    return S


def mass_matrix(model: Model) -> np.ndarray:
    """The mass matrix M = diag(m_1 … m_n) ⊗ I3, dense.

    Parameters
    ----------
    model : Model
        Its ``vertex_mass``, shape (n,) [kg].

    Returns
    -------
    ndarray, shape (3n, 3n)
        M in the interleaved layout (x0 y0 z0 x1 …) [kg].
    """
    return np.kron(np.diag(model.vertex_mass), np.eye(3))


def stiffness_matrix(model: Model) -> np.ndarray:
    """The stiffness Laplacian L = (Σ_i k_i A_i A_iᵀ) ⊗ I3, one spring at a time, dense.

    Parameters
    ----------
    model : Model
        Its springs' vertices (s, 2) and stiffnesses k_i (s,) [N/m].

    Returns
    -------
    ndarray, shape (3n, 3n)
        L in the interleaved layout [N/m].
    """
    n = model.vertex_count
    Ls = np.zeros((n, n))
    for (a, b), k in zip(model.springs.spring_vertices, model.springs.spring_stiffness):
        A = incidence_vector(n, a, b)
        Ls += k * np.outer(A, A)
    return np.kron(Ls, np.eye(3))


def spring_matrix(model: Model) -> np.ndarray:
    """The spring matrix J = (Σ_i k_i A_i S_iᵀ) ⊗ I3, one spring at a time, dense.

    Parameters
    ----------
    model : Model
        Its springs' vertices (s, 2) and stiffnesses k_i (s,) [N/m].

    Returns
    -------
    ndarray, shape (3n, 3s)
        J in the interleaved layout (rows per vertex, columns per spring) [N/m].
    """
    n, s = model.vertex_count, model.spring_count
    Js = np.zeros((n, s))
    for i, ((a, b), k) in enumerate(zip(model.springs.spring_vertices,
                                        model.springs.spring_stiffness)):
        Js += k * np.outer(incidence_vector(n, a, b), indicator_vector(s, i))
    return np.kron(Js, np.eye(3))


def local_step(model: Model, x: np.ndarray) -> np.ndarray:
    """The local step d_i = r_i p_i / |p_i|, p_i = x_{a_i} − x_{b_i}, one spring at a time.

    Minimizes |p_i − d_i|² over |d_i| = r_i (paper, Sec. 4). Where the two ends coincide
    (|p_i| = 0) any direction is optimal; this literal version leaves d_i = 0 there.

    Parameters
    ----------
    model : Model
        Its springs' vertices (s, 2) and rest lengths r_i (s,) [m].
    x : ndarray, shape (n, 3)
        Vertex positions [m].

    Returns
    -------
    ndarray, shape (s, 3)
        The spring vectors d [m].
    """
    d = np.zeros((model.spring_count, 3))
    for i, ((a, b), r) in enumerate(zip(model.springs.spring_vertices,
                                        model.springs.spring_rest_length)):
        p = x[a] - x[b]
        length = np.sqrt(p @ p)
        if length > 0:
            d[i] = r * p / length
    return d


def spring_energy(model: Model, x: np.ndarray) -> float:
    """The springs' energy E_springs(x) = Σ_i ½ k_i (|x_{a_i} − x_{b_i}| − r_i)², literally.

    Parameters
    ----------
    model : Model
        Its springs' vertices, stiffnesses [N/m] and rest lengths [m].
    x : ndarray, shape (n, 3)
        Vertex positions [m].

    Returns
    -------
    float
        The energy [J].
    """
    e = 0.0
    for (a, b), k, r in zip(model.springs.spring_vertices, model.springs.spring_stiffness,
                            model.springs.spring_rest_length):
        e += 0.5 * k * (np.linalg.norm(x[a] - x[b]) - r) ** 2
    return e


def spring_gradient(model: Model, x: np.ndarray) -> np.ndarray:
    """∇E_springs(x) one spring at a time, shape (n, 3) [N].

    Spring i adds k_i (|p_i| − r_i) p_i / |p_i| to vertex a_i and subtracts it from b_i,
    p_i = x_{a_i} − x_{b_i} (nothing when the ends coincide).

    Parameters
    ----------
    model : Model
        Its springs' vertices, stiffnesses [N/m] and rest lengths [m].
    x : ndarray, shape (n, 3)
        Vertex positions [m].

    Returns
    -------
    ndarray, shape (n, 3)
        The gradient ∂E_springs/∂x [N].
    """
    grad = np.zeros((model.vertex_count, 3))
    for (a, b), k, r in zip(model.springs.spring_vertices, model.springs.spring_stiffness,
                            model.springs.spring_rest_length):
        p = x[a] - x[b]
        length = np.sqrt(p @ p)
        if length > 0:
            g = k * (length - r) * p / length
            grad[a] += g
            grad[b] -= g
    return grad


def global_step(model: Model, problem, d: np.ndarray) -> np.ndarray:
    """The global step in the paper's 3n form: (M + h² L) x = h² J d + M y + h² f.

    Dense and literal: the 3n × 3n matrix and the 3n right-hand side in the interleaved
    layout, penalty anchors adding h² k to the diagonal and h² k q to b, exactly pinned
    vertices P moved to the right-hand side (A_FF x_F = b_F − A_FP x_P), then one dense
    solve.

    Parameters
    ----------
    model : Model
        Masses [kg], springs' stiffnesses [N/m], vertices and rest lengths [m].
    problem : clothsim.problem.StepProblem
        The step's h, y, f_ext and pins (read only; not imported here, so that this
        module stays below the solvers in the pipeline).
    d : ndarray, shape (s, 3)
        Spring directions from the local step [m].

    Returns
    -------
    ndarray, shape (n, 3)
        x after the global step [m].
    """
    n, h2 = model.vertex_count, problem.h ** 2
    M = mass_matrix(model)
    A = M + h2 * stiffness_matrix(model)
    b = h2 * spring_matrix(model) @ d.reshape(-1) + M @ problem.y.reshape(-1)
    if problem.f_ext is not None:
        b += h2 * problem.f_ext.reshape(-1)
    for v, q, k in zip(problem.anchor_vertices, problem.anchor_positions,
                       problem.anchor_stiffness):
        for c in range(3):
            A[3 * v + c, 3 * v + c] += h2 * k
            b[3 * v + c] += h2 * k * q[c]
    x = np.zeros(3 * n)
    fixed = np.zeros(3 * n, bool)
    for v, q in zip(problem.fixed_vertices, problem.fixed_positions):
        x[3 * v:3 * v + 3] = q
        fixed[3 * v:3 * v + 3] = True
    free = ~fixed
    rhs = b[free] - A[np.ix_(free, fixed)] @ x[fixed]
    x[free] = np.linalg.solve(A[np.ix_(free, free)], rhs)
    return x.reshape(n, 3)


def iteration(model: Model, problem, x: np.ndarray) -> tuple[np.ndarray,
                                                                           np.ndarray]:
    """One local/global iteration from x: the local step, then the global step.

    d_i = r_i p_i / |p_i| (:func:`local_step`), then (M + h² L) x = h² J d + M y + h² f
    (:func:`global_step`).

    Parameters
    ----------
    model : Model
    problem : clothsim.problem.StepProblem
        The step's h [s], y [m], f_ext [N] and pins.
    x : ndarray, shape (n, 3)
        The current iterate [m].

    Returns
    -------
    x_next : ndarray, shape (n, 3)
        The next iterate [m].
    d : ndarray, shape (s, 3)
        The local step's directions at x [m].
    """
    d = local_step(model, x)
    return global_step(model, problem, d), d
