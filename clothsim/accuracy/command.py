"""``clothsim accuracy``: the whole study of one scene, as a library function.

:func:`run_accuracy` records the scene's step problems along one converged run, certifies a
reference per step, measures every configuration on the same problems (errors),
optionally the time-step and trajectory errors, then times the configurations in
interleaved repeats (repeating only those an answer could choose, :mod:`.dominance`, and
those an answer row has not yet told apart, :mod:`.decide`), extrapolates local/global's
iterations to targets none of its settings reached (:mod:`.extrapolate`), and
writes ``accuracy.csv``,
``accuracy.json`` (machine, versions, threads, one-off costs), ``steps.md`` and the plots.
It returns the text the command prints: the answer table first.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..factorization import cholmod_available
from ..io.common import write_text
from ..io.outfolder import OutputFolder
from .answer import BASELINE, TRAJECTORY, answer_table, questions, short_answer
from .converged import warm_started
from .decide import choose, undecided
from .dominance import MARGIN as DOMINANCE_MARGIN
from .limits import limit_stops, method_limits, worse_minimum_notes
from .parallel import check_scheduler
from .phases import Phases
from .problems import load_problems, record_problems, save_problems
from .report import (
    fixed_budget_measure,
    fixed_budget_table,
    reference_uncertainty,
    rows,
    steps_table,
    worse_than_local_global,
    write_csv,
)
from .runs import method_runs, run_count, stops
from .study import (
    BUDGETS,
    DEFAULT_CAP,
    KINDS,
    TOLERANCES,
    ConfigResult,
    chebyshev_rho,
    default_configurations,
    measure,
    prepare_steps,
)
from .sweep import TRAJECTORY_LEVELS
from .timing import (
    _limited_threads,
    installed_version,
    machine_info,
    one_off_costs,
    source_commit,
    time_configurations,
    timing_clock,
)
from .trace import ACCURACY_LEVELS, ITERATIVE_METHODS
from .trajectory import steps_per_frame

log = logging.getLogger(__name__)

QUICK = {"problems": 4, "budgets": (1, 5, 10, 20, 100), "tolerances": (1e-3, 1e-6),
         "repeats": 1, "cap": 1000}
"""What ``--quick`` runs (at most: problems and repeats are capped, never raised)."""
QUICK_TIME_STEP_FRAMES = 6
"""Frames of ``--quick``'s time-step check (at h and h/2; no trajectory errors)."""


def scene_factory(scene):
    """(factory, model, frame_time) for a scene: ``factory(method, h, iterations,
    tolerance)`` builds a fresh simulation at step h (h must divide 1 / fps).

    Parameters
    ----------
    scene : clothsim.scene.Scene
        A validated scene.

    Returns
    -------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``, h [s].
    model : Model
        The scene's model (shared by every simulation the factory builds).
    frame_time : float
        1 / fps [s].
    """
    model = scene.build_model()
    frame_time = 1.0 / scene.fps

    def factory(method, h, iterations, tolerance):
        substeps = steps_per_frame(frame_time, h)
        return scene.build_simulation(model, method=method, iterations=iterations,
                                      tolerance=tolerance, substeps=substeps)

    return factory, model, frame_time


