"""Spring vectors p_i = x_{a_i} − x_{b_i} by strided slices where the spring list is regular.

The local step gathers every spring's two end positions each iteration. ``np.take`` reads
an index and then a position for each end; a grid cloth's springs, though, come in families
whose ends step through the vertices at fixed strides (:func:`clothsim.springs.grid_pairs`:
spring (i, j) of a family joins vertex a_0 + i r_a + j c_a to b_0 + i r_b + j c_b). Over
such a block of consecutive springs, p is one subtraction of two strided views of x, read in
order with no index array: about twice as fast as the two takes on a grid cloth
(``python -m benchmarks.cpp_side_by_side`` times both on its step).

:func:`affine_blocks` finds the blocks in any spring order (consecutive springs whose two
ends advance by constant steps form a row; consecutive rows of equal length and steps whose
starts advance by constant steps form a block); :class:`SpringGather` gathers block springs
by slices and the rest by ``take``. The arithmetic is the same subtraction of the same two
floats for every spring, so the result is bit for bit the takes' (tested). A mesh without
regular runs (a general triangle mesh) has no blocks and is gathered by ``take`` alone.
"""

from __future__ import annotations

import numpy as np

#: blocks of fewer springs are gathered by take: a block costs microseconds of calls and
#: saves nanoseconds a spring (benchmarks.cpp_side_by_side times the slices against the
#: takes on a whole step)
MIN_BLOCK = 1024
#: the slices are used only when the blocks hold all springs but at most this share
MAX_REST = 1 / 8
#: give up looking for rows when the steps change more often than once in this many springs
MIN_MEAN_RUN = 8


def _rows(a: np.ndarray, b: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Runs of consecutive springs whose ends advance by constant steps, in spring order.

    Returns (start, length, c_a, c_b) for each run, greedily from the first spring; an empty
    list when the steps change too often (no regular structure worth the bookkeeping).
    """
    s = len(a)
    if s < 2:
        return []
    da, db = np.diff(a), np.diff(b)
    change = np.flatnonzero((da[1:] != da[:-1]) | (db[1:] != db[:-1])) + 1
    if len(change) + 1 > s / MIN_MEAN_RUN:
        return []
    seg_end = (np.append(change, len(da)) - 1).tolist()   # last diff index of each segment
    starts, k, seg = [], 0, 0
    while k < s - 1:
        while seg_end[seg] < k:
            seg += 1
        end = seg_end[seg]                            # diffs k..end share da[k], db[k]
        starts.append((k, end))
        k = end + 2
    first = np.array([k for k, _ in starts], dtype=np.intp)
    rows = [(k, end - k + 2, ca, cb) for (k, end), ca, cb
            in zip(starts, da[first].tolist(), db[first].tolist())]
    if k == s - 1:
        rows.append((k, 1, 0, 0))
    return rows


def affine_blocks(a: np.ndarray, b: np.ndarray) -> tuple[list[tuple], np.ndarray]:
    """Blocks of springs whose ends are affine in a row and a column index.

    Parameters
    ----------
    a, b : ndarray of int, shape (s,)
        The springs' end vertices.

    Returns
    -------
    blocks : list of tuple
        ``(k0, R, L, a0, r_a, c_a, b0, r_b, c_b)``: springs k0 + i L + j (i < R, j < L) join
        a0 + i r_a + j c_a to b0 + i r_b + j c_b; each block has at least
        :data:`MIN_BLOCK` springs.
    rest : ndarray of int
        The springs in no block, ascending.
    """
    a = np.asarray(a, dtype=np.intp)
    b = np.asarray(b, dtype=np.intp)
    blocks, covered = [], np.zeros(len(a), dtype=bool)
    rows = _rows(a, b)
    i = 0
    while i < len(rows):
        k0, length, ca, cb = rows[i]
        count = 1
        if i + 1 < len(rows) and rows[i + 1][1:] == (length, ca, cb):
            ra, rb = int(a[rows[i + 1][0]] - a[k0]), int(b[rows[i + 1][0]] - b[k0])
            while (i + count < len(rows) and rows[i + count][1:] == (length, ca, cb)
                   and a[rows[i + count][0]] - a[rows[i + count - 1][0]] == ra
                   and b[rows[i + count][0]] - b[rows[i + count - 1][0]] == rb):
                count += 1
        else:
            ra = rb = 0
        if count * length >= MIN_BLOCK:
            blocks.append((k0, count, length, int(a[k0]), ra, ca, int(b[k0]), rb, cb))
            covered[k0:k0 + count * length] = True
        i += count
    return blocks, np.flatnonzero(~covered)


class SpringGather:
    """p = x_a − x_b for coordinate-major positions, block springs by strided slices.

    Parameters
    ----------
    a, b : ndarray of int, shape (s,)
        The springs' end vertices (indices into the positions' columns).
    """

    def __init__(self, a: np.ndarray, b: np.ndarray):
        self.a = np.ascontiguousarray(a, dtype=np.intp)
        self.b = np.ascontiguousarray(b, dtype=np.intp)
        self.blocks, rest = affine_blocks(self.a, self.b)
        self._rest = None
        if len(rest) > MAX_REST * len(self.a):
            self.blocks = []
        if self.blocks and len(rest):
            self._rest = (rest, self.a[rest], self.b[rest], np.empty(len(rest)),
                          np.empty(len(rest)))
        self._tmp = None   # the takes' second operand, allocated only if they run

    def _takes(self, xT: np.ndarray, pT: np.ndarray) -> None:
        if self._tmp is None:
            self._tmp = np.empty(len(self.a))
        a, b, tmp = self.a, self.b, self._tmp
        for xc, pc in zip(xT, pT):  # mode="clip": no bounds check (indices valid by construction)
            xc.take(a, out=pc, mode="clip")
            xc.take(b, out=tmp, mode="clip")
            np.subtract(pc, tmp, out=pc)

    def __call__(self, xT: np.ndarray, pT: np.ndarray) -> None:
        """Write the spring vectors of ``xT`` (shape (k, n)) into ``pT`` (shape (k, s)).

        Both must be float64; the slices need both C-contiguous (else everything is taken).
        """
        if not (self.blocks and xT.flags.c_contiguous and pT.flags.c_contiguous
                and xT.dtype == pT.dtype == np.float64):
            self._takes(xT, pT)
            return
        k, n = xT.shape
        s = pT.shape[1]
        for k0, rows, length, a0, ra, ca, b0, rb, cb in self.blocks:
            shape = (k, rows, length)
            xa = np.ndarray(shape, np.float64, xT, 8 * a0, (8 * n, 8 * ra, 8 * ca))
            xb = np.ndarray(shape, np.float64, xT, 8 * b0, (8 * n, 8 * rb, 8 * cb))
            out = np.ndarray(shape, np.float64, pT, 8 * k0, (8 * s, 8 * length, 8))
            np.subtract(xa, xb, out=out)
        if self._rest is not None:
            rest, ar, br, pa, pb = self._rest
            for xc, pc in zip(xT, pT):
                xc.take(ar, out=pa, mode="clip")
                xc.take(br, out=pb, mode="clip")
                np.subtract(pa, pb, out=pa)
                pc[rest] = pa
