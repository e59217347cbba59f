"""The effect protocol: how a declared effect takes part in a time step.

An effect overrides only the hooks it needs (:data:`HOOKS`);
:class:`~clothsim.simulation.Simulation` calls only overridden hooks, so an effect that a
scene does not declare costs nothing and the hooks of a declared one are the only extra
work. The simulation first calls :meth:`Effect.bind` once (it stores ``self.model`` and the
time step ``self.h``: hooks read h from there), then ``connect_pins`` on effects that
need to know which vertices are pinned. One step from t to t + h runs:

1. ``add_force(t, state, f)``                add external forces f (n, 3) [N]
2. ``adjust_target(t, state, y) -> y``       change the inertial target y (damping)
3. ``pins(t + h) -> PinSet``                  exact pins and penalty anchors for the step
   ``hold_contacts(t + h) -> ContactSet``       contact planes held during the step
4. the solver minimizes g(x) (on the held contact planes); each holding obstacle's
   :attr:`ContactSet.forces <clothsim.contacts.ContactSet>` is then set
5. ``correct_positions(t + h, state, x) -> x``    move x after the solve (collisions, …)
6. v = (x − x_n) / h, then ``correct_velocities(t + h, state, x, v) -> v``

Within each hook the simulation calls the effects in the order they were declared, each
one receiving what the previous one returned. Hooks read the time step from ``self.h`` and
the model from ``self.model``; they never change the model. Arrays are (n, 3), one row per
vertex, in the model's vertex order, float64.

What an effect carries from one step into the next (an obstacle's held contacts) it hands
out through :meth:`Effect.get_state` and takes back through :meth:`Effect.set_state`:
``clothsim run`` saves it with every frame (:func:`effect_states`) and ``--resume``
restores it, so a resumed run is bit for bit the uninterrupted one. Every other hook must
depend only on the time, the state and the model.

An effect instance belongs to one simulation: binding it to a second one is an
:class:`~clothsim.errors.InputError` (it keeps per-run data such as contacts). A
simulation's effects are fixed when it is built (:class:`BoundEffects`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..contacts import ContactSet
from ..errors import InputError
from ..problem import PinSet

#: Every hook an effect may override, in the order a step calls them (``connect_pins``
#: is called once, after :meth:`Effect.bind`).
HOOKS = ("add_force", "adjust_target", "pins", "hold_contacts", "correct_positions",
         "correct_velocities", "connect_pins")


class Effect:
    """Base class of effects. Subclasses set ``kind`` and override the hooks they need.

    Attributes
    ----------
    kind : str
        The scene's name of the effect.
    model : Model
        The model, set by :meth:`bind`.
    h : float
        The time step [s], set by :meth:`bind`; hooks read it from here.
    """

    kind = "effect"
    _simulation = None  # the Simulation this instance is bound to (one only)

    def bind(self, model, h: float) -> None:
        """Check the effect against ``model`` and precompute what it needs.

        Called once by the :class:`~clothsim.simulation.Simulation` constructor, before
        ``connect_pins`` and before the first step (every hook may rely on ``self.model``
        and ``self.h``). Subclasses call ``super().bind(model, h)`` first, then validate
        their parameters against the model (vertex indices in range, …) and raise
        :class:`~clothsim.errors.InputError` naming the field on bad input.

        Parameters
        ----------
        model : Model
            The cloth model (n vertices); stored as ``self.model``.
        h : float
            Time step [s]; stored as ``self.h``.
        """
        self.model = model
        self.h = h

    def add_force(self, t: float, state, f: np.ndarray) -> None:
        """Add this effect's external force to ``f`` in place.

        Called by :meth:`~clothsim.simulation.Simulation.problem` first: at the start of
        every step, and again whenever ``problem()`` is called (the port tools do), so it
        must not change the effect's state. ``f`` starts at zero and collects every
        declared force effect's contribution; the sum becomes f_ext of the step (the
        −xᵀ f_ext term of E(x), so h² f_ext enters the global step's right-hand side).
        Forces are evaluated at the start of the step (x_n, v_n at time t): an explicit
        treatment of position- or velocity-dependent forces.

        Parameters
        ----------
        t : float
            Time at the start of the step [s].
        state : State
            The state x_n, v_n at time t.
        f : ndarray, shape (n, 3)
            Force accumulator [N]; add to it, never replace it. Do not modify ``state``.
        """
        raise NotImplementedError

    def adjust_target(self, t: float, state, y: np.ndarray) -> np.ndarray:
        """Return a changed inertial target y (do not modify ``y`` in place).

        Called by ``Simulation.problem()`` after ``add_force`` (at every step, and whenever
        ``problem()`` is called: keep no state here); the step then minimizes
        g(x) = ½ (x − y)ᵀ M (x − y) + h² E(x) with the returned y. Used by damping models
        (e.g. y = x_n + a h v_n). Effects are chained: each receives the previous one's y.

        Parameters
        ----------
        t : float
            Time at the start of the step [s].
        state : State
            The state at time t.
        y : ndarray, shape (n, 3)
            Inertial target so far [m] (x_n + h v_n before any adjustment).

        Returns
        -------
        ndarray, shape (n, 3)
            The new inertial target [m] (a new array).
        """
        raise NotImplementedError

    def pins(self, t: float) -> PinSet:
        """The pins active in the step ending at time ``t``.

        Called by ``Simulation.problem()`` (with t = t_n + h) after ``adjust_target``; the
        pin sets of all pin effects are merged (:meth:`PinSet.merge`) into the step's
        :class:`~clothsim.problem.StepProblem`. Also called at construction (a vertex
        held by two pins is an :class:`~clothsim.errors.InputError`) and whenever an
        effect asks ``pinned(t)`` (see :meth:`connect_pins`), so it must not change the
        effect's state. Exact pins are removed from the unknowns; penalty anchors add
        zero-rest-length springs (k_j to L's diagonal, h² k_j q_j to the right-hand side).

        Parameters
        ----------
        t : float
            Time at the end of the step [s].

        Returns
        -------
        PinSet
            Fixed vertices (p,) with positions (p, 3) [m]; anchor vertices (q,), anchor
            points (q, 3) [m] and stiffnesses (q,) [N/m].
        """
        raise NotImplementedError

    def hold_contacts(self, t: float) -> ContactSet:
        """The contact planes this effect holds vertices on during the step ending at ``t``.

        Called by ``Simulation.problem()`` after ``pins`` (also by the port tools: it must
        not change the effect's state); the sets of all effects are merged into the step's
        :class:`~clothsim.problem.StepProblem`, whose solution keeps every listed vertex
        on its plane. After the solve the simulation sets the returned set's ``forces``
        (the normal force of each plane [N]), which ``correct_positions`` may read.

        Parameters
        ----------
        t : float
            Time at the end of the step [s].

        Returns
        -------
        ContactSet
            Vertices (c,), unit normals (c, 3) and offsets (c,) [m] of the planes n·x = o.
        """
        raise NotImplementedError

    def correct_positions(self, t: float, state, x: np.ndarray) -> np.ndarray:
        """Return corrected end-of-step positions (do not modify ``x`` in place).

        Called once per step after the solver, outside the optimization (the paper's
        collision handling: a vertex inside an obstacle is moved to its surface). The
        velocities are then computed from the corrected positions, v = (x − x_n) / h, so a
        correction also changes the velocity. Effects are chained in declaration order.

        Parameters
        ----------
        t : float
            Time at the end of the step [s].
        state : State
            The state at the start of the step.
        x : ndarray, shape (n, 3)
            Positions after the solve (and earlier corrections) [m].

        Returns
        -------
        ndarray, shape (n, 3)
            Corrected positions [m] (a new array, or ``x`` itself when nothing changes).
        """
        raise NotImplementedError

    def correct_velocities(self, t: float, state, x: np.ndarray,
                           v: np.ndarray) -> np.ndarray:
        """Return corrected end-of-step velocities (do not modify ``v`` in place).

        Called once per step, last, after v = (x − x_n) / h (friction, restitution,
        velocity damping). The returned v is the next step's v_n; positions can no longer
        change. Effects are chained in declaration order.

        Parameters
        ----------
        t : float
            Time at the end of the step [s].
        state : State
            The state at the start of the step.
        x : ndarray, shape (n, 3)
            Final positions of the step [m].
        v : ndarray, shape (n, 3)
            Velocities (x − x_n) / h after earlier corrections [m/s].

        Returns
        -------
        ndarray, shape (n, 3)
            Corrected velocities [m/s] (a new array, or ``v`` itself).
        """
        raise NotImplementedError

    def connect_pins(self, pinned: Callable[[float], np.ndarray]) -> None:
        """Receive the simulation's pin query (for effects that must not move pins).

        Called once by the simulation right after every effect is bound, before the first
        step. Store ``pinned`` and call it from other hooks (e.g. strain limiting leaves
        pinned vertices where the pins put them).

        Parameters
        ----------
        pinned : callable
            ``pinned(t)`` returns the sorted vertices held by any pin (exact or penalty)
            in the step ending at time t, shape (p,), int.
        """
        raise NotImplementedError

    def get_state(self) -> dict[str, np.ndarray]:
        """What this effect carries from one step into the next (for a bit-for-bit resume).

        Most effects are functions of the time and the state (x, v) alone and carry nothing
        (``{}``, the default); an obstacle in ``"hold"`` mode carries the contacts it hands
        the next step. ``clothsim run`` saves it with every frame (:func:`effect_states`).

        Returns
        -------
        dict of str to ndarray
            Copies: the caller may keep them while the simulation steps on.
        """
        return {}

    def state_bytes(self, vertex_count: int) -> int:
        """Bytes of :meth:`get_state`'s arrays at most, for a cloth of ``vertex_count``
        vertices (the disk a run plans for; 0 by default).

        Parameters
        ----------
        vertex_count : int

        Returns
        -------
        int
        """
        return 0

    def set_state(self, state: dict, name: str | None = None) -> None:
        """Restore what :meth:`get_state` returned, after :meth:`bind` (the default has
        nothing to restore).

        Parameters
        ----------
        state : mapping of str to ndarray
        name : str, optional
            Names the source in an error message.
        """

    def describe(self) -> dict:
        """JSON-ready description of the effect as built (for run.json).

        Returns
        -------
        dict
            At least ``{"kind": kind}``; subclasses add their parameters (SI units).
        """
        return {"kind": self.kind}


def overrides(effect: Effect, hook: str) -> bool:
    """Whether ``effect`` implements ``hook`` (the simulation calls only those).

    Parameters
    ----------
    effect : Effect
    hook : str
        One of :data:`HOOKS`.

    Returns
    -------
    bool
        True when the effect's class overrides the hook of :class:`Effect` and the
        instance does not list it in ``unused_hooks`` (an obstacle in the seed's contact
        mode holds no contacts; a frictionless one adds no force).
    """
    return (getattr(type(effect), hook) is not getattr(Effect, hook)
            and hook not in getattr(effect, "unused_hooks", ()))


def effect_states(effects) -> dict[str, np.ndarray]:
    """Every effect's :meth:`Effect.get_state`, flat: key ``"<index>.<kind>.<name>"``.

    Parameters
    ----------
    effects : sequence of Effect
        A simulation's effects, in order.

    Returns
    -------
    dict of str to ndarray
        Empty when no effect carries anything between steps.
    """
    return {f"{i}.{e.kind}.{k}": a for i, e in enumerate(effects)
            for k, a in e.get_state().items()}


def restore_effect_states(effects, arrays, source: str = "state") -> None:
    """Give each effect its part of :func:`effect_states`' output back.

    Parameters
    ----------
    effects : sequence of Effect
        The same effects, bound (the same scene).
    arrays : mapping of str to ndarray
    source : str
        Names where ``arrays`` came from in an error (a file).

    Raises
    ------
    InputError
        An array for an effect that is not there (another scene), or one an effect rejects.
    """
    parts: dict[int, dict] = {}
    for key, a in arrays.items():
        index, kind, name = (key.split(".", 2) + ["", ""])[:3]
        i = int(index) if index.isdigit() else -1
        if not 0 <= i < len(effects) or effects[i].kind != kind:
            raise InputError(f"{source}: holds {key!r}, but effects[{index}] of this scene is "
                             f"not a {kind or '?'}", field=source)
        parts.setdefault(i, {})[name] = a
    lacking = [i for i, e in enumerate(effects) if i not in parts and e.get_state()]
    if lacking:
        raise InputError(f"{source}: holds nothing for effects[{lacking[0]}] "
                         f"({effects[lacking[0]].kind}), which carries state", field=source)
    for i, part in parts.items():
        effects[i].set_state(part, f"{source} (effects[{i}], {effects[i].kind})")


class BoundEffects(tuple):
    """The effects a :class:`~clothsim.simulation.Simulation` runs: a tuple, fixed when it
    is built.

    The simulation binds its effects, sets up its hooks, its pins and the checks between
    them once, so an effect added afterwards would be silently ignored: the changes a list
    allows (``append``, ``extend``, ``insert``, ``remove``, ``pop``, ``clear``, item
    assignment and deletion, ``+=``) raise an :class:`~clothsim.errors.InputError` naming
    ``Simulation.effects`` and what to do instead.
    """

    __slots__ = ()

    def _refuse(self, *args, **kwargs):
        """Refuse a change: every method by which a list changes is this one.

        Raises
        ------
        InputError
            Always, naming ``Simulation.effects`` and what to do instead.
        """
        raise InputError("Simulation.effects: fixed when the simulation is built (its hooks and "
                         "pins are set up from them, so a later change would be ignored); pass "
                         "every effect to Simulation(..., effects=[...]) or build a new "
                         "Simulation")

    append = extend = insert = remove = pop = clear = sort = reverse = _refuse
    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse


__all__ = ["HOOKS", "BoundEffects", "ContactSet", "Effect", "PinSet", "effect_states",
           "overrides", "restore_effect_states"]
