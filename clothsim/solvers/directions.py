"""The local step on coordinate-major buffers, and the direction it carries over.

The local step (Liu et al. 2013, Section 4) is, spring by spring,

    d_i = r_i p_i / |p_i|,   p_i = x_{a_i} − x_{b_i}.

Where a spring's two ends coincide (|p_i| = 0) every d_i with |d_i| = r_i is optimal: the
previous local step's d_i is kept ("carried"), so d never jumps and nothing divides by zero.
Before the first local step the previous d is the rest mesh's.

The iteration of :class:`~clothsim.solvers.LocalGlobalSolver` needs e = d − p(y), not d
(its right-hand side is h² J (d − p(y)) + c): :meth:`SpringDirections.e_into` turns the
spring vectors into e in place, so no (3, s) buffer holds d. What the previous d was is
remembered instead by the positions it was computed at (which the iteration keeps intact
for one more local step) and the few carried values; :meth:`SpringDirections.current`
rebuilds d from them, by the same arithmetic, only when asked (a port export reads it).

All arrays are coordinate-major: positions xT of shape (3, n), spring vectors (3, s).
"""

from __future__ import annotations

import numpy as np

from .spring_blocks import SpringGather

_NONE = np.zeros(0, dtype=np.intp)
_NO_VALUES = np.zeros((3, 0))
_NO_VALUES.flags.writeable = False


