"""g at two points of a fused step without cancellation (Anderson's and L-BFGS's checks).

:class:`EnergyDifferences` is the part of :class:`~.fused.FusedStep` that compares the
objective at a candidate with the current iterate (:meth:`~EnergyDifferences.trial`) and
moves there without recomputing its spring vectors (:meth:`~EnergyDifferences.accept`);
see :mod:`clothsim.solvers.fused` for how the candidate's spring vectors are kept in step
with its positions. It relies on the step's buffers and parts (``_place``, ``_swap``,
``_local``, ``free``, ``runs``, ``delta``, ``h2``), which :class:`~.fused.FusedStep` sets up.
"""

from __future__ import annotations

import math

import numpy as np

#: :meth:`EnergyDifferences.accept` gathers the spring vectors from the positions on the
#: first accepted move and every RESYNC-th after it; in between p' = p + Δp (trial)
RESYNC = 8


def _norm(aT: np.ndarray) -> float:
    flat = aT.reshape(-1)
    with np.errstate(over="ignore"):  # inf is the answer: the solver names its cause
        return math.sqrt(float(np.dot(flat, flat)))


class EnergyDifferences:
    """g(candidate) − g(x) and the move to the candidate, for a :class:`~.fused.FusedStep`."""

    def _setup_energy(self, solver, problem) -> None:
        model = solver.model
        self._mF = np.ascontiguousarray(model.vertex_mass[self.free])
        self._k = model.springs.spring_stiffness
        self._two_r = 2.0 * model.springs.spring_rest_length
        self._fT = None if problem.f_ext is None else np.ascontiguousarray(problem.f_ext.T)
        self._anchor = None
        if len(problem.anchor_vertices):
            self._anchor = (problem.anchor_vertices, problem.anchor_positions.T,
                            problem.anchor_stiffness)
        self._dxT = np.zeros_like(self.yT)
        self._dpT = np.empty_like(self.eT)
        self._accepted = 0
        self._w = np.empty_like(self.eT)                  # p + p'
        self._s, self._num = np.empty(len(self._k)), np.empty(len(self._k))
        self._mv = np.empty((3, len(self._mF)))
        if self.runs is not None:   # Δx over the free vertices: views of its runs
            self._dx_runs = [self._dxT[:, start:stop] for start, stop, _ in self.runs]
            self._dxF = np.empty_like(self._mv)

    def trial(self, deltaT: np.ndarray, step: np.ndarray | None = None) -> float:
        """g(y + δ) − g(x) without cancellation, x the current iterate [J·s²].

        Puts the candidate x' in the spare buffer with its spring vectors p' = p + Δp;
        :meth:`accept` then moves there without recomputing them (until the next
        :meth:`trial`; see the module docstring for how p' is kept in step with x'). As in
        :func:`~.descent.objective_difference`, everything is formed from Δx = x' − x (exact:
        a difference of nearby floats) and the spring vectors' changes Δp = Δx_a − Δx_b, so
        the comparison still resolves g's change far below 1e-8 relative residual.

        Parameters
        ----------
        deltaT : ndarray, shape (3, f)
            The candidate's δ_F [m].
        step : ndarray, shape (3, f), optional
            The move δ' − δ as the caller formed it (a line search's α p, exact): then Δx
            is this step, not x' − x, which carries the rounding of y + δ' (eps |y|: deep in
            a solve, that noise swamps g's change; :class:`~.held_accel.HeldStep`'s L-BFGS).

        Returns
        -------
        float
            ½ Δxᵀ M (2(x − y) + Δx) + h² [Σ ½ k (l' − l)(l' + l − 2r) + anchors − Δxᵀ f],
            with l' − l = (2p + Δp)·Δp / (l + l').
        """
        xT = self._place(deltaT)
        p, pn, dxT, dp = self._p, self._p_trial, self._dxT, self._dpT
        if step is None:
            np.subtract(xT, self._xT, out=dxT)
        else:   # zero at the pins (dxT starts zero there and only free columns are set)
            dxT[:, self.free] = step
        self.dirs.vectors_into(dxT, dp)
        np.add(p, dp, out=pn)                          # p' = p + Δp (accept re-syncs)
        ln = self._l_spare                             # |p'|, kept for accept
        np.einsum("ij,ij->j", pn, pn, out=ln)
        np.sqrt(ln, out=ln)
        self._trial_delta = deltaT
        s, num, w = self._s, self._num, self._w
        np.add(self._l, ln, out=s)
        np.add(p, pn, out=w)
        np.einsum("ij,ij->j", w, dp, out=num)        # (2p + Δp)·Δp, Δp exact to rounding
        if s.min() > 0:
            np.divide(num, s, out=num)
        else:                                          # springs whose ends coincide twice
            np.divide(num, s, out=num, where=s > 0)
            num[~(s > 0)] = 0.0
        np.multiply(num, self._k, out=num)
        np.subtract(s, self._two_r, out=s)
        e = 0.5 * float(np.dot(num, s))
        if self._fT is not None:
            e -= float(np.vdot(dxT, self._fT))
        if self._anchor is not None:
            av, qT, k = self._anchor
            da = dxT[:, av]
            e += float(np.sum(k * da * (self._xT[:, av] - qT + 0.5 * da)))
        # ½ Δxᵀ M (2(x − y) + Δx), 2(x − y) + Δx = δ + δ' to rounding (a factor, not a
        # difference): over the free vertices, where Δx lives
        if self.runs is None:
            dxF = dxT[:, self.free]
        else:
            dxF = np.concatenate(self._dx_runs, axis=1, out=self._dxF)
        mv = self._mv
        np.add(self.delta, deltaT, out=mv)
        np.multiply(mv, self._mF, out=mv)
        mass = 0.5 * float(np.dot(dxF.reshape(-1), mv.reshape(-1)))
        return mass + self.h2 * e

    def accept(self) -> None:
        """Move to the last :meth:`trial`'s candidate: local step there and its rhs."""
        deltaT = self._trial_delta
        self._swap(deltaT)
        self._p, self._p_trial = self._p_trial, self._p
        self._l, self._l_spare = self._l_spare, self._l
        self._accepted += 1
        if self._accepted % RESYNC == 1:   # the first move and every RESYNC-th: p(x) afresh
            self.dirs.vectors_into(self._xT, self._p)
            np.einsum("ij,ij->j", self._p, self._p, out=self._l)
            np.sqrt(self._l, out=self._l)
        self._local(self._l, self._p)
