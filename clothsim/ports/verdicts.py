"""The checker's verdicts: one per step, and the summary line of a whole check.

Verdicts that pass:

``agrees``
    Every vertex within the tolerance, or the port's answer is itself within the tolerance
    of the minimizer of g that clothsim's answer converges to (a port converged further, or
    with another stopping rule).
``non-unique``
    Both answers lead to certified minima of the same g (positive definite Hessian), the
    pinned vertices included, and they differ: a buckling step has two valid answers.

Verdicts that fail:

``pinned vertex moved``
    A vertex the scene pins exactly is not at its target in the port's answer.
``start-dependent``
    Neither answer is a minimizer (a fixed iteration count stops short): the answer depends
    on where the iteration starts and how many iterations it takes, so the step cannot be
    judged. Not the port's error: match the settings named in the note.
``ill-conditioned``
    The port's answer meets the optimality criterion but is farther than the tolerance
    from the minimizer: g is too flat there for the criterion to place it
    (:mod:`clothsim.ports.flat` gives the evidence and what would decide).
    Undecided, like ``start-dependent``.
``too coarse``
    The output is printed with too few digits to judge the step (fewer than 5, or a
    rounding above 1e-3 of the cloth's size), and the error is within what that printing
    alone moves a right answer by: undecided, like ``start-dependent``
    (:mod:`clothsim.ports.precision`). An error beyond it is judged as any other.
``not converged``
    The port's answer is heading for clothsim's minimizer but is not there yet.
``not a minimizer``
    The port's answer is not optimal for g, by a local error at the vertex named.
``model differs``
    The port solves another problem: a fitted model explains its steps and the note names
    it (:mod:`clothsim.ports.causes`), or clothsim's step is converged and the port's
    answer is far from it nearly everywhere (``clothsim diff-model``).
``float32 rounding``
    Checked as float64, but the difference is within what float32 arithmetic gives.
``frame repeated``
    The port's x_{k+1} is its x_k where clothsim's step moves the cloth: a frame written
    twice (frame k printed as k + 1; :mod:`clothsim.ports.frame_order`).
``noisy``
    The difference from clothsim's step is as rough as independent noise (vertices joined
    by a spring differ as much as any two) and spread over the cloth, and no model or
    setting reproduces it: the port's arithmetic or output adds it
    (:mod:`clothsim.ports.noise`). Pinned vertices off by the same noise, where the free
    vertices are off by more than the tolerance, are noisy too, not "missing pins".
``start differs``
    The port's x_{k+1} is clothsim's step from another state than the frame k it wrote:
    for k = 0 the scene's initial state (frame 0 written otherwise than the port starts),
    for k ≥ 1 its x_k with its v_{k−1} (the velocities of the frame after written at each
    frame; :func:`clothsim.ports.frame_order.stepped_from`).
``not finite``
    The port's frame k or k + 1 holds NaN or infinity: no step from it, or no answer
    (a run that blew up; the note names the first such frame).
``velocities differ``
    Positions agree but v_{k+1} does not (a damping or velocity update that differs; a
    damping left out or of another coefficient is named, :mod:`clothsim.ports.effect_causes`).
``contacts differ``
    Hold mode: the port's planes of the step are not the ones clothsim decides from the
    port's state (held by one and free in the other, sticking and sliding, another plane,
    the normal's sign), or its answer is clothsim's step under another contact treatment
    (:mod:`clothsim.ports.held_verdicts`). Post-solve mode: vertices clothsim's
    projection moved are off in a port whose answer otherwise minimizes g
    (:mod:`clothsim.ports.postsolve_margins`).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

PASSING = ("agrees", "non-unique")
#: Failing verdicts that are not the port's error: a check whose failing steps all have one
#: of these is UNDECIDED, not FAIL.
UNDECIDED = ("start-dependent", "ill-conditioned", "too coarse")


@dataclass
class StepCheck:
    """Verdict on the port's step k → k + 1.

    Attributes
    ----------
    k : int
    status : str
        One of the verdicts of :mod:`clothsim.ports.verdicts`.
    error : float
        max over vertices of |x_clothsim − x_port| [m].
    vertex : int
        The vertex named (largest error, or largest gradient difference).
    gradient_port, gradient_clothsim : float
        ‖∇g(x)‖ / ‖∇g(x_0)‖ of the two answers (x_0 the initial guess).
    note : str
        Why, and what to change.
    role : str
        How the named vertex is held (e.g. "pinned by a 1e+10 N/m penalty"), or "".
    tolerance : float
        The per-vertex tolerance this step was judged with [m].
    settings : str
        The solver settings with which clothsim's own iterations reproduce the port's
        answer, when the checker found them (e.g. ``[solver] initial_guess = "x_n" and
        iterations = 50``), else "".
    further : bool
        The step differs beyond a setting named at an earlier step and carried to it (a
        second difference of the port's; :func:`clothsim.ports.held_follow.followed`).
    """

    k: int
    status: str
    error: float
    vertex: int
    gradient_port: float = float("nan")
    gradient_clothsim: float = float("nan")
    note: str = ""
    role: str = ""
    tolerance: float = float("nan")
    settings: str = ""
    further: bool = False

    @property
    def passed(self) -> bool:
        return self.status in PASSING

    def line(self) -> str:
        """One line naming the step, its verdict, error [m] and vertex (and its role).

        Returns
        -------
        str
        """
        role = f" ({self.role})" if self.role else ""
        text = (f"step {self.k} -> {self.k + 1}: {self.status}, max error {self.error:.3e} m "
                f"at vertex {self.vertex}{role}")
        if np.isfinite(self.gradient_port):
            text += (f", relative gradient port {self.gradient_port:.2e} / clothsim "
                     f"{self.gradient_clothsim:.2e}")
        return text + (f" ({self.note})" if self.note else "")


def _count(n: int, noun: str) -> str:
    """"1 step", "2 steps"."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _steps_text(steps, limit=5) -> str:
    more = f" and {len(steps) - limit} more" if len(steps) > limit else ""
    return ", ".join(f"{s.k} -> {s.k + 1}" for s in steps[:limit]) + more


@dataclass
class CheckReport:
    """All steps' verdicts; ``passed`` when every step agrees or is non-unique.

    Attributes
    ----------
    steps : list of StepCheck
        One verdict per checked step.
    tolerance : float
        The float64 per-vertex tolerance [m] (float32 steps carry their own).
    precision : {"float32", "float64"}
        The port's floating-point precision.
    notes : list of str
        Remarks on the whole check.
    expected_steps : int or None
        The steps the port's output had to hold (the scene's frames); when it holds fewer,
        the check fails naming both counts.
    printed : str
        How the port's numbers are printed, when that widened the tolerance (e.g. "printed
        with 6 significant digits"), else "".
    start : str
        Why the port's frame 0 is not the scene's start (its vertices in another order,
        the output starting at a later frame; :mod:`clothsim.ports.frame_order`), else "".
        The check then fails, naming it first.
    """

    steps: list[StepCheck]
    tolerance: float
    precision: str
    notes: list[str] = field(default_factory=list)
    expected_steps: int | None = None
    printed: str = ""
    start: str = ""

    @property
    def short(self) -> bool:
        """True when the port's output holds fewer steps than :attr:`expected_steps`."""
        return self.expected_steps is not None and len(self.steps) < self.expected_steps

    @property
    def passed(self) -> bool:
        return all(s.passed for s in self.steps) and not self.short and not self.start

    @property
    def first_failure(self) -> StepCheck | None:
        return next((s for s in self.steps if not s.passed), None)

    @property
    def non_unique(self) -> list[StepCheck]:
        return [s for s in self.steps if s.status == "non-unique"]

    def summary(self) -> str:
        """One line: PASS, FAIL or UNDECIDED, with the first failing step and vertex.

        A PASS whose largest error is above the tolerance says which steps passed by
        optimality and why. UNDECIDED: every failing step is start-dependent (the settings
        differ), ill-conditioned (g too flat for the criterion) or too coarsely printed to
        judge: not the port's error.

        Returns
        -------
        str
        """
        n = len(self.steps)
        worst = max((s.error for s in self.steps), default=0.0)
        tol = max((s.tolerance for s in self.steps if np.isfinite(s.tolerance)),
                  default=self.tolerance)
        above = [s for s in self.steps if s.passed and s.error > s.tolerance]
        nu = self.non_unique
        extra = ""
        if above:
            by_minimizer = [s for s in above if s.status == "agrees"]
            if by_minimizer:
                extra += (f"; {len(by_minimizer)} step(s) above the tolerance agree because the "
                          f"port's answer is the minimizer clothsim's converges to: "
                          f"{_steps_text(by_minimizer)}")
        if nu:
            extra += (f"; {len(nu)} non-unique step(s) (two certified minima of g): "
                      f"{_steps_text(nu)}")
        if self.printed:
            extra += f"; the output is {self.printed}: judged at that precision"
        failing = [s for s in self.steps if not s.passed]
        head = ""
        if self.short:
            written = "the 1 step written" if n == 1 else f"the {n} steps written"
            head = (f"FAIL: the port's output has {n + 1} frames ({_count(n, 'step')}), the "
                    f"scene asks for {self.expected_steps} steps ({self.expected_steps + 1} "
                    f"frames; --steps N checks only the first N); of {written}, ")
        if self.start:
            head = f"FAIL: {self.start}; " + (head[len("FAIL: "):] if head else
                                              "of the steps as written, ")
        if not failing:
            agree = "1 step agrees" if n == 1 else f"{n} steps agree"
            return (f"{head or 'PASS: '}{agree} within {tol:.3e} m ({self.precision}), "
                    f"max error {worst:.3e} m{extra}")
        second = next((s for s in failing if s.further), None)
        if second is not None:
            extra = (f"; and beyond the setting named first, a further difference from step "
                     f"{second.k} -> {second.k + 1}: {second.status}, max error "
                     f"{second.error:.3e} m at vertex {second.vertex}" + extra)
        counts = Counter(s.status for s in failing)
        tally = ", ".join(f"{c} {status}" for status, c in counts.most_common())
        word = "UNDECIDED" if set(counts) <= set(UNDECIDED) else "FAIL"
        return (f"{head + 'the first fails' if head else word} at {failing[0].line()}; "
                f"{len(failing)} of {n} steps fail: {tally}{extra}")
