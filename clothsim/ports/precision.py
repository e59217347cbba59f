"""How precisely a port's numbers are written: printed digits, float32 values.

A port writes its frames as text more often than not, and C++'s default (``std::cout``,
``%g``) prints 6 significant digits: a correct float64 solution then differs from clothsim's
step by the printing alone, about 5e-6 of |x|, far above the float64 tolerance (1e-9 of
the cloth size). The check therefore reads the precision off the numbers themselves:

:func:`significant_digits` (:mod:`clothsim.ports.digits`)
    the most significant digits any value needs (its shortest decimal that reads back as
    the same float64): 6 for ``%g``, 9 for ``%.9g``, 15 to 17 for a float64 written in full;
:func:`float32_valued`
    whether the values are float32 numbers, written exactly or with at least 9 digits
    (data of a float32 port);
:func:`printed_tolerances`
    the per-step distance [m] that d printed digits alone can make (docs/ports.md,
    "Printed precision").

Printing with d digits rounds each coordinate by at most u |c|, u = ½ 10^(1−d). One step
of the check sees it three times: in the port's x_{k+1} (the answer), and in x_k and v_k,
the state clothsim restarts from. The step's answer depends on that state through the
inertial target y = x_k + h v_k (and the start point), with a sensitivity ∂x_{k+1}/∂y =
(M + h²∇²E)⁻¹ M whose ∞-norm is at most 1 when M + h²∇²E is an M-matrix (a spring
Laplacian, positive pins): an error of the start moves the answer by no more than itself.
Without stored velocities v_k = (x_k − x_{k−1}) / h, so y = 2 x_k − x_{k−1} carries 3 u |x|.

That sensitivity bound holds for a step that is a contraction of its start: a converged
minimizer, or local/global iterations. An accelerated solver stopped after a fixed number
of iterations (Anderson, L-BFGS, Chebyshev) is a nonlinear function of its start and can
move its answer more than the start moved: the drape-sphere's Anderson 30 step 13 → 14 of a
6-digit port misses the bound by 2 %. A step that fails the bound is therefore replayed
(:meth:`Printed.replayed`, :mod:`clothsim.ports.printed_replay`): clothsim's own step from
the port's start moved by the printed rounding, in a few sign patterns, bounds the start's
effect by the spread of the answers.
"""

from __future__ import annotations

import numpy as np

from ..simulation import State
from .compare import cloth_size
from .digits import FULL, describe, float32_valued, significant_digits, unit  # noqa: F401
from .printed_replay import moved_starts, spread_tolerance

#: Safety factor over the printed-rounding bound: the sensitivity bound of 1 assumes an
#: M-matrix Hessian; compressed springs and a nonlinear step are allowed twice that.
MARGIN = 2.0
#: Fewer digits than this are too coarse to judge a step at (5e-5 of |x|): the check
#: keeps its tolerance and says so, rather than pass anything.
COARSEST = 5
#: A printed precision whose step tolerance exceeds this fraction of the cloth's size is
#: too coarse to judge a step (6 digits at |x| = 1000 m round a 1 m cloth by centimetres).
COARSE = 1e-3


def printed_tolerances(positions, velocities, h: float, digits: int,
                       velocity_digits: int | None = None) -> np.ndarray:
    """Per step k → k + 1, the distance [m] by which printing alone moves a correct answer.

    ``MARGIN`` · √3 · (u max|x_{k+1}| + u max|x_k| + h u_v max|v_k|), with stored
    velocities (printed with ``velocity_digits``, unit u_v), else
    ``MARGIN`` · √3 · (u max|x_{k+1}| + 3 u max|x_k|): the answer's own rounding plus that of
    the inertial target the step starts from (module docstring).

    Parameters
    ----------
    positions : ndarray, shape (frames, n, 3)
        The port's x_k [m].
    velocities : ndarray, shape (frames, n, 3), or None
        The port's stored v_k [m/s]; None when they are derived from the positions.
    h : float
        Time step [s].
    digits : int
        Significant digits of the positions.
    velocity_digits : int, optional
        Significant digits of the velocities (default ``digits``).

    Returns
    -------
    ndarray, shape (frames − 1,)
        Tolerance [m] per step.
    """
    x = np.abs(np.asarray(positions, np.float64)).reshape(len(positions), -1).max(axis=1)
    u = unit(digits)
    if velocities is None:
        start = 3 * u * x[:-1]
    else:
        v = np.abs(np.asarray(velocities, np.float64)).reshape(len(velocities), -1).max(axis=1)
        uv = unit(digits if velocity_digits is None else velocity_digits)
        start = u * x[:-1] + h * uv * v[:-1]
    return MARGIN * np.sqrt(3.0) * (u * x[1:] + start)


