"""Springs: which vertices they join, how stiff they are, and their rest lengths.

Second stage of the pipeline. Two builders:

grid_springs
    the student report's three families on a :func:`clothsim.mesh.grid`:
    structural (i,j)–(i,j+1), (i,j)–(i+1,j); shear (i,j)–(i+1,j+1), (i+1,j)–(i,j+1);
    bending (i,j)–(i,j+2), (i,j)–(i+2,j).
mesh_springs
    Any triangle mesh: structural springs on every edge (and strand), bending springs
    joining the two vertices opposite each interior edge.

A family whose stiffness is None is not built. Rest lengths come from the initial shape.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError, check_finite, check_positive
from .mesh import Mesh

FAMILIES = ("structural", "shear", "bending")
BENDING_PATTERNS = ("every", "alternate")


@dataclass(frozen=True, eq=False)
class Springs:
    """A set of s springs.

    Attributes
    ----------
    spring_vertices : ndarray, shape (s, 2), int64
        End vertices (a_i, b_i) of each spring; the paper's incidence vector A_i has +1 at
        a_i and −1 at b_i.
    spring_stiffness : ndarray, shape (s,), float64
        k_i [N/m], >= 0.
    spring_rest_length : ndarray, shape (s,), float64
        r_i [m], >= 0.
    spring_family : ndarray, shape (s,), int8
        Index into :data:`FAMILIES`.
    vertex_count : int or None
        Vertices of the mesh the springs were built for (set by the builders below; a
        :class:`~clothsim.model.Model` refuses springs built for a mesh of another size).
    spring_damping : ndarray, shape (s,), float64
        c_i [N·s/m], >= 0 (default 0): damping along the spring, as newton's and warp's
        ``spring_damping`` (see :meth:`implicit_damping`).
    """

    spring_vertices: np.ndarray
    spring_stiffness: np.ndarray
    spring_rest_length: np.ndarray
    spring_family: np.ndarray
    vertex_count: int | None = None
    spring_damping: np.ndarray | None = None

    def __post_init__(self):
        idx = _vertex_pairs(self.spring_vertices)
        s = len(idx)
        k = _per_spring("spring_stiffness",
                        check_positive("spring_stiffness", self.spring_stiffness,
                                       allow_zero=True), s)
        r = _per_spring("spring_rest_length",
                        check_positive("spring_rest_length", self.spring_rest_length,
                                       allow_zero=True), s)
        fam = _per_spring("spring_family", np.asarray(self.spring_family, dtype=np.int8), s)
        c = _per_spring("spring_damping",
                        check_positive("spring_damping", 0.0 if self.spring_damping is None
                                       else self.spring_damping, allow_zero=True), s)
        self_loops = np.flatnonzero(idx[:, 0] == idx[:, 1])
        if len(self_loops):
            raise InputError(f"spring_vertices[{self_loops[0]}]: a spring joins vertex "
                             f"{idx[self_loops[0], 0]} to itself")
        for name, a in (("spring_vertices", idx), ("spring_stiffness", k),
                        ("spring_rest_length", r), ("spring_family", fam),
                        ("spring_damping", c)):
            a.flags.writeable = False
            object.__setattr__(self, name, a)

    @property
    def spring_count(self) -> int:
        return len(self.spring_vertices)

    def family_count(self, family: str) -> int:
        """Number of springs of one family.

        Parameters
        ----------
        family : str
            One of :data:`FAMILIES`.

        Returns
        -------
        int
        """
        return int(np.count_nonzero(self.spring_family == FAMILIES.index(family)))

    def with_stiffness(self, stiffness) -> Springs:
        """A copy with new stiffnesses (same pairs, rest lengths and families).

        Parameters
        ----------
        stiffness : float or array_like, shape (s,)
            New k [N/m], one value or one per spring.

        Returns
        -------
        Springs
        """
        return Springs(self.spring_vertices, stiffness, self.spring_rest_length,
                       self.spring_family, self.vertex_count, self.spring_damping)

    def implicit_damping(self, h: float, positions: np.ndarray) -> Springs:
        """The springs whose energy is this step's springs plus their damping potential.

        A spring of damping c_i contributes to one implicit Euler step the dissipation
        potential D_i(x) = c_i / (2h) (ℓ_i(x) − ℓ_i(x_n))², ℓ_i the spring's length, whose
        force −∇D_i = −(c_i/h)(ℓ_i(x) − ℓ_i(x_n)) d̂_i ≈ −c_i (v_rel · d̂_i) d̂_i is the
        damping force of newton's VBD solver (warp.sim's, taken at the end of the step).
        As a function of ℓ, ½ k (ℓ − r)² + c/(2h) (ℓ − ℓ_n)² is ½ k' (ℓ − r')² plus a
        constant, with k' = k + c/h and r' = (k r + (c/h) ℓ_n) / k': the step minimizes the
        paper's g for springs of stiffness k' and rest length r' (``docs/math.md``).

        Parameters
        ----------
        h : float
            Time step [s].
        positions : ndarray, shape (n, 3)
            x_n, the positions at the start of the step [m].

        Returns
        -------
        Springs
            Stiffness k' [N/m] and rest length r' [m] (no damping); the same object when no
            spring is damped.
        """
        c = self.spring_damping
        if not c.any():
            return self
        sv = self.spring_vertices
        length = np.linalg.norm(positions[sv[:, 0]] - positions[sv[:, 1]], axis=1)
        k = self.spring_stiffness + c / h
        safe = np.where(k > 0, k, 1.0)
        rest = np.where(k > 0, (self.spring_stiffness * self.spring_rest_length
                                + (c / h) * length) / safe, self.spring_rest_length)
        return Springs(sv, k, rest, self.spring_family, self.vertex_count)

    @staticmethod
    def concatenate(parts: list[Springs]) -> Springs:
        """Join several spring sets into one (built for the same mesh)."""
        if not parts:
            return Springs(np.zeros((0, 2), np.int64), np.zeros(0), np.zeros(0),
                           np.zeros(0, np.int8))
        counts = {p.vertex_count for p in parts} - {None}
        if len(counts) > 1:
            raise InputError(f"springs: the parts were built for meshes of different sizes "
                             f"({', '.join(map(str, sorted(counts)))} vertices)")
        # the parts were checked when they were made: their join is not checked again
        # (at 513², 1.6 million springs, that took 0.1 s of the run's start-up)
        joined = object.__new__(Springs)
        object.__setattr__(joined, "vertex_count", counts.pop() if counts else None)
        for name in ("spring_vertices", "spring_stiffness", "spring_rest_length",
                     "spring_family", "spring_damping"):
            a = np.concatenate([getattr(p, name) for p in parts])
            a.flags.writeable = False
            object.__setattr__(joined, name, a)
        return joined


def _vertex_pairs(value) -> np.ndarray:
    """Spring end vertices as int64 (s, 2); non-integer or negative indices are rejected."""
    arr = np.asarray(value)
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        if arr.dtype.kind != "f":
            raise InputError(f"spring_vertices: must be integer vertex indices, got dtype "
                             f"{arr.dtype}")
        check_finite("spring_vertices", arr)
        if not np.all(np.mod(arr, 1) == 0):
            bad = int(np.flatnonzero(np.mod(arr, 1).reshape(-1) != 0)[0])
            raise InputError(f"spring_vertices[{bad // 2}]: must be integer vertex indices, "
                             f"got {arr.reshape(-1)[bad]!r}")
    if arr.size % 2:
        raise InputError(f"spring_vertices: expected shape (s, 2), got {arr.shape}")
    idx = arr.astype(np.int64).reshape(-1, 2)
    # the smallest index first: a minimum along each row is ten times slower (0.03 s at
    # 513²), and needed only to name the first spring with a negative index
    if idx.size and idx.min() < 0:
        neg = np.flatnonzero(idx.min(axis=1) < 0)
        raise InputError(f"spring_vertices[{neg[0]}]: vertex index {int(idx[neg[0]].min())} "
                         f"is negative")
    return idx


def _per_spring(name: str, value: np.ndarray, s: int) -> np.ndarray:
    """One value, or one per spring, as a writable (s,) array; other shapes are an error."""
    if value.ndim == 0 or value.shape == (s,):
        return np.broadcast_to(value, (s,)).copy()
    raise InputError(f"{name}: expected one value or {s} (one per spring), got shape "
                     f"{value.shape}")


def _check_stiffness(family: str, k) -> float | None:
    if k is None:
        return None
    return float(check_positive(f"springs.{family}", k, allow_zero=True))


def _family(vertices: np.ndarray, pairs: np.ndarray, k: float, family: str) -> Springs:
    pairs = pairs.reshape(-1, 2).astype(np.int64)
    rest = np.linalg.norm(vertices[pairs[:, 0]] - vertices[pairs[:, 1]], axis=1)
    return Springs(pairs, np.full(len(pairs), k), rest,
                   np.full(len(pairs), FAMILIES.index(family), np.int8), len(vertices))


def grid_pairs(nx: int, ny: int, family: str, bending_pattern: str = "every") -> np.ndarray:
    """Vertex pairs of one spring family on an nx × ny grid (vertex (i, j) = i * nx + j).

    Parameters
    ----------
    family : {"structural", "shear", "bending"}
    bending_pattern : {"every", "alternate"}
        ``"every"``: a bending spring starts at every vertex. ``"alternate"``: only at every
        other vertex along the spring's direction (columns/rows 0, 2, 4, …), as the C++
        ports do; for an odd n × n grid this gives the student report's count s = (n − 1)(5n − 2).

    Returns
    -------
    ndarray, shape (k, 2), int64
    """
    if bending_pattern not in BENDING_PATTERNS:
        raise InputError(f"springs.bending_pattern: must be one of "
                         f"{', '.join(map(repr, BENDING_PATTERNS))}, got {bending_pattern!r}")
    ii, jj = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
    idx = ii * nx + jj

    def pairs(di: int, dj: int, step_i: int = 1, step_j: int = 1) -> np.ndarray:
        i0 = max(0, -di)
        i1 = ny - max(0, di)
        j0 = max(0, -dj)
        j1 = nx - max(0, dj)
        a = idx[i0:i1:step_i, j0:j1:step_j]
        b = idx[i0 + di:i1 + di:step_i, j0 + dj:j1 + dj:step_j]
        return np.stack([a.ravel(), b.ravel()], axis=1)

    if family == "structural":
        return np.concatenate([pairs(0, 1), pairs(1, 0)])
    if family == "shear":
        return np.concatenate([pairs(1, 1), pairs(1, -1)])
    if family == "bending":
        step = 2 if bending_pattern == "alternate" else 1
        return np.concatenate([pairs(0, 2, 1, step), pairs(2, 0, step, 1)])
    raise InputError(f"springs: unknown family {family!r}; expected one of {FAMILIES}")


def grid_springs(
    mesh: Mesh,
    *,
    structural: float | None = None,
    shear: float | None = None,
    bending: float | None = None,
    bending_pattern: str = "every",
) -> Springs:
    """The student report's spring families on a grid mesh.

    Parameters
    ----------
    mesh : Mesh
        Made by :func:`clothsim.mesh.grid` (it must have ``grid_shape``).
    structural, shear, bending : float or None
        Stiffness of each family [N/m]; None leaves the family out.
    bending_pattern : {"every", "alternate"}
        See :func:`grid_pairs`.

    Returns
    -------
    Springs
        For an n × n grid: 2n(n−1) structural, 2(n−1)² shear and 2n(n−2) ("every") or
        n(n−1) ("alternate", odd n) bending springs.
    """
    if mesh.grid_shape is None:
        raise InputError("cloth.shape: grid springs need a grid mesh; use mesh_springs")
    ny, nx = mesh.grid_shape
    parts = []
    for family, k in (("structural", structural), ("shear", shear), ("bending", bending)):
        k = _check_stiffness(family, k)
        if k is not None:
            parts.append(_family(mesh.vertices, grid_pairs(nx, ny, family, bending_pattern),
                                 k, family))
    return Springs.concatenate(parts)


def mesh_springs(
    mesh: Mesh,
    *,
    structural: float | None = None,
    bending: float | None = None,
) -> Springs:
    """Springs of a general mesh: one per edge, one across every interior edge.

    Parameters
    ----------
    mesh : Mesh
    structural : float or None
        Stiffness [N/m] of the springs on every edge (triangle edges and strands).
    bending : float or None
        Stiffness [N/m] of the springs joining the two vertices opposite each interior edge.

    Returns
    -------
    Springs
        The structural springs, then the bending ones; rest lengths r_i [m] from the mesh.
    """
    parts = []
    k = _check_stiffness("structural", structural)
    if k is not None:
        parts.append(_family(mesh.vertices, mesh.edges, k, "structural"))
    k = _check_stiffness("bending", bending)
    if k is not None:
        parts.append(_family(mesh.vertices, bending_pairs(mesh), k, "bending"))
    return Springs.concatenate(parts)


def bending_pairs(mesh: Mesh) -> np.ndarray:
    """The pairs of vertices opposite each interior edge, each unordered pair once.

    Two interior edges can share their opposite pair (on a grid triangulated with
    alternating diagonals, the two diagonals of a "diamond"); one bending spring joins
    such a pair, not two.

    Parameters
    ----------
    mesh : Mesh
        A triangle mesh.

    Returns
    -------
    ndarray, shape (k, 2), int64
        Pairs (min, max), in the order of their first occurrence.
    """
    pairs = np.sort(np.asarray(mesh.interior_edge_opposites, np.int64).reshape(-1, 2), axis=1)
    if len(pairs) == 0:
        return pairs
    _, first = np.unique(pairs, axis=0, return_index=True)
    return pairs[np.sort(first)]


def springs_from_pairs(mesh: Mesh, pairs, stiffness, *, family: str = "structural") -> Springs:
    """Springs on explicit vertex pairs with rest lengths from ``mesh``'s shape.

    Parameters
    ----------
    mesh : Mesh
        Supplies the rest positions [m]; r_i = |X_{a_i} − X_{b_i}|.
    pairs : array_like, shape (s, 2), int
        Vertex pairs (a_i, b_i).
    stiffness : float or array_like, shape (s,)
        k_i [N/m].
    family : str, default "structural"
        One of :data:`FAMILIES`, recorded for every spring.

    Returns
    -------
    Springs
    """
    pairs = _vertex_pairs(pairs)
    n = mesh.vertex_count
    if pairs.size and (pairs.min() < 0 or pairs.max() >= n):
        raise InputError(f"springs: vertex index out of range 0..{n - 1}")
    k = check_finite("spring_stiffness", stiffness)
    rest = np.linalg.norm(mesh.vertices[pairs[:, 0]] - mesh.vertices[pairs[:, 1]], axis=1)
    if k.ndim > 1 or (k.ndim == 1 and k.shape != (len(pairs),)):
        raise InputError(f"spring_stiffness: expected one value or {len(pairs)} (one per "
                         f"pair), got shape {k.shape}")
    return Springs(pairs, np.broadcast_to(k, (len(pairs),)), rest,
                   np.full(len(pairs), FAMILIES.index(family), np.int8), n)
