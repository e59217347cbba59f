"""A certified reference solution x* per step problem, and the set of minima it belongs to.

Newton (:class:`~clothsim.solvers.NewtonSolver`, which never stops at a saddle) is run to its
rounding floor from y — the reference x* — and from further starts: x_n, and the point plain
local/global reaches (1e-6 relative residual, then Newton to the floor). Each end point is
*certified* when ‖∇g‖ is at its rounding floor and the free Hessian factors without shift
(λ_min > 0): a strict local minimum. The certificate reports

- whether x* is certified, and if not why (:attr:`CertifiedReference.at_floor`,
  :attr:`CertifiedReference.positive_definite`);
- the final relative residual ‖∇g(x*)‖ / ‖∇g(y)‖ and ‖∇g(x*)‖ over its rounding floor;
- the smallest eigenvalue of H = ∇²g(x*) divided by the smallest vertex mass (> 0: a
  strict local minimum; dense below 400 unknowns, else Lanczos/``eigsh``);
- the distinct certified minima the starts reached (:attr:`CertifiedReference.minima`):
  when they agree, their largest distance relative to ‖x* − x_n‖ is the reference's
  uncertainty; when they differ by more than :data:`SAME_POINT`, the step has several
  minima, and the lowest one, x_best, with g(y) − g(x_best) (computed from differences,
  without cancellation), defines the relative objective gap
  (g(x) − g(x_best)) / (g(y) − g(x_best)) by which any solver's answer is measured there.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..model import Model
from ..solvers import NewtonSolver, StepProblem, objective_gradient
from ..solvers.curvature import smallest_eigenvalue as eigenvalue_in_metric
from ..solvers.descent import objective_difference
from .runs import Stop, run_stops

SAME_POINT = 1e-6


REFERENCE_ITERATIONS = 200
"""Newton's iteration cap for a reference (more than any step has needed)."""
LOCAL_GLOBAL_CAP = 5000
"""Default iteration cap of the reference's local/global run (the study passes its own cap,
as for the other methods' own limits: 5000, ``--quick`` 1000)."""
LOCAL_GLOBAL_TOLERANCE = 1e-6
"""Relative residual at which that run stops (then Newton polishes)."""


@dataclass
class CertifiedReference:
    """x* of one step with its certificate (see the module text).

    Attributes
    ----------
    x : ndarray, shape (n, 3)
        Newton's solution from y [m].
    residual : float
        Final relative residual ‖∇g(x*)‖ / ‖∇g(y)‖.
    floor_ratio : float
        ‖∇g(x*)‖ over its rounding floor.
    min_eigenvalue : float
        Smallest eigenvalue of ∇²g(x*) / min mass (dimensionless; M alone gives 1). NaN if
        Lanczos did not converge.
    uncertainty : float
        ‖x* − x₂‖ / ‖x* − x_n‖ between the two starts (when they agree).
    two_minima : bool
        The starts reached several distinct certified minima.
    objective_difference : float
        g(x_best) − g(x*) [J·s²] (≤ 0; negative: another start found a lower minimum).
    certified : bool
        x* is a certified minimum (gradient at its floor, H ≻ 0).
    at_floor : bool
        Newton from y ended with ‖∇g‖ at its rounding floor.
    positive_definite : bool
        H(x*) factors without shift.
    minima : int
        Distinct certified minima reached from the starts.
    x_best : ndarray, shape (n, 3)
        The lowest certified minimum [m] (x* when it is the only one).
    objective_scale : float
        g(y) − g(x_best) [J·s²], the denominator of the relative objective gap.
    minimum_points : list of ndarray
        The distinct certified minima [m] (more are added by
        :func:`~clothsim.accuracy.limits.method_limits`: each method's own limit).
    local_global : NewtonResult or None
        Newton to the floor from converged local/global: local/global's own limit (reused
        by :func:`~clothsim.accuracy.limits.method_limits`).
    local_global_converged : bool
        Local/global reached its 1e-6 relative residual before that polish.
    local_global_runs : dict
        :class:`~.runs.Stop` → :class:`~.runs.Solve`: the iterates of that local/global run
        kept at the ``local_global_stops`` asked for (the study's local/global settings,
        read off this run instead of running them again).
    """

    x: np.ndarray
    residual: float
    floor_ratio: float
    min_eigenvalue: float
    uncertainty: float
    two_minima: bool
    objective_difference: float
    certified: bool = True
    at_floor: bool = True
    positive_definite: bool = True
    minima: int = 1
    x_best: np.ndarray | None = None
    objective_scale: float = math.nan
    minimum_points: list = field(default_factory=list)
    local_global: object = None
    local_global_converged: bool = False
    local_global_runs: dict = field(default_factory=dict)

    def objective_gap(self, model: Model, problem: StepProblem, x: np.ndarray) -> float:
        """(g(x) − g(x_best)) / (g(y) − g(x_best)), without cancellation.

        Parameters
        ----------
        model, problem : Model, StepProblem
            The step.
        x : ndarray, shape (n, 3)
            A solver's answer [m].

        Returns
        -------
        float
            0 at x_best, 1 at y (dimensionless; negative when x is lower than every
            certified minimum); inf when x is not finite.
        """
        best = self.x if self.x_best is None else self.x_best
        if not np.all(np.isfinite(x)):
            return math.inf
        scale = self.objective_scale
        if not (scale > 0):
            return math.nan
        return objective_difference(model, problem, best, x - best) / scale


