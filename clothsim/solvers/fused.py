"""The fused local/global iteration of one step, as a kernel the accelerated solvers share.

:class:`FusedStep` holds one step's constants and buffers and runs the local/global
iteration's three parts on coordinate-major arrays over the free vertices F, in the
displacement δ = x − y (docs/performance.md):

- :meth:`FusedStep.solve`: the global step's solve δ̂ = A_FF⁻¹ rhs with the cached factor;
- :meth:`FusedStep.advance`: x = y + δ for any δ (a global step's δ̂, or an accelerated
  combination), then the local step at x and its right-hand side
  rhs(x) = h² (J (d(x) − p(y)))_F + c_F, c_F = (h² f + h² K_anchor (q − y))_F − A_FP δ_P;
- the gradient for free: ∇g(x)_F = A_FF δ_F − rhs(x). A solver that tracks a = A_FF δ gets
  ‖∇g‖ from one subtraction. For a global step's δ̂, A_FF δ̂ = rhs(x_k), so
  ∇g(x_{k+1}) = rhs(x_k) − rhs(x_{k+1}) (local/global); a linear combination of solves
  (Chebyshev, Anderson) has the same combination of their right-hand sides as its a.

Anderson and L-BFGS also compare g at two points: :meth:`FusedStep.trial` puts a
candidate's positions in the spare buffer and returns g(candidate) − g(x) from spring
vectors the local step needs anyway (:meth:`FusedStep.accept` then takes it without
recomputing them), without cancellation: from δ's change and the change of spring lengths,
as :func:`~clothsim.solvers.descent.objective_difference`. The candidate's spring vectors
are p' = p + Δp, Δp = Δx_a − Δx_b gathered from the exact position change Δx = x' − x (one
gather instead of two). They differ from x'_a − x'_b by rounding, which would add up over
accepted moves: :meth:`FusedStep.accept` therefore gathers p from the positions on the
first move (where x_0's pins may jump to their targets and pinned-together ends become
exactly coincident) and every :data:`~.fused_energy.RESYNC`-th after it, so the spring
vectors are never more than RESYNC additions (each one rounding of p) away from the
positions' own. Those two comparisons live in :mod:`clothsim.solvers.fused_energy`.

Every iterate after x_0 has its exactly pinned vertices at their targets (the x_0 a caller
passes may not: its gradient is then computed from the definition; the default x_0 has
them there, and its gradient is the one product A_FF δ_F − rhs(x_0), cheaper than
the definition's spring gather (docs/data/cpp-side-by-side.md times both).
"""

from __future__ import annotations

import numpy as np

from ..factorization import spmv_add
from .fused_energy import RESYNC, EnergyDifferences, _norm

__all__ = ["RESYNC", "FusedStep"]


