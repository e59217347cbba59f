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
exactly coincident) and every :data:`RESYNC`-th after it, so the spring vectors are never
more than RESYNC additions (each one rounding of p) away from the positions' own.

Every iterate after x_0 has its exactly pinned vertices at their targets (the x_0 a caller
passes may not: its gradient is then computed from the definition; the default x_0 has
them there, and its gradient is the one product A_FF δ_F − rhs(x_0), about 7× cheaper than
the definition's spring gather at 129² and 257², docs/data/cpp-side-by-side.md).
"""

from __future__ import annotations

import math

import numpy as np

from ..factorization import spmv_add

#: :meth:`FusedStep.accept` gathers the spring vectors from the positions on the first
#: accepted move and every RESYNC-th after it; in between p' = p + Δp (trial)
RESYNC = 8


def _norm(aT: np.ndarray) -> float:
    flat = aT.reshape(-1)
    return math.sqrt(float(np.dot(flat, flat)))


class FusedStep:
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
        c = np.zeros_like(y) if problem.f_ext is None else h2 * problem.f_ext
        problem.anchors.add_rhs(c, h2, origin=y)
        cT[...] = c[free].T
        self.cT = cT
        x_fixed_T = None
        if len(fixed):
            x_pinned = x if x0 is None else problem.initial_guess()
            x_fixed_T = np.ascontiguousarray(x_pinned[fixed].T)
            cT -= (sysf.A_FP @ (x_pinned[fixed] - y[fixed])).T
        # free vertices as runs of consecutive indices: x_F = y_F + δ_F by slices
        self.runs = sysf.free_runs
        self.free = free
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
        self.delta = np.ascontiguousarray((x[free] - y[free]).T)
        if from_y:        # δ_F = 0 at x_0, so ∇g(x_0)_F = (A δ)_F − (b − A y)_F = −rhs_F
            self.a0 = np.zeros_like(self._rhs)
            self.norm0 = _norm(self._rhs)
        elif x0 is None:  # pins at their targets: ∇g(x_0)_F = A_FF δ_F − rhs_F, one product
            dT = np.zeros_like(xT)           # (A δ̃)_F with δ̃ zero on the pins is A_FF δ_F
            dT[:, free] = self.delta
            self.a0 = np.ascontiguousarray((sysf.A @ dT.T)[free].T)
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

    # -- energy differences (Anderson, L-BFGS) ---------------------------------------------
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
        # spring ends of all three coordinates at once, in (3, n) arrays read flat
        n = self.yT.shape[1]
        shift = (np.arange(3) * n)[:, None]
        self._a3 = np.ascontiguousarray((self.dirs.a[None, :] + shift).reshape(-1))
        self._b3 = np.ascontiguousarray((self.dirs.b[None, :] + shift).reshape(-1))
        self._tmp = np.empty(self.eT.size)
        self._accepted = 0
        self._w = self._tmp.reshape(self.eT.shape)       # p + p' (after the gathers)
        self._s, self._num = np.empty(len(self._k)), np.empty(len(self._k))
        self._mv = np.empty((3, len(self._mF)))
        if self.runs is not None:   # Δx over the free vertices: views of its runs
            self._dx_runs = [self._dxT[:, start:stop] for start, stop, _ in self.runs]
            self._dxF = np.empty_like(self._mv)

    def _vectors(self, xT: np.ndarray, pT: np.ndarray) -> None:
        """p = x_a − x_b into pT, all coordinates in two takes (as SpringDirections does)."""
        flat, out = xT.reshape(-1), pT.reshape(-1)
        flat.take(self._a3, out=out, mode="clip")
        flat.take(self._b3, out=self._tmp, mode="clip")
        np.subtract(out, self._tmp, out=out)

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
        self._vectors(dxT, dp)
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
            self._vectors(self._xT, self._p)
            np.einsum("ij,ij->j", self._p, self._p, out=self._l)
            np.sqrt(self._l, out=self._l)
        self._local(self._l, self._p)
