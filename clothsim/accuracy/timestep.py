"""Time-step error, separated from solver error.

Converged solves only (Newton to 1e-10) at several h, against a Richardson-extrapolated
run at a much smaller h (:func:`~.converged.reference_trajectory`). The fitted slope of
error against h is implicit Euler's order (1) only once ω_max h ≲ 1, ω_max the stiffest
angular frequency (2 / the explicit stability limit). Far above that, implicit Euler damps
the stiff modes completely and the error hardly changes with h: :func:`time_step_study`
then says so instead of fitting a slope. Contact changes the equations (an obstacle or a
strain limit moves vertices after the solve), so the error is fitted only on the longest
window of frames in which no run, reference included, had a position correction
(:func:`contact_free_window`); without such a window there is no time-step error.
"""

from __future__ import annotations

import logging
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..solvers import stable_time_step
from .converged import converged_run
from .parallel import map_jobs
from .phases import advance
from .trajectory import (
    SimulationFactory,
    run_trajectory,
    trajectory_error,
)

log = logging.getLogger(__name__)

CONVERGED = ("newton", 100, 1e-10)


@dataclass
class TimeStepStudy:
    """Time-step error of converged solves against h.

    Attributes
    ----------
    time_steps : list of float
        h [s], at least three.
    errors : list of float
        ‖X(h) − X_ref‖ / ‖X_ref − X_a‖ over the frames a … b of ``window`` (NaN without a
        window).
    slope : float
        Log-log slope of error against h (NaN when not fitted).
    omega_max : float
        Stiffest angular frequency [rad/s], 2 / stable explicit step.
    asymptotic_h : float
        1 / ω_max [s]: below it the error falls like h.
    reference_error : float
        Estimated relative error of the unextrapolated reference.
    note : str
        One line: the slope, or why there is none.
    reference : ndarray, shape (frames + 1, n, 3)
        The reference frames [m].
    window : tuple of int or None
        (a, b): the frames a … b fitted (the longest run without contact), or None.
    contact : ndarray, shape (frames,), bool
        Frame f → f + 1 had a position correction in some run.
    """

    time_steps: list
    errors: list
    slope: float
    omega_max: float
    asymptotic_h: float
    reference_error: float
    note: str
    reference: np.ndarray
    window: tuple | None = None
    contact: np.ndarray | None = None


def contact_free_window(contact: np.ndarray) -> tuple[int, int] | None:
    """The longest run of frames a … b (b > a) whose transitions f → f + 1, a ≤ f < b, are
    all free of contact (the earliest among equals); None when every frame has contact.

    Parameters
    ----------
    contact : ndarray, shape (frames,), bool
        Whether a position correction moved a vertex during frame f → f + 1.

    Returns
    -------
    tuple of int or None
        The window (a, b) of frames, or None.
    """
    best, start = None, None
    for f, c in enumerate(list(np.asarray(contact, dtype=bool)) + [True]):
        if not c and start is None:
            start = f
        elif c and start is not None:
            if best is None or f - start > best[1] - best[0]:
                best = (start, f)
            start = None
    return best


def time_step_study(factory: SimulationFactory, *, frame_time: float, frames: int,
                    time_steps: Sequence[float], reference_h: float | None = None,
                    jobs: int = 1) -> TimeStepStudy:
    """Converged runs at each h against a small-h reference (see the module text).

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation`` (fresh each call).
    frame_time : float
        Time between compared frames [s]; each h must divide it.
    frames : int
        Frames compared.
    time_steps : sequence of float
        At least three h [s].
    reference_h : float, optional
        Default min(time_steps) / 8.
    jobs : int, default 1
        Parallel workers, one converged run each (:func:`~.parallel.map_jobs`; the runs
        are deterministic, so the result does not depend on it).

    Returns
    -------
    TimeStepStudy
        Errors per h, their fitted slope, ω_max and the note on the asymptotic regime.
    """
    hs = sorted(float(h) for h in time_steps)
    h_ref = hs[0] / 8.0 if reference_h is None else reference_h
    # the reference runs (h_ref and 2 h_ref, as reference_runs) and the measured ones, all
    # converged alike; the coarse reference run is reused when it is a measured h
    own = [h for h in hs if not math.isclose(h, 2.0 * h_ref, rel_tol=1e-12)]
    steps = [h_ref, 2.0 * h_ref, *own]          # the longest run first, for the workers
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        done = map_jobs(_converged_run, [(factory, step, frames, frame_time) for step in steps],
                        jobs=jobs, each=None if jobs == 1 else lambda _: advance(frames))
        fine, coarse = done[0], done[1]
        by_h = dict(zip(own, done[2:]))
        runs = [by_h.get(h, coarse) for h in hs]
        sim = factory(*CONVERGED[:1], hs[0], *CONVERGED[1:])
        problem = sim.problem()
    ref = 2.0 * fine.frames - coarse.frames
    ref_err = trajectory_error(coarse.frames, fine.frames)
    contact = np.logical_or.reduce([r.contact for r in (fine, coarse, *runs)])
    window = contact_free_window(contact)
    if window is None:
        return TimeStepStudy(hs, [math.nan] * len(hs), math.nan, math.nan, math.nan, ref_err,
                             f"no time-step error: every one of the {frames} frames has "
                             f"contact (a position correction), no contact-free window; what "
                             f"to do: the contact corrections, not h, set the trajectory "
                             f"error here; to see the time-step error, study frames before "
                             f"the contact (--frames) or the scene without its obstacle",
                             ref, None, contact)
    a, b = window
    errs = [trajectory_error(r.frames[a:b + 1], ref[a:b + 1]) for r in runs]
    where = f"on frames {a}–{b} (the longest window without contact)"
    omega = 2.0 / stable_time_step(sim.model, anchor_vertices=problem.anchor_vertices,
                                   anchor_stiffness=problem.anchor_stiffness)
    h_asym = 1.0 / omega
    ok = [(h, e) for h, e in zip(hs, errs) if math.isfinite(e) and e > 0]
    slope = math.nan
    if len(ok) >= 2:  # --quick checks two time steps
        slope = float(np.polyfit(*np.log(np.array(ok)).T, 1)[0])
    if math.isfinite(slope) and slope >= 0.7:
        note = (f"time-step error falls like h^{slope:.2f} (implicit Euler: first order), "
                f"{where}")
    else:
        note = (f"time-step error does not fall like h here (slope {slope:.2f}): h ≥ "
                f"{hs[0]:.3g} s is far above 1/ω_max = {h_asym:.3g} s (ω_max = "
                f"{omega:.3g} rad/s); the asymptotic regime starts near h ≈ {h_asym:.2g} s; "
                f"{where}")
    note += "; " + what_to_do(errs[-1], slope, hs[-1], h_asym, frame_time)
    return TimeStepStudy(hs, errs, slope, omega, h_asym, ref_err, note, ref, window, contact)


