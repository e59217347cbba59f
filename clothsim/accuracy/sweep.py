"""The sweep: every configuration (method × iterations or tolerance × h) run and measured."""

from __future__ import annotations

import csv
import logging
import math
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.common import atomic_path
from .converged import reference_trajectory
from .trace import ACCURACY_LEVELS, EXPLICIT_METHODS, IterateTrace
from .trajectory import (
    SimulationFactory,
    SweepRow,
    _stable_explicit_step,
    run_trajectory,
    steps_per_frame,
    trajectory_error,
)

log = logging.getLogger(__name__)

TRAJECTORY_LEVELS = (0.5, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001)
"""Trajectory accuracy targets (time discretization dominates: implicit Euler is first order)."""
CSV_FIELDS = ("method", "h", "iterations", "tolerance", "steps_per_frame", "seconds_per_step",
              "seconds_per_frame", "solver_error", "objective_gap", "trajectory_error")


def run_sweep(factory: SimulationFactory, *, time_steps: Sequence[float],
              frame_time: float, frames: int,
              methods: Sequence[str] = ("local-global", "chebyshev", "anderson", "lbfgs",
                                        "newton", "symplectic-euler"),
              iterations: Sequence[int] = (1, 2, 5, 10, 20, 50),
              newton_iterations: Sequence[int] = (1, 2, 3, 5),
              tolerances: Sequence[float] = (),
              reference_h: float | None = None, reference_method: str = "newton",
              reference_tolerance: float = 1e-10, reference_iterations: int = 50,
              reference: np.ndarray | None = None, probe_frame: int | None = None,
              backend: str = "auto", progress: bool = False) -> list[SweepRow]:
    """Run every configuration (method × iterations or tolerance × h) and measure it.

    Parameters
    ----------
    factory : callable
        ``factory(method, h, iterations, tolerance) -> Simulation``; each call must
        return a fresh simulation at the scene's initial state.
    time_steps : sequence of float
        Time steps h [s] for the implicit methods; each must divide ``frame_time``.
    frame_time : float
        Time between recorded frames [s] (1 / fps).
    frames : int
        Frames to run; trajectories are compared at every frame.
    methods : sequence of str
        ``"symplectic-euler"`` runs once, at the largest frame_time / 2^j below 0.9 × its
        stability limit.
    iterations : sequence of int
        Iterations per step for local/global and Chebyshev.
    newton_iterations : sequence of int
        Iterations per step for Newton.
    tolerances : sequence of float
        Extra configurations with a relative-residual tolerance (iterations up to 10000).
    reference_h : float, optional
        Reference time step; default min(time_steps) / 16.
    reference_method, reference_tolerance, reference_iterations
        The reference run (:func:`reference_trajectory`, Richardson-extrapolated) is
        solved by this method to this relative residual, with at most this many
        iterations per step.
    reference : ndarray, shape (frames + 1, n, 3), optional
        A precomputed reference trajectory (then ``reference_*`` are ignored).
    probe_frame : int, optional
        Frame at whose first step the solver error is measured (default frames // 2).
    backend : {"auto", "cholmod", "splu"}
        Factorization backend of the solver-error probe.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of SweepRow
        One row per configuration, in the order run.
    """
    if frames < 1:
        raise InputError(f"accuracy.frames: must be >= 1, got {frames}")
    probe = frames // 2 if probe_frame is None else probe_frame
    h_ref = min(time_steps) / 16.0 if reference_h is None else reference_h
    configs: list[tuple[str, float, int | None, float | None]] = []
    for method in methods:
        if method in EXPLICIT_METHODS:
            configs.append((method, math.nan, 1, None))
            continue
        its = newton_iterations if method == "newton" else iterations
        for h in time_steps:
            steps_per_frame(frame_time, h)
            configs += [(method, h, int(k), None) for k in its]
            configs += [(method, h, 10000, float(t)) for t in tolerances]
    bar = _progress(len(configs) + 1, progress)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if reference is None:
            reference, ref_error = reference_trajectory(
                factory, h=h_ref, frames=frames, frame_time=frame_time,
                method=reference_method, tolerance=reference_tolerance,
                iterations=reference_iterations)
            log.info("reference h=%.4g s: unextrapolated relative error about %.2e",
                     h_ref, ref_error)
    bar.update(1)
    rows = []
    for method, h, its, tol in configs:
        bar.set_description(f"{method} h={h:.4g} it={its}")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if method in EXPLICIT_METHODS:
                probe_sim = factory(method, frame_time, 1, None)
                h = _stable_explicit_step(probe_sim.model, frame_time, probe_sim.problem())
            sim = factory(method, h, its, tol)
            traj = run_trajectory(sim, frames=frames, frame_time=frame_time,
                                  probe_frame=probe, backend=backend)
        per_step = float(np.median(traj.step_seconds[1:] or traj.step_seconds))
        spf = steps_per_frame(frame_time, h)
        rows.append(SweepRow(method, h, its, tol, spf, per_step, per_step * spf,
                             traj.solver_error, traj.objective_gap,
                             trajectory_error(traj.frames, reference)))
        bar.update(1)
    bar.close()
    return rows


