"""The obstacle or contact setting under which clothsim's held steps are a port's.

A hold-mode port whose box is a centimetre larger, whose sphere is off, whose friction
coefficient differs, which ignores static friction or keeps a vertex held after the cloth
pulls it away, takes steps that are clothsim's held steps with that one setting changed.
Its contact decisions are carried from step to step (:mod:`clothsim.ports.held_steps`),
so one step replayed from the port's state cannot show them: :func:`shadow` therefore
takes clothsim's steps again with the change, from the port's states, from the last step
at which clothsim's decision held nothing (:attr:`HeldSteps.window`) up to the failing
one, carrying the changed decisions forward as clothsim's own run would.

The changes tried (:func:`changes`), for each holding obstacle the port's answer comes
near:

- its size or place read off the port's vertices in contact: a box face's coordinate
  (that face moved, the box grown by as much on every side, or moved along that axis), a
  sphere's radius (their common distance from the centre) or its centre and radius (the
  sphere they lie on), a plane's offset;
- its friction coefficient: 0, twice the scene's, and the coefficient fitted to the port's
  answer (the step taken as linear in μ between the two replays nearest it: a secant,
  refined once);
- its contact rules: static friction ignored (every held vertex slides, under kinetic
  friction), and a held vertex kept after its normal force turned negative (clinging).

A change is named when its replay lands within the step's tolerance of the port's answer,
or :data:`~clothsim.ports.held_verdicts.NEARER` times nearer than clothsim's step; of
several, the nearest. The rules run through :mod:`clothsim.effects.holding`'s own
functions (its ``hold_step``, ``Holding``), only their inputs changed.
"""

from __future__ import annotations

import logging
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from ..effects.holding import Holding
from ..simulation import State
from .held_model import model_changes
from .held_readings import NEAR, geometry, shift_in_range
from .held_steps import _copy
from .held_verdicts import NEARER

log = logging.getLogger(__name__)

__all__ = ["Change", "changes", "explain", "shadow"]



@dataclass
class Change:
    """One setting of one obstacle, changed.

    Attributes
    ----------
    obstacle : Obstacle
        Or another effect (gravity), or the solver: :mod:`clothsim.ports.held_model`.
    words : str
        The change as the verdict says it: "a box of max (0.26, 0.51, 0.26) m instead of …".
    setting : str
        Where to look: the scene key or the port's code.
    values : dict
        Attribute → value set on the obstacle while the change is replayed.
    rule : str
        "" or a contact rule replaced: "no-stick", "clinging".
    carried : list or None
        The decision clothsim's held steps with the change left after the last step
        :func:`shadow` took (per obstacle: holding, contact vertices and normals), where
        :func:`clothsim.ports.held_follow.carry` goes on from.
    span : tuple or None
        A box moved sideways: (axis, least, most), the range of shifts along the axis its
        reading allows (:func:`clothsim.ports.held_readings.shift_in_range`).
    """

    obstacle: object
    words: str
    setting: str
    values: dict = field(default_factory=dict)
    rule: str = ""
    carried: list | None = None
    span: tuple | None = None

    @property
    def status(self) -> str:
        """``model differs`` for another obstacle, ``contacts differ`` for another rule."""
        return "contacts differ" if self.rule else "model differs"

    @contextmanager
    def applied(self):
        """The obstacle with the change; restored afterwards.

        Returns
        -------
        contextmanager
            Yields None while the obstacle carries the change.
        """
        e = self.obstacle      # (or another effect, or the solver: held_model's changes)
        margin = getattr(e, "set_margin", None)
        saved = {name: getattr(e, name) for name in self.values}
        try:
            for name, value in self.values.items():
                setattr(e, name, value)
            if margin:
                margin(e.margin)                  # the contact surface follows the size
            if self.rule == "clinging":
                e.correct_positions = _clinging(e)
            yield
        finally:
            for name, value in saved.items():
                setattr(e, name, value)
            if margin:
                margin(e.margin)
            e.__dict__.pop("correct_positions", None)

    def before_step(self, x) -> None:
        """The rule's change of the decision the step starts from (``no-stick``).

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            The port's x_k [m] (the planes' offsets stay where clothsim put them).
        """
        if self.rule == "no-stick":
            h = self.obstacle._holding
            c = len(h.vertices)
            out = Holding(x, h.vertices, h.normals, np.zeros(c, bool), h.normal_force, h.pull)
            if c:
                out.planes.offsets[:c] = h.planes.offsets[:c]   # where clothsim put them
            self.obstacle._holding = out


