"""Chebyshev, Anderson and L-BFGS on a step with held contacts (:mod:`.held`).

A held step's feasible set is affine: pins at their targets, each held vertex on its
contact plane(s) (a vertex on two or three planes moves along their intersection or not at
all). The three accelerations keep their iterates in it:

- **Chebyshev** and **Anderson** combine feasible points (the held local/global iterates
  G(x_j) = :meth:`HeldSystem.global_step` and earlier iterates) with weights that sum to 1,
  so each combination is feasible. Anderson keeps its energy safeguard: an extrapolation
  that does not lower g is replaced by G(x_k), which never raises it (block descent on ĝ
  over the feasible set).
- **L-BFGS** runs on the gradient on the set, P ∇g (:meth:`HeldSystem.gradient`), with
  the inverse of the constrained global-step matrix P A P + α D as initial Hessian: a
  tangential vector in gives a tangential vector out, so every pair s_j, t_j and every
  direction lies in the set's tangent space. Its Armijo search uses
  :func:`~.descent.objective_difference` along that direction.

Chebyshev's and Anderson's iterates are moved back onto the pins and planes
(:func:`~.held.feasible`): that only removes rounding (the combinations are feasible in exact
arithmetic). L-BFGS's are not: its step α p is exactly what its line search measured, p is
projected onto the tangent space, so the iterates leave the planes only by the rounding of
the steps (eps times the path length).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from .base import Iterate
from .descent import ARMIJO_C, MAX_HALVINGS, objective_difference
from .held import feasible, held_start


class _Point:
    """An iterate x with its local step d(x), b(d) − A y and P ∇g(x) (fixed rows zero)."""

    __slots__ = ("x", "d", "rhs", "grad", "norm")

    def __init__(self, solver, held, problem, x: np.ndarray):
        self.x = x
        self.d = solver.local_step(x)
        self.rhs = solver.displacement_right_hand_side(problem, self.d)
        grad = held.tangential(held.As @ (x - problem.y) - self.rhs)
        grad[held.fixed] = 0.0
        self.grad = grad
        self.norm = float(np.linalg.norm(grad))

    def iterate(self, k: int) -> Iterate:
        return Iterate(k, self.x, self.norm, d=self.d)


def _start(solver, problem, x0):
    held, x = held_start(solver, problem, x0)
    return held, _Point(solver, held, problem, x)


def chebyshev_iterates(solver, problem, x0=None):
    """Chebyshev-accelerated held local/global iterates (:class:`~.ChebyshevSolver`).

    x_{k+1} = ω_{k+1} (γ_k G(x_k) + (1 − γ_k) x_k) + (1 − ω_{k+1}) x_{k−1}: weights
    summing to 1, so the iterate stays on the planes. ρ is the solver's (estimated on the
    first step it solves); the held step's spectrum lies inside the unconstrained one's
    (a compression of the pencil (∇²g, A) to the tangent space), so that ρ is not an
    underestimate.

    Parameters
    ----------
    solver, problem, x0
        As for :func:`~.held.held_start`, ``solver`` a :class:`~.ChebyshevSolver`.

    Yields
    ------
    Iterate
        k, x_k (n, 3) [m], ‖P ∇g(x_k)‖ [N·s²] and d(x_k).
    """
    held, cur = _start(solver, problem, x0)
    yield cur.iterate(0)
    z, Az = held.prepare(problem)
    x_prev = cur.x
    gamma, delay, rho2 = solver.gamma, solver.delay, solver.shifted_rho ** 2
    omega, k = 1.0, 0
    while True:
        gx = held.global_step(problem, cur.rhs.copy(), z, Az)
        if k < delay:
            omega, g = 1.0, 1.0
        else:
            omega = 2.0 / (2.0 - rho2) if k == delay else 4.0 / (4.0 - rho2 * omega)
            g = gamma
        y = problem.y   # combined as displacements from y: no cancellation of coordinates
        new = y + (omega * g * (gx - y) + omega * (1.0 - g) * (cur.x - y)
                   + (1.0 - omega) * (x_prev - y))
        x_prev = cur.x
        cur = _Point(solver, held, problem, feasible(problem, new))
        k += 1
        yield cur.iterate(k)


def anderson_iterates(solver, problem, x0=None):
    """Anderson-accelerated held local/global iterates with the energy safeguard.

    θ = argmin ‖f_k − ΔF θ‖ over the window, f_j = G(x_j) − x_j; the candidate
    G(x_k) − ΔG θ (weights 1 − Σθ on G(x_k) and ±θ_j on earlier G: sum 1) is kept only
    when g decreases, else x_{k+1} = G(x_k) and the window restarts
    (:class:`~.AndersonSolver`). Returns when G(x) = x in floating point.

    Parameters
    ----------
    solver, problem, x0
        As for :func:`~.held.held_start`, ``solver`` a :class:`~.AndersonSolver`.

    Yields
    ------
    Iterate
        k, x_k (n, 3) [m], ‖P ∇g(x_k)‖ [N·s²] and d(x_k).
    """
    held, cur = _start(solver, problem, x0)
    model = solver.model
    yield cur.iterate(0)
    z, Az = held.prepare(problem)
    dF, dG = deque(maxlen=solver.window), deque(maxlen=solver.window)
    last = None   # (f, G(x)) of the previous iteration, while the window runs
    k = 0
    while True:
        gx = held.global_step(problem, cur.rhs.copy(), z, Az)
        f = (gx - cur.x).ravel()
        if not f.any():
            return  # a fixed point in floating point
        if last is not None:
            dF.append(f - last[0])
            dG.append(gx.ravel() - last[1])
        last = (f, gx.ravel())
        new = gx
        if dF:
            F = np.array(dF).T
            theta = np.linalg.lstsq(F, f, rcond=None)[0]
            cand = feasible(problem, gx - (theta @ np.array(dG)).reshape(gx.shape))
            # a non-finite candidate has a NaN or +inf difference, never < 0
            if objective_difference(model, problem, cur.x, cand - cur.x) < 0.0:
                new = cand
            else:
                solver.rejections += 1   # safeguard: the plain held iterate
                dF.clear()
                dG.clear()
                last = None
        cur = _Point(solver, held, problem, new)
        k += 1
        yield cur.iterate(k)


def lbfgs_iterates(solver, problem, x0=None):
    """L-BFGS on the held step's feasible set (:class:`~.LBFGSSolver`).

    Directions p = −H P ∇g(x_k) from the two-loop recursion (Nocedal and Wright Alg. 7.4)
    over pairs of tangential s_j and t_j = P ∇g(x_{j+1}) − P ∇g(x_j), with H₀ the inverse
    of the constrained global-step matrix on the tangent space (without pairs, p is the
    held local/global step from x_k with d = d(x_k)); backtracking Armijo on the exact
    energy difference. Returns when no step length along p decreases g.

    Parameters
    ----------
    solver, problem, x0
        As for :func:`~.held.held_start`, ``solver`` a :class:`~.LBFGSSolver`.

    Yields
    ------
    Iterate
        k, x_k (n, 3) [m], ‖P ∇g(x_k)‖ [N·s²] and d(x_k).
    """
    held, cur = _start(solver, problem, x0)
    model = solver.model
    yield cur.iterate(0)
    pairs: deque = deque(maxlen=solver.window)   # (s, t, 1 / sᵀt), flattened

    def h0(q):   # (P A P + α D)⁻¹ on tangential q, over the free vertices
        u = np.zeros_like(q)
        u[held.free] = held.factor.solve(q[held.free].reshape(-1)).reshape(-1, 3)
        return held.tangential(u)

    k = 0
    while True:
        q = cur.grad.ravel().copy()
        alphas = []
        for s, t, rho in reversed(pairs):
            a = rho * float(s @ q)
            q -= a * t
            alphas.append(a)
        r = h0(q.reshape(cur.grad.shape)).ravel()
        for (s, t, rho), a in zip(pairs, reversed(alphas)):
            r += (a - rho * float(t @ r)) * s
        # exactly tangential (to p's own rounding): a normal part of the s_j's rounding
        # (eps |x|, not eps |s|) times the contact force would swamp the slope deep down
        p = held.tangential(-r.reshape(cur.grad.shape))
        p[held.fixed] = 0.0
        slope = float(cur.grad.ravel() @ p.ravel())
        if not slope < 0.0:
            return  # no descent direction at working precision
        alpha = 1.0
        for _ in range(MAX_HALVINGS):
            if objective_difference(model, problem, cur.x, alpha * p) <= ARMIJO_C * alpha * slope:
                break
            alpha *= 0.5
        else:
            return  # no decrease at working precision: optimal to rounding
        # not re-held: x + α p is what the search measured (it drifts off the planes by
        # eps times the path length at most)
        new = _Point(solver, held, problem, cur.x + alpha * p)
        s = (new.x - cur.x).ravel()
        t = (new.grad - cur.grad).ravel()
        st = float(s @ t)
        if st > 0.0:   # skip negative curvature (buckling): H stays positive definite
            pairs.append((s, t, 1.0 / st))
        cur = new
        k += 1
        yield cur.iterate(k)