def run_accuracy(scene, out, *, methods: Sequence[str] = ITERATIVE_METHODS,
                 problems: int = 8, frames: int | None = None, repeats: int = 5,
                 jobs: int = 1, scheduler: str | None = None, target: float | None = None,
                 budgets: Sequence[int] = BUDGETS, tolerances: Sequence[float] = TOLERANCES,
                 time_steps: bool = True, plots: bool = True, threads: int = 1,
                 steps_file=None, quick: bool = False, force: bool = False) -> str:
    """Run the accuracy study of ``scene`` into folder ``out``; return the printed report.

    Parameters
    ----------
    scene : clothsim.scene.Scene
    out : path
        Output folder (created): missing, empty or an earlier accuracy study's
        (:class:`clothsim.io.outfolder.OutputFolder`); locked while the study runs;
        ``accuracy.json`` says ``running`` while it runs, then ``complete``, or
        ``interrupted`` / ``failed`` with the error.
    methods : sequence of str
        Solver names (see :data:`clothsim.solvers.SOLVERS`).
    problems : int
        Step problems recorded, spread over the run.
    frames : int, optional
        Frames of the recorded run; default the scene's own.
    repeats : int
        Interleaved timing repeats (≥ 5 for a referee; fewer only to try things).
    jobs : int
        Parallel workers for the references, the methods' own limits, the error
        measurement, the time-step study's runs and the trajectory runs (joblib; the
        results do not depend on it).
    scheduler : str, optional
        Dask scheduler address (joblib's dask backend).
    target : float, optional
        Report only this solver-error level in the answer table.
    budgets, tolerances : sequences
        Iterations per step, and relative-residual tolerances, of the configurations.
    time_steps : bool
        Also measure the time-step error (converged runs at h, h/2, h/4).
    plots : bool
        Write the PNG figures (needs matplotlib).
    threads : int
        BLAS threads during timing.
    steps_file : path, optional
        A ``problems.npz`` an earlier study wrote: measure exactly those step problems
        instead of recording new ones.
    quick : bool
        A first look in seconds (:data:`QUICK`): at most 4 problems, budgets 1, 5, 10, 20,
        100, tolerances 1e-3 and 1e-6 (at most 1000 iterations), 1 timing repeat (more for
        the settings an answer must tell apart, :mod:`.decide`), no trajectory errors, a
        time-step check of :data:`QUICK_TIME_STEP_FRAMES` frames at h and h/2 only.
    force : bool
        Write into ``out`` even when it holds files that are not an accuracy study's.

    Returns
    -------
    str
        The report: answer table, fixed-budget table, steps and notes.
    """
    if jobs < 1:
        raise InputError(f"accuracy.jobs: must be >= 1, got {jobs}")
    if repeats < 1:
        raise InputError(f"accuracy.repeats: must be >= 1, got {repeats}")
    if target is not None and not (target > 0):
        raise InputError(f"accuracy.target: must be positive, got {target}")
    from ..solvers import SOLVERS

    for m in methods:
        if m not in SOLVERS or m == "symplectic-euler":
            raise InputError(f"accuracy.methods: {m!r} is not an iterative solver; choose from "
                             f"{', '.join(s for s in SOLVERS if s != 'symplectic-euler')}")
    if not methods:
        raise InputError("accuracy.methods: no solver given; name one or more of "
                         + ", ".join(ITERATIVE_METHODS))
    if frames is not None and frames < 1:
        raise InputError(f"accuracy.frames: must be >= 1 (a study needs a step), got {frames}")
    if steps_file is not None:  # a file that is no problem set: refused before any writing
        load_problems(steps_file)
    if scheduler is not None:
        check_scheduler(scheduler)  # the slowest check, last; before anything is written
    if quick:
        problems, repeats = min(problems, QUICK["problems"]), min(repeats, QUICK["repeats"])
        budgets, tolerances = QUICK["budgets"], QUICK["tolerances"]
    commit = source_commit()  # of the code that runs (HEAD may move while it runs)
    cholmod_available()  # load CHOLMOD's BLAS and OpenMP first, so that their pools are limited
    # one BLAS/OpenMP thread throughout: reproducible, and on a shared machine faster than
    # idle worker threads; an interruption or an error marks the study so (OutputFolder)
    with OutputFolder(out, "accuracy", force=force) as folder, _limited_threads(threads):
        if folder.earlier.kind != "accuracy":  # mark the folder as a study's from the start
            _begin(folder, scene)
        return _run(scene, folder, methods, problems, frames, repeats, jobs, scheduler,
                    target, budgets, tolerances, time_steps, plots, threads, steps_file, quick,
                    commit)


#: what a study writes besides accuracy.json and problems.npz (removed when a new one begins)
FIGURE = "fixed_budget.png"
OUTPUTS = ("accuracy.csv", "steps.md", FIGURE)


def _begin(folder: OutputFolder, scene) -> None:
    """Mark the folder as a study in progress: accuracy.json says ``running`` (the study's own
    record replaces it at the end) and an earlier study's other files are removed, so that
    what the folder holds is, at every instant, one study's (maybe unfinished) work."""
    folder.mark("writing", {"clothsim": installed_version(), "scene": scene.name})
    for name in OUTPUTS:
        (folder.path / name).unlink(missing_ok=True)