def _clinging(obstacle):
    """The obstacle's correct_positions with no negative normal force: a held vertex the
    cloth pulls away is kept (the forces of its normal planes clamped at 0)."""
    correct = type(obstacle).correct_positions

    def clinging(t, state, x):
        h = obstacle._holding
        if h.planes.forces is not None:
            c = len(h.vertices)
            h.planes.forces[:c] = np.maximum(h.planes.forces[:c], 0.0)
        return correct(obstacle, t, state, x)

    return clinging


def shadow(held, change: Change, window) -> list[np.ndarray]:
    """clothsim's held steps with ``change``, from the port's states.

    Parameters
    ----------
    held : HeldSteps
        The check's; its simulation, obstacles and state are restored afterwards.
    change : Change
    window : list of (State, list)
        The port's states of the steps to replay and, for the first, clothsim's decision
        (:attr:`HeldSteps.window`).

    Returns
    -------
    list of ndarray, shape (n, 3)
        x_{j+1} of each replayed step [m].
    """
    sim, saved = held.sim, held.sim.state
    out = []
    try:
        with change.applied():
            holdings = window[0][1]
            for state, _ in window:
                x = state.positions
                for e, (h, cv, cn) in zip(held.obstacles, holdings, strict=True):
                    e._holding = _copy(h, x)
                    e.contact_vertices, e.contact_normals = cv, cn
                change.before_step(x)
                sim.state = State(x.copy(), state.velocities.copy(), state.time, state.step)
                sim.step()
                out.append(sim.state.positions.copy())
                holdings = [(e._holding, e.contact_vertices, e.contact_normals)
                            for e in held.obstacles]
        change.carried = holdings
    except (ValueError, ArithmeticError, RuntimeError) as error:   # a change too far
        log.debug("replay of %s failed: %s", change.words, error)
        change.carried = None
        return out[:0]
    finally:
        held.restore()
        sim.state = saved
    return out


def changes(held, x_port, tol, later=()) -> list[Change]:
    """The changes worth replaying for a failing step (module docstring).

    Parameters
    ----------
    held : HeldSteps
    x_port : ndarray, shape (n, 3)
        The port's x_{k+1} [m].
    tol : float
        The step's tolerance [m].
    later : sequence of (int, ndarray)
        The port's later frames (frame index, positions): an obstacle the port's answer
        has not touched yet (a smaller sphere the cloth falls past) is read off them.

    Returns
    -------
    list of Change
        Geometry first, then friction (0, twice the scene's), then the rules; the fitted
        friction is tried by :func:`explain` after those two.
    """
    scale = max(float(np.ptp(x_port, axis=0).max()), 1e-9)
    effects = list(held.sim.effects)
    out = []
    for e in held.obstacles:
        q, _ = e.closest(x_port)
        gap = np.linalg.norm(q - x_port, axis=1)
        if gap.min() > NEAR * scale and not len(e._holding.vertices):
            continue                       # the port's answer is nowhere near it
        index = effects.index(e)
        read = [Change(e, *found) for found in geometry(e, x_port, index, tol)]
        for frame, x in later if not read else ():   # touched in a later frame?
            read = [Change(e, f"{words[:-1]} in frame {frame})" if words.endswith(")")
                           else words, *rest) for words, *rest in geometry(e, x, index, tol)]
            if read:
                break
        out += read
        if e.friction > 0:
            out.append(Change(e, f"the {e.kind}'s friction coefficient 0 instead of "
                                 f"{e.friction:g}", f"effects[{index}].friction (the {e.kind})",
                              {"friction": 0.0}))
            out.append(Change(e, f"the {e.kind}'s friction coefficient {2 * e.friction:g} "
                                 f"instead of {e.friction:g}", f"effects[{index}].friction "
                                 f"(the {e.kind})", {"friction": 2 * e.friction}))
            out.append(Change(e, f"static friction ignored on the {e.kind} (every held vertex "
                                 f"slides under kinetic friction μ F_n, none is held in all "
                                 f"three directions)", "the port's stick/slide rule "
                              "(|F_t| <= μ F_n sticks)", rule="no-stick"))
        out.append(Change(e, f"held vertices kept on the {e.kind} after the cloth pulls them "
                             f"away (normal force F < 0 not released: clinging)",
                          "the port's release rule (F < 0 releases)", rule="clinging"))
    return out


