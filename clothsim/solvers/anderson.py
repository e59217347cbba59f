"""Local/global iterations with Anderson acceleration and an energy safeguard.

Local/global is a fixed-point iteration x ↦ G(x) (one local step, one global step).
Anderson acceleration (type II, window m) extrapolates from the last m + 1 iterates: with
residuals f_j = G(x_j) − x_j and the differences ΔF = [f_{j+1} − f_j], ΔG = [G(x_{j+1}) −
G(x_j)] over the window,

    θ = argmin_θ ‖f_k − ΔF θ‖,    x_{k+1} = G(x_k) − ΔG θ.

The extrapolated point can increase g. Peng et al. (2018) guard it with the energy: an
accelerated iterate is accepted only when g decreased; otherwise the plain local/global
iterate G(x_prev) — which never increases g — is taken and the window restarts. The
comparison uses :func:`~clothsim.solvers.descent.objective_difference`, computed from the
displacement and spring-length changes, so the guard still decides correctly at relative
residuals far below 1e-8 (two evaluations of g would compare rounding noise there).

Each iteration runs on local/global's fused iteration (:class:`~.fused.FusedStep`): one
local step, one solve, one energy difference from the spring vectors the next local step
needs anyway (plus one more local step when an accelerated iterate is rejected) and a
least-squares problem with m columns; ‖∇g‖ comes for free, as A_FF of an extrapolation is
the same extrapolation of the right-hand sides.

References
----------
Y. Peng, B. Deng, J. Zhang, F. Geng, W. Qin, L. Liu. Anderson Acceleration for Geometry
Optimization and Physics Simulation. ACM Transactions on Graphics 37(4), 42, 2018.
H. F. Walker, P. Ni. Anderson acceleration for fixed-point iterations. SIAM J. Numer.
Anal. 49(4), 2011.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator

import numpy as np

from ..errors import InputError
from ..model import Model
from .base import Iterate, StepProblem
from .held_accel import fused_step
from .local_global import LocalGlobalSolver


class AndersonSolver(LocalGlobalSolver):
    """Anderson-accelerated local/global iterations (Peng et al. 2018).

    Parameters
    ----------
    model : Model
    iterations : int, default 10
        Iterations per step; the maximum when ``tolerance`` is set.
    tolerance : float, optional
        Stop once ‖∇g(x_k)‖ / ‖∇g(x_0)‖ is at most this.
    window : int, default 6
        m: how many past differences enter the extrapolation (Peng et al. use 5–10).
    backend : {"auto", "cholmod", "splu"}
        Sparse factorization of M + h² L (:class:`~clothsim.factorization.Factor`).
    check_conditioning : bool, default True
        Warn when a new factor's condition estimate passes 1e12.

    Attributes
    ----------
    rejections : int
        Accelerated iterates rejected by the energy safeguard (over the solver's life).
    window : int
        m, as given.
    """

    name = "anderson"

    def __init__(self, model: Model, *, iterations: int = 10, tolerance: float | None = None,
                 backend: str = "auto", check_conditioning: bool = True, window: int = 6):
        super().__init__(model, iterations=iterations, tolerance=tolerance, backend=backend,
                         check_conditioning=check_conditioning)
        if not isinstance(window, (int, np.integer)) or window < 1:
            raise InputError(f"solver.window: must be an integer >= 1, got {window!r}")
        self.window = int(window)
        self.rejections = 0

    def iterates(self, problem: StepProblem, x0: np.ndarray | None = None) -> Iterator[Iterate]:
        """Yield the initial guess, then each accepted iterate, g never increasing.

        With f_j = G(x_j) − x_j over the free vertices, each iteration solves
        θ = argmin ‖f_k − ΔF θ‖ and proposes x_{k+1} = G(x_k) − ΔG θ (Peng et al. 2018,
        type II); it is kept only when g(x_{k+1}) < g(x_k), else x_{k+1} = G(x_k) and the
        window restarts. Returns when G(x) = x in floating point (nothing left to improve).

        Parameters
        ----------
        problem : StepProblem
            The step's h [s], y [m], f_ext [N] and pins.
        x0 : ndarray, shape (n, 3), optional
            Initial guess [m]; default y with the pins applied.

        Yields
        ------
        Iterate
            k, x of shape (n, 3) [m] (the solver's array: copy it to keep it) and
            ‖∇g(x)‖ over the free degrees of freedom [N·s²].
        """
        step = fused_step(self, problem, x0, energy=True)   # held contacts: .held_accel
        yield Iterate(0, step.x, step.norm0, d=step.current_directions())
        shape, m = step.delta.shape, step.delta.size
        # in δ = x − y over the free vertices, coordinate-major; each point is kept as the
        # row [δ | a] with a = A_FF δ: G(x_j) = y + δ̂_j has a = rhs(x_j), and the
        # extrapolation combines rows, so ‖∇g‖ = ‖a − rhs(x)‖ comes for free (fused.py)
        window = _Window(self.window, m)
        # preallocated rows, two of each in turn: f and [δ̂ | rhs] of this iteration and
        # the last; the candidate's row (its δ part becomes step.delta when accepted, so
        # the next candidate goes to the other buffer)
        fs, gs, cands = np.empty((2, m)), np.empty((2, 2 * m)), np.empty((2, 2 * m))
        have_prev = False
        k = 0
        while True:
            delta_hat = step.solve()
            f, gx, cand = fs[k % 2], gs[k % 2], cands[k % 2]
            np.subtract(delta_hat.reshape(-1), step.delta.reshape(-1), out=f)
            if not np.dot(f, f) and not f.any():
                return  # a fixed point in floating point
            gx[:m] = delta_hat.reshape(-1)
            gx[m:] = step.rhs.reshape(-1)
            if have_prev:
                window.append(f, fs[1 - k % 2], gx, gs[1 - k % 2])
            have_prev = True
            new = gx
            if window.count:
                np.subtract(gx, window.extrapolation(f), out=cand)
                # a non-finite candidate needs no check of its own: its energy difference
                # is then +inf or NaN (the mass term ½ m Δx (δ + δ') is), never < 0
                accept = step.trial(cand[:m].reshape(shape)) < 0.0
                if accept if self.decisions is None else self.decisions(accept):
                    step.accept()
                    new = cand
                else:
                    self.rejections += 1  # safeguard: take the plain local/global iterate
                    window.clear()
                    have_prev = False
            if new is gx:
                step.advance(delta_hat)
            k += 1
            yield Iterate(k, step.x, step.gradient_norm(new[m:].reshape(shape)),
                          d=step.current_directions())


@functools.cache
def _posv():
    """LAPACK's dposv (scipy.linalg loads on first use: a run without Anderson skips it)."""
    from scipy.linalg import lapack
    return lapack.get_lapack_funcs("posv", dtype=np.float64)


class _Window:
    """The last m differences ΔF (rows of length M) and ΔG, with their Gram matrix ΔFᵀΔF.

    θ = argmin ‖f − ΔF θ‖ from the normal equations (ΔFᵀΔF) θ = ΔFᵀ f, the Gram matrix
    updated by one row per new difference (m dot products instead of a QR or SVD of the
    M × m matrix each iteration); a singular or non-finite solve falls back to lstsq.
    """

    def __init__(self, size: int, length: int):
        self.size, self.count, self.head = size, 0, 0
        self.F = np.empty((size, length))
        self.G = np.empty((size, 2 * length))
        self.gram = np.empty((size, size))
        self._out = np.empty(2 * length)

    def clear(self) -> None:
        self.count = self.head = 0

    def append(self, f, f_prev, g, g_prev) -> None:
        """Keep ΔF = f − f_prev and ΔG = g − g_prev (dropping the oldest when full)."""
        slot = self.head
        np.subtract(f, f_prev, out=self.F[slot])
        np.subtract(g, g_prev, out=self.G[slot])
        self.count = min(self.count + 1, self.size)
        row = self.F[:self.count] @ self.F[slot]
        self.gram[slot, :self.count] = row
        self.gram[:self.count, slot] = row
        self.head = (slot + 1) % self.size

    def extrapolation(self, f: np.ndarray) -> np.ndarray:
        """ΔG θ with θ = argmin ‖f − ΔF θ‖ (rows of ΔG: [Δδ | ΔA δ])."""
        n = self.count
        F = self.F[:n]
        _, theta, info = _posv()(self.gram[:n, :n], F @ f)   # Cholesky of the Gram matrix
        if info != 0 or not np.all(np.isfinite(theta)):    # singular: least squares
            theta = np.linalg.lstsq(F.T, f, rcond=None)[0]
        return np.dot(theta, self.G[:n], out=self._out)
