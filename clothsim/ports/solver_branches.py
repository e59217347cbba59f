"""A solver's discrete choices in one step, recorded and replayed: the branch a port took.

Anderson acceleration keeps an extrapolated iterate only when it lowers g (its energy
safeguard; a rejection restarts its window), and L-BFGS halves its step until the Armijo
test holds. Each is a comparison, and one whose energy change is within rounding of its
threshold is decided by the rounding of the step's start. The two branches then run
different iterations, and after a fixed number of them end far more apart than the starts
were: drop-on-square in post-solve mode with Anderson 30, step 14 → 15 printed with
``%g``: the safeguard test of iteration 22 sees an energy change of −2e-8 J from the
printed start and +6e-7 J from 3 of 4 starts moved by the rounding, whose answers land
5.5e-3 m from the printed start's (the port, on the printed start's branch, is 3e-5 m
from it).

The checker measures how far a printed start moves a step by replaying it from starts
moved by the rounding (:mod:`clothsim.ports.printed_replay`); across a branch that spread
is the jump between branches, not the step's sensitivity. :class:`SolverBranches` therefore

1. records the choices of clothsim's step from the printed start and of each replay: the
   distinct sequences are the branches the rounding reaches (a choice that differs
   between them was too close to call from the port's state);
2. takes the step from the printed start along each branch and keeps the one nearest the
   port's answer: the port's branch (clothsim's own unless another is nearer);
3. replays the moved starts along that branch (its choices followed), where the step is a
   smooth function of its start, so that their spread bounds the start's effect.

A 1 mm fault is still a 1 mm fault on every branch: the branches move the answer by what
the solver's choices do, not by what the port does.
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

__all__ = ["Choices", "SolverBranches"]

#: Solvers whose iteration makes discrete choices (:attr:`Solver.decisions`).
DECIDING = ("anderson", "lbfgs")
_WHAT = {"anderson": "energy safeguard test", "lbfgs": "Armijo test"}


class Choices:
    """A solver's ``decisions`` hook: records each choice, following ``path`` while it lasts.

    Parameters
    ----------
    path : sequence of bool, optional
        The choices to take, in order (the solver's own after them).

    Attributes
    ----------
    taken : list of bool
        The choices made.
    """

    def __init__(self, path=()):
        self.path = tuple(path)
        self.taken: list[bool] = []

    def __call__(self, own: bool) -> bool:
        i = len(self.taken)
        choice = bool(self.path[i]) if i < len(self.path) else bool(own)
        self.taken.append(choice)
        return choice


def _distance(a, b) -> float:
    d = np.linalg.norm(np.asarray(a) - np.asarray(b), axis=1)
    return float(np.nan_to_num(d, nan=np.inf).max())


class SolverBranches:
    """The branch of a step's discrete solver choices a port took, for the replays.

    Parameters
    ----------
    sim : Simulation
        The checking simulation (its solver, or the one it builds for a damped step).

    Attributes
    ----------
    path : tuple of bool or None
        The port's branch of the last :meth:`choose` (None: before any).
    adopted : bool
        That branch is not the one clothsim's step from the printed start takes.
    note : str
        What :meth:`choose` found ("" when every replay took clothsim's choices).
    """

    def __init__(self, sim):
        self.sim = sim
        self.path, self.adopted, self.note = None, False, ""

    def __bool__(self):
        return self.sim.solver.name in DECIDING

    @contextmanager
    def following(self, path=()):
        """Within the block, the simulation's steps record their choices, following ``path``.

        Parameters
        ----------
        path : sequence of bool, default ()
            The choices to take, in order (the solver's own after them).

        Yields
        ------
        list of Choices
            The hook of each step taken in the block, in order.
        """
        sim, hooks = self.sim, []
        saved = sim.__dict__.get("_step_solver")
        own = sim._step_solver

        def step_solver(state):
            solver = own(state)
            hooks.append(Choices(path))
            solver.decisions = hooks[-1]
            return solver

        sim._step_solver = step_solver
        try:
            yield hooks
        finally:
            if saved is None:
                del sim._step_solver
            else:
                sim._step_solver = saved
            sim.solver.decisions = None

    def choose(self, restart, x, v, starts, x_port):
        """The port's branch: clothsim's step from the printed start nearest ``x_port``.

        Parameters
        ----------
        restart : callable
            (x, v) -> clothsim's x_{k+1} from that start (run within :meth:`following`).
        x, v : ndarray, shape (n, 3)
            The port's start as read.
        starts : list of (ndarray, ndarray)
            The starts moved by the printed rounding (:func:`~.printed_replay.moved_starts`).
        x_port : ndarray, shape (n, 3)
            The port's x_{k+1} [m].

        Returns
        -------
        ndarray, shape (n, 3)
            clothsim's step from the printed start along the port's branch [m]; the
            branch is :attr:`path`.
        """
        with self.following() as hooks:
            answer = restart(x, v)
        own = tuple(hooks[-1].taken)
        answers, reached = {own: answer}, 0
        for xm, vm in starts:
            with self.following() as hooks:
                restart(xm, vm)
            path = tuple(hooks[-1].taken)
            if path != own:
                reached += 1
            if path not in answers:
                with self.following(path):
                    answers[path] = restart(x, v)
        self.path = min(answers, key=lambda p: _distance(answers[p], x_port))
        self.adopted = self.path != own
        self.note = ""
        if reached:
            other = next(p for p in answers if p != own)
            first = next((i for i, (a, b) in enumerate(zip(own, other)) if a != b),
                         min(len(own), len(other)))
            what = _WHAT.get(self.sim.solver.name, "choice")
            taken = ("the port's branch taken" if self.adopted else
                     "clothsim's own is the port's")
            self.note = (f"{reached} of {len(starts)} starts within the printed rounding "
                         f"take other choices of the {self.sim.solver.name} iteration "
                         f"({what} {first + 1} too close to call from the port's state; "
                         f"{len(answers)} branches, {taken}): replayed along the port's "
                         f"branch")
        return answers[self.path]
