"""Strain limiting (Provot 1995): no spring may end a step longer than (1 + τ) r.

After the solve, for ``iterations`` passes, every limited spring with |p| > (1 + τ) r is
shortened to exactly (1 + τ) r by moving its ends toward each other along p, in inverse
proportion to their masses (w = 1/m; a pinned vertex has w = 0 and does not move):

    x_a ← x_a − w_a / (w_a + w_b) (|p| − (1 + τ) r) p/|p|,
    x_b ← x_b + w_b / (w_a + w_b) (|p| − (1 + τ) r) p/|p|.

Vectorization (Gauss–Seidel by colours): the limited springs are split into groups in
which no two springs share a vertex (an edge colouring computed once in ``bind`` by
:func:`matching_groups`, about 2Δ groups for largest vertex degree Δ). Within a group the
corrections are independent, so one numpy assignment applies them all exactly; groups are
applied one after another, as in Provot's sequential loop. A pass with no over-long spring
ends the loop early. The simulation then derives v = (x − x_n)/h from the corrected
positions, which also removes the over-stretching velocity.

Shortening one spring can stretch its neighbours, so a bounded number of passes reduces
but need not remove every violation; the residual maximum strain is in
:attr:`StrainLimit.last_max_strain`. Compression is not limited. Pinned vertices (exact
or penalty pins) come from the simulation through :meth:`StrainLimit.connect_pins`.

Reference: X. Provot, "Deformation constraints in a mass-spring model to describe rigid
cloth behavior", Graphics Interface 1995.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..errors import InputError, check_finite
from ..springs import FAMILIES
from .base import Effect


def matching_groups(pairs: np.ndarray, vertex_count: int, *, seed: int = 0) -> list[np.ndarray]:
    """Colour edges so that no two edges of one colour share a vertex (vectorized).

    Jones–Plassmann with random priorities: each round takes every remaining edge whose
    priority is the largest among the remaining edges at both its ends (these share no
    vertex) and gives it the smallest colour not yet used at either end (per-vertex bit
    masks). Greedy colouring uses at most 2Δ − 1 colours (Δ: largest vertex degree).

    Parameters
    ----------
    pairs : ndarray, shape (s, 2), int
        Edge end vertices.
    vertex_count : int
    seed : int
        Seed of the random priorities (fixed, so the grouping is reproducible).

    Returns
    -------
    list of ndarray of int
        Indices into ``pairs``, one array per colour; every edge is in exactly one.
    """
    s = len(pairs)
    if s == 0:
        return []
    # bit masks hold 62 colours; beyond (a vertex with > 31 springs) one colour per round
    greedy = 2 * np.bincount(pairs.ravel(), minlength=vertex_count).max() - 1 <= 62
    rounds = 0
    priority = np.random.default_rng(seed).permutation(s)
    used = np.zeros(vertex_count, np.int64)          # bit c set: colour c used at the vertex
    colour = np.empty(s, np.int64)
    remaining = np.arange(s)
    while len(remaining):
        a, b = pairs[remaining, 0], pairs[remaining, 1]
        p = priority[remaining]
        best = np.full(vertex_count, -1)
        np.maximum.at(best, a, p)
        np.maximum.at(best, b, p)
        take = (best[a] == p) & (best[b] == p)
        if greedy:
            ta, tb = a[take], b[take]
            busy = used[ta] | used[tb]
            bit = ~busy & (busy + 1)                  # lowest free colour bit
            colour[remaining[take]] = np.log2(bit.astype(np.float64)).astype(np.int64)
            used[ta] |= bit
            used[tb] |= bit
        else:
            colour[remaining[take]] = rounds
        rounds += 1
        remaining = remaining[~take]
    order = np.argsort(colour, kind="stable")
    cuts = np.flatnonzero(np.diff(colour[order])) + 1
    return np.split(order, cuts)


class StrainLimit(Effect):
    """Provot's strain limiting after every step.

    Parameters
    ----------
    max_strain : float, default 0.1
        τ: the largest allowed relative elongation |p|/r − 1 (> 0).
    iterations : int, default 15
        Maximum passes over the springs per step (>= 1).
    families : list of str, optional
        Spring families to limit (from ``"structural"``, ``"shear"``, ``"bending"``);
        default all. Springs with r = 0 are never limited.

    Attributes
    ----------
    last_passes : int
        Passes done in the last step.
    last_max_strain : float
        Largest strain of a limited spring after the last step's correction.
    """

    kind = "strain-limit"

    def __init__(self, max_strain: float = 0.1, *, iterations: int = 15,
                 families: list[str] | None = None):
        tau = check_finite("strain-limit.max_strain", max_strain)
        if tau.ndim != 0 or tau <= 0:
            raise InputError(f"strain-limit.max_strain: must be one positive number, got "
                             f"{max_strain!r}")
        if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) \
                or iterations < 1:
            raise InputError(f"strain-limit.iterations: must be an integer >= 1, got "
                             f"{iterations!r}")
        if families is not None:
            if isinstance(families, str) or not hasattr(families, "__iter__"):
                raise InputError(f"strain-limit.families: expected a list of family names, "
                                 f"got {families!r}")
            families = list(families)
            for i, name in enumerate(families):
                if name not in FAMILIES:
                    raise InputError(f"strain-limit.families[{i}]: must be one of "
                                     f"{', '.join(map(repr, FAMILIES))}, got {name!r}")
            if not families:
                raise InputError("strain-limit.families: must not be empty")
        self.max_strain = float(tau)
        self.iterations = int(iterations)
        self.families = families
        self.pinned_vertices_at: Callable[[float], np.ndarray] = lambda t: np.zeros(0, np.int64)
        self.last_passes = 0
        self.last_max_strain = 0.0

    def connect_pins(self, pinned_vertices_at: Callable[[float], np.ndarray]) -> None:
        """Called by the simulation: store the query of pinned vertices.

        Parameters
        ----------
        pinned_vertices_at : callable
            ``pinned_vertices_at(t)`` returns the sorted vertices held by a pin in the step
            ending at time t [s], shape (p,), int; they are not moved by the limiting.
        """
        self.pinned_vertices_at = pinned_vertices_at

    def bind(self, model, h):
        super().bind(model, h)
        springs = model.springs
        keep = springs.spring_rest_length > 0
        if self.families is not None:
            codes = [FAMILIES.index(f) for f in self.families]
            keep &= np.isin(springs.spring_family, codes)
        index = np.flatnonzero(keep)
        self._a = springs.spring_vertices[index, 0]
        self._b = springs.spring_vertices[index, 1]
        self._limit = (1.0 + self.max_strain) * springs.spring_rest_length[index]
        m = model.vertex_mass
        self._inverse_mass = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)  # 0: pinned
        self._groups = [(self._a[g], self._b[g], self._limit[g]) for g in
                        matching_groups(springs.spring_vertices[index], model.vertex_count)]

    def correct_positions(self, t, state, x):
        w = self._inverse_mass
        pinned = self.pinned_vertices_at(t)
        if len(pinned):
            w = w.copy()
            w[pinned] = 0.0
        copied = False
        self.last_passes = 0
        for _ in range(self.iterations):
            changed = False
            for a, b, limit in self._groups:
                p = x[a] - x[b]
                length = np.sqrt(np.einsum("ij,ij->i", p, p))
                over = length > limit
                if not over.any():
                    continue
                wa, wb = w[a], w[b]
                over &= wa + wb > 0
                if not over.any():
                    continue
                if not copied:
                    x = x.copy()
                    copied = True
                changed = True
                a, b, p, wa, wb = a[over], b[over], p[over], wa[over], wb[over]
                scale = (length[over] - limit[over]) / (length[over] * (wa + wb))
                step = scale[:, None] * p
                x[a] -= wa[:, None] * step
                x[b] += wb[:, None] * step
            if not changed:
                break
            self.last_passes += 1
        p = x[self._a] - x[self._b]
        strain = np.linalg.norm(p, axis=1) / (self._limit / (1.0 + self.max_strain)) - 1.0
        self.last_max_strain = float(strain.max()) if len(strain) else 0.0
        return x

    def describe(self):
        out = {"kind": self.kind, "max_strain": self.max_strain, "iterations": self.iterations}
        if self.families is not None:
            out["families"] = list(self.families)
        return out