def _distance(x, x_port) -> float:
    return float(np.linalg.norm(x - x_port, axis=1).max()) if x is not None else np.inf


def explain(held, x_port, x_cs, err, tol, later=(), models=False):
    """The single change whose held steps are the port's at its failing step, in words.

    Parameters
    ----------
    held : HeldSteps
        Anchored at the failing step k and stepped.
    x_port, x_cs : ndarray, shape (n, 3)
        The port's and clothsim's x_{k+1} [m].
    err : ndarray, shape (n,)
        |x_clothsim − x_port| of the step [m].
    tol : float
    later : sequence of (int, ndarray)
        The port's later frames (:func:`clothsim.ports.held_causes.changes`).
    models : bool, default False
        Also gravity, the iteration count and a wider box (:mod:`clothsim.ports.held_model`)
        when no obstacle setting is within the tolerance: on a first failing step, not on
        one read again after a named setting (each costs a replay of the whole window).

    Returns
    -------
    (Change or None, str, float)
        The change named (None: none), the note's words ("" when no obstacle is near:
        nothing was tried), and how far its replay lands from the port's answer [m]
        (inf: none named).
    """
    window = held.window
    found = changes(held, x_port, tol, later)
    if not found or not window:   # no obstacle near: the model's fits and replays decide
        return None, "", np.inf
    scene = float(err.max())
    start = window[0][0].step
    tried, best = [], None

    def test(change):
        nonlocal best
        xs = shadow(held, change, window)
        d = _distance(xs[-1] if xs else None, x_port)
        log.debug("step %d: %s replayed from step %d: %.3e m", window[-1][0].step,
                  change.words, start, d)
        tried.append(change)
        if (d <= tol or d * NEARER <= scene) and (best is None or d < best[1]):
            best = (change, d)
        return xs[-1] if xs else None

    frictions = {}
    for change in found:
        x = test(change)
        if "friction" in change.values and x is not None:
            e = change.obstacle
            frictions.setdefault(id(e), [(e.friction, x_cs)]).append(
                (change.values["friction"], x))
            if len(frictions[id(e)]) == 3 and (best is None or best[1] > tol):
                _fit_friction(change, frictions[id(e)], x_port, test)
        if best is not None and best[1] <= tol:
            break
    for change in (c for c in found if c.span is not None):   # a box moved sideways: its
        if best is not None and best[1] <= tol:                # range's middle not this
            break                                              # step's shift
        shift_in_range(change, x_port, test, tol)
    if models and (best is None or best[1] > tol):   # gravity, the iteration count, …
        model_changes(held, x_port, x_cs, test, tol, Change)
    if best is None:
        kinds = sorted({c.setting.split(" (")[0] for c in tried})
        return None, (f"no single obstacle or contact setting reproduces the port's step "
                      f"(replayed from step {start} with {len(tried)} changes of: "
                      f"{'; '.join(kinds)})"), np.inf
    change, d = best
    return change, (f"the port's steps are clothsim's held steps with {change.words} "
                    f"(replayed from step {start}, the port's states, the contact decisions "
                    f"carried: {d:.1e} m off the port's answer, against {scene:.1e} m with "
                    f"the scene's; look at {change.setting})"), d


def _fit_friction(probe: Change, points, x_port, test) -> None:
    """The friction coefficient fitted on the replays at the scene's μ, 0 and 2 μ: the
    step taken as linear in μ between the two nearest the port's answer (secant), then
    replayed; once refined the same way."""
    e = probe.obstacle
    mu = e.friction
    points = sorted(points, key=lambda p: _distance(p[1], x_port))[:2]
    for _ in range(2):
        (a, xa), (b, xb) = points[-2:]
        dx = xb - xa
        denom = float(np.sum(dx * dx))
        if denom == 0:
            return
        c = a + (b - a) * float(np.sum((x_port - xa) * dx)) / denom
        if not 0 <= c <= 10 * mu or min(abs(c - a), abs(c - b)) <= 1e-3 * mu:
            return
        change = Change(e, f"the {e.kind}'s friction coefficient {c:.3g} instead of {mu:g}",
                        probe.setting, {"friction": float(c)})
        x = test(change)
        if x is None:
            return
        points.append((c, x))
