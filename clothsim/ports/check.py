"""The per-step checker: is each of a port's steps the step clothsim takes from the same state?

For every frame k the port's state (x_k, v_k) is handed to clothsim, which takes one step;
its x_{k+1} is compared with the port's. Chaotic divergence of two long runs therefore
cannot hide or fake a bug: each step is judged on its own. A step that does not agree is
judged by the optimality of the port's answer for clothsim's objective g (the implicit
Euler objective of the paper, Eq. 4):

``agrees``
    Every vertex within the tolerance, or the port's answer is a minimizer of g (relative
    gradient ‖∇g(x)‖ / ‖∇g(x_0)‖ at most ``optimality``) and Newton's method from it and
    from clothsim's answer reaches the same minimizer (a port converged further or with
    another stopping rule).
``non-unique``
    Different but both optimal: Newton's method from the two answers reaches two different
    minimizers (a buckling step has two valid answers). Passes.
``not a minimizer``
    The port's answer is not optimal for g; the vertex named is the one whose gradient
    differs most from that of clothsim's answer.
``model differs``
    Not optimal, more than half of the vertices disagree, and the port's answer is far from
    the nearest minimizer of g (Newton's method from it) at more than half of the vertices
    (not one local error): the port solves another problem (other springs, masses, pins,
    forces or h); see :mod:`clothsim.ports.diff`.
``velocities differ``
    Positions agree but the port's v_{k+1} differs by more than tolerance / h (a damping
    model or velocity update that differs).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..effects.base import overrides
from ..errors import InputError
from ..simulation import State
from ..solvers.base import gradient_noise_floor, objective, objective_gradient
from .compare import EPS32, RTOL64, cloth_size, condition_number

PASSING = ("agrees", "non-unique")


@dataclass
class StepCheck:
    """Verdict on the port's step k → k + 1.

    Attributes
    ----------
    k : int
    status : str
        One of "agrees", "non-unique", "not a minimizer", "model differs",
        "velocities differ".
    error : float
        max over vertices of |x_clothsim − x_port| [m].
    vertex : int
        The vertex named (largest error, or largest gradient difference).
    gradient_port, gradient_clothsim : float
        ‖∇g(x)‖ / ‖∇g(x_0)‖ of the two answers (x_0 the initial guess).
    note : str
    """

    k: int
    status: str
    error: float
    vertex: int
    gradient_port: float = float("nan")
    gradient_clothsim: float = float("nan")
    note: str = ""

    @property
    def passed(self) -> bool:
        return self.status in PASSING

    def line(self) -> str:
        """One line naming the step, its verdict, error [m] and vertex.

        Returns
        -------
        str
        """
        text = (f"step {self.k} -> {self.k + 1}: {self.status}, max error {self.error:.3e} m "
                f"at vertex {self.vertex}")
        if np.isfinite(self.gradient_port):
            text += (f", relative gradient port {self.gradient_port:.2e} / clothsim "
                     f"{self.gradient_clothsim:.2e}")
        return text + (f" ({self.note})" if self.note else "")


@dataclass
class CheckReport:
    """All steps' verdicts; ``passed`` when every step agrees or is non-unique.

    Attributes
    ----------
    steps : list of StepCheck
        One verdict per checked step.
    tolerance : float
        Allowed per-vertex distance [m] (:func:`step_tolerance`).
    precision : {"float32", "float64"}
        The port's floating-point precision.
    notes : list of str
        Remarks on the whole check.
    """

    steps: list[StepCheck]
    tolerance: float
    precision: str
    notes: list[str] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return all(s.passed for s in self.steps)

    @property
    def first_failure(self) -> StepCheck | None:
        return next((s for s in self.steps if not s.passed), None)

    @property
    def non_unique(self) -> list[StepCheck]:
        return [s for s in self.steps if s.status == "non-unique"]

    def summary(self) -> str:
        """One line: PASS or FAIL, with the first failing step and vertex.

        Returns
        -------
        str
        """
        n = len(self.steps)
        worst = max((s.error for s in self.steps), default=0.0)
        nu = self.non_unique
        extra = (f"; {len(nu)} non-unique step(s) (both optimal): "
                 f"{', '.join(f'{s.k} -> {s.k + 1}' for s in nu[:5])}" if nu else "")
        first = self.first_failure
        if first is None:
            return (f"PASS: {n} steps agree within {self.tolerance:.3e} m ({self.precision}), "
                    f"max error {worst:.3e} m{extra}")
        return f"FAIL at {first.line()}{extra}"


def as_simulation(source):
    """A fresh Simulation from a Scene, a Simulation factory, or a Simulation.

    Parameters
    ----------
    source : Scene, Simulation or callable returning a Simulation

    Returns
    -------
    Simulation
        Built from the scene or the factory; a Simulation is returned as is.
    """
    if hasattr(source, "build_simulation"):
        return source.build_simulation(source.build_model())
    if callable(source):
        return source()
    if hasattr(source, "step") and hasattr(source, "problem"):
        return source
    raise InputError("simulation: expected a Scene, a Simulation or a function returning one")


def step_tolerance(sim, x: np.ndarray, precision: str = "float64") -> float:
    """Allowed per-vertex distance of one step [m] (docs/ports.md derives it).

    float64: 1e-9 of the cloth size. float32: κ(M + h²L) ε₃₂ max|x| (at least the float64
    tolerance), with κ of the system matrix including penalty pins.

    Parameters
    ----------
    sim : Simulation
        The simulation at the step's start (supplies M, L, h and the pins).
    x : ndarray, shape (n, 3)
        Positions [m] setting the cloth size.
    precision : {"float64", "float32"}
        The port's precision.

    Returns
    -------
    float
        Tolerance [m].
    """
    if precision not in ("float32", "float64"):
        raise InputError(f"precision: must be 'float32' or 'float64', got {precision!r}")
    tol = RTOL64 * cloth_size(x)
    if precision == "float32":
        tol = max(tol, system_condition_number(sim) * EPS32 * float(np.abs(x).max()))
    return tol


def system_condition_number(sim) -> float:
    """κ(M + h²L) of the simulation's next step, with its penalty pins.

    Parameters
    ----------
    sim : Simulation

    Returns
    -------
    float
        The 2-norm condition number (:func:`clothsim.ports.compare.condition_number`).
    """
    p = sim.problem(sim.state)
    return condition_number(sim.model, sim.h, anchor_vertices=p.anchor_vertices,
                            anchor_stiffness=p.anchor_stiffness)


def _refine(model, problem, x):
    from ..solvers.newton import NewtonSolver

    return NewtonSolver(model, iterations=100, tolerance=1e-13).solve(problem, x).x


def check_steps(simulation, positions, velocities=None, *, precision: str = "float64",
                tolerance: float | None = None, optimality: float = 1e-6,
                steps: int | None = None) -> CheckReport:
    """Check every step k → k + 1 of a port's trajectory against clothsim's step.

    Parameters
    ----------
    simulation : Scene, Simulation or callable
        The model (a fresh Simulation is built from a Scene or a factory; its state is reset
        to the port's before each step).
    positions : ndarray, shape (frames, n, 3)
        The port's x_k [m].
    velocities : ndarray, shape (frames, n, 3), optional
        The port's v_k [m/s] (after its damping). Default: (x_k − x_{k−1}) / h, and 0 at
        frame 0 — only right without a velocity-changing damping.
    precision : {"float64", "float32"}
        The port's arithmetic; sets the default tolerance (:func:`step_tolerance`).
    tolerance : float, optional
        Allowed per-vertex distance [m]; overrides the precision's.
    optimality : float, default 1e-6
        Largest relative gradient counted as a minimizer (raised to 10 × the rounding floor
        of ‖∇g‖, ε₃₂-based for float32).
    steps : int, optional
        Check only the first this many steps.

    Returns
    -------
    CheckReport
    """
    sim = as_simulation(simulation)
    xs = np.asarray(positions, np.float64)
    n = sim.model.vertex_count
    if xs.ndim == 2:
        xs = xs.reshape(len(xs), -1, 3)
    if xs.ndim != 3 or xs.shape[1:] != (n, 3):
        raise InputError(f"positions: expected (frames, {n}, 3), got {xs.shape}")
    if len(xs) < 2:
        raise InputError("positions: need at least 2 frames to check a step")
    h = sim.h
    if velocities is None:
        vs = np.concatenate([np.zeros_like(xs[:1]), np.diff(xs, axis=0) / h])
        notes = ["no port velocities: v_k = (x_k - x_{k-1}) / h assumed"]
    else:
        vs = np.asarray(velocities, np.float64).reshape(xs.shape[0], -1, 3)
        notes = []
    if steps is not None and steps < 1:
        raise InputError(f"steps: must be >= 1, got {steps}")
    tol = tolerance if tolerance is not None else step_tolerance(sim, xs[0], precision)
    count = len(xs) - 1 if steps is None else min(int(steps), len(xs) - 1)
    model = sim.model
    projected = [e.kind for e in sim.effects if overrides(e, "correct_positions")]
    out = []
    t = sim.state.time  # accumulated as the simulation does (time-dependent effects)
    for k in range(count):
        state = State(xs[k].copy(), vs[k].copy(), t, k)
        t = t + h
        problem = sim.problem(state)
        sim.state = state
        sim.step()
        x_cs, v_cs = sim.state.positions, sim.state.velocities
        x_port = xs[k + 1]
        err = np.linalg.norm(x_cs - x_port, axis=1)
        err = np.where(np.isfinite(err), err, np.inf)
        worst = int(np.argmax(err))
        if err[worst] <= tol:
            verr = np.linalg.norm(v_cs - vs[k + 1], axis=1) if velocities is not None else err * 0
            if verr.max() <= 10 * tol / h:
                out.append(StepCheck(k, "agrees", float(err[worst]), worst))
            else:
                out.append(StepCheck(k, "velocities differ", float(err[worst]),
                                     int(np.argmax(verr)),
                                     note=f"|v_clothsim - v_port| = {verr.max():.3e} m/s"))
            continue
        step = _judge(model, problem, k, x_cs, x_port, err, tol, optimality, precision)
        if projected:
            step.note += (f"; positions are corrected after the solve by {', '.join(projected)}, "
                          f"so optimality for g alone is only indicative")
        out.append(step)
    first = next((s for s in out if not s.passed), None)
    if first is not None and precision == "float64" and tolerance is None:
        bound = step_tolerance(sim, xs[first.k], "float32")
        if first.error <= bound:
            notes.append(f"the first failing step's error {first.error:.3e} m is within float32 "
                         f"rounding (κ ε32 max|x| = {bound:.3e} m): if the port computes in "
                         f"float32, check with precision float32")
    return CheckReport(out, float(tol), precision, notes)


def _judge(model, problem, k, x_cs, x_port, err, tol, optimality, precision) -> StepCheck:
    """Classify a step whose positions differ (see the module docstring)."""
    g0 = float(np.linalg.norm(objective_gradient(model, problem, problem.initial_guess())))
    g0 = g0 if g0 > 0 else 1.0
    grad_p = objective_gradient(model, problem, x_port)
    grad_c = objective_gradient(model, problem, x_cs)
    rp = float(np.linalg.norm(grad_p)) / g0
    rc = float(np.linalg.norm(grad_c)) / g0
    floor = gradient_noise_floor(model, problem, x_port) / g0
    if precision == "float32":
        floor *= EPS32 / float(np.finfo(np.float64).eps)
    worst = int(np.argmax(err))
    if not np.isfinite(rp):
        return StepCheck(k, "not a minimizer", float(err[worst]), worst, rp, rc,
                         "the port's positions are not finite")
    if rp <= max(optimality, 10 * floor):
        xp_star = _refine(model, problem, x_port)
        xc_star = _refine(model, problem, x_cs)
        gap = np.linalg.norm(xp_star - xc_star, axis=1)
        if gap.max() <= max(tol, 1e-9 * cloth_size(x_port)):
            return StepCheck(k, "agrees", float(err[worst]), worst, rp, rc,
                             "the port's answer is a minimizer of g and the one clothsim's "
                             "answer converges to (another stopping rule)")
        gp, gc = objective(model, problem, xp_star), objective(model, problem, xc_star)
        lower = "the port's" if gp < gc else "clothsim's"
        return StepCheck(k, "non-unique", float(err[worst]), worst, rp, rc,
                         f"different but both optimal: two minimizers {gap.max():.3e} m apart, "
                         f"g = {gp:.9g} (port) vs {gc:.9g} (clothsim); {lower} is lower")
    excess = np.linalg.norm(grad_p - grad_c, axis=1)
    vertex = int(np.argmax(excess))
    if np.mean(err > tol) > 0.5:
        moved = np.linalg.norm(_refine(model, problem, x_port) - x_port, axis=1)
        spread = float(np.mean(moved > max(tol, 0.01 * moved.max())))
        if spread > 0.5:
            return StepCheck(k, "model differs", float(err[worst]), vertex, rp, rc,
                             f"{np.mean(err > tol):.0%} of the vertices disagree and the "
                             f"minimizer of clothsim's g nearest to the port's answer differs "
                             f"from it at {spread:.0%} of the vertices: compare the models "
                             f"(clothsim diff-model)")
    return StepCheck(k, "not a minimizer", float(err[worst]), vertex, rp, rc,
                     f"largest gradient difference at vertex {vertex}: "
                     f"|grad g| = {np.linalg.norm(grad_p[vertex]):.3e} there")
