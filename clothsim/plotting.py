"""Pictures of a run: an animated preview, the final frame, residual curves (matplotlib).

matplotlib is imported inside the functions, never at ``import clothsim``. Figures are
made with :class:`matplotlib.figure.Figure` and the Agg canvas, so nothing touches pyplot's
global state or needs a display. The cloth is drawn in 2-D through an orthographic
:class:`View` (y up) with depth-sorted, shaded triangles: much faster than mplot3d.

Functions
---------
write_preview
    ``preview.gif``: at most ``max_frames`` evenly spaced frames (fewer for big meshes, so
    it stays quick), a small figure, written with :class:`matplotlib.animation.PillowWriter`.
write_final_image
    ``final.png``: one frame.
plot_residual_curve
    Relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ against iteration k, log scale.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

#: Triangles drawn over the whole preview at most (frames × triangles), to bound its time.
PREVIEW_TRIANGLE_BUDGET = 250_000
FACE_COLOR = (0.35, 0.55, 0.85)
EDGE_COLOR = (0.15, 0.25, 0.45)


def _matplotlib():
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as exc:  # pragma: no cover - matplotlib is a declared dependency
        raise ImportError("clothsim needs matplotlib for pictures: pip install matplotlib") \
            from exc
    return Figure, FigureCanvasAgg


class View:
    """Orthographic camera, y up: azimuth about y and elevation above the xz plane [deg].

    ``project(x)`` maps points (…, 3) to screen coordinates u (right), v (up) and a depth
    that grows toward the camera. Drawing in 2-D with a depth sort (painter's algorithm)
    is much faster than mplot3d and looks the same for a cloth.
    """

    def __init__(self, azimuth: float = 35.0, elevation: float = 25.0):
        a, e = np.radians(azimuth), np.radians(elevation)
        self.toward = np.array([np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)])
        self.right = np.array([np.cos(a), 0.0, -np.sin(a)])
        self.up = np.cross(self.toward, self.right)
        self.light = self.toward + 0.5 * self.up
        self.light /= np.linalg.norm(self.light)

    def project(self, x: np.ndarray) -> np.ndarray:
        """(…, 3) points → (…, 3) as (u, v, depth)."""
        return x @ np.stack([self.right, self.up, self.toward], axis=1)


class _Artist:
    """Triangles (shaded, depth-sorted) and strands of one mesh, updatable per frame."""

    def __init__(self, ax, mesh, view: View, x: np.ndarray, edges: bool):
        from matplotlib.collections import LineCollection, PolyCollection

        self.view = view
        self.tris = np.asarray(mesh.triangles)
        self.strands = np.asarray(mesh.strands)
        self.poly = self.lines = self.points = None
        if len(self.tris):
            self.poly = PolyCollection([], edgecolors=EDGE_COLOR if edges else "face",
                                       linewidths=0.15 if edges else 0.3, antialiased=False)
            ax.add_collection(self.poly)
        if len(self.strands):
            self.lines = LineCollection([], colors="k", linewidths=1.0)
            ax.add_collection(self.lines)
            if not len(self.tris):  # a spring network: show the masses too
                self.points = ax.plot([], [], "o", ms=3, color="C3")[0]
        self.update(x)

    def update(self, x: np.ndarray):
        p = self.view.project(x)
        if self.poly is not None:
            t = self.tris
            n = np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            shade = 0.35 + 0.65 * np.abs(n @ self.view.light)  # two-sided Lambert
            order = np.argsort(p[t].mean(axis=1)[:, 2])         # far to near
            self.poly.set_verts(p[t[order]][..., :2])
            self.poly.set_facecolor(shade[order, None] * np.asarray(FACE_COLOR))
        if self.lines is not None:
            self.lines.set_segments(p[self.strands][..., :2])
        if self.points is not None:
            self.points.set_data(p[:, 0], p[:, 1])


def _axes(fig, view: View, X: np.ndarray):
    """2-D axes framing every point of X (…, 3) seen through ``view``, equal scale."""
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.88))
    p = view.project(X.reshape(-1, 3))
    lo, hi = p.min(axis=0), p.max(axis=0)
    mid = (lo + hi) / 2
    half = max(float(np.max((hi - lo)[:2])) / 2, 1e-6) * 1.05
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_aspect("equal")
    ax.set_axis_off()
    return ax


def preview_frame_indices(frame_count: int, triangle_count: int, *,
                          max_frames: int = 60) -> np.ndarray:
    """Evenly spaced frame indices for a preview (first and last always included).

    At most ``max_frames``, and at most ``PREVIEW_TRIANGLE_BUDGET / triangle_count``
    (never fewer than 2 when there are 2 frames or more).
    """
    budget = PREVIEW_TRIANGLE_BUDGET // max(1, triangle_count)
    k = max(min(max_frames, budget, frame_count), min(2, frame_count))
    return np.unique(np.round(np.linspace(0, frame_count - 1, k)).astype(int))


def write_preview(path, positions, mesh, *, times=None, max_frames: int = 60,
                  size: float = 3.2, dpi: int = 72) -> Path:
    """Write an animated GIF of a trajectory.

    Parameters
    ----------
    path : str or Path
        Output ``.gif``.
    positions : ndarray, shape (F, n, 3)
        Positions of every frame [m].
    mesh : Mesh
        Triangles and strands to draw.
    times : ndarray, shape (F,), optional
        Frame times [s], shown in the title.
    max_frames : int
        Upper bound on the frames drawn.
    size, dpi
        Figure size [inch] and resolution.
    """
    from matplotlib.animation import PillowWriter

    Figure, FigureCanvasAgg = _matplotlib()
    path = Path(path)
    X = np.asarray(positions, dtype=np.float64)
    idx = preview_frame_indices(len(X), len(mesh.triangles), max_frames=max_frames)
    fig = Figure(figsize=(size, size), dpi=dpi)
    FigureCanvasAgg(fig)
    view = View()
    ax = _axes(fig, view, X[idx])
    art = _Artist(ax, mesh, view, X[idx[0]], edges=len(mesh.triangles) < 3000)
    title = fig.suptitle("", fontsize=8)

    def draw(j):
        art.update(X[idx[j]])
        if times is not None:
            title.set_text(f"t = {float(times[idx[j]]):.2f} s")
        return ()

    span = float(times[idx[-1]] - times[idx[0]]) if times is not None and len(idx) > 1 else 0
    fps = max(1.0, min(30.0, (len(idx) - 1) / span)) if span > 0 else 10.0
    tmp = path.with_name(f".{path.stem}.tmp.gif")
    writer = PillowWriter(fps=fps)
    with writer.saving(fig, tmp, dpi):  # one draw per frame (FuncAnimation draws twice)
        for j in range(len(idx)):
            draw(j)
            writer.grab_frame()
    tmp.replace(path)
    log.info("wrote %s (%d frames)", path, len(idx))
    return path


def write_final_image(path, positions, mesh, *, title: str = "", size: float = 4.0,
                      dpi: int = 100) -> Path:
    """Write one frame (positions (n, 3) [m]) of ``mesh`` as a PNG image."""
    Figure, FigureCanvasAgg = _matplotlib()
    path = Path(path)
    x = np.asarray(positions, dtype=np.float64)
    fig = Figure(figsize=(size, size), dpi=dpi)
    FigureCanvasAgg(fig)
    view = View()
    ax = _axes(fig, view, x)
    _Artist(ax, mesh, view, x, edges=len(mesh.triangles) < 3000)
    if title:
        fig.suptitle(title, fontsize=9)
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp, format="png")
    tmp.replace(path)
    return path


def plot_residual_curve(histories, path=None, *, labels=None, ax=None,
                        title: str = "Residual per iteration"):
    """Plot relative residual ‖∇g(x_k)‖ / ‖∇g(x_0)‖ against iteration k (log scale).

    Parameters
    ----------
    histories : sequence of float, or sequence of sequences
        One residual history (as in ``StepRecord.residual_history`` or run.json's
        ``frames[i].residual_history``) or several.
    path : str or Path, optional
        Save the figure here (PNG).
    labels : sequence of str, optional
        Legend entry per history.
    ax : matplotlib Axes, optional
        Draw into it instead of a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    Figure, FigureCanvasAgg = _matplotlib()
    hs = list(histories)
    if hs and np.ndim(hs[0]) == 0:
        hs = [hs]
    if ax is None:
        fig = Figure(figsize=(4.5, 3.2), dpi=100)
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    for i, h in enumerate(hs):
        r = np.asarray(h, dtype=np.float64)
        r = np.where(r > 0, r, np.nan)  # an exact zero cannot be drawn on a log scale
        ax.semilogy(np.arange(len(r)), r, marker=".", ms=3,
                    label=None if labels is None else labels[i])
    ax.set_xlabel("iteration k")
    ax.set_ylabel("‖∇g(x_k)‖ / ‖∇g(x_0)‖")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    if labels is not None:
        ax.legend(fontsize=7)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path)
    return fig


__all__ = ["write_preview", "write_final_image", "plot_residual_curve",
           "preview_frame_indices"]
