"""The per-step checker: is each of a port's steps the step clothsim takes from the same state?

For every frame k the port's state (x_k, v_k) is handed to clothsim, which takes one step;
its x_{k+1} is compared with the port's. Chaotic divergence of two long runs therefore
cannot hide or fake a bug: each step is judged on its own. First the vertices the scene
pins exactly must be at their targets; then a step within the tolerance agrees; a step that
does not is judged by the optimality of both answers for clothsim's objective g (the
implicit Euler objective of the paper, Eq. 4). The verdicts are listed in
:mod:`clothsim.ports.verdicts`; docs/ports.md explains each with an example.
"""

from __future__ import annotations

from contextlib import ExitStack

import numpy as np

from ..effects.base import overrides
from ..errors import InputError
from ..simulation import State
from ..solvers import make_solver
from ..solvers.local_global import LocalGlobalSolver
from .causes import FITTED, StepData, name_cause
from .compare import EPS32
from .contact_planes import PortPlanes
from .damping_fit import damping_model_cause
from .effect_causes import damping_cause, obstacle_cause
from .frame_order import (
    not_finite,
    port_frames,
    repeated_frame,
    start_mismatch,
    stepped_from,
    velocity_cause,
)
from .held_causes import explain
from .held_follow import beyond, followed, transient
from .held_margins import adopt, position_rounding
from .held_settle import marginal_entries, settle
from .held_steps import HeldSteps
from .held_verdicts import (
    off_plane_note,
    on_port_planes,
    planes_verdict,
    variant_verdict,
)
from .judge import CONVERGING, gradient_scale, judge, pin_role, pinned_moved
from .noise import noise_note
from .postsolve_margins import PortDecisions
from .precision import Printed
from .replays import Factors
from .rounding import float32_tolerance
from .solver_branches import SolverBranches
from .step_setup import (
    as_simulation,
    fixed_settings,
    float32_report,
    step_tolerance,
    system_condition_number,
)
from .verdicts import PASSING, CheckReport, StepCheck

#: Failing steps an obstacle of another size is read off (one or two replays each), and
#: steps whose velocities alone differ that a damping is fitted to (three replays each).
MAX_EFFECT = 3
#: Failing steps whose settings are searched for along clothsim's iterations (the rest
#: are judged without the search: a long failing run stays quick to check).
MAX_SEARCHES = 3

__all__ = ["PASSING", "CheckReport", "StepCheck", "as_simulation", "check_steps",
           "float32_report", "step_tolerance", "system_condition_number"]


