"""Time stepping: a model, declared effects and a solver, advanced one implicit Euler step
at a time.

Data flows one way: the :class:`~clothsim.model.Model` never changes; a :class:`State`
holds positions, velocities and time; each :meth:`Simulation.step` builds the step's
problem from the declared effects only, hands it to the solver and applies the effects'
corrections. Velocities follow the paper: v_{n+1} = (x_{n+1} − x_n) / h.
"""

from __future__ import annotations

import logging
import time as _time

import numpy as np

from .blowups import force_cause, state_cause
from .contacts import ContactSet
from .effects.base import HOOKS, BoundEffects, Effect, overrides
from .effects.pins import Pin
from .errors import InputError, NonFiniteStateError, check_finite
from .magnitudes import check_step
from .model import Model
from .objective import objective_gradient
from .problem import PinSet, check_initial_guess
from .solvers import Solver, StepProblem, StepResult, make_solver
from .state import State, StepRecord

log = logging.getLogger(__name__)


class Simulation:
    """Advance a cloth through time.

    Parameters
    ----------
    model : Model
    h : float
        Time step [s].
    effects : sequence of Effect
        The declared effects (gravity, pins, obstacles, …). Nothing else is simulated,
        except that the model's vertices of mass 0 that no pin holds get an exact
        :class:`~clothsim.effects.Pin` (first in :attr:`effects`).
    solver : str or Solver, default "local-global"
        A solver instance, or a method name for :func:`clothsim.solvers.make_solver`.
    iterations, tolerance, backend
        Passed to the solver when ``solver`` is a name.
    initial_guess : {"y", "x_n"}, default "y"
        Where each step's iteration starts: the inertial target y = x_n + h v_n (the paper)
        or the previous positions x_n (most ports; the assignment's ``main.cpp``). With a
        fixed iteration count the answer depends on it; a converged step does not.
    state : State, optional
        Initial state; default: the model's positions at rest, zero velocity, t = 0.

    Examples
    --------
    >>> import clothsim as cs
    >>> mesh = cs.grid(5, 5, size=(1.0, 1.0), plane="xy")
    >>> springs = cs.grid_springs(mesh, structural=100.0, shear=100.0, bending=10.0)
    >>> model = cs.Model.build(mesh, springs, total_mass=1.0)
    >>> sim = cs.Simulation(model, h=1 / 30, effects=[cs.Gravity(), cs.Pin([20, 24])])
    >>> records = sim.run(10)
    >>> bool(sim.state.positions[0, 1] < mesh.vertices[0, 1])   # the free corner fell
    True
    """

    def __init__(self, model: Model, *, h: float, effects=(), solver="local-global",
                 iterations: int = 10, tolerance: float | None = None, backend: str = "auto",
                 state: State | None = None, initial_guess: str = "y", **solver_options):
        self.model = model
        self.initial_guess = check_initial_guess(initial_guess)
        self.h = float(check_finite("h", h))
        if self.h <= 0:
            raise InputError(f"h: the time step must be positive, got {self.h!r}")
        if isinstance(iterations, bool) or not isinstance(iterations, int | np.integer):
            raise InputError(f"solver.iterations: must be an integer, got "
                             f"{type(iterations).__name__}")
        iterations = int(iterations)
        if "method" in solver_options:  # the scene's key is solver.method; here: solver=
            raise InputError(f"method: Simulation takes the method as solver=, e.g. "
                             f"solver={solver_options['method']!r}")
        if isinstance(effects, Effect) or not hasattr(effects, "__iter__"):
            raise InputError(f"effects: expected a list of effects, got "
                             f"{type(effects).__name__} (write effects=[...])")
        if tolerance is not None:
            check_finite("solver.tolerance", tolerance)
        if isinstance(solver, Solver):
            self.solver = solver
        else:
            self.solver = make_solver(solver, model, iterations=iterations, tolerance=tolerance,
                                      backend=backend, **solver_options)
        self._damped = bool(model.springs.spring_damping.any())
        self._solver_options = dict(iterations=self.solver.iterations,
                                    tolerance=self.solver.tolerance, backend=backend,
                                    **solver_options)
        effects = list(effects)
        for i, e in enumerate(effects):
            if not isinstance(e, Effect):
                raise InputError(f"effects[{i}]: expected an Effect, got {type(e).__name__}")
            if e._simulation is not None or any(e is o for o in effects[:i]):
                raise InputError(f"effects[{i}] ({e.kind}): already bound to another "
                                 f"simulation; create one effect per simulation")
        for e in effects:
            e.bind(model, self.h)
        # no float64 overflow, singular M + h²L or motion lost to rounding (a frozen cloth)
        check_step(model, self.h, [(f"effects[{i}]", e) for i, e in enumerate(effects)])
        self._effects = BoundEffects(effects)
        self._hooks = {hook: [e for e in effects if overrides(e, hook)] for hook in HOOKS}
        t1 = (0.0 if state is None else float(getattr(state, "time", 0.0))) + self.h
        massless = np.setdiff1d(model.massless_vertices, self._pin_list(t1))
        if len(massless):  # mass 0 means pinned (an inverse mass of 0, as the engines read it)
            log.info("%d vertices of mass 0 are pinned at their initial positions",
                     len(massless))
            pin = Pin(massless)
            pin.bind(model, self.h)
            self._effects = BoundEffects([pin, *effects])
            self._hooks = {hook: [e for e in self._effects if overrides(e, hook)]
                           for hook in HOOKS}
        for e in self._hooks["connect_pins"]:  # effects that must not move pinned vertices
            e.connect_pins(self.pinned_vertices)
        n = model.vertex_count
        if state is None:
            state = State(model.mesh.vertices.copy(), np.zeros((n, 3)))
        elif not isinstance(state, State):
            raise InputError(f"state: expected a State, got {type(state).__name__}")
        elif state.positions.shape != (n, 3):
            raise InputError(f"state.positions: expected shape ({n}, 3) for this model, got "
                             f"{state.positions.shape}")
        self.state = state
        self._check_pin_overlap()
        for e in self.effects:
            e._simulation = self
        self._check_initial_overlap()

    @property
    def effects(self) -> BoundEffects:
        """The effects this simulation runs, in the order their hooks are called: fixed when
        it is built (an :class:`~clothsim.errors.InputError` on ``append`` and the like)."""
        return self._effects

    @effects.setter
    def effects(self, value) -> None:
        self._effects._refuse()

    @property
    def effects_built(self) -> list[str]:
        """Kinds of the effects this simulation runs."""
        return [e.kind for e in self.effects]

    def _pin_list(self, t: float) -> np.ndarray:
        """Every vertex each pin holds in the step ending at t (a vertex twice if two do)."""
        sets = [e.pins(t) for e in self._hooks["pins"]]
        return np.concatenate([np.zeros(0, np.int64)]
                              + [np.concatenate([p.fixed_vertices, p.anchor_vertices])
                                 for p in sets])

    def _check_pin_overlap(self) -> None:
        uniq, counts = np.unique(self._pin_list(self.state.time + self.h), return_counts=True)
        if np.any(counts > 1):
            raise InputError(f"effects.pin: vertex {uniq[counts > 1][0]} is pinned by more than "
                             f"one pin")

    def _check_initial_overlap(self) -> None:
        """Warn when an obstacle holds cloth vertices at t = 0 (they would be launched)."""
        for i, e in enumerate(self.effects):
            inside = getattr(e, "inside", None)
            if inside is None or not overrides(e, "correct_positions"):
                continue
            count = int(np.count_nonzero(inside(self.state.positions)))
            if count:
                log.warning("effects[%d] (%s): %d of %d cloth vertices start inside the "
                            "obstacle; they will be pushed out in the first step", i, e.kind,
                            count, self.model.vertex_count)

    def pinned_vertices(self, t: float) -> np.ndarray:
        """Vertices held by a pin (exact or penalty) in the step ending at time t.

        Parameters
        ----------
        t : float
            Time at the end of the step [s].

        Returns
        -------
        ndarray, shape (p,), int
            Sorted, unique vertex indices.
        """
        return np.unique(self._pin_list(t))

    def problem(self, state: State | None = None) -> StepProblem:
        """The implicit Euler problem of the next step from ``state``.

        Calls the effects' ``add_force``, ``adjust_target`` and ``pins`` hooks: f_ext is
        the sum of the forces, y = x_n + h v_n as adjusted, pins at t + h; the problem
        starts its iteration from :attr:`initial_guess`.

        Parameters
        ----------
        state : State, optional
            Start of the step; default the current state.

        Returns
        -------
        StepProblem
            h [s], x_n (n, 3) [m], v_n (n, 3) [m/s], y (n, 3) [m], f_ext (n, 3) [N] or
            None, and the pins.
        """
        s = self.state if state is None else state
        h, t = self.h, s.time
        f = None
        if self._hooks["add_force"]:
            f = np.zeros_like(s.positions)
            for e in self._hooks["add_force"]:
                e.add_force(t, s, f)
            if not np.isfinite(f).all():  # a blow-up an effect's force met first
                raise NonFiniteStateError(force_cause(self._hooks["add_force"], s))
        y = s.positions + h * s.velocities
        for e in self._hooks["adjust_target"]:
            y = e.adjust_target(t, s, y)
        pins = self._pins(t + h)
        held = ContactSet.merge([ContactSet()] + self._held_sets(t + h))
        return StepProblem(h, s.positions, s.velocities, y, f, pins.fixed_vertices,
                           pins.fixed_positions, pins.anchor_vertices, pins.anchor_positions,
                           pins.anchor_stiffness, start=self.initial_guess,
                           contact_vertices=held.vertices, contact_normals=held.normals,
                           contact_offsets=held.offsets)

    def _pins(self, t: float) -> PinSet:   # the pins of the step ending at t, merged
        return PinSet.merge([e.pins(t) for e in self._hooks["pins"]] or [PinSet()])

    def prepare(self) -> None:
        """Factor the next step's system now (cached by h and pins: the step's answer is the
        same); ``clothsim run`` writes frame 0 after it, off a large factorization's 2 cores.

        Returns
        -------
        None
            (Nothing to do without a cached factor, or for a damped model's per-step one.)
        """
        if self._damped or not hasattr(self.solver, "system"):
            return
        s, pins = self.state, self._pins(self.state.time + self.h)
        self.solver.system(StepProblem(  # h and the pins: no force or contact hook runs
            self.h, s.positions, s.velocities, s.positions, None, pins.fixed_vertices,
            pins.fixed_positions, pins.anchor_vertices, pins.anchor_positions,
            pins.anchor_stiffness, start=self.initial_guess))

    def _held_sets(self, t: float) -> list[ContactSet]:
        return [e.hold_contacts(t) for e in self._hooks["hold_contacts"]]

    def _contact_forces(self, problem: StepProblem, x: np.ndarray, t: float) -> None:
        """Tell each holding obstacle the normal force [N] its planes exerted in the step."""
        sets = [c for c in self._held_sets(t) if len(c)]
        if not sets:
            return
        grad = objective_gradient(self.model, problem, x, feasible=False)
        # the solve's unbalanced force per vertex (root mean square over the free ones): what
        # an unconverged iteration leaves in every force estimate
        g = problem.tangential(grad)
        noise = float(np.sqrt(np.mean(np.einsum("ij,ij->i", g, g)))) / self.h ** 2
        for c in sets:
            c.forces = np.einsum("ij,ij->i", grad[c.vertices], c.normals) / self.h ** 2
            c.noise = noise

    def step_model(self, state: State | None = None) -> Model:
        """The model whose objective g the next step minimizes.

        :attr:`model` itself, unless springs are damped: then the springs of
        :meth:`~clothsim.springs.Springs.implicit_damping` at x_n (stiffness k + c/h, rest
        length (k r + (c/h) ℓ(x_n)) / (k + c/h)), whose g is the damped step's.

        Parameters
        ----------
        state : State, optional
            Start of the step; default the current state.

        Returns
        -------
        Model
        """
        if not self._damped:
            return self.model
        s = self.state if state is None else state
        m = self.model
        return Model(m.mesh, m.springs.implicit_damping(self.h, s.positions), m.vertex_mass)

    def _step_solver(self, state: State) -> Solver:
        """The solver of the next step: :attr:`solver`, or one for the damped step model."""
        if not self._damped:
            return self.solver
        solver = make_solver(self.solver.name, self.step_model(state), **self._solver_options)
        if hasattr(solver, "expected_solves"):   # its factor serves this one step
            solver.expected_solves, solver.expected_final = solver.iterations, True
        return solver

    def expect_steps(self, steps: int | None, *, final: bool = True) -> None:
        """Tell the solver how many steps follow, so that its next factorization's mode
        (:func:`clothsim.factor_mode.choose_cholmod_mode`) weighs the solves ahead:
        ``steps`` × iterations. :func:`clothsim.run_scene` passes the whole run (``final``);
        :meth:`run` passes its steps as a lower bound, since more may follow (with a
        tolerance, a step may stop after one iteration: the bound is then ``steps``).
        Solvers without a factorization ignore it.

        Parameters
        ----------
        steps : int or None
            Steps of length h still to come; None: unknown.
        final : bool, default True
            Whether ``steps`` is the whole run. When False, the count is a lower bound and
            the ski-rental rule decides: a factor in the mode cheaper to factor is
            refactored in the mode with the faster solves once it has served its switch
            point.
        """
        solver = self.solver
        if hasattr(solver, "expected_solves"):
            final = bool(final) and steps is not None
            per_step = solver.iterations if final or solver.tolerance is None else 1
            solver.expected_solves = None if steps is None else max(int(steps), 1) * per_step
            solver.expected_final = final

    def step(self) -> StepRecord:
        """Advance one time step h.

        Solves x_{n+1} = argmin g(x), applies ``correct_positions``, sets
        v_{n+1} = (x_{n+1} − x_n) / h, applies ``correct_velocities`` and replaces
        :attr:`state`.

        Returns
        -------
        StepRecord
            What the solver did (iterations, residual, wall seconds, convergence).

        Raises
        ------
        NonFiniteStateError
            When the new positions or velocities are not finite (a blow-up); :attr:`state`
            stays the last finite one.
        """
        start = _time.perf_counter()
        s, h = self.state, self.h
        # An overflow ends as inf, which the solver (overflow_cause) or the check below
        # names as a NonFiniteStateError; numpy's "overflow encountered in dot" lines said
        # nothing more, after the error (Newton's wind force, Chebyshev's noise floor).
        with np.errstate(over="ignore"):
            problem = self.problem(s)
            result: StepResult = self._step_solver(s).solve(problem)
            x = result.x
            t1 = s.time + h
            if problem.has_contacts:
                self._contact_forces(problem, x, t1)
            for e in self._hooks["correct_positions"]:
                x = e.correct_positions(t1, s, x)
            v = (x - s.positions) / h
            for e in self._hooks["correct_velocities"]:
                v = e.correct_velocities(t1, s, x, v)
        blowup = state_cause(x, v, s.time)
        if blowup:
            raise NonFiniteStateError(blowup)
        self.state = State(x, v, t1, s.step + 1)
        return StepRecord(result.iterations, result.residual, _time.perf_counter() - start,
                          result.converged, result.residual_history)

    def run(self, steps: int, callback=None) -> list[StepRecord]:
        """Take several steps.

        More steps may follow (another :meth:`run`, :meth:`step`): the solver's factor is
        chosen for at least these steps, not for these alone (:meth:`expect_steps`).

        Parameters
        ----------
        steps : int
            Number of steps of length h.
        callback : callable, optional
            ``callback(simulation, record)`` is called after each step.

        Returns
        -------
        list of StepRecord
            One record per step.
        """
        records = []
        self.expect_steps(steps, final=False)
        for _ in range(int(steps)):
            rec = self.step()
            records.append(rec)
            if callback is not None:
                callback(self, rec)
        return records
