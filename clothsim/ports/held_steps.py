"""The contact state of a hold-mode check: the planes and friction each step holds.

In ``[contact] mode = "hold"`` (the default) a step keeps some vertices on contact planes
and lets friction stick or slide them; which ones, on which planes, and with what friction
is decided at the end of the step before, from its solve (:mod:`clothsim.effects.holding`:
the planes' normal forces release vertices pulled away, the friction cone makes others
stick). That decision is part of the step's problem
(:meth:`clothsim.simulation.Simulation.problem`: the held planes, and kinetic friction in
its external force), the one object the solvers, ``accuracy`` and ``check`` share.

``check`` restarts clothsim from the port's state every frame, so the contact state must
come from there too: :class:`HeldSteps` keeps each holding obstacle's decision of
clothsim's step k − 1 (taken from the port's state k − 1, by the simulation's own code:
which vertices are held, their normals, which stick, the forces of kinetic friction). A
held vertex stays on the contact plane that step put it on (a box's face, the sphere's
tangent plane), and a sticking one also where the port has it: its two tangent planes go
through the port's x_k (:meth:`HeldSteps.anchor`). clothsim's own export therefore checks
with no glue, and a port's step k is judged on the planes its own state implies. The
contact planes are not moved to the port's printed x_k: a vertex rounded 1e-7 m into the
box would change the normal forces, and with them which vertices the next step releases
(measured on drop-on-square 25² printed with ``%g``, planes through the printed x_k: 221
vertices held in step 10 against the 181 of clothsim's own run).

:meth:`HeldSteps.replay` takes the same step under another contact treatment, to name what
a port does instead (:data:`VARIANTS`): resolving contact after the solve (the seed's
projection), holding without friction, or deciding which vertices to hold from contact
forces of the wrong sign.
"""

from __future__ import annotations

import numpy as np

from ..effects.holding import Holding
from ..simulation import State

#: The contact treatments a port may use instead of clothsim's held step, as replayed by
#: :meth:`HeldSteps.replay`, with the words the verdict uses for each.
VARIANTS = {
    "post-solve": ("resolves contact after the solve (the seed's projection, "
                   "[contact] mode = \"post-solve\") instead of holding the vertices on their "
                   "contact planes in the solve"),
    "frictionless": ("holds the vertices on their contact planes without friction (no "
                     "sticking planes, no kinetic friction on held vertices)"),
    "flipped": ("reads the contact force along the inward normal, -n . grad g (the contact "
                "normal's sign flipped): it releases the vertices the obstacle pushes and "
                "keeps those the cloth pulls away"),
}

#: Steps :attr:`HeldSteps.window` keeps at most (the port's states a replay of another
#: obstacle or contact setting starts from; :mod:`clothsim.ports.held_causes`).
WINDOW = 12


def holding_obstacles(sim) -> list:
    """The simulation's obstacles in ``"hold"`` mode.

    Parameters
    ----------
    sim : Simulation

    Returns
    -------
    list of Obstacle
    """
    return [e for e in sim.effects if getattr(e, "contact", None) == "hold"
            and isinstance(getattr(e, "_holding", None), Holding)]


def face_name(obstacle, normal) -> str:
    """Words for the face of ``obstacle`` whose outward normal is ``normal``.

    Parameters
    ----------
    obstacle : Obstacle
    normal : array_like, shape (3,)

    Returns
    -------
    str
        "the box's top", "the box's -x side", "the sphere", "the plane", …
    """
    if obstacle.kind != "box":
        return f"the {obstacle.kind}"
    n = np.asarray(normal, np.float64)
    axis = int(np.argmax(np.abs(n)))
    up = n[axis] > 0
    if axis == 1:
        return f"the box's {'top' if up else 'bottom'}"
    return f"the box's {'+' if up else '-'}{'xyz'[axis]} side"


def _copy(h: Holding, x: np.ndarray, *, friction: bool = True) -> Holding:
    """A fresh Holding with ``h``'s decision: its contact planes where clothsim put them,
    a sticking vertex's two tangent planes through ``x`` (where the port has it)."""
    c = len(h.vertices)
    if friction:
        out = Holding(x, h.vertices, h.normals, h.stick, h.normal_force, h.pull)
    else:
        out = Holding(x, h.vertices, h.normals, np.zeros(c, bool), np.zeros(c),
                      np.zeros((c, 3)))
    out.planes.offsets[:c] = h.planes.offsets[:c]
    return out


