"""One implicit Euler step as an optimization problem: the data every solver minimizes over.

One step (Liu et al. 2013, Eq. 4) asks for

    x_{n+1} = argmin_x g(x),   g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x),

with y the inertial target (y = x_n + h v_n unless a damping effect changes it), external
forces f, exact pins (fixed vertices at prescribed positions, removed from the unknowns)
and penalty pins ("anchors": zero-rest-length springs of stiffness k to fixed points q).
:class:`StepProblem` holds exactly these data; every solver minimizes the same g.

Contact enters the step as **held contacts** (an obstacle's ``[contact] mode = "hold"``, the
default): vertex v_c, in contact with an obstacle at the end of the last step and pushed by
it, stays on its contact plane during this step, n_c · x_{v_c} = o_c, and slides freely in
it. The step then minimizes g over that affine set: x_{n+1} = argmin g(x) subject to the
pins and n_c · x_{v_c} = o_c. Its optimality measure is the gradient on the set,
∇g with the normal part removed at every held vertex (:meth:`StepProblem.tangential`,
used by :func:`~clothsim.objective.objective_gradient`). In the seed's mode
(``"post-solve"``) there are no held contacts and the step is the unconstrained minimum;
the obstacles then correct x after the solve.

- :class:`PinSet`: the pins active during one step (what effects hand the simulation);
- :class:`StepProblem`: the data of one step;
- :class:`PenaltyAnchors`: the anchor terms (energy, gradient, right-hand side).

The objective g, its gradient and the augmented objective are in
:mod:`clothsim.objective`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import contacts
from .errors import InputError, check_finite

_EMPTY_I = np.zeros(0, np.int64)
_EMPTY_X = np.zeros((0, 3))


def _index_array(name: str, value, n: int | None = None) -> np.ndarray:
    """Vertex indices as int64, shape (p,); floats that are not whole numbers, or indices
    out of range 0..n−1, are an :class:`InputError` naming ``name``."""
    arr = np.asarray(value)
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        if arr.dtype.kind != "f":
            raise InputError(f"{name}: must be integer vertex indices, got dtype {arr.dtype}")
        check_finite(name, arr)
        if not np.all(np.mod(arr, 1) == 0):
            raise InputError(f"{name}: must be integer vertex indices, got a non-integer value")
    arr = arr.astype(np.int64).reshape(-1)
    if n is not None and arr.size:
        bad = np.flatnonzero((arr < 0) | (arr >= n))
        if len(bad):
            raise InputError(f"{name}[{bad[0]}]: vertex {arr[bad[0]]} out of range 0..{n - 1}")
    return arr


def _points(name: str, value, rows: int | None) -> np.ndarray:
    """(rows, 3) float64 array of finite numbers, or an :class:`InputError` naming ``name``."""
    arr = check_finite(name, value)
    if arr.ndim != 2 or arr.shape[1] != 3 or (rows is not None and arr.shape[0] != rows):
        want = f"({rows}, 3)" if rows is not None else "(p, 3)"
        raise InputError(f"{name}: expected shape {want}, got {arr.shape}")
    return arr


#: The starting points an iteration may take: the inertial target y (the paper) or x_n.
INITIAL_GUESSES = ("y", "x_n")


def check_initial_guess(value) -> str:
    """``value`` if it names a starting point of :data:`INITIAL_GUESSES`.

    Parameters
    ----------
    value : str
        ``"y"`` (the inertial target, the paper's choice) or ``"x_n"`` (the previous
        positions).

    Returns
    -------
    str
        ``value``.

    Raises
    ------
    InputError
        At ``initial_guess`` for any other value.
    """
    if not isinstance(value, str) or value not in INITIAL_GUESSES:
        raise InputError(f"initial_guess: expected \"y\" or \"x_n\", got {value!r}")
    return value


@dataclass
class PinSet:
    """Pins active during one step (see :class:`StepProblem` for the meaning of each array).

    Attributes
    ----------
    fixed_vertices : ndarray, shape (p,), int
    fixed_positions : ndarray, shape (p, 3) [m]
    anchor_vertices : ndarray, shape (q,), int
    anchor_positions : ndarray, shape (q, 3) [m]
    anchor_stiffness : ndarray, shape (q,) [N/m]
    """

    fixed_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    fixed_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    anchor_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @staticmethod
    def merge(parts: list[PinSet]) -> PinSet:
        """One PinSet holding every pin of ``parts``.

        Parameters
        ----------
        parts : list of PinSet

        Returns
        -------
        PinSet
            Their arrays concatenated in order (``parts[0]`` itself when there is one).
        """
        if len(parts) == 1:
            return parts[0]
        cat = np.concatenate
        return PinSet(
            cat([p.fixed_vertices for p in parts]), cat([p.fixed_positions for p in parts]),
            cat([p.anchor_vertices for p in parts]), cat([p.anchor_positions for p in parts]),
            cat([p.anchor_stiffness for p in parts]))


@dataclass(frozen=True, eq=False)
class PenaltyAnchors:
    """Penalty pins: zero-rest-length springs of stiffness k_j from vertex v_j to point q_j.

    Their energy ½ Σ_j k_j |x_{v_j} − q_j|² is part of E(x); its Hessian adds k_j to
    L_s[v_j, v_j] (:func:`clothsim.matrices.system_matrix`) and its linear part h² k_j q_j
    to the global step's right-hand side. Every solver writes these terms through this
    class.

    Attributes
    ----------
    vertices : ndarray, shape (q,), int
    positions : ndarray, shape (q, 3) [m]
    stiffness : ndarray, shape (q,) [N/m]
    """

    vertices: np.ndarray
    positions: np.ndarray
    stiffness: np.ndarray

    def __len__(self) -> int:
        return len(self.vertices)

    def energy(self, x: np.ndarray) -> float:
        """Anchor energy E_anchor(x) = ½ Σ_j k_j |x_{v_j} − q_j|².

        Parameters
        ----------
        x : ndarray, shape (n, 3), positions [m]

        Returns
        -------
        float, the energy [J]
        """
        q = x[self.vertices] - self.positions
        return 0.5 * float(np.sum(self.stiffness[:, None] * q * q))

    def add_gradient(self, out: np.ndarray, x: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """Add the anchors' gradient: out[v_j] += scale k_j (x_{v_j} − q_j), in place.

        Parameters
        ----------
        out : ndarray, shape (n, 3), accumulator (repeated vertices accumulate)
        x : ndarray, shape (n, 3), positions [m]
        scale : float
            1 adds the gradient [N], −1 the force [N], h² the term of ∇g [N·s²].

        Returns
        -------
        out : ndarray, shape (n, 3)
        """
        if len(self.vertices):
            np.add.at(out, self.vertices,
                      scale * self.stiffness[:, None] * (x[self.vertices] - self.positions))
        return out

    def add_rhs(self, out: np.ndarray, scale: float = 1.0,
                origin: np.ndarray | None = None) -> np.ndarray:
        """Add the anchors' part of the global step's right-hand side, in place.

        out[v_j] += scale k_j q_j, the anchors' term of h² J d + M y + h² f with scale = h²
        [s²]; with ``origin`` (n, 3) [m], scale k_j (q_j − origin_{v_j}) instead (the
        right-hand side of a solve for the displacement x − origin).

        Parameters
        ----------
        out : ndarray, shape (n, 3), accumulator
        scale : float
        origin : ndarray, shape (n, 3), optional

        Returns
        -------
        out : ndarray, shape (n, 3)
        """
        if len(self.vertices):
            q = self.positions if origin is None else self.positions - origin[self.vertices]
            np.add.at(out, self.vertices, scale * self.stiffness[:, None] * q)
        return out


@dataclass(eq=False)
class StepProblem:
    """Data of one implicit Euler step.

    Attributes
    ----------
    h : float
        Time step [s].
    x : ndarray, shape (n, 3)
        Positions x_n at the start of the step [m].
    v : ndarray, shape (n, 3)
        Velocities v_n [m/s].
    y : ndarray, shape (n, 3)
        Inertial target [m]; default x + h v.
    f_ext : ndarray, shape (n, 3) or None
        External force on each vertex [N]; None means none.
    fixed_vertices : ndarray, shape (p,), int
        Exact pins: vertices removed from the unknowns.
    fixed_positions : ndarray, shape (p, 3)
        Their positions at the end of the step [m].
    anchor_vertices, anchor_positions, anchor_stiffness : ndarray, shapes (q,), (q, 3), (q,)
        Penalty pins: zero-rest-length springs of stiffness k [N/m] to points q [m].
    start : {"y", "x_n"}
        Where the iteration starts (:meth:`initial_guess`): the inertial target y (the
        paper, default) or the previous positions x_n (what most ports do).
    contact_vertices, contact_normals, contact_offsets : ndarray, shapes (c,), (c, 3), (c,)
        Held contacts: vertex v_c stays on the plane n_c · x = o_c [m] (n_c a unit vector)
        during the step. Contacts at exactly pinned vertices are dropped (the pin holds).
    """

    h: float
    x: np.ndarray
    v: np.ndarray
    y: np.ndarray | None = None
    f_ext: np.ndarray | None = None
    fixed_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    fixed_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    anchor_positions: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    anchor_stiffness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    start: str = "y"
    contact_vertices: np.ndarray = field(default_factory=lambda: _EMPTY_I)
    contact_normals: np.ndarray = field(default_factory=lambda: _EMPTY_X)
    contact_offsets: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self):
        self.start = check_initial_guess(self.start)
        h = float(check_finite("h", self.h))
        if h <= 0:
            raise InputError(f"h: the time step must be positive, got {h!r}")
        self.h = h
        # a NaN/inf in the state or forces (bad input, or a blow-up) is named, never solved
        self.x = _points("state.positions", self.x, None)
        n = len(self.x)
        self.v = _points("state.velocities", self.v, n)
        if self.y is None:
            self.y = self.x + h * self.v
        self.y = _points("inertial_target", self.y, n)
        if self.f_ext is not None:
            self.f_ext = _points("external_force", self.f_ext, n)
        self.fixed_vertices = _index_array("pins.fixed_vertices", self.fixed_vertices, n)
        self.fixed_positions = _points("pins.fixed_positions",
                                       np.reshape(self.fixed_positions, (-1, 3)),
                                       len(self.fixed_vertices))
        self.anchor_vertices = _index_array("pins.anchor_vertices", self.anchor_vertices, n)
        self.anchor_positions = _points("pins.anchor_positions",
                                        np.reshape(self.anchor_positions, (-1, 3)),
                                        len(self.anchor_vertices))
        k = check_finite("pins.anchor_stiffness", self.anchor_stiffness)
        if k.ndim > 1 or (k.ndim == 1 and len(k) != len(self.anchor_vertices)):
            raise InputError(f"pins.anchor_stiffness: expected one value per anchor "
                             f"({len(self.anchor_vertices)}), got shape {k.shape}")
        self.anchor_stiffness = np.broadcast_to(k, self.anchor_vertices.shape)
        self.anchors = PenaltyAnchors(self.anchor_vertices, self.anchor_positions,
                                      self.anchor_stiffness)
        cv = _index_array("contacts.vertices", self.contact_vertices, n)
        cn = _points("contacts.normals", np.reshape(self.contact_normals, (-1, 3)), len(cv))
        co = check_finite("contacts.offsets", np.reshape(self.contact_offsets, -1))
        if len(co) != len(cv):
            raise InputError(f"contacts.offsets: expected one per contact ({len(cv)}), got "
                             f"{len(co)}")
        if len(cv) and np.abs(np.linalg.norm(cn, axis=1) - 1.0).max() > 1e-9:
            raise InputError("contacts.normals: must be unit vectors")
        keep = ~np.isin(cv, self.fixed_vertices)
        self.contact_vertices, self.contact_normals = cv[keep], cn[keep]
        self.contact_offsets = co[keep].astype(np.float64)
        self._basis = None

    def initial_guess(self) -> np.ndarray:
        """The iteration's starting point x_0, with fixed vertices at their prescribed positions.

        x_0 = y (the paper) or x_n, as :attr:`start` says, held contacts moved onto their
        planes (:meth:`hold`). Penalty pins are springs of the energy, not constraints:
        their vertices start where y or x_n puts them.

        Returns
        -------
        ndarray, shape (n, 3), a new array of positions [m]
        """
        x0 = np.array(self.x if self.start == "x_n" else self.y, dtype=np.float64)
        x0[self.fixed_vertices] = self.fixed_positions
        return self.hold(x0)

    @property
    def has_contacts(self) -> bool:
        """Whether the step holds vertices on contact planes (see the module docstring)."""
        return len(self.contact_vertices) > 0

    def hold(self, x: np.ndarray) -> np.ndarray:
        """Move every held vertex onto its contact plane(s), in place
        (:func:`clothsim.contacts.hold`).

        Parameters
        ----------
        x : ndarray, shape (n, 3), positions [m]

        Returns
        -------
        x : ndarray, shape (n, 3), the same array
        """
        return contacts.hold(x, self.contact_vertices, self.contact_normals,
                             self.contact_offsets)

    def tangential(self, g: np.ndarray) -> np.ndarray:
        """``g`` without its normal part at held vertices: the gradient on the feasible set.

        Parameters
        ----------
        g : ndarray, shape (n, 3)
            A gradient [N·s²] (or any per-vertex vector field).

        Returns
        -------
        ndarray, shape (n, 3)
            ``g`` itself without held contacts, else a copy with g_v − (b·g_v) b at every
            held vertex v, for each direction b of :meth:`contact_basis`.
        """
        if not len(self.contact_vertices):
            return g
        return contacts.tangential(g, self.contact_basis())

    def contact_basis(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Orthonormal constrained directions of the held vertices (computed once).

        Returns
        -------
        list of (ndarray (u,) of int, ndarray (u, 3))
            :func:`clothsim.contacts.contact_basis` of the held contacts.
        """
        if self._basis is None:
            self._basis = contacts.contact_basis(self.contact_vertices, self.contact_normals)
        return self._basis

    def free_mask(self, n: int) -> np.ndarray:
        """Which vertices are unknowns (not exactly pinned).

        Parameters
        ----------
        n : int, number of vertices

        Returns
        -------
        ndarray, shape (n,), bool
            True for free vertices, False for ``fixed_vertices``.
        """
        mask = np.ones(n, bool)
        mask[self.fixed_vertices] = False
        return mask
