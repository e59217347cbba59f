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

Each iteration costs one local step, one global step and one energy difference (plus one
extra global step when an accelerated iterate is rejected) and a least-squares problem
with m columns.

References
----------
Y. Peng, B. Deng, J. Zhang, F. Geng, W. Qin, L. Liu. Anderson Acceleration for Geometry
Optimization and Physics Simulation. ACM Transactions on Graphics 37(4), 42, 2018.
H. F. Walker, P. Ni. Anderson acceleration for fixed-point iterations. SIAM J. Numer.
Anal. 49(4), 2011.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator

import numpy as np

from ..errors import InputError
from ..model import Model
from .base import Iterate, StepProblem
from .descent import objective_difference
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
        sysf = self.system(problem)
        free = sysf.free
        x = problem.initial_guess() if x0 is None else np.array(x0, dtype=np.float64)
        d = self.local_step(x)
        k = 0
        yield Iterate(k, x, float(np.linalg.norm(self.gradient(problem, x, d))), d)
        gx = self.global_step(problem, d)
        dF: deque[np.ndarray] = deque(maxlen=self.window)
        dG: deque[np.ndarray] = deque(maxlen=self.window)
        f_prev = g_prev = None
        while True:
            f = (gx - x)[free].ravel()
            if not np.any(f):
                return  # a fixed point in floating point
            if f_prev is not None:
                dF.append(f - f_prev)
                dG.append((gx - g_prev)[free].ravel())
            f_prev, g_prev = f, gx
            x_new = gx
            if dF:
                F = np.column_stack(dF)
                theta = np.linalg.lstsq(F, f, rcond=None)[0]
                x_new = gx.copy()
                x_new[free] -= (np.column_stack(dG) @ theta).reshape(-1, 3)
                if not (np.all(np.isfinite(x_new))
                        and objective_difference(self.model, problem, x, x_new - x) < 0.0):
                    self.rejections += 1  # safeguard: take the plain local/global iterate
                    x_new = gx
                    dF.clear()
                    dG.clear()
                    f_prev = g_prev = None
            x = x_new
            d = self.local_step(x)
            k += 1
            yield Iterate(k, x, float(np.linalg.norm(self.gradient(problem, x, d))), d)
            gx = self.global_step(problem, d)
