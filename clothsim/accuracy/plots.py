"""Figures of the accuracy study (matplotlib imported here only; the backend is the user's).

Every function writes one PNG and returns its path; none prints or changes matplotlib's
global backend (figures are created with ``matplotlib.figure.Figure`` and saved directly).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.common import atomic_path
from .damping import single_spring_heights
from .sweep import TRAJECTORY_LEVELS, cheapest, pareto_front
from .trace import ACCURACY_LEVELS, EXPLICIT_METHODS, IterateTrace
from .trajectory import SweepRow, convergence_slope

_COLORS = {"local-global": "C0", "chebyshev": "C1", "newton": "C2", "symplectic-euler": "C3",
           "anderson": "C4", "lbfgs": "C5"}


class _Figures:
    """Stand-in for pyplot's two calls used here, on the object-oriented API."""

    @staticmethod
    def subplots(*args, **kwargs):
        from matplotlib.figure import Figure

        fig = Figure(figsize=kwargs.pop("figsize", None))
        return fig, fig.subplots(*args, **kwargs)

    @staticmethod
    def close(fig):
        pass


def _pyplot():
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:  # pragma: no cover - matplotlib is a dependency
        raise InputError("plots need matplotlib: pip install matplotlib") from exc
    return _Figures


def _save(plt, fig, path) -> Path:
    """Lay out, write (110 dpi) and close a figure; returns its path."""
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:   # never half a figure on disk
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path


def plot_solver_accuracy(traces: dict[str, IterateTrace], path, *, title: str = "") -> Path:
    """Two panels: relative error against iterations, and against cumulative wall time.

    Parameters
    ----------
    traces : dict of str to IterateTrace
        Method name → trace (:func:`~clothsim.accuracy.trace.solver_accuracy`).
    path : str or Path
        The PNG file to write (overwritten).
    title : str, optional
        Figure title (default: a description of the plot).

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, tr in traces.items():
        keep = tr.error > 0
        c = _COLORS.get(name)
        a.semilogy(tr.iterations[keep], tr.error[keep], "-", color=c, label=name,
                   marker="o" if name == "newton" else None, ms=3)
        b.loglog(tr.seconds[keep][1:] * 1e3, tr.error[keep][1:], "-", color=c, label=name,
                 marker="o" if name == "newton" else None, ms=3)
    a.set_xlabel("iterations")
    b.set_xlabel("cumulative wall time [ms]")
    for ax in (a, b):
        ax.set_ylabel("relative error ‖x_k − x*‖ / ‖x* − x_n‖")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.suptitle(title or "solver accuracy within one implicit Euler step")
    return _save(plt, fig, path)


def plot_frontier(rows: Sequence[SweepRow], path, *, title: str = "") -> Path:
    """Trajectory and solver error against seconds per frame, with the Pareto front and
    the cheapest configuration for each accuracy level marked.

    Parameters
    ----------
    rows : sequence of SweepRow
        The sweep (:func:`~clothsim.accuracy.sweep.run_sweep`).
    path : str or Path
        The PNG file to write (overwritten).
    title : str, optional
        Figure title (default: a description of the plot).

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for ax, col, levels in zip(axes, ("trajectory_error", "solver_error"),
                               (TRAJECTORY_LEVELS, ACCURACY_LEVELS)):
        for method in dict.fromkeys(r.method for r in rows):
            pts = [r for r in rows if r.method == method and math.isfinite(getattr(r, col))
                   and getattr(r, col) > 0]
            if pts:
                ax.loglog([r.seconds_per_frame * 1e3 for r in pts],
                          [getattr(r, col) for r in pts], "o", ms=4, alpha=0.6,
                          color=_COLORS.get(method), label=method)
        front = [r for r in pareto_front(rows, error=col) if getattr(r, col) > 0]
        if front:
            ax.loglog([r.seconds_per_frame * 1e3 for r in front],
                      [getattr(r, col) for r in front], "k-", lw=1, label="frontier")
        for level, r in cheapest(rows, error=col, levels=levels):
            if r is None:
                continue
            ax.axhline(level, color="0.85", lw=0.6, zorder=0)
            ax.plot(r.seconds_per_frame * 1e3, getattr(r, col), "*", ms=11,
                    color=_COLORS.get(r.method), mec="k")
        ax.set_xlabel("wall time per frame [ms]")
        ax.set_ylabel(col.replace("_", " "))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title("trajectory vs. small-h converged reference")
    axes[1].set_title("solver error within a step (vs. Newton x*)")
    fig.suptitle(title or "accuracy/time frontier (★ = cheapest for each accuracy level)")
    return _save(plt, fig, path)