def what_to_do(error: float, slope: float, h: float, h_asym: float, frame_time: float) -> str:
    """The time-step note's advice, for a student: what the error at h means, what to change.

    Parameters
    ----------
    error : float
        Time-step error of a converged solve at h (dimensionless).
    slope : float
        Fitted order (NaN: none).
    h : float
        The scene's time step [s].
    h_asym : float
        1 / ω_max [s].
    frame_time : float
        1 / fps [s].

    Returns
    -------
    str
        One clause.
    """
    substeps = max(1, round(frame_time / h))
    if math.isfinite(slope) and slope >= 0.7:
        return (f"what to do: even a fully converged solve is {error:.2g} off at h = {h:.3g} s "
                f"(time-step error); more solver iterations cannot go below that: to halve "
                f"it, halve h (--set scene.substeps={2 * substeps})")
    need = max(1, math.ceil(frame_time / h_asym))
    halving = (f"halving h removes only {100 * (1 - 2.0 ** -slope):.0f}% of it (slope "
               f"{slope:.2f})" if math.isfinite(slope) and slope > 0
               else "halving h does not reduce it")
    return (f"what to do: even a converged solve is {error:.2g} off at h = {h:.3g} s and "
            f"{halving}: implicit Euler damps the stiffest springs' motion at this h, and "
            f"first-order convergence needs h near {h_asym:.2g} s (--set "
            f"scene.substeps={need}); for plausible cloth keep h and spend the time on "
            f"solver iterations, for an accurate trajectory take many more substeps")


TRAJECTORY_BUDGETS = (1, 5, 10, 20)


def trajectory_errors(factory: SimulationFactory, configs, reference: np.ndarray, *,
                      h: float, frame_time: float, jobs: int = 1) -> dict:
    """Trajectory error (against ``reference``) of the configurations a user would run
    for a whole trajectory: budgets 1, 5, 10, 20 and every tolerance, at step h.

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``.
    configs : sequence of Configuration
        The study's configurations (those with other budgets are skipped).
    reference : ndarray, shape (frames + 1, n, 3)
        The reference trajectory [m].
    h : float
        Time step [s].
    frame_time : float
        Time between frames [s].
    jobs : int, default 1
        Parallel workers (joblib, loky backend), one run each; every run is
        deterministic, so any ``jobs`` gives the same errors.

    Returns
    -------
    dict
        Configuration → ‖X − X_ref‖ / ‖X_ref − X_0‖ (time-step and solver error together);
        inf for a run that blew up (a non-finite state or force): it is recorded, and the
        other runs go on.
    """
    chosen = [c for c in configs
              if c.tolerance is not None or c.iterations in TRAJECTORY_BUDGETS]
    if jobs > 1:   # the likely longest runs first, so that no worker is left with them last
        chosen.sort(key=_likely_cost, reverse=True)
    frames = len(reference) - 1
    errs = map_jobs(_trajectory_error,
                    [(factory, c, reference, h, frame_time) for c in chosen], jobs=jobs,
                    each=None if jobs == 1 else lambda _: advance(frames))
    return dict(zip(chosen, errs))


def _likely_cost(c) -> tuple:
    """A sort key: Newton's runs (a factorization per iteration) before the others, then
    tight tolerances before loose ones, then large budgets before small ones."""
    tight = -math.log10(c.tolerance) if c.tolerance is not None else 0.0
    return (c.method == "newton", tight, c.iterations if c.tolerance is None else 0)


def _converged_run(factory, h, frames, frame_time):
    """One converged run at h with its contact flags (:data:`CONVERGED`, warm-started)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return converged_run(factory, h, frames, frame_time, *CONVERGED)


def _trajectory_error(factory, c, reference, h, frame_time) -> float:
    """One configuration's trajectory error (inf when it blew up)."""
    from .study import BLOW_UPS

    frames = len(reference) - 1
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            sim = factory(c.method, h, c.iterations, c.tolerance)
            for name, value in c.options:  # the study's settings, e.g. Chebyshev's ρ
                setattr(sim.solver, name, value)
            err = trajectory_error(run_trajectory(sim, frames=frames,
                                                  frame_time=frame_time).frames, reference)
        except BLOW_UPS as exc:
            log.warning("%s: trajectory diverged: %s", c.label, exc)
            err = math.inf
    return err if math.isfinite(err) else math.inf