class Printed:
    """The precision of a port's frames, as the check uses it.

    Parameters
    ----------
    positions : ndarray, shape (frames, n, 3)
        The port's x_k [m], as read.
    velocities : ndarray, shape (frames, n, 3), or None
        The port's stored v_k [m/s] (None: derived from the positions).
    h : float
        Time step [s].
    tolerance : float
        The float64 tolerance [m]: printing that moves a step by less is not mentioned.

    Attributes
    ----------
    digits : int
        Significant digits of the numbers (the fewer of positions and velocities).
    float32 : bool
        The positions are float32 values (:func:`float32_valued`).
    tolerances : ndarray, shape (frames − 1,)
        Per step, the float64 tolerance widened to the printed precision [m].
    text : str
        "printed with d significant digits" when that widened a tolerance, else "".
    unit : float or None
        Relative rounding of the numbers when :attr:`text` is set (the gradient's rounding
        floor scales with it), else None.
    units : tuple of float or None
        The relative rounding of the positions and of the velocities when :attr:`text` is
        set (:func:`replayed_tolerance`), else None.
    limit : float
        The largest tolerance a replayed step may get [m]: :data:`COARSE` of the cloth's
        size.
    unplaced : dict
        Step k → the note of a replay beyond :attr:`limit` (:meth:`annotate`).
    spread : dict
        Step k → that replay's tolerance [m]: an error within it is the printing's as
        much as the port's (:meth:`too_coarse`).
    coarse : ndarray, shape (frames − 1,), or None
        When the printing is too coarse to judge a step: per step, the distance by which
        printing alone moves a correct answer [m]; a step within it is ``too coarse`` to
        judge (undecided), one beyond it still fails.
    note : str
        Why the tolerance was not widened when the printing is too coarse to judge a step
        (below :data:`COARSEST` digits, or a tolerance above :data:`COARSE` of the cloth's
        size), else "".
    """

    def __init__(self, positions, velocities, h: float, tolerance: float):
        xd = significant_digits(positions)
        vd = None if velocities is None else significant_digits(velocities)
        self.digits = min(xd, 17 if vd is None else vd)
        self.float32 = float32_valued(positions, xd)
        self.tolerances = np.full(len(positions) - 1, float(tolerance))
        self.text, self.unit, self.note, self.units = "", None, "", None
        self.limit = COARSE * cloth_size(np.asarray(positions)[0])
        self.unplaced: dict[int, str] = {}
        self.spread: dict[int, float] = {}
        self.coarse = None
        coarse = (f"the output is {describe(self.digits)}: too coarse to judge a step; "
                  f"print 17 digits (float64) or 9 (float32)")
        if self.digits < FULL:
            printed = printed_tolerances(positions, velocities, h, xd, vd)
        if self.digits < COARSEST:
            self.note, self.coarse = coarse, printed
        elif self.digits < FULL:
            size = cloth_size(np.asarray(positions)[0])
            if printed.max() > COARSE * size:
                self.coarse = printed
                self.note = coarse.replace(": too coarse", f": rounding by up to "
                                           f"{printed.max():.1e} m on a {size:.3g} m cloth, "
                                           f"too coarse")
            elif printed.max() > tolerance:
                self.tolerances = np.maximum(self.tolerances, printed)
                self.text, self.unit = describe(self.digits), unit(self.digits)
                self.units = (unit(xd), unit(xd if vd is None else vd))

    def hint32(self, step, error: float, bound) -> None:
        """Name float32 arithmetic on a step that fails when checked as float64, in place.

        float32 values (:attr:`float32`) whose error is within the step's float32 bound get
        the status "float32 rounding" and the flag to use; beyond it, the same flag in the
        note. Numbers of fewer than 9 digits cannot be told from float64 ones: within the
        bound they get the status with an "if the port computes in float32" hint.

        Parameters
        ----------
        step : StepCheck
            A failing step of a float64 check (changed in place).
        error : float
            Its largest error [m].
        bound : callable
            () -> the step's float32 tolerance [m] (computed only when needed).
        """
        if not (self.float32 or self.digits < 9):
            return None
        b32 = bound()
        if error <= b32 and not step.settings:
            step.status = "float32 rounding"
            step.note = (f"the error is within float32 rounding of this step ({b32:.3e} m): "
                         + ("the port's numbers are float32 values; check with --precision "
                            "float32" if self.float32 else
                            f"the numbers carry {self.digits} digits, too few to tell float32 "
                            f"from float64: if the port computes in float32, check with "
                            f"--precision float32"))
        elif self.float32:
            step.note += "; the port's numbers are float32 values: check with --precision float32"

    def replayed(self, k: int, sim, held, state, x_answer, x_port, tol: float,
                 x_before=None, branches=None) -> float:
        """A failing step's tolerance, widened by replay (:func:`replayed_tolerance`).

        Parameters
        ----------
        k : int
            The step k → k + 1 (its note, when the replay exceeds :attr:`limit`, is kept
            for :meth:`annotate`).
        sim : Simulation
            The checking simulation (its state is left as the replays leave it).
        held : HeldSteps
            Its holding obstacles: the replays keep the step's anchored contact planes.
        state : State
            The port's (x_k, v_k) of the step.
        x_answer, x_port : ndarray, shape (n, 3)
            clothsim's and the port's x_{k+1} [m].
        tol : float
            The step's tolerance so far [m].
        x_before : ndarray, shape (n, 3), optional
            x_{k−1} [m] when the velocities are derived from the positions.
        branches : SolverBranches, optional
            For a solver whose iteration makes discrete choices: the replays follow the
            port's branch of them (:mod:`clothsim.ports.solver_branches`; its
            :attr:`~SolverBranches.adopted` says when that is not clothsim's own).

        Returns
        -------
        float
            The tolerance [m], at least ``tol``; ``tol`` itself when the replayed tolerance
            exceeds :attr:`limit` (the printed start cannot place the step's answer).
        """

        def restart(x, v):
            moved = State(x, v, state.time, state.step)
            if held:
                return held.replay(moved, "hold")
            sim.state = moved
            sim.step()
            return sim.state.positions.copy()

        solids = [e for e in sim.effects if e.kind in ("sphere", "plane", "box")]
        starts = moved_starts(state.positions, state.velocities, *self.units, sim.h, x_before,
                              solids=solids)
        replay = restart
        if branches:   # the solver's choices along the port's branch
            x_answer = branches.choose(restart, state.positions, state.velocities, starts,
                                       x_port)

            def replay(x, v, path=branches.path):
                with branches.following(path):
                    return restart(x, v)
        replayed = spread_tolerance(replay, starts, x_answer, x_port, self.units[0])
        if replayed <= self.limit:
            return max(tol, replayed)
        self.spread[k] = replayed
        self.unplaced[k] = (f"replayed from the port's start moved by its printed rounding, "
                            f"clothsim's step would need a tolerance of {replayed:.1e} m, "
                            f"over {self.limit:.1e} m (1e-3 of the cloth): the printed state "
                            f"cannot place this step's answer; print 17 digits (float64) or 9 "
                            f"(float32)")
        return tol

    def too_coarse(self, k: int, error: float) -> str:
        """The note of a step the coarse printing alone could move by ``error``, else "".

        Parameters
        ----------
        k : int
            The step k → k + 1.
        error : float
            The step's largest distance from clothsim's answer [m].

        Returns
        -------
        str
            Why the step is ``too coarse`` to judge, or "" (fine printing, or an error
            beyond the printing's rounding of the step: judged as any other). A step whose
            replays from the printed start spread beyond :attr:`limit` (:meth:`replayed`)
            is too coarse when its error lies within that spread.
        """
        if k in self.spread and error <= self.spread[k]:
            return (f"the output is {describe(self.digits)}; replayed from the port's start "
                    f"moved by that rounding, clothsim's step spreads over "
                    f"{self.spread[k]:.1e} m (beyond {self.limit:.1e} m, 1e-3 of the cloth) "
                    f"and the error lies within it: the printing alone may explain it; print "
                    f"17 digits (float64) or 9 (float32) to judge it")
        if self.coarse is None or error > self.coarse[k]:
            return ""
        return (f"the output is {describe(self.digits)}, which rounds this step by up to "
                f"{self.coarse[k]:.3e} m: the error may be the printing's alone; print 17 "
                f"digits (float64) or 9 (float32) to judge it")

    def annotate(self, steps) -> None:
        """Add to each failing step the printed state cannot place the note saying so.

        Parameters
        ----------
        steps : list of StepCheck
            The checked steps, changed in place (after their causes are named).
        """
        for step in steps:
            if self.coarse is not None and not step.passed and step.status != "too coarse":
                step.note = "; ".join(filter(None, (step.note, (
                    f"the output is {describe(self.digits)}: beyond what that rounding "
                    f"explains, but too coarse for a replay to name the cause"))))
            if step.k in self.unplaced and not step.passed:
                step.note = "; ".join(filter(None, (step.note, self.unplaced[step.k])))