def plot_convergence(rows: Sequence[SweepRow], path, *, title: str = "") -> Path:
    """Trajectory error against h (log-log), one line per (method, iterations), with a
    slope-1 guide (implicit Euler is first order) and each line's fitted slope.

    Parameters
    ----------
    rows : sequence of SweepRow
        The sweep, with several h per series.
    path : str or Path
        The PNG file to write (overwritten).
    title : str, optional
        Figure title (default: a description of the plot).

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    series = dict.fromkeys((r.method, r.iterations) for r in rows
                           if r.method not in EXPLICIT_METHODS)
    styles = ["-", "--", ":", "-."]
    for i, (method, its) in enumerate(series):
        pts = sorted((r.h, r.trajectory_error) for r in rows
                     if (r.method, r.iterations) == (method, its)
                     and math.isfinite(r.trajectory_error))
        if len(pts) < 2:
            continue
        h, e = np.array(pts).T
        slope = convergence_slope(rows, method=method, iterations=its)
        ax.loglog(h, e, styles[i % 4], marker="o", ms=3, color=_COLORS.get(method),
                  label=f"{method} {its} it (slope {slope:.2f})")
    h_all = np.array(sorted({r.h for r in rows if math.isfinite(r.h)}))
    if len(h_all):
        best = min((r for r in rows if r.h == h_all[0] and math.isfinite(r.trajectory_error)),
                   key=lambda r: r.trajectory_error, default=None)
        if best is not None:
            ax.loglog(h_all, best.trajectory_error * h_all / h_all[0], "k:", lw=1,
                      label="slope 1")
    ax.set_xlabel("time step h [s]")
    ax.set_ylabel("trajectory error ‖X − X_ref‖ / ‖X_ref − X_0‖")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title(title or "trajectory error against h")
    return _save(plt, fig, path)


def plot_damping(path, *, h: float = 1 / 30, steps: int = 90,
                 cloth_curves: dict[str, np.ndarray] | None = None,
                 frame_time: float = 1 / 30, cloth_ylabel: str = "mechanical energy [J]",
                 cloth_title: str = "cloth: energy, iterations per step") -> Path:
    """Implicit Euler's damping: the single spring against its closed-form envelope, and
    (optionally) a cloth quantity (:func:`energy_curves`) for a few iteration counts.

    The envelope is (1 + ω²h²)^(−n/2) for a linear spring (ω = 10 rad/s here).

    Parameters
    ----------
    path : str or Path
        The PNG file to write (overwritten).
    h : float, default 1/30
        Time step of the single spring [s].
    steps : int, default 90
        Steps of the single spring.
    cloth_curves : dict of str to ndarray, optional
        Label → per-frame cloth quantity (second panel).
    frame_time : float, default 1/30
        Time between the cloth curves' samples [s].
    cloth_ylabel, cloth_title : str
        Labels of the second panel.

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    panels = 2 if cloth_curves else 1
    fig, axes = plt.subplots(1, panels, figsize=(5.6 * panels, 4.2), squeeze=False)
    t, curves, env = single_spring_heights(h=h, steps=steps)
    ax = axes[0, 0]
    for label, y in curves.items():
        ax.plot(t, y, "-", lw=1.2, label=label)
    ax.plot(t, env, "k--", lw=1, label="(1 + ω²h²)^(−n/2), closed form")
    ax.plot(t, -env, "k--", lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("displacement [m]")
    ax.set_title(f"one spring, ω = 10 rad/s, h = {h:.4g} s")
    ax.legend(fontsize=8)
    if cloth_curves:
        ax = axes[0, 1]
        for label, y in cloth_curves.items():
            ax.plot(np.arange(len(y)) * frame_time, y, lw=1.1, label=label)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(cloth_ylabel)
        ax.set_title(cloth_title)
        ax.legend(fontsize=8)
    return _save(plt, fig, path)




def plot_fixed_budget(table, path, *, title: str = "", uncertainty: float = 0.0) -> Path:
    """Solver error (median; dotted: p90) against iterations per step; levels below the
    reference's ``uncertainty`` are not plotted (a grey band marks them).

    Parameters
    ----------
    table : sequence of Row
        The study's rows (:func:`~clothsim.accuracy.report.rows`).
    path : str or Path
        The PNG file to write (overwritten).
    title : str, optional
        Figure title (default: a description of the plot).
    uncertainty : float, default 0
        The references' relative uncertainty.

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    fig = fixed_budget_figure(table, title=title, uncertainty=uncertainty)
    return _save(plt, fig, path)


def fixed_budget_figure(table, *, title: str = "", uncertainty: float = 0.0):
    """The figure of :func:`plot_fixed_budget` (a ``matplotlib.figure.Figure``, not saved).

    The band "below the reference's uncertainty" spans from the bottom of the axes up to
    ``uncertainty``; the y axis is extended down to a third of it when every point lies
    above it, so the band is always drawn under the points it bounds.

    Parameters
    ----------
    table : sequence of Row
    title : str, optional
    uncertainty : float, default 0

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    shown = []
    for method in dict.fromkeys(r.method for r in table):
        pts = sorted((r.iterations, r.solver_error_median, r.solver_error_p90) for r in table
                     if r.method == method and r.tolerance is None
                     and math.isfinite(r.solver_error_median)
                     and r.solver_error_median > max(uncertainty, 0.0))
        if not pts:
            continue
        k, med, p90 = np.array(pts).T
        p90 = np.where(p90 > uncertainty, p90, np.nan)
        shown += [*med, *p90[np.isfinite(p90)]]
        c = _COLORS.get(method)
        ax.loglog(k, med, "-o", ms=3, color=c, label=f"{method} (median)")
        ax.loglog(k, p90, ":", color=c, lw=1)
    for b in (5, 10, 20):
        ax.axvline(b, color="0.85", lw=0.6, zorder=0)
    if uncertainty > 0:
        ax.set_yscale("log")
        low, high = (min(shown) / 1.5, max(shown) * 1.5) if shown else (uncertainty,) * 2
        low, high = min(low, uncertainty / 3), max(high, 3 * uncertainty)
        ax.axhspan(low, uncertainty, color="0.9", zorder=0,
                   label="below the reference's uncertainty")
        ax.set_ylim(low, high)
    ax.set_xlabel("iterations per step")
    ax.set_ylabel("solver error ‖x − x*‖ / ‖x* − x_n‖ (dotted: p90)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or "fixed budget: error after k iterations per step")
    return fig


def plot_paper(path, lg_iterations, lg_errors, seconds_per_iteration: float, newton_errors,
               newton_seconds, extrapolated=()) -> Path:
    """The paper's Fig. 1 comparison: relative error against wall time, local/global and
    Newton on one step (:func:`~clothsim.accuracy.paper.paper_report`).

    Parameters
    ----------
    path : str or Path
        The PNG file to write (overwritten).
    lg_iterations, lg_errors : array_like
        Local/global's traced iterations and relative errors.
    seconds_per_iteration : float
        Time of one local/global iteration [s].
    newton_errors, newton_seconds : array_like
        Newton's relative error and cumulative time [s] per iterate.
    extrapolated : sequence of (float, float)
        (level, iterations) local/global reaches beyond its trace (drawn dashed).

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    k, e = np.asarray(lg_iterations, float), np.asarray(lg_errors, float)
    keep = (k > 0) & (e > 0)
    ms = 1e3 * seconds_per_iteration
    ax.loglog(k[keep] * ms, e[keep], "-", color=_COLORS["local-global"], label="local/global")
    far = [(lev, it) for lev, it in extrapolated if math.isfinite(it)]
    if far and keep.any():
        ax.loglog([k[keep][-1] * ms] + [it * ms for _, it in far], [e[keep][-1]]
                  + [lev for lev, _ in far], "--", color=_COLORS["local-global"],
                  label="local/global, extrapolated")
    ne, ns = np.asarray(newton_errors, float), np.asarray(newton_seconds, float)
    good = (ne > 0) & (ns > 0)
    ax.loglog(ns[good] * 1e3, ne[good], "-o", ms=3, color=_COLORS["newton"], label="Newton")
    ax.set_xlabel("wall time [ms]")
    ax.set_ylabel("relative error ‖x − x*‖ / ‖x* − x_n‖")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("the paper's Fig. 1 setup: error against time")
    return _save(plt, fig, path)