class HeldSteps:
    """The holding obstacles of a checking simulation, and their state between steps.

    Parameters
    ----------
    sim : Simulation
        The simulation ``check`` steps from the port's states.

    Attributes
    ----------
    obstacles : list of Obstacle
        Those in ``"hold"`` mode (empty: a scene without held contacts).
    """

    def __init__(self, sim):
        self.sim = sim
        self.obstacles = holding_obstacles(sim)
        #: The contact state the last :meth:`replay` held (as :meth:`planes`).
        self.replayed: list = []
        self._before: list | None = None
        self._after: list | None = None
        self._previous: tuple | None = None    # (State, holdings) of the step before
        self._state: State | None = None
        self._x: np.ndarray | None = None
        #: (State, decision) of the steps since the last one at which clothsim's decision
        #: held nothing (at most :data:`WINDOW`, the last one the step anchored): where
        #: replays of another setting start (:mod:`clothsim.ports.held_causes`).
        self.window: list = []

    def __bool__(self) -> bool:
        return bool(self.obstacles)

    def anchor(self, x: np.ndarray) -> None:
        """Hold the next step's sticking vertices where the port has them, ``x``.

        Each obstacle keeps its decision (held vertices, normals and contact planes, which
        stick, the normal forces and pulls of kinetic friction); the tangent planes of a
        sticking vertex v become t · x' = t · x_v.

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            The port's x_k [m].
        """
        for e in self.obstacles:
            e._holding = _copy(e._holding, x)
        self._previous = None if self._before is None else (self._state, self._before)
        self._before = [(e._holding, e.contact_vertices, e.contact_normals)
                        for e in self.obstacles]
        self._x = np.array(x, dtype=np.float64)
        self._state = None

    def starts(self, state: State) -> None:
        """Remember the port's state of the step just anchored (where the ``"flipped"``
        replay of the next step takes this one again).

        Parameters
        ----------
        state : State
            The port's (x_k, v_k) and time.
        """
        self._state = State(state.positions.copy(), state.velocities.copy(), state.time,
                            state.step)
        if not any(len(h.vertices) for h, _, _ in self._before):
            self.window = []
        self.window = (self.window + [(self._state, self._before)])[-WINDOW:]

    def x(self) -> np.ndarray:
        """The port's positions the step was anchored at.

        Returns
        -------
        ndarray, shape (n, 3)
            x_k [m].
        """
        return self._x

    def previous_planes(self):
        """The contact state of the step before.

        Returns
        -------
        list of (Obstacle, Holding)
            As :meth:`planes`; its planes' forces are the ones that decided this step.
            Empty at the first step.
        """
        if self._previous is None:
            return []
        return [(e, h) for e, (h, _, _) in zip(self.obstacles, self._previous[1], strict=True)]

    def previous_decision(self) -> list | None:
        """The contact state the step before was anchored at, with its vertices in contact.

        Returns
        -------
        list of (Holding, ndarray, ndarray) or None
            Per obstacle: its holding, contact vertices and normals; None at the first step.
        """
        return None if self._previous is None else self._previous[1]

    def previous_state(self) -> State | None:
        """The port's state at the start of the step before.

        Returns
        -------
        State or None
            (x_{k−1}, v_{k−1}); None at the first step.
        """
        return None if self._previous is None else self._previous[0]

    def replace(self, planes) -> None:
        """Hold another contact state in the step (:func:`clothsim.ports.held_margins.adopt`).

        Parameters
        ----------
        planes : list of (Obstacle, Holding)
        """
        for e, h in planes:
            e._holding = h
        self._before = [(h, cv, cn) for (_, h), (_, cv, cn) in zip(planes, self._before,
                                                                  strict=True)]

    def decision(self) -> list:
        """The step's anchored decision, as :meth:`restart` takes it back.

        Returns
        -------
        list
            Per obstacle: its holding, contact vertices and normals.
        """
        return list(self._before)

    def restart(self, decision) -> None:
        """Anchor the step at ``decision`` again (:meth:`decision`; after :meth:`replace`).

        Parameters
        ----------
        decision : list
        """
        self._before = list(decision)
        self.again()

    def again(self, *, friction: bool = True, holdings=None) -> None:
        """Put the obstacles back to the step's anchored decision (the start of every
        :meth:`replay`), so that clothsim's step can be taken again from the port's state
        (along another branch of the solver's choices: the step taken before left the
        obstacles' next decision in their place).

        Parameters
        ----------
        friction : bool, default True
            False: the held vertices without friction (no sticking planes, no kinetic
            friction; the ``"frictionless"`` replay).
        holdings : list of Holding, optional
            Per obstacle, another decision of the step's held vertices (the ``"flipped"``
            replay's); default the anchored one. Its vertices in contact stay the step's.
        """
        for i, (e, (h, cv, cn)) in enumerate(zip(self.obstacles, self._before, strict=True)):
            h = h if holdings is None else holdings[i]
            e._holding = _copy(h, self._x, friction=friction)
            e.contact_vertices, e.contact_normals = cv, cn

    def stepped(self) -> None:
        """Remember the state the step left (the next step's decision)."""
        self._after = [(e._holding, e.contact_vertices, e.contact_normals)
                       for e in self.obstacles]

    def planes(self):
        """The contact state of the step last anchored, per obstacle.

        Returns
        -------
        list of (Obstacle, Holding)
            Each holding's ``planes`` are what ``hold_contacts`` handed the step.
        """
        return [(e, h) for e, (h, _, _) in zip(self.obstacles, self._before or (),
                                               strict=False)]

    def replay(self, state: State, variant: str) -> np.ndarray | None:
        """clothsim's step from ``state`` under another contact treatment (:data:`VARIANTS`).

        The simulation's state and the obstacles' decision are restored afterwards.

        Parameters
        ----------
        state : State
            The port's state of the step (the one :meth:`anchor` was given).
        variant : {"post-solve", "frictionless", "flipped", "hold"}
            ``"hold"``: the step as anchored (its start moved, :mod:`clothsim.ports.precision`).

        Returns
        -------
        ndarray, shape (n, 3) or None
            x_{k+1} of that step [m]; None for ``"flipped"`` at the first step (no step
            before it to decide again).
        """
        sim, saved = self.sim, self.sim.state
        try:
            if variant == "flipped":
                if self._previous is None or self._previous[0] is None:
                    return None
                self._decide_flipped()
            self.again(friction=variant != "frictionless", holdings=[
                e._holding for e in self.obstacles] if variant == "flipped" else None)
            for e in self.obstacles:
                if variant == "post-solve":
                    e.contact = "post-solve"
                if variant == "flipped":
                    e.correct_positions = _flipped(e)
            self.replayed = [(e, e._holding) for e in self.obstacles]
            sim.state = State(state.positions.copy(), state.velocities.copy(), state.time,
                              state.step)
            sim.step()
            return sim.state.positions.copy()
        finally:
            self.restore()
            sim.state = saved

    def restore(self) -> None:
        """The obstacles as the check's step left them (after a replay changed them)."""
        for e, (h, cv, cn) in zip(self.obstacles, self._after, strict=True):
            e.contact = "hold"
            e.__dict__.pop("correct_positions", None)
            e._holding, e.contact_vertices, e.contact_normals = h, cv, cn

    def _decide_flipped(self) -> None:
        """Take the step before again from the port's state, its contact forces read with
        the opposite sign: the obstacles' next decision is then what such a port holds."""
        state, before = self._previous
        for e, (h, cv, cn) in zip(self.obstacles, before, strict=True):
            e._holding = _copy(h, state.positions)
            e.contact_vertices, e.contact_normals = cv, cn
            e.correct_positions = _flipped(e)
        self.sim.state = state
        self.sim.step()
        for e in self.obstacles:
            del e.correct_positions


def _flipped(obstacle):
    """The obstacle's correct_positions with each plane's force read along −n."""
    correct = type(obstacle).correct_positions

    def flipped(t, state, x):
        planes = obstacle._holding.planes
        if planes.forces is not None:
            planes.forces = -planes.forces
        return correct(obstacle, t, state, x)

    return flipped


__all__ = ["VARIANTS", "WINDOW", "HeldSteps", "face_name", "holding_obstacles"]