def check_steps(simulation, positions, velocities=None, *, precision: str = "float64",
                tolerance: float | None = None, optimality: float = 1e-6,
                steps: int | None = None, expected_steps: int | None = None,
                contacts=None) -> CheckReport:
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
        frame 0 — only right without a velocity-changing damping; in a scene with
        post-solve obstacles, put through the scene's velocity corrections (the contacts
        read off the port's frames, :meth:`PortDecisions.derived_velocities`).
    precision : {"float64", "float32"}
        The port's arithmetic; sets the default tolerance (:func:`step_tolerance`).
    tolerance : float, optional
        Allowed per-vertex distance [m]; overrides the precision's.
    optimality : float, default 1e-6
        Largest relative gradient counted as a minimizer (raised to 10 × the rounding floor
        of ‖∇g‖, ε₃₂-based for float32).
    steps : int, optional
        Check only the first this many steps.
    expected_steps : int, optional
        The steps a whole output holds (``clothsim check`` passes the scene's frames unless
        ``--steps`` is given): a port that wrote fewer fails, naming both counts (the
        steps it did write are still judged). Default: any number.

    Returns
    -------
    CheckReport
    """
    sim = as_simulation(simulation)
    if expected_steps is not None and expected_steps < 0:
        raise InputError(f"expected_steps: must be >= 0, got {expected_steps}")
    xs, vs, notes = port_frames(sim, positions, velocities, steps)
    if precision not in ("float32", "float64"):
        raise InputError(f"precision: must be 'float32' or 'float64', got {precision!r}")
    h = sim.h
    tol64 = tolerance if tolerance is not None else step_tolerance(sim, xs[0])
    count = len(xs) - 1 if steps is None else min(int(steps), len(xs) - 1)
    printed = Printed(xs[:count + 1], None if velocities is None else vs[:count + 1], h,
                      tol64) if tolerance is None else None
    if printed is not None and printed.note:
        notes.append(printed.note)
    post = PortDecisions(sim)   # post-solve obstacles: their decisions too close to call
    factors = Factors()   # M + h² L of the cause search's replays, shared
    if velocities is None and post:   # the seed's velocity correction at the port's contacts
        notes[0] += ("; then the scene's velocity corrections (post-solve contact at the "
                     "vertices the port's x_k has on an obstacle, damping)")
        vs = post.derived_velocities(xs, vs, max(tol64, float(position_rounding(
            xs[0], printed.digits if printed else 17, bool(printed and printed.float32),
            tol64).max())))
    tol0 = tol64 if printed is None else float(printed.tolerances[0])
    start = start_mismatch(sim, xs[0], tol0 if precision == "float64" else
                           max(tol0, 4 * EPS32 * float(np.abs(xs[0]).max())),
                           None if sim is simulation else lambda: as_simulation(simulation))
    projected = [e.kind for e in sim.effects if overrides(e, "correct_positions")]
    iterations = sim.solver.iterations
    iterated = sim.solver.name != "newton"   # a converged method: the converged floor only
    held = HeldSteps(sim)
    branches = SolverBranches(sim)   # the solver's own choices too close to call
    if contacts is not None and not isinstance(contacts, PortPlanes):
        contacts = PortPlanes(contacts, sim.model.vertex_count)
    if contacts is not None:
        notes.append(f"the port's held planes: {contacts.path}" if held else
                     f"{contacts.path}: ignored, the scene holds no contacts (no obstacle in "
                     f"[contact] mode = \"hold\")")
        contacts = contacts if held else None
    out, searches, unexplained, others = [], 0, [], []
    # the failing steps an effect's cause was sought for (after a None: obstacles only
    # when the scene has one)
    obstacles = [None] if any(e.kind in ("sphere", "plane", "box") for e in sim.effects) \
        else []
    dampings, held_causes = [], []   # failing held steps a contact setting was sought for
    noisy, seconds = {}, []   # step k -> a noise's note; further steps searched again
    named = None   # (Change, k): the setting that reproduced step k, carried on
    gravity = next((e.acceleration for e in sim.effects if e.kind == "gravity"), None)

    t = sim.state.time  # accumulated as the simulation does (time-dependent effects)
    initial = (sim.state.positions.copy(), sim.state.velocities.copy())
    for k in range(count):
        if (nan := not_finite(xs, vs, k)) is not None:   # no step from it, or no answer
            out.append(StepCheck(k, "not finite", float("inf"), nan[0], note=nan[1]))
            t = t + h
            continue
        rounding = position_rounding(xs[k], printed.digits if printed else 17,
                                     precision == "float32" or bool(printed and
                                                                    printed.float32), tol64)
        state = State(post.start(xs[k], rounding), vs[k].copy(), t, k)
        t = t + h
        if held:
            held.anchor(xs[k])   # the planes clothsim decided, sticking ones at the port's x_k
            held.starts(state)
        model = sim.step_model(state)
        x_port = xs[k + 1]
        estimations = getattr(sim.solver, "rho_estimations", 0)
        problem, x_cs, v_cs, err, worst = _step(sim, held, state, x_port)
        carried = _carried(sim, estimations, model, problem, precision,
                           printed.unit if printed else None)

        def bound32(model=model, problem=problem, x_cs=x_cs):
            return float32_tolerance(model, problem, iterations, tol64, x=x_cs,
                                     iterated=iterated)

        tol = tol_k = tol64 if printed is None else float(printed.tolerances[k])
        if precision == "float32" and tolerance is None and err[worst] > tol_k:
            tol = max(tol_k, bound32())
        adopted = ""
        if held and (contacts is not None or err[worst] > tol):
            solved, adopted = settle(k, held, model, problem, tol, contacts, x_port, x_cs,
                                     rounding, lambda s=state, x=x_port: _step(sim, held, s, x))
            if solved is not None:   # too close to call from the port's state: the port's
                problem, x_cs, v_cs, err, worst = solved   # decision
        with ExitStack() as stack:
            if post and err[worst] > tol:   # post-solve decisions too close to call
                stack.enter_context(post.adopted(x_port, rounding, err))
                problem, x_cs, v_cs, err, worst = _step(sim, held, state, x_port)
                adopted = post.note()
            if printed is not None and printed.units and err[worst] > tol:   # contraction?
                tol = printed.replayed(k, sim, held, state, x_cs, x_port, tol,
                                       xs[k - 1] if velocities is None and k else None,
                                       branches)
                adopted_branch = bool(branches) and branches.adopted
                if not held or adopted_branch:   # the obstacles' state the port's start left
                    with ExitStack() as along:
                        if adopted_branch:
                            along.enter_context(branches.following(branches.path))
                        if held:   # from the step's anchored decision, as the replays were
                            held.again()
                        problem, x_cs, v_cs, err, worst = _step(sim, held, state, x_port)
                if branches and branches.note:
                    adopted = "; ".join(filter(None, (adopted, branches.note)))
        moved = pinned_moved(problem, x_port, tol if precision == "float64"
                             else max(tol_k, 4 * EPS32 * float(np.abs(x_port).max())))
        planes, differing = (None, []) if contacts is None else planes_verdict(
            k, held, contacts, xs[k], problem.fixed_vertices, err, tol)
        variant, off = ((None, np.inf) if moved is not None or err[worst] <= tol
                        or not held else variant_verdict(k, held, state, x_port, err, tol))
        if planes is not None:   # and the port's solve, on its own planes?
            adopt(held, differing, contacts.step(k))
            planes.note += "; " + on_port_planes(_step(sim, held, state, x_port)[3], tol)
        change, why_held, further = None, "", ""
        if named is not None and moved is None:   # the setting named before, carried on
            change, why_held, further = followed(held, named, state, x_port, err, tol)
            if further:   # read again here: the same setting, its value read off this step?
                again, words, nearer = explain(held, x_port, x_cs, err, tol)
                if again is not None and again.setting == named[0].setting:
                    change, why_held, further, named = again, words, "", (again, k)
                elif len(seconds) < MAX_EFFECT:   # a second setting, the first one kept?
                    seconds.append(k)
                    change, also = beyond(held, named[0], x_port, x_cs, err, tol)
                    further = f"{further}; {also}" if also else further
            variant = None if change is not None else variant
        elif (held and moved is None and off > tol and err[worst] > tol
                and len(held_causes) < MAX_EFFECT):   # a setting of the port's?
            held_causes.append(k)
            change, why_held, nearer = explain(held, x_port, x_cs, err, tol, [
                (j, xs[j]) for j in range(k + 2, min(k + 4, len(xs)))], models=True)
            if change is not None and nearer < off:
                variant = None          # the setting reproduces the step better
                named = (change, k) if nearer <= tol else None
            elif variant is not None:
                change, why_held = None, ""
        if planes is not None and variant is not None:   # the treatment behind the planes
            planes.note += "; " + variant.note
            variant = None
        if moved is not None:
            v, dist = moved
            noise = noise_note(model, problem, x_cs, x_port, tol)
            free = np.delete(err, problem.fixed_vertices).max(initial=0.0) > tol
            step = StepCheck(k, "noisy" if noise and free else "pinned vertex moved",
                             float(err[worst]), v, role=pin_role(problem, v), tolerance=tol,
                             note=f"the port moved it {dist:.3e} m from its target: " + (
                                 f"by the noise its free vertices carry too (it computes its "
                                 f"pinned vertices rather than holding them); {noise}"
                                 if noise else "its pins are missing or act elsewhere"))
        elif planes is not None or variant is not None:
            step = planes or variant
            step.note += f"; {why_held}" if why_held else ""
        elif printed is not None and (coarse := printed.too_coarse(k, float(err[worst]))):
            step = StepCheck(k, "too coarse", float(err[worst]), worst, tolerance=tol,
                             note=coarse)
        elif (again := repeated_frame(xs, vs, k, x_cs, err, tol, h)):
            step = StepCheck(k, "frame repeated", float(err[worst]), worst, tolerance=tol,
                             note=again)
        elif err[worst] > tol and not held and (other := stepped_from(
                sim, initial, xs, vs, k, state.time, tol)):
            step = StepCheck(k, "start differs", float(err[worst]), worst, tolerance=tol,
                             note=other)
        elif err[worst] <= tol:
            step = StepCheck(k, "agrees", float(err[worst]), worst, tolerance=tol)
            if velocities is not None:
                verr = np.linalg.norm(v_cs - vs[k + 1], axis=1)
                entry = held and marginal_entries(held, x_port, rounding, tol,
                                                  verr > 10 * tol / h)
                if entry:   # a contact entry too close to call: the port's
                    step.note = entry
                elif verr.max() > 10 * tol / h:
                    step = StepCheck(k, "velocities differ", float(err[worst]),
                                     int(np.argmax(verr)), tolerance=tol,
                                     note=f"|v_clothsim - v_port| = {verr.max():.3e} m/s")
                    dampings.append(k)
                    why = velocity_cause(xs, vs, k, h, x_cs, v_cs, 10 * tol / h) or (
                        "" if held or len(dampings) > MAX_EFFECT else
                        damping_cause(sim, state, vs[k + 1], 10 * tol / h)) or \
                        damping_model_cause(sim, x_cs, v_cs, vs[k + 1], 10 * tol / h)
                    step.note += f"; {why}" if why else ""
        else:
            step = judge(sim, model, problem, k, x_cs, x_port, err, tol, optimality, precision,
                         search=searches < MAX_SEARCHES, unit=printed and printed.unit)
            searches += 1
            why = ""
            unprojected = post.unprojected(err, tol) if step.passed else ""
            if obstacles and not held and not step.passed and len(obstacles) <= MAX_EFFECT:
                obstacles.append(k)
                why = obstacle_cause(sim, state, x_port, tol)
            if unprojected:   # the minimizer of g knows no obstacle; the port's answer did
                step.status, step.note = "contacts differ", unprojected   # not reach it
            elif change is not None:   # an obstacle or contact setting of the port's
                step.status, step.note = change.status, why_held
            elif why:
                step.status, step.note = "model differs", why
            elif (step.status in FITTED + ("start-dependent",) and not step.settings
                    and step.gradient_port >= CONVERGING):   # not a port that only stops short
                g0, opt = gradient_scale(model, problem, x_port, optimality, precision,
                                         printed and printed.unit)
                (unexplained if step.status in FITTED else others).append(StepData(
                    k, model, problem, x_port, g0, opt, step.gradient_clothsim,
                    float(err[worst]), tol, _replayer(sim, state, factors),
                    step.status == "not converged",
                    fixed_settings(sim), gravity=gravity, derived=velocities is None,
                    blind=optimality < step.gradient_clothsim <= opt,
                    effects=tuple(sim.effects), time=state.time))
            if step.status in ("start-dependent", "not a minimizer") and not step.settings \
                    and (noise := noise_note(model, problem, x_cs, x_port, tol)):
                noisy[k] = noise   # unless a model fitted after the loop explains the step
            if precision == "float64" and printed is not None and not step.passed:
                printed.hint32(step, float(err[worst]), lambda b=bound32, t=tol_k: max(t, b()))
            if why_held and change is None:
                step.note += f"; {why_held}"
            off = off_plane_note(held, x_port, tol) if held else ""
            if off:
                step.note += f"; {off}"
            if projected:
                step.note += (f"; positions are corrected after the solve by "
                              f"{', '.join(projected)}, so optimality for g alone is only "
                              f"indicative")
        if not step.role:
            step.role = pin_role(problem, step.vertex)
        if adopted:
            step.note = f"{step.note}; {adopted}" if step.note else adopted
        if further and not step.passed:   # beyond the setting named at an earlier step
            step.note, step.further = "; ".join(filter(None, (further, step.note))), True
        sim.solver.set_state(carried)
        out.append(step)
    name_cause({s.k: s for s in out}, unexplained, others)   # a model the port solves?
    for s in out:   # no model, no settings, and a difference as rough as noise
        if s.k in noisy and s.status in ("start-dependent", "not a minimizer"):
            hint = "; the port's numbers are float32 values: check with --precision float32"
            s.status, s.note = "noisy", noisy[s.k] + (hint if hint in s.note else "")
    transient(out)   # a further difference the named setting reproduces after: not one
    if printed is not None:   # the steps the printed state cannot place say so
        printed.annotate(out)
    return CheckReport(out, float(tol64), precision, notes, expected_steps=expected_steps,
                       printed=printed.text if printed is not None else "", start=start)




def _carried(sim, estimations, model, problem, precision, unit) -> dict:
    """What the solver carries to the next step, as the port's run would (Chebyshev's ρ).

    The replays and searches of a step solve from other starts: the state after the
    step's own solve is restored after them. Chebyshev estimates ρ at its first step that
    does not converge at once (ρ = 0 stays provisional). From a printed start, a step the
    port solved in one local/global iteration (a free fall) no longer does so to float64
    rounding, only to the printed rounding: an estimate made on a step whose first
    iterate meets the rounding floor of the port's precision (:func:`gradient_scale`:
    ``precision``, and ``unit`` the printed rounding) is dropped, as the port's run
    dropped it.
    """
    if getattr(sim.solver, "rho_estimations", 0) > estimations:
        first = next(it for it in LocalGlobalSolver.iterates(sim.solver, problem)
                     if it.k == 1)
        g0, floor = gradient_scale(model, problem, first.x, 0.0, precision, unit)
        if first.gradient_norm <= floor * g0:
            sim.solver.set_state({"rho": None})
    return sim.solver.get_state()


def _replayer(sim, state, factors):
    """``solve(model, problem) -> x``: clothsim's step of another model from ``state`` with
    the scene's solver settings (on the check's shared ``factors``), its position
    corrections (post-solve contact) applied; a hold-mode obstacle's is not (it would change
    the contacts the check holds)."""
    hooks = [e for e in sim.effects if overrides(e, "correct_positions")
             and getattr(e, "contact", None) != "hold"]

    def solve(model, problem):
        x = factors.solve(make_solver(sim.solver.name, model, iterations=sim.solver.iterations,
                                      tolerance=sim.solver.tolerance), model, problem).x
        for e in hooks:
            x = e.correct_positions(state.time + sim.h, state, x)
        return x
    return solve


def _step(sim, held, state, x_port):
    """clothsim's step from the port's state: its problem, x, v, per-vertex error, worst."""
    problem = sim.problem(state)
    sim.state = state
    sim.step()
    held.stepped()
    x_cs, v_cs = sim.state.positions, sim.state.velocities
    err = np.linalg.norm(x_cs - x_port, axis=1)
    err = np.where(np.isfinite(err), err, np.inf)
    return problem, x_cs, v_cs, err, int(np.argmax(err))