def smallest_eigenvalue(newton: NewtonSolver, problem: StepProblem, x: np.ndarray) -> float:
    """Smallest eigenvalue of ∇²g(x) over free degrees of freedom / min vertex mass.

    ∇²g(x) = M + h² ∇²E(x); a negative value means g is not convex at x (buckling).

    Parameters
    ----------
    newton : NewtonSolver
        Builds the Hessian (:meth:`~clothsim.solvers.NewtonSolver.hessian`).
    problem : StepProblem
        The step (h, pins).
    x : ndarray, shape (n, 3)
        Where to evaluate [m].

    Returns
    -------
    float
        λ_min(∇²g) / min m_i (dimensionless; 1 for M alone); NaN when there is no free
        degree of freedom or ARPACK does not converge.
    """
    free = np.repeat(problem.free_mask(newton.model.vertex_count), 3)
    H = newton.hessian(problem, x)[free][:, free]
    m = float(newton.model.vertex_mass.min())
    mass = np.full(H.shape[0], m)  # λ(H) / m_min: the metric m_min I
    return eigenvalue_in_metric(H, mass)


def certified_reference(model: Model, problem: StepProblem, *, backend: str = "auto",
                        second_start: bool = True,
                        local_global_cap: int = LOCAL_GLOBAL_CAP,
                        local_global_stops: Sequence[Stop] = ()) -> CertifiedReference:
    """Newton to the rounding floor from y, certified, with the minima of other starts.

    Parameters
    ----------
    model : Model
        The cloth.
    problem : StepProblem
        The step.
    backend : {"auto", "cholmod", "splu"}
        Factorization backend.
    second_start : bool
        Also solve from x_n and from the converged local/global point (the uncertainty
        and several-minima checks).
    local_global_cap : int
        Iteration cap of that local/global run (to relative residual 1e-6).
    local_global_stops : sequence of Stop
        Iterates of that run to keep besides (:attr:`CertifiedReference.local_global_runs`;
        the run goes on until each is reached).

    Returns
    -------
    CertifiedReference
    """
    from dataclasses import replace

    from ..solvers.base import gradient_noise_floor

    def newton():
        return NewtonSolver(model, iterations=REFERENCE_ITERATIONS, tolerance=1e-15,
                            backend=backend)

    solver = newton()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = solver.solve(problem)
        x = res.x
        g_norm = float(np.linalg.norm(objective_gradient(model, problem, x)))
        floor = gradient_noise_floor(model, problem, x)
        scale = float(np.linalg.norm(x - problem.x)) or 1.0
        ends = [res]
        if second_start:
            x_n = replace(problem, start="x_n").initial_guess()
            ends.append(newton().solve(problem, x0=x_n))
            own = Stop(int(local_global_cap), LOCAL_GLOBAL_TOLERANCE)
            kept = list(dict.fromkeys([own, *local_global_stops]))
            lg_runs = dict(zip(kept, run_stops(model, problem, "local-global", {}, kept,
                                               backend)))
            lg_end = lg_runs[own]
            if lg_end.x is None:
                raise FloatingPointError("local/global blew up on the reference's step")
            ends.append(newton().solve(problem, x0=lg_end.x))
    minima = []  # distinct certified minima, x* first when certified
    for r in ends:
        if r.certified and all(float(np.linalg.norm(r.x - m)) / scale > SAME_POINT
                               for m in minima):
            minima.append(r.x)
    agree = [float(np.linalg.norm(r.x - x)) / scale for r in ends[1:]
             if r.certified and float(np.linalg.norm(r.x - x)) / scale <= SAME_POINT]
    dgs = [objective_difference(model, problem, x, m - x) for m in minima]
    i_best = int(np.argmin(dgs)) if minima else None
    x_best = minima[i_best] if minima else x
    y0 = problem.initial_guess()
    objective_scale = objective_difference(model, problem, x_best, y0 - x_best)
    several = len(minima) > 1
    return CertifiedReference(x, res.residual, g_norm / floor if floor > 0 else math.inf,
                              smallest_eigenvalue(solver, problem, x),
                              math.nan if several else max(agree, default=0.0), several,
                              dgs[i_best] if minima else 0.0, bool(res.certified),
                              bool(res.at_floor), bool(res.positive_definite), len(minima),
                              x_best, float(objective_scale), minima,
                              ends[2] if second_start else None,
                              bool(second_start and lg_end.converged),
                              lg_runs if second_start else {})