class FusedStep(EnergyDifferences):
    """One step of the fused local/global iteration (see the module docstring).

    Parameters
    ----------
    solver : LocalGlobalSolver
        Gives the cached factor, the spring directions and the work buffers.
    problem : StepProblem
        The step's h [s], y [m], forces [N] and pins.
    x0 : ndarray, shape (n, 3), optional
        Initial guess [m]; default :meth:`StepProblem.initial_guess`.
    energy : bool, default False
        Keep what :meth:`trial` needs (the spring vectors and lengths of the current x).

    Attributes
    ----------
    x : ndarray, shape (n, 3)
        The current iterate [m] (a view of a buffer: valid until the next :meth:`advance`).
    delta : ndarray, shape (3, f)
        Its displacement δ_F = (x − y)_F [m], coordinate-major (valid as ``x``).
    rhs : ndarray, shape (3, f)
        rhs(x) [kg·m] (valid as ``x``).
    a0 : ndarray, shape (3, f)
        A_FF δ_F at x_0 in the sense ∇g(x_0)_F = a0 − rhs(x_0) [kg·m].
    norm0 : float
        ‖∇g(x_0)‖ over the free vertices [N·s²].
    """

    def __init__(self, solver, problem, x0: np.ndarray | None = None, *, energy: bool = False):
        sysf = solver.system(problem)
        self.sysf, self.problem = sysf, problem
        free, fixed = sysf.free, sysf.fixed
        self.dirs = dirs = solver._dirs
        a, b = dirs.a, dirs.b
        from_y = x0 is None and problem.start == "y"   # x_0 = y: p(x_0) is p(y)
        x = problem.initial_guess() if x0 is None else np.array(x0, dtype=np.float64)
        xT = np.ascontiguousarray(x.T)
        y = problem.y
        self.yT = yT = np.ascontiguousarray(y.T)
        self.h2J_F, self._solve_columns = sysf.h2J_F, sysf.A_FF_factor.solve_columns
        self._rhs, self._rhs_next, cT = sysf.work
        self.pyT, self.eT = pyT, eT = solver._pyT, solver._eT
        dirs.vectors_into(yT, pyT)
        h2 = self.h2 = problem.h ** 2
        # free vertices as runs of consecutive indices: x_F = y_F + δ_F by slices
        self.runs = sysf.free_runs
        self.free = free
        self.cT = self._constant(problem, h2, cT)
        x_fixed_T = None
        if len(fixed):   # − A_FP δ_P, on the rows coupled to a pin (the others subtract 0)
            x_pinned = x if x0 is None else problem.initial_guess()
            x_fixed_T = np.ascontiguousarray(x_pinned[fixed].T)
            rows, A_rows = sysf.coupled
            cT[:, rows] -= (A_rows @ (x_pinned[fixed] - y[fixed])).T
        self._yFT = np.ascontiguousarray(yT[:, free]) if self.runs is None else None
        self._xFT = np.empty_like(self._yFT) if self.runs is None else None
        if energy:   # spring vectors of x_0, kept before the local step turns them into e
            self._p = np.empty_like(eT)
            dirs.vectors_into(xT, self._p)
            self._l = np.sqrt(np.einsum("ij,ij->j", self._p, self._p))
            self._p_trial, self._l_spare = np.empty_like(eT), np.empty_like(self._l)
            self._setup_energy(solver, problem)
        self.energy = energy
        # local step at x_0; x_0 = y (pins applied) has p(y)'s vectors but at the exact pins
        if from_y:
            np.copyto(eT, pyT)
            pinned = sysf.pinned_springs
            if len(pinned):
                eT[:, pinned] = xT[:, a[pinned]] - xT[:, b[pinned]]
        else:
            dirs.vectors_into(xT, eT)
        self._right_hand_side(dirs.e_into(xT, eT, pyT), self._rhs)
        self.delta = self._free_difference(xT, yT)
        if from_y:        # δ_F = 0 at x_0, so ∇g(x_0)_F = (A δ)_F − (b − A y)_F = −rhs_F
            self.a0 = np.zeros_like(self._rhs)
            self.norm0 = _norm(self._rhs)
        elif x0 is None:  # pins at their targets: ∇g(x_0)_F = A_FF δ_F − rhs_F, one product
            self.a0 = sysf.free_product(self._free_difference(x, y, rows=True))
            self.norm0 = _norm(self.a0 - self._rhs)
        else:   # a caller's x_0 may have its pins off their targets: from the definition
            g0 = solver.gradient(problem, x, dirs.current().T)
            self.a0 = self._rhs + g0.T
            self.norm0 = float(np.linalg.norm(g0))
        self.x = x
        # two position buffers in turn: the last local step's x stays intact for the next
        # one (the carried directions are rebuilt from it, clothsim.solvers.directions);
        # the iteration writes only free vertices, so both hold the pins' targets
        self._xT = xT
        self._xT_spare = xT.copy()
        if x_fixed_T is not None:
            self._xT_spare[:, fixed] = x_fixed_T
        self._x_fixed_T = x_fixed_T
        self._first = True
        self.grad = np.empty_like(self._rhs)

    def _constant(self, problem, h2: float, cT: np.ndarray) -> np.ndarray:
        """c_F = (h² f + h² K_anchor (q − y))_F into cT (the pins' part is added after)."""
        f = problem.f_ext
        if self.runs is None or len(problem.anchor_vertices):
            c = np.zeros_like(problem.y) if f is None else h2 * f
            problem.anchors.add_rhs(c, h2, origin=problem.y)
            cT[...] = c[self.free].T
        elif f is None:
            cT.fill(0.0)
        else:             # the same products, over the free runs only
            for start, stop, offset in self.runs:
                np.multiply(f[start:stop].T, h2, out=cT[:, offset:offset + stop - start])
        return cT

    def _free_difference(self, u: np.ndarray, v: np.ndarray, rows: bool = False) -> np.ndarray:
        """(u − v) over the free vertices: coordinate-major (3, f) from (3, n) arrays, or
        with ``rows`` vertex-major (f, 3) from (n, 3) arrays; a new array."""
        if self.runs is None:
            return u[self.free] - v[self.free] if rows else u[:, self.free] - v[:, self.free]
        out = np.empty((len(self.free), 3) if rows else (3, len(self.free)))
        for start, stop, offset in self.runs:
            if rows:
                np.subtract(u[start:stop], v[start:stop], out=out[offset:offset + stop - start])
            else:
                np.subtract(u[:, start:stop], v[:, start:stop],
                            out=out[:, offset:offset + stop - start])
        return out

    # -- the parts -------------------------------------------------------------------------
    @property
    def rhs(self) -> np.ndarray:
        return self._rhs

    @property
    def rhs_previous(self) -> np.ndarray:
        """rhs of the iterate before the current one (valid until the next advance)."""
        return self._rhs_next

    def current_directions(self):
        """The current iterate's d(x), built only when called (for :class:`Iterate`).

        Returns
        -------
        callable
            Returns d(x) [m], coordinate-major, shape (3, s); valid until the next move.
        """
        return self.dirs.current

    def _right_hand_side(self, eT: np.ndarray, out: np.ndarray) -> np.ndarray:
        np.copyto(out, self.cT)
        for c in range(3):
            spmv_add(self.h2J_F, eT[c], out[c])
        return out

    def solve(self) -> np.ndarray:
        """The global step from the current x, as a displacement.

        Returns
        -------
        ndarray, shape (3, f)
            δ̂ = A_FF⁻¹ rhs(x) [m], a new array; A_FF δ̂ = rhs(x) (:attr:`rhs`).
        """
        return self._solve_columns(self._rhs)

    def solve_columns(self, bT: np.ndarray) -> np.ndarray:
        """A_FF⁻¹ b with the cached factor (L-BFGS's H₀).

        Parameters
        ----------
        bT : ndarray, shape (3, f)
            Right-hand sides, coordinate-major [kg·m].

        Returns
        -------
        ndarray, shape (3, f)
            A_FF⁻¹ b [m], a new array.
        """
        return self._solve_columns(bT)

    def _place(self, deltaT: np.ndarray) -> np.ndarray:
        """x = y + δ over the free vertices of the spare buffer; returns the buffer."""
        xT = self._xT_spare
        if self.runs is None:
            np.add(self._yFT, deltaT, out=self._xFT)
            xT[:, self.free] = self._xFT
        else:
            yT = self.yT
            for start, stop, offset in self.runs:
                np.add(yT[:, start:stop], deltaT[:, offset:offset + stop - start],
                       out=xT[:, start:stop])
        return xT

    def _swap(self, deltaT: np.ndarray) -> None:
        self._xT, self._xT_spare = self._xT_spare, self._xT
        if self._first and self._x_fixed_T is not None:   # x_0's buffer: next holds x_2
            self._xT_spare[:, self.sysf.fixed] = self._x_fixed_T
        self._first = False
        self.x, self.delta = self._xT.T, deltaT

    def _local(self, length: np.ndarray | None = None,
               source: np.ndarray | None = None) -> None:
        """Local step at the current x (its spring vectors in eT or ``source``, their
        lengths if known) and its rhs."""
        self._right_hand_side(self.dirs.e_into(self._xT, self.eT, self.pyT, length, source),
                              self._rhs_next)
        self._rhs, self._rhs_next = self._rhs_next, self._rhs

    def advance(self, deltaT: np.ndarray) -> None:
        """Move to x = y + δ: local step there and rhs(x).

        Parameters
        ----------
        deltaT : ndarray, shape (3, f)
            δ_F [m]; kept as :attr:`delta` (not copied: do not write to it afterwards).
        """
        xT = self._place(deltaT)
        self._swap(deltaT)
        if self.energy:   # the spring vectors stay in _p for the next trial
            self.dirs.vectors_into(xT, self._p)
            np.einsum("ij,ij->j", self._p, self._p, out=self._l)
            np.sqrt(self._l, out=self._l)
            self._local(self._l, self._p)
        else:
            self.dirs.vectors_into(xT, self.eT)
            self._local()

    def tangential(self, vT: np.ndarray) -> np.ndarray:
        """``vT`` itself: without held contacts every direction is free
        (:class:`~.held_accel.HeldStep` projects onto the contact planes).

        Parameters
        ----------
        vT : ndarray, shape (3, f)

        Returns
        -------
        vT : ndarray, shape (3, f)
        """
        return vT

    def gradient(self, aT: np.ndarray, out: np.ndarray) -> np.ndarray:
        """∇g(x) over the free vertices from A_FF δ_F, without a product with A_FF.

        Parameters
        ----------
        aT : ndarray, shape (3, f)
            a = A_FF δ_F of the current x [kg·m] (carried by the caller).
        out : ndarray, shape (3, f)
            Receives a − rhs(x) [N·s²].

        Returns
        -------
        out : ndarray, shape (3, f)
        """
        return np.subtract(aT, self._rhs, out=out)

    def gradient_norm(self, aT: np.ndarray) -> float:
        """‖∇g(x)‖ over the free vertices (:meth:`gradient`).

        Parameters
        ----------
        aT : ndarray, shape (3, f)
            a = A_FF δ_F of the current x [kg·m] (carried by the caller).

        Returns
        -------
        float
            ‖∇g(x)‖ [N·s²]; ∇g itself is left in :attr:`grad`.
        """
        return _norm(self.gradient(aT, self.grad))
