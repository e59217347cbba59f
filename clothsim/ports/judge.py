"""Judging one step whose two answers differ (the verdicts of :mod:`clothsim.ports.verdicts`).

The questions, in order: is the port's answer optimal for clothsim's g (relative gradient)?
If so, do the two answers lead to the same minimizer, or to two certified minima (a
positive definite Hessian at each: Newton on buckling cloth can end at a saddle)? If not,
is clothsim's own answer optimal? A fixed iteration count that stops short leaves both
answers unconverged, and then the answer depends on where the iteration starts: the port is
not blamed, and the settings that reproduce it (start point, iteration count) are searched
for along clothsim's own iterations. Two unconverged answers whose gradients differ mostly
at one vertex differ by a local error there, not by their start: that vertex is named.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import FactorizationError
from ..factorization import Factor
from ..objective import gradient_noise_floor, objective, objective_gradient
from ..solvers.local_global import LocalGlobalSolver
from ..solvers.newton import NewtonSolver
from .compare import EPS32, cloth_size
from .flat import flat_evidence
from .verdicts import StepCheck

#: Longest iteration path searched for the port's answer (start y and x_n each).
MAX_SEARCH = 1000
#: A port whose relative gradient is below this, for a converged clothsim step, is on its
#: way to clothsim's minimizer ("not converged") rather than solving another problem.
CONVERGING = 1e-3
#: When one vertex carries more than this share of ‖∇g(x_port) − ∇g(x_clothsim)‖, the two
#: unconverged answers differ by a local error there, not by where the iteration started.
LOCAL = 0.5


def pin_role(problem, v: int) -> str:
    """How vertex ``v`` is held in the step: "pinned exactly", "pinned by a … N/m penalty".

    Parameters
    ----------
    problem : StepProblem
    v : int

    Returns
    -------
    str
        "" when the vertex is free.
    """
    if np.any(problem.fixed_vertices == v):
        return "pinned exactly"
    k = problem.anchor_stiffness[problem.anchor_vertices == v]
    return f"pinned by a {float(k.sum()):.3g} N/m penalty" if len(k) else ""


def pinned_moved(problem, x_port: np.ndarray, tol: float):
    """The exactly pinned vertex farthest from its target in the port's answer, if > tol.

    Parameters
    ----------
    problem : StepProblem
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    tol : float
        Allowed distance [m].

    Returns
    -------
    (int, float) or None
        The vertex and its distance from the target [m].
    """
    fv = problem.fixed_vertices
    if not len(fv):
        return None
    d = np.linalg.norm(x_port[fv] - problem.fixed_positions, axis=1)
    d = np.where(np.isfinite(d), d, np.inf)
    i = int(np.argmax(d))
    return (int(fv[i]), float(d[i])) if d[i] > tol else None


def refine(model, problem, x):
    """Newton's method from ``x`` to a stationary point of g (relative gradient 1e-13).

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3)
        Start [m].

    Returns
    -------
    ndarray, shape (n, 3)
        The stationary point Newton's method reaches [m].
    """
    return NewtonSolver(model, iterations=100, tolerance=1e-13).solve(problem, x).x


def is_minimum(model, problem, x) -> bool:
    """True when ∇²g(x) over the free vertices is positive definite (a Cholesky succeeds).

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x : ndarray, shape (n, 3)
        A stationary point of g [m].

    Returns
    -------
    bool
    """
    H = NewtonSolver(model).hessian(problem, x)
    free = np.setdiff1d(np.arange(model.vertex_count), problem.fixed_vertices)
    dofs = (3 * free[:, None] + np.arange(3)).ravel()
    try:
        Factor(H[dofs][:, dofs], check_conditioning=False)
    except FactorizationError:
        return False
    return True


def match_settings(sim, model, problem, x_port, tol):
    """Search clothsim's own iterations from y and from x_n for the port's answer.

    Parameters
    ----------
    sim : Simulation
        Supplies the iteration count K (the search runs max(2K, 100) ≤ 1000 iterations).
    model : Model
        The step's model (damping folded in).
    problem : StepProblem
    x_port : ndarray, shape (n, 3)
        The port's answer [m].
    tol : float
        Distance [m] counted as a match.

    Returns
    -------
    (str, int, float) or None
        Start ("y" or "x_n"), iteration count and distance [m] of the first match.
    """
    count = min(MAX_SEARCH, max(2 * sim.solver.iterations, 100))
    solver = LocalGlobalSolver(model, iterations=count)
    for start in ("y", "x_n"):
        p = dataclasses.replace(problem, start=start)
        for it in solver.iterates(p):
            dist = float(np.linalg.norm(it.x - x_port, axis=1).max())
            if dist <= tol:
                return start, it.k, dist
            if it.k >= count:      # the iteration is endless: stop at the search's length
                break
    return None


def _settings_text(start, k) -> str:
    return f'[solver] initial_guess = "{start}" and iterations = {k}'


def gradient_scale(model, problem, x_port, optimality, precision, unit=None):
    """‖∇g(x₀)‖ of the step (what relative gradients refer to) and the optimality tolerance.

    Parameters
    ----------
    model : Model
    problem : StepProblem
    x_port : ndarray, shape (n, 3)
        The port's answer [m] (sets the rounding floor).
    optimality : float
        The relative gradient asked for.
    precision : {"float64", "float32"}
    unit : float, optional
        Relative rounding of the port's printed numbers when coarser than its precision.

    Returns
    -------
    (float, float)
        ‖∇g(x₀)‖ [N·s²] (1 when it is 0) and max(optimality, 10 × the rounding floor of
        ‖∇g‖ relative to it: ε₆₄-, ε₃₂- or ``unit``-based).
    """
    g0 = float(np.linalg.norm(objective_gradient(model, problem, problem.initial_guess())))
    g0 = g0 if g0 > 0 else 1.0
    floor = gradient_noise_floor(model, problem, x_port) / g0
    eps64 = float(np.finfo(np.float64).eps)
    floor *= max(unit or 0.0, EPS32 if precision == "float32" else eps64) / eps64
    return g0, max(optimality, 10 * floor)


def judge(sim, model, problem, k, x_cs, x_port, err, tol, optimality, precision,
          search: bool = True, unit: float | None = None) -> StepCheck:
    """Classify a step whose answers differ by more than ``tol`` somewhere.

    Parameters
    ----------
    sim : Simulation
        The checking simulation (its solver's iteration count and tolerance).
    model : Model
        The step's model.
    problem : StepProblem
    k : int
        The step k → k + 1.
    x_cs, x_port : ndarray, shape (n, 3)
        clothsim's and the port's x_{k+1} [m].
    err : ndarray, shape (n,)
        |x_cs − x_port| per vertex [m].
    tol : float
        Tolerance [m].
    optimality : float
        Relative gradient counted as a minimizer (raised to 10 × the rounding floor).
    precision : {"float64", "float32"}
    search : bool, default True
        Search clothsim's iterations for the port's settings (:func:`match_settings`).
    unit : float, optional
        Relative rounding of the port's numbers when they are printed coarser than its
        precision (:class:`clothsim.ports.precision.Printed`): the gradient's rounding
        floor scales with it.

    Returns
    -------
    StepCheck
    """
    g0, opt = gradient_scale(model, problem, x_port, optimality, precision, unit)
    grad_p = objective_gradient(model, problem, x_port)
    grad_c = objective_gradient(model, problem, x_cs)
    rp = float(np.linalg.norm(grad_p)) / g0
    rc = float(np.linalg.norm(grad_c)) / g0
    worst = int(np.argmax(err))
    settings = ""

    def verdict(status, vertex, note):
        return StepCheck(k, status, float(err[worst]), int(vertex), rp, rc, note,
                         tolerance=tol, settings=settings)

    if not np.isfinite(rp):
        return verdict("not a minimizer", worst, "the port's positions are not finite")
    # a criterion raised to the printing's rounding that takes clothsim's own stopped-short
    # answer (rc above the stated optimality) for a minimizer too is blind to optimality
    if rp <= opt and not optimality < rc <= opt:
        return _optimal(model, problem, x_cs, x_port, tol, verdict, worst,
                        (rp, optimality, opt, g0))
    hint = match_settings(sim, model, problem, x_port, tol) if search else None
    if hint is not None and hint[1] == 0:   # iterations = 0 is no setting clothsim takes
        return verdict("not a minimizer", worst, f"the port's answer is its start point "
                       f"{hint[0]} itself ({hint[2]:.1e} m): its solve does not move the cloth")
    settings = _settings_text(*hint[:2]) if hint is not None else ""
    # the gradient difference as a displacement (over the Hessian's diagonal, where a
    # 1e10 N/m pin turns 1e-10 m into newtons); a vertex within the tolerance is no evidence
    excess = np.where(err > tol, np.linalg.norm(grad_p - grad_c, axis=1)
                      / hessian_diagonal(model, problem), 0.0)
    vertex = int(np.argmax(excess))
    total = float(np.linalg.norm(excess))
    local = total > 0 and excess[vertex] > LOCAL * total
    if rc > opt and (hint is not None or (rp <= 10 * rc and not local)):
        if hint is not None:
            note = (f"neither answer is a minimizer of g; the port's is clothsim's from "
                    f"{hint[0]} after {hint[1]} iterations ({hint[2]:.1e} m): set "
                    f"{_settings_text(hint[0], hint[1])}")
        elif search:   # the settings were searched: no start or count of clothsim's gives it
            note = (f"neither answer is a minimizer of g, and clothsim's local/global "
                    f"iterations from y and from x_n (1 to "
                    f"{min(MAX_SEARCH, max(2 * sim.solver.iterations, 100))}) never come within "
                    f"the tolerance of the port's answer: the port iterates otherwise or "
                    f"solves another model; converge both (a tolerance) to decide")
        else:
            note = (f"neither answer is a minimizer of g, and the answer of a fixed iteration "
                    f"count depends on its start point: match the port's settings "
                    f"([solver] initial_guess, now \"{problem.start}\"; iterations, now "
                    f"{sim.solver.iterations}) or converge both (a tolerance)")
        return verdict("start-dependent", worst, note)
    if hint is not None:
        return verdict("not converged", worst, f"the port's answer is clothsim's from {hint[0]} "
                       f"after {hint[1]} iterations ({hint[2]:.1e} m), short of the minimizer: "
                       f"raise the port's iterations, or check with "
                       f"{_settings_text(hint[0], hint[1])}")
    if rc <= opt and rp < CONVERGING:
        return verdict("not converged", worst, f"the port's relative gradient {rp:.1e} is "
                       f"above {opt:.1e}: it stops short of the minimizer; raise its "
                       f"iterations or tighten its tolerance")
    if (rc <= opt and rp < 1 and not local and _descends(model, problem, x_port)
            and _approaches(problem, x_port, x_cs)):
        return verdict("not converged", worst, f"the port's answer lowers g below its start "
                       f"and its gradient to {rp:.1e} of the start's, but stops short of the "
                       f"minimizer: raise its iterations (if it is converged by its own "
                       f"measure, it solves another problem: clothsim diff-model)")
    if rc <= opt and np.mean(err > tol) > 0.5:   # "model differs" only for a converged step
        moved = np.linalg.norm(refine(model, problem, x_port) - x_port, axis=1)
        spread = float(np.mean(moved > max(tol, 0.01 * moved.max())))
        if spread > 0.5:
            return verdict("model differs", worst, f"{np.mean(err > tol):.0%} of the vertices "
                           f"disagree and the minimizer of clothsim's g nearest to the port's "
                           f"answer differs from it at {spread:.0%} of the vertices: compare "
                           f"the models (clothsim diff-model)")
    note = (f"largest gradient difference at vertex {vertex}: |grad g| = "
            f"{np.linalg.norm(grad_p[vertex]):.3e} there")
    role = pin_role(problem, vertex)
    if role.startswith("pinned by"):
        j = np.flatnonzero(problem.anchor_vertices == vertex)[0]
        q = problem.anchor_positions[j]
        away_p, away_c = (np.linalg.norm(x[vertex] - q) for x in (x_port, x_cs))
        note += (f"; {role} in the scene: the port holds it {away_p:.3e} m from its target, "
                 f"clothsim {away_c:.3e} m (a port whose pin is missing or of another "
                 f"stiffness)")
    return verdict("not a minimizer", worst, note)


def hessian_diagonal(model, problem) -> np.ndarray:
    """m_v + h² (Σ k of v's springs + its pins' k): ∇²g's diagonal per vertex.

    Parameters
    ----------
    model : Model
    problem : StepProblem

    Returns
    -------
    ndarray, shape (n,)
        [kg]; the gradient difference over it is a displacement [m].
    """
    n = model.vertex_count
    a, b = model.springs.spring_vertices.T
    k = model.springs.spring_stiffness
    d = np.bincount(a, k, n) + np.bincount(b, k, n)
    d += np.bincount(problem.anchor_vertices, problem.anchor_stiffness, n)
    return model.vertex_mass + problem.h ** 2 * d + 1e-300


def _approaches(problem, x_port, x_cs) -> bool:
    """The port's answer nearer clothsim's than the step's start is: an iteration towards it."""
    return bool(np.linalg.norm(x_port - x_cs) < np.linalg.norm(problem.initial_guess() - x_cs))


def _descends(model, problem, x_port) -> bool:
    """g(x_port) below g at the step's start (an iteration of the same g has made progress)."""
    return bool(objective(model, problem, x_port)
                < objective(model, problem, problem.initial_guess()))


def _optimal(model, problem, x_cs, x_port, tol, verdict, worst, gradient) -> StepCheck:
    """The port's answer is optimal: same minimizer, two certified minima, or a saddle.

    ``gradient`` is (the port's relative gradient, the stated optimality, the optimality
    raised to the rounding floor, ‖∇g(x_0)‖). Off the minimizer by more than ``tol``, an
    answer that meets the stated optimality is "ill-conditioned" (undecided, with the
    evidence of :mod:`clothsim.ports.flat`); one that meets only the rounding floor of ∇g
    (a float32 port, whose gradient cannot resolve the distance) is "not converged".
    """
    xp, xc = refine(model, problem, x_port), refine(model, problem, x_cs)
    gap = float(np.linalg.norm(xp - xc, axis=1).max())
    off = float(np.linalg.norm(x_port - xp, axis=1).max())
    if gap <= max(tol, 1e-9 * cloth_size(x_port)):
        if off <= tol:
            return verdict("agrees", worst, "the port's answer is within the tolerance of the "
                           "minimizer of g that clothsim's answer converges to (another "
                           "stopping rule)")
        rp, stated, opt, g0 = gradient
        if rp <= stated:
            return verdict("ill-conditioned", worst,
                           flat_evidence(model, problem, x_port, xp, g0, rp, tol))
        return verdict("not converged", worst, f"its relative gradient {rp:.1e} is within the "
                       f"rounding floor of the gradient at this precision ({opt:.1e}), which "
                       f"therefore cannot judge it; it is {off:.3e} m from the minimizer, "
                       f"beyond the tolerance {tol:.3e} m: raise its iterations or tighten its "
                       f"tolerance")
    if not is_minimum(model, problem, xp):
        return verdict("not a minimizer", worst, "the port's answer leads to a saddle point of "
                       "g (an indefinite Hessian), not a minimum")
    gp, gc = objective(model, problem, xp), objective(model, problem, xc)
    lower = "the port's" if gp < gc else "clothsim's"
    other = ("two certified minima" if is_minimum(model, problem, xc)
             else "the port's a certified minimum, clothsim's a saddle")
    return verdict("non-unique", worst, f"different but both optimal: {other} {gap:.3e} m "
                   f"apart, g = {gp:.9g} (port) vs {gc:.9g} (clothsim); {lower} is lower")
