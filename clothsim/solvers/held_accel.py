"""Chebyshev, Anderson and L-BFGS on a step with held contacts (:mod:`.held`), fused.

A held step's feasible set is affine: pins at their targets, each held vertex on its
contact plane(s) (a vertex on two or three planes moves along their intersection or not at
all). :class:`HeldStep` is the fused iteration of :mod:`.fused` on that set, so the three
accelerations run their unconstrained loops unchanged (one local step and one global step
per iteration, the gradient without a product with A, no allocation per iteration beyond
the global step's):

- the global step is :meth:`HeldSystem.global_step <.held.HeldSystem.global_step>`
  (x = y + z + P u, (P A P + α D) u = P (rhs − A z)), returned as the displacement δ̂ over
  the free vertices;
- the gradient on the set is P ∇g = P (A δ − rhs(x)). For a global step's δ̂,
  P A δ̂ = P rhs(x_k) (P A P u = P (rhs − A z), as D u = 0), so the loops' bookkeeping
  a = A δ of :mod:`.fused` (the right-hand side of each solve, combined with the iterates'
  weights) gives P ∇g with one projection of a − rhs, exactly as without contacts;
- L-BFGS's initial Hessian is (P A P + α D)⁻¹ on tangential vectors
  (:meth:`HeldStep.solve_columns`): a tangential vector in gives a tangential vector out,
  and its loop projects each direction onto the tangent space (:meth:`HeldStep.tangential`),
  so every pair s_j, t_j and every direction lies in it and the Armijo search measures
  exactly the step it takes.

Chebyshev and Anderson combine feasible points with weights that sum to 1, so each
combination is feasible up to the rounding of the combination; their iterates are not
projected back (the normal components of the rounding stay bounded: the Chebyshev
recurrence contracts them, and Anderson's safeguard falls back to a global step, which is
feasible to rounding). L-BFGS's iterates leave the planes only by the rounding of its steps.
"""

from __future__ import annotations

import math

import numpy as np

from .fused import FusedStep
from .held import held_start


class HeldStep(FusedStep):
    """:class:`~.fused.FusedStep` on a step with held contacts (module text).

    Parameters
    ----------
    solver : LocalGlobalSolver
        Gives the cached factors (the held-contact system of the step's contact set,
        :func:`~.held.held_start`), the spring directions and the work buffers.
    problem : StepProblem
        A step whose :attr:`~clothsim.problem.StepProblem.has_contacts`.
    x0 : ndarray, shape (n, 3), optional
        Initial guess [m]; moved onto the pins and contact planes. Default
        :meth:`StepProblem.initial_guess`.
    energy : bool, default False
        As for :class:`~.fused.FusedStep`.

    Attributes
    ----------
    held : HeldSystem
        The global step's system for this contact set.
    norm0 : float
        ‖P ∇g(x_0)‖ over the free vertices [N·s²].
    """

    def __init__(self, solver, problem, x0: np.ndarray | None = None, *,
                 energy: bool = False):
        held, x = held_start(solver, problem, x0)
        super().__init__(solver, problem, x, energy=energy)
        self.held = held
        self.z, self.Az = held.prepare(problem)
        sysf = self.sysf
        # global_step takes b(d) − A y over all rows; the fused rhs is (b − A y)_F − A_FP z_P
        self._coupling = sysf.A_FP @ self.z[sysf.fixed] if len(sysf.fixed) else None
        self._rhs_n = np.zeros_like(problem.y)
        self._held_pos = np.searchsorted(self.free, held.held)   # held vertices among F
        self._blocks = held.blocks                               # their 3 x 3 blocks of P
        self._A_FF = held.A_FF
        g = self.gradient(self.a0, np.empty_like(self.a0)).reshape(-1)
        self.norm0 = math.sqrt(float(np.dot(g, g)))

    def tangential(self, vT: np.ndarray) -> np.ndarray:
        """P applied at the held vertices, in place.

        Parameters
        ----------
        vT : ndarray, shape (3, f)
            A vector over the free vertices, coordinate-major.

        Returns
        -------
        vT : ndarray, shape (3, f)
            The same array, without its constrained components.
        """
        p = self._held_pos
        vT[:, p] = np.einsum("vij,jv->iv", self._blocks, vT[:, p])
        return vT

    def solve(self) -> np.ndarray:
        """The held global step from the current x, as a displacement.

        Returns
        -------
        ndarray, shape (3, f)
            δ̂ = x̂_F − y_F [m], x̂ on the pins and planes; P A_FF δ̂ = P rhs(x).
        """
        if self._coupling is None:   # no pins: every row is free
            x = self.held.global_step(self.problem, self._rhs.T, self.z, self.Az)
            return np.subtract(x.T, self.yT)
        rhs_n = self._rhs_n
        rhs_n[self.free] = self._rhs.T
        rhs_n[self.free] += self._coupling
        x = self.held.global_step(self.problem, rhs_n, self.z, self.Az)
        return np.ascontiguousarray((x[self.free] - self.problem.y[self.free]).T)

    def solve_columns(self, bT: np.ndarray) -> np.ndarray:
        """(P A P + α D)⁻¹ b over the free vertices, tangential (L-BFGS's H₀).

        Parameters
        ----------
        bT : ndarray, shape (3, f)
            A tangential right-hand side, coordinate-major [kg·m].

        Returns
        -------
        ndarray, shape (3, f)
            The solution [m], a new array, projected onto the tangent space.
        """
        r = np.zeros_like(self.problem.y)
        r[self.free] = bT.T
        return self.tangential(np.ascontiguousarray(self.held.solve(r)[self.free].T))

    def gradient(self, aT: np.ndarray, out: np.ndarray) -> np.ndarray:
        """P ∇g(x) over the free vertices, from the current δ (``aT`` is not read).

        The carried a of the loops is right in exact arithmetic (module text), but the held
        global step's δ̂ comes from absolute positions, so its rounding would build up in a
        over thousands of iterations and stall a deep solve (L-BFGS at 1e-9); one product
        with A_FF (a fraction of the held solve's cost) keeps the gradient exact.

        Parameters
        ----------
        aT : ndarray, shape (3, f)
            Unused (the loops' carried A_FF δ_F).
        out : ndarray, shape (3, f)
            Receives P (A_FF δ_F − rhs(x)) [N·s²].

        Returns
        -------
        out : ndarray, shape (3, f)
        """
        np.subtract((self._A_FF @ self.delta.T).T, self._rhs, out=out)
        return self.tangential(out)


def fused_step(solver, problem, x0: np.ndarray | None = None, *,
               energy: bool = False) -> FusedStep:
    """The fused iteration of a step: :class:`HeldStep` when it holds contacts, else
    :class:`~.fused.FusedStep`.

    Parameters
    ----------
    solver, problem, x0, energy
        As for :class:`~.fused.FusedStep`.

    Returns
    -------
    FusedStep
    """
    cls = HeldStep if problem.has_contacts else FusedStep
    return cls(solver, problem, x0, energy=energy)