class SpringDirections:
    """The local step's arithmetic for one spring set, with the carried directions.

    Parameters
    ----------
    a, b : ndarray of int, shape (s,)
        The springs' end vertices (p_i = x_{a_i} − x_{b_i}).
    rest : ndarray, shape (s,)
        Rest lengths r [m].
    rest_positions_T : ndarray, shape (3, n)
        The rest mesh's positions [m]: the "previous" d before any local step.
    """

    def __init__(self, a: np.ndarray, b: np.ndarray, rest: np.ndarray,
                 rest_positions_T: np.ndarray):
        self._gather = SpringGather(a, b)
        self.a, self.b = self._gather.a, self._gather.b
        self.rest = np.ascontiguousarray(rest, dtype=np.float64)
        self._length = np.empty(len(self.a))
        # the last local step: a materialized d (3, s), or (when _d is None) the positions
        # _xT it was computed at with its carried springs and their d
        self._xT = None
        self._carried = (_NONE, np.zeros((3, 0)))
        self._d = np.zeros((3, len(self.a)))   # zero-length rest springs: d = 0 to start
        self._d = self.local_step(np.ascontiguousarray(rest_positions_T, dtype=np.float64))

    # -- the arithmetic ---------------------------------------------------------------------
    def vectors_into(self, xT: np.ndarray, pT: np.ndarray) -> None:
        """The spring vectors p_i = x_{a_i} − x_{b_i}, written into ``pT``.

        Regular runs of springs (a grid's families) are gathered by strided slices, the
        rest by ``take`` (:mod:`clothsim.solvers.spring_blocks`): the same values.

        Parameters
        ----------
        xT : ndarray, shape (3, n)
            Positions [m], coordinate-major, contiguous rows (C-contiguous for the slices).
        pT : ndarray, shape (3, s)
            Output [m], coordinate-major, contiguous rows (overwritten).
        """
        self._gather(xT, pT)

    def _scale(self, pT: np.ndarray, length_given: np.ndarray | None = None,
               source: np.ndarray | None = None) -> np.ndarray:
        """pT = (r / |p|) p, p = ``source`` (default pT itself); returns the springs with
        |p| = 0 (left at 0 in pT)."""
        length = self._length
        if source is None:
            source = pT
        if length_given is None:
            np.einsum("ij,ij->j", source, source, out=length)   # |p|
            np.sqrt(length, out=length)
        else:                                                # |p| known by the caller
            np.copyto(length, length_given)
        coincident = _NONE
        if len(length) and not length.min() > 0:             # rare: some ends coincide
            coincident = np.flatnonzero(length == 0)
            length[coincident] = np.inf                      # r / inf = 0, no division by 0
        np.divide(self.rest, length, out=length)             # d = (r / |p|) p
        np.multiply(source, length, out=pT)
        return coincident

    def previous(self, springs: np.ndarray) -> np.ndarray:
        """The last local step's d at some springs (what a coincident spring keeps).

        Parameters
        ----------
        springs : ndarray of int, shape (m,)
            Spring indices, ascending.

        Returns
        -------
        ndarray, shape (3, m)
            d [m] of the last local step at those springs (the rest mesh's before any).
        """
        if self._d is not None:
            return self._d[:, springs]
        idx, values = self._carried
        pT = self._xT[:, self.a[springs]] - self._xT[:, self.b[springs]]
        length = np.sqrt(np.einsum("ij,ij->j", pT, pT))
        zero = length == 0
        length[zero] = np.inf
        d = pT * (self.rest[springs] / length)
        if zero.any():  # were coincident then too: carried from before
            d[:, zero] = values[:, np.searchsorted(idx, springs[zero])]
        return d

    def _record(self, xT: np.ndarray, dT: np.ndarray, coincident: np.ndarray) -> None:
        """Remember the local step just done at xT (which must stay unchanged until the
        next local step) with d = dT; the carried values are copied."""
        self._d, self._xT = None, xT
        self._carried = (coincident, dT[:, coincident].copy() if len(coincident) else _NO_VALUES)

    # -- the local step three ways ----------------------------------------------------------
    def local_step(self, xT: np.ndarray) -> np.ndarray:
        """The local step at xT; its d becomes the one coincident springs keep next.

        Parameters
        ----------
        xT : ndarray, shape (3, n)
            Positions [m], coordinate-major.

        Returns
        -------
        ndarray, shape (3, s)
            d [m], a new array.
        """
        dT = np.empty((3, len(self.a)))
        self.vectors_into(xT, dT)
        coincident = self._scale(dT)
        if len(coincident):
            dT[:, coincident] = self.previous(coincident)
        self._d, self._xT, self._carried = dT, None, (_NONE, np.zeros((3, 0)))
        return dT

    def e_into(self, xT: np.ndarray, pT: np.ndarray, pyT: np.ndarray,
               length: np.ndarray | None = None,
               source: np.ndarray | None = None) -> np.ndarray:
        """e = d(x) − p(y) in place over pT, which holds x's spring vectors p(x) on entry.

        Parameters
        ----------
        xT : ndarray, shape (3, n)
            The positions p(x) came from [m]. The caller keeps them unchanged until its
            next local step (:meth:`previous` and :meth:`current` rebuild d from them).
        pT : ndarray, shape (3, s)
            p(x) on entry, e on return [m].
        pyT : ndarray, shape (3, s)
            p(y) [m].
        length : ndarray, shape (s,), optional
            |p(x)| [m] when the caller has it (the same values the step would compute).
        source : ndarray, shape (3, s), optional
            p(x) [m] when it is held elsewhere (then pT's content on entry is ignored and
            ``source`` is left unchanged).

        Returns
        -------
        ndarray, shape (3, s)
            pT, now e [m].
        """
        coincident = self._scale(pT, length, source)
        if len(coincident):
            pT[:, coincident] = self.previous(coincident)
        self._record(xT, pT, coincident)
        np.subtract(pT, pyT, out=pT)   # differences only: momentum kept to their rounding
        return pT

    def current(self) -> np.ndarray:
        """The last local step's d (rebuilt once after :meth:`e_into`, then kept).

        Returns
        -------
        ndarray, shape (3, s)
            d [m]; valid until the next local step.
        """
        if self._d is None:
            dT = np.empty((3, len(self.a)))
            self.vectors_into(self._xT, dT)
            self._scale(dT)
            idx, values = self._carried
            dT[:, idx] = values
            self._d = dT
        return self._d
