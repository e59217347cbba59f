"""The model: an immutable cloth (mesh, springs, masses) that solvers and effects read.

Third stage of the pipeline. Build it once with :meth:`Model.build`; it never changes
during a simulation. A solver that precomputes from it (the cached factor of M + h²L)
must be rebuilt or invalidated when a new model is made.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError, check_positive
from .mesh import Mesh
from .springs import Springs

MASS_LUMPINGS = ("uniform", "area")


@dataclass(frozen=True, eq=False)
class Model:
    """A cloth ready to simulate.

    Attributes
    ----------
    mesh : Mesh
        Initial (rest) shape and connectivity; ``mesh.vertices`` is x at t = 0 [m].
    springs : Springs
        Spring topology, stiffness k [N/m], rest length r [m].
    vertex_mass : ndarray, shape (n,), float64
        m_i [kg], all ≥ 0. A vertex of mass 0 is pinned (as the engines read an inverse
        mass of 0): a :class:`~clothsim.simulation.Simulation` holds it exactly at its
        initial position (:attr:`massless_vertices`).
    """

    mesh: Mesh
    springs: Springs
    vertex_mass: np.ndarray

    def __post_init__(self):
        m = check_positive("vertex_mass", self.vertex_mass, allow_zero=True)
        n = self.mesh.vertex_count
        m = np.broadcast_to(m, (n,)).copy() if m.ndim == 0 else m.copy()  # the caller's
        # array stays theirs: writable and unchanged
        if m.shape != (n,):
            raise InputError(f"vertex_mass: expected {n} values (one per vertex), got {m.shape}")
        if not isinstance(self.springs, Springs):
            raise InputError(f"springs: expected Springs, got {type(self.springs).__name__}")
        if self.springs.vertex_count is not None and self.springs.vertex_count != n:
            raise InputError(f"springs: built for a mesh of {self.springs.vertex_count} "
                             f"vertices, this mesh has {n}")
        sv = self.springs.spring_vertices
        if sv.size and sv.max() >= n:
            bad = int(np.flatnonzero(sv.max(axis=1) >= n)[0])
            raise InputError(f"spring_vertices[{bad}]: vertex index {int(sv[bad].max())} "
                             f"out of range 0..{n - 1}")
        m.flags.writeable = False
        object.__setattr__(self, "vertex_mass", m)

    @property
    def massless_vertices(self) -> np.ndarray:
        """Vertices of mass 0, which a simulation pins at their initial positions.

        Returns
        -------
        ndarray, shape (p,), int64
            Sorted indices.
        """
        return np.flatnonzero(self.vertex_mass == 0)

    @classmethod
    def build(
        cls,
        mesh: Mesh,
        springs: Springs,
        *,
        total_mass: float | None = None,
        vertex_mass=None,
        mass_lumping: str = "uniform",
    ) -> Model:
        """Make a model from a mesh, springs and either a total or per-vertex mass.

        Parameters
        ----------
        total_mass : float, optional
            Total mass [kg] spread over the vertices by ``mass_lumping``.
        vertex_mass : float or (n,) array_like, optional
            Mass of each vertex [kg]; not together with ``total_mass``.
        mass_lumping : {"uniform", "area"}
            ``"uniform"``: every vertex the same (the student report). ``"area"``: proportional to a
            third of the adjacent triangles' area (strand length for strand meshes).
        """
        if vertex_mass is not None:
            if total_mass is not None:
                raise InputError("total_mass: give either total_mass or vertex_mass, not both")
            return cls(mesh, springs, check_positive("vertex_mass", vertex_mass,
                                                     allow_zero=True))
        if total_mass is None:
            total_mass = 1.0
        total = check_positive("mass", total_mass)
        if total.ndim:
            raise InputError(f"total_mass: must be one number [kg], got shape {total.shape} "
                             "(vertex_mass= takes one mass per vertex)")
        total = float(total)
        n = mesh.vertex_count
        if mass_lumping == "uniform":
            m = np.full(n, total / n)
        elif mass_lumping == "area":
            a = mesh.vertex_areas()
            if np.any(a <= 0):
                bad = int(np.flatnonzero(a <= 0)[0])
                raise InputError(f"mass_lumping: vertex {bad} touches no triangle or strand, so "
                                 f"area lumping gives it zero mass; use 'uniform'")
            m = total * a / a.sum()
        else:
            raise InputError(f"mass_lumping: must be one of {', '.join(map(repr, MASS_LUMPINGS))},"
                             f" got {mass_lumping!r}")
        return cls(mesh, springs, m)

    @property
    def vertex_count(self) -> int:
        """n."""
        return self.mesh.vertex_count

    @property
    def spring_count(self) -> int:
        """s."""
        return self.springs.spring_count

    @property
    def total_mass(self) -> float:
        return float(self.vertex_mass.sum())