def _run(scene, folder, methods, problems, frames, repeats, jobs, scheduler, target, budgets,
         tolerances, time_steps, plots, threads, steps_file, quick, commit) -> str:
    out = folder.path
    factory, model, frame_time = scene_factory(scene)
    frames = scene.frames if frames is None else frames
    h = scene.h
    phases = Phases()
    if steps_file is not None:
        recorded = load_problems(steps_file, model, h)
    else:
        sim = warm_started(factory("newton", h, 100, 1e-10))
        with phases.phase("recording", max(1, frames * scene.substeps), "step"):
            recorded = record_problems(sim, steps=max(1, frames * scene.substeps),
                                       count=problems)
    _begin(folder, scene)  # an earlier study's files go now that this one has its steps
    save_problems(recorded, out / "problems.npz", model)
    cap = QUICK["cap"] if quick else DEFAULT_CAP
    # the references' local/global runs (its own limit) keep the local/global settings too
    lg_stops = stops(default_configurations(
        [m for m in methods if m == BASELINE], budgets=budgets, tolerances=tolerances,
        cap=cap)).get((BASELINE, ()), [])
    if lg_stops:   # and the tail of a run of cap iterations, should an answer extrapolate
        from .extrapolate import tail_stops

        lg_stops += tail_stops(cap)
    with phases.phase("references", len(recorded), "step"):
        steps = prepare_steps(model, recorded, jobs=jobs, cap=cap, local_global_stops=lg_stops)
    ends = {(s.step.index, BASELINE, (), k): v for s in steps if s.measured
            for k, v in s.reference.local_global_runs.items()}
    options = {}
    if "chebyshev" in methods:
        options["chebyshev"] = {"rho": chebyshev_rho(model, steps)}
    configs = default_configurations(methods, budgets=budgets, tolerances=tolerances,
                                     options=options, cap=cap)
    measured = sum(1 for s in steps if s.measured)
    # each method's limit run also stops at its configurations (clothsim.accuracy.runs):
    # the error measurement reads them off it
    limit_runs = limit_stops(steps, methods, options=options, cap=cap)
    for key, wanted in stops(configs).items():
        if key in limit_runs:
            limit_runs[key] = wanted + limit_runs[key]
    with phases.phase("limits", measured * (len(methods) + run_count(limit_runs)), "limit"):
        ends |= method_runs(model, steps, limit_runs, jobs=jobs)
        method_limits(model, steps, methods, options=options, cap=cap,  # may add minima
                      jobs=jobs, runs=ends)
    notes = []
    nothing = not any(s.measured for s in steps)
    if nothing:  # early stop: no step can be measured, so nothing below would be used
        notes.append("no recorded step can be measured (see steps.md): errors and timings "
                     "were not run" + (", nor the time-step check" if quick else ""))
        results = [ConfigResult(c, np.zeros(0), np.zeros(0, dtype=int)) for c in configs]
    else:
        rest = {k: w for k, w in stops(configs).items()
                if k not in limit_runs and k != (BASELINE, ())}
        with phases.phase("errors", measured * run_count(rest), "run"):
            results = measure(model, steps, configs, jobs=jobs, scheduler=scheduler,
                              runs=ends)
    write_csv(rows(results, steps, h=h), out / "accuracy.csv")  # errors kept if later fails
    ts_error, ts, traj = math.nan, None, {}
    if time_steps and frames > 0 and not (nothing and quick):
        from .timestep import TRAJECTORY_BUDGETS, time_step_study, trajectory_errors

        ts_frames = min(frames, QUICK_TIME_STEP_FRAMES if quick else 30)
        ts_hs = (h, h / 2) if quick else (h, h / 2, h / 4)
        runs = 2 + sum(1 for x in ts_hs if not math.isclose(x, h / 4))  # h/4 is reused
        with phases.phase("time-step study", ts_frames * runs, "frame"):
            ts = time_step_study(factory, frame_time=frame_time, frames=ts_frames,
                                 time_steps=ts_hs, reference_h=h / 8, jobs=jobs)
        # no contact-free window: the CSV cell stays empty
        ts_error = ts.errors[ts.time_steps.index(h)] if ts.window is not None else None
        notes.append(ts.note)
        if not quick:
            runs = sum(1 for c in configs
                       if c.tolerance is not None or c.iterations in TRAJECTORY_BUDGETS)
            with phases.phase("trajectories", ts_frames * runs, "frame"):
                traj = trajectory_errors(factory, configs, ts.reference, h=h,
                                         frame_time=frame_time, jobs=jobs)
    table = rows(results, steps, h=h, time_step_error=ts_error, trajectory_errors=traj)
    write_csv(table, out / "accuracy.csv")
    levels = (target,) if target is not None else ACCURACY_LEVELS
    short = (target,) if target is not None else (1e-3,)   # the short answer's
    unc = reference_uncertainty(steps)
    asked = questions(table, levels=levels, short_levels=short, uncertainty=unc,
                      trajectory_levels=TRAJECTORY_LEVELS if traj else ())
    extrapolated = {}
    if not nothing:   # last: which settings an answer could choose is known by now
        errors = [(r.solver_error_p90, r.objective_gap_p90, r.trajectory_error) for r in table]
        answered = ([v for v in levels if v >= unc] + list(short), levels,
                    TRAJECTORY_LEVELS if traj else ())

        def still_open():   # the answer rows not yet decided by their timings
            return undecided(rows(results, steps, h=h, time_step_error=ts_error,
                                  trajectory_errors=traj), asked)

        with phases.phase("timing", repeats * len(configs), "config"):
            once = time_configurations(model, steps, results, repeats=repeats,
                                       threads=threads, errors=errors, levels=answered,
                                       undecided=still_open)
        table = rows(results, steps, h=h, time_step_error=ts_error, trajectory_errors=traj)
        write_csv(table, out / "accuracy.csv")
        if once:
            notes.append(f"{len(once)} configuration(s) timed twice only (column 'repeats'): "
                         f"for each, another setting reaches every target it reaches, in "
                         f"every error, in at most 1/{DOMINANCE_MARGIN:g} of its time, so no "
                         f"answer can choose it")
        if "local-global" in methods:
            extrapolated = _extrapolate(model, steps, table, asked, cap, phases)
    info = machine_info(threads) | one_off_costs(model, steps, threads=threads)
    info |= {"status": "complete", "commit": commit, "scene": scene.name, "h": h,
             "frames": frames, "repeats": repeats,
             "chebyshev_rho": options.get("chebyshev", {}).get("rho"),
             "timing_clock": timing_clock(threads)[1],
             "phase_seconds": phases.seconds}
    folder.mark("complete", info)
    write_text(out / "steps.md", steps_table(steps) + "\n")
    kinds = [s.kind for s in steps]
    missed = sum(1 for r in recorded if r.converged is False)
    if missed:
        notes.append(f"{missed} recorded step(s): the recording solve missed its tolerance "
                     f"(column 'recorded' in steps.md)")
    diverged = [r.setting for r in table if r.status == "diverged"]
    if diverged:
        notes.append(f"{len(diverged)} configuration(s) diverged (status 'diverged' in the "
                     f"CSV, never an answer): {'; '.join(diverged)}")
    if kinds.count("several-minima"):
        notes.append(f"{kinds.count('several-minima')} step(s) have several certified minima "
                     f"(Newton from y, x_n and converged local/global end at different "
                     f"minima): measured by the relative objective gap, not by a distance")
    notes += worse_minimum_notes(steps, target if target is not None else 1e-3)
    failed = kinds.count("saddle") + kinds.count("reference-failed")
    if failed:
        notes.append(f"{failed} step(s) have no certified reference ({kinds.count('saddle')} "
                     f"saddle, {kinds.count('reference-failed')} reference failed): not "
                     f"measured, see steps.md")
    if plots and any(s.kind == "unique" for s in steps):  # it plots the solver error
        from .plots import plot_fixed_budget

        plot_fixed_budget(table, out / FIGURE, title=scene.name, uncertainty=unc)
    classes = ", ".join(f"{kinds.count(k)} {k}" for k in KINDS)
    text = [f"# accuracy of {scene.name}: h = {h:.4g} s, {measured} of {len(steps)} recorded "
            f"steps measured ({classes})", "",
            *short_answer(table, short, extrapolated=extrapolated), "",
            answer_table(table, levels=levels, uncertainty=unc, extrapolated=extrapolated,
                         trajectory_levels=TRAJECTORY_LEVELS if traj else ()), "",
            f"Fixed budget ({fixed_budget_measure(table)} after k iterations per step):", "",
            fixed_budget_table(table), ""]
    text += [f"note: {n}" for n in worse_than_local_global(table)]
    if not nothing:
        notes.append(f"timings are {timing_clock(threads)[1]} seconds per step"
                     + (" (one BLAS thread): the solver's work, not the time spent waiting "
                        "for a core on a shared machine" if threads == 1 else ""))
    text += [f"note: {n}" for n in notes]
    text.append(f"wrote {out / 'accuracy.csv'} ({len(table)} configurations), "
                f"{out / 'accuracy.json'}, {out / 'steps.md'}, {out / 'problems.npz'} "
                f"(clothsim commit {info['commit']})")
    return "\n".join(text)


def _extrapolate(model, steps, table, asked, cap, phases) -> dict:
    """(column, level) → local/global's extrapolated iterations, for each printed level
    that no local/global setting reaches (:mod:`.extrapolate`)."""
    from .extrapolate import extrapolate, tail_runs

    want = sorted({(col, lev) for col, lev, _ in asked if col != TRAJECTORY
                   and choose(table, lev, error=col, method=BASELINE).row is None})
    if not want:
        return {}
    out = {}
    for col in dict.fromkeys(c for c, _ in want):
        measure = "solver error" if col.startswith("solver") else "objective gap"
        count = sum(1 for s in steps if (s.kind == "unique" if measure == "solver error"
                                         else s.measured))
        with phases.phase("extrapolation", count, "step"):
            tails = tail_runs(model, steps, iterations=cap, measure=measure)
        for c, lev in want:
            if c == col and (e := extrapolate(tails, lev, measure)) is not None:
                out[(c, lev)] = e
    return out