class _NoBar:
    def update(self, n=1):
        pass

    def set_description(self, text):
        pass

    def close(self):
        pass


def _progress(total: int, enabled: bool):
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, unit="config")


def write_csv(rows: Iterable[SweepRow], path) -> Path:
    """Write the sweep to ``path`` (columns :data:`CSV_FIELDS`).

    Parameters
    ----------
    rows : iterable of SweepRow
        The sweep's rows.
    path : str or Path
        The CSV file to write (overwritten).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    with atomic_path(path) as tmp, tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
        w.writeheader()
        for row in rows:
            w.writerow({k: ("" if v is None else v) for k, v in asdict(row).items()})
    return path


def cheapest(rows: Sequence[SweepRow], *, error: str = "trajectory_error",
             levels: Sequence[float] = ACCURACY_LEVELS) -> list[tuple[float, SweepRow | None]]:
    """For each accuracy level, the configuration with the least seconds per frame whose
    ``error`` column is at most the level (None when no configuration reaches it).

    Parameters
    ----------
    rows : sequence of SweepRow
        The sweep.
    error : str, default "trajectory_error"
        The SweepRow column to compare (relative, dimensionless).
    levels : sequence of float
        The accuracy levels.

    Returns
    -------
    list of (float, SweepRow or None)
        (level, cheapest row) per level.
    """
    out = []
    for level in levels:
        ok = [r for r in rows if math.isfinite(getattr(r, error))
              and getattr(r, error) <= level]
        out.append((level, min(ok, key=lambda r: r.seconds_per_frame) if ok else None))
    return out


def cheapest_in_step(traces: dict[str, IterateTrace], *,
                     levels: Sequence[float] = ACCURACY_LEVELS
                     ) -> list[tuple[float, str | None, int, float]]:
    """For each level, (level, method, iterations, seconds) of the fastest method to reach
    that relative error within the step (method None when none does).

    Parameters
    ----------
    traces : dict of str to IterateTrace
        Method name → its trace on one step.
    levels : sequence of float
        Relative errors ‖x_k − x*‖ / ‖x* − x_n‖.

    Returns
    -------
    list of (float, str or None, int, float)
        (level, method, iterations, seconds [s]); seconds is inf when no method reaches it.
    """
    out = []
    for level in levels:
        best = (level, None, 0, math.inf)
        for name, tr in traces.items():
            hit = tr.first_below(level)
            if hit is not None and hit[1] < best[3]:
                best = (level, name, hit[0], hit[1])
        out.append(best)
    return out


def pareto_front(rows: Sequence[SweepRow], *, error: str = "trajectory_error") -> list[SweepRow]:
    """Configurations that no other is both cheaper and more accurate than, by cost.

    Parameters
    ----------
    rows : sequence of SweepRow
        The sweep.
    error : str, default "trajectory_error"
        The SweepRow column to compare.

    Returns
    -------
    list of SweepRow
        The Pareto front, cheapest first (error decreasing).
    """
    pts = sorted((r for r in rows if math.isfinite(getattr(r, error))),
                 key=lambda r: (r.seconds_per_frame, getattr(r, error)))
    front, best = [], math.inf
    for r in pts:
        if getattr(r, error) < best:
            front.append(r)
            best = getattr(r, error)
    return front


