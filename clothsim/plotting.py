"""Pictures of a run: the cloth and the scene it interacts with (matplotlib).

matplotlib is imported inside the functions, never at ``import clothsim``. Figures are
made with :class:`matplotlib.figure.Figure` and the Agg canvas, so nothing touches pyplot's
global state or needs a display. The cloth is drawn in 2-D through an orthographic
:class:`~clothsim.camera.View` (y up) with depth-sorted, shaded triangles (much faster
than mplot3d; the artists: :mod:`clothsim.painter`, layers and shading:
:mod:`clothsim.camera`), together with the obstacles
(plane, sphere, box; :mod:`clothsim.display`) and the pinned vertices (red dots). A cloth
of more than :data:`MAX_TRIANGLES` triangles is drawn decimated, and the title says so; only
the vertices drawn are then projected, shaded and framed
(:func:`clothsim.display.picture_mesh`), so a picture's cost does not grow with the cloth.
The picture is framed on the cloth and its obstacles, and its axes are the screen axes of
the view, in metres.

Functions
---------
draw
    Draw a cloth (and its obstacles and pins) into a given matplotlib Axes (notebooks).
write_preview
    ``preview.gif``: at most ``max_frames`` evenly spaced frames (fewer for big meshes, so
    it stays quick), 512 × 512 px; the still parts drawn once, the cloth per frame
    (blitting), saved with Pillow.
write_final_image
    ``final.png``: one frame, 600 × 600 px.
draw_run_pictures, write_run_pictures
    Both pictures of a run drawn in memory, then written (the runner draws them while the
    last frame is written on its background thread, and writes them once the run is
    complete).
"""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from .camera import View
from .display import obstacle_surfaces, picture_mesh
from .io.common import atomic_path
from .painter import SceneArtist, frame_axes

log = logging.getLogger(__name__)

#: Triangles drawn over the whole preview at most (frames × triangles), to bound its time.
PREVIEW_TRIANGLE_BUDGET = 250_000
#: Triangles of the cloth drawn in one picture at most; a larger cloth is drawn decimated
#: (:func:`clothsim.display.decimate`) and the title says so.
MAX_TRIANGLES = 10_000
#: Cloths with fewer triangles are drawn with their edges (above, shading alone).
EDGE_LIMIT = 3000


def _matplotlib():
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as exc:  # pragma: no cover - matplotlib is a declared dependency
        raise ImportError("clothsim needs matplotlib for pictures: pip install matplotlib") \
            from exc
    return Figure, FigureCanvasAgg


def draw(ax, mesh, positions, *, effects=(), view: View | None = None, t: float = 0.0,
         frame_on=None, edges: bool | None = None, shading: bool = True,
         max_triangles: int = MAX_TRIANGLES):
    """Draw a cloth, its obstacles and its pinned vertices into a matplotlib Axes.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Target axes (2-D); limits, aspect and labels [m] are set.
    mesh : Mesh
        Triangles and strands of the cloth.
    positions : ndarray, shape (n, 3)
        Vertex positions [m].
    effects : iterable of Effect, optional
        The simulation's effects: planes, spheres and boxes are drawn as surfaces, bound
        pins as red dots (others are ignored).
    view : View, optional
        Camera (default azimuth 35°, elevation 25°).
    t : float
        Time [s] (for pins released at some time).
    frame_on : ndarray, shape (..., 3), optional
        Points to frame the picture on (default: the vertices drawn, all of ``positions``
        unless the cloth is decimated, and the obstacles).
    edges : bool, optional
        Draw triangle edges (default: when the mesh has fewer than ``EDGE_LIMIT`` = 3000
        triangles).
    shading : bool
        Shade the cloth and the obstacles (light from the camera's side); False draws
        each in one flat colour (:data:`clothsim.painter.FACE_COLOR`,
        :data:`clothsim.display.OBSTACLE_COLORS`).
    max_triangles : int
        A cloth with more triangles is drawn decimated (:func:`clothsim.display.decimate`).

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.

    Notes
    -----
    The cloth an obstacle hides from the camera is drawn under the obstacle's front faces,
    the rest over them; cloth lying on an obstacle is drawn on it
    (:func:`clothsim.camera.hidden_triangles`).

    Examples
    --------
    >>> import clothsim as cs
    >>> from matplotlib.figure import Figure
    >>> mesh = cs.grid(4, 4, size=(1.0, 1.0))
    >>> ax = Figure().add_subplot()
    >>> ax is draw(ax, mesh, mesh.vertices, effects=[cs.Box([-.2, -.5, -.2], [.2, -.1, .2])])
    True
    """
    _draw(ax, mesh, positions, effects, view, t, frame_on, edges, shading, max_triangles)
    return ax


def _draw(ax, mesh, positions, effects, view, t, frame_on, edges, shading,
          max_triangles) -> str:
    """:func:`draw`; returns the decimation note ("" when the whole cloth is drawn)."""
    x = np.asarray(positions, dtype=np.float64)
    view = view or View()
    drawn, take, note = picture_mesh(mesh, max_triangles)
    # framed on what is drawn: a decimated cloth keeps its outline (display.decimate)
    X = (x if take is None else x[take]) if frame_on is None else np.asarray(
        frame_on, dtype=np.float64)
    surfaces = obstacle_surfaces(effects, X)
    depth_range = frame_axes(ax, view, X, surfaces)
    edges = mesh.triangle_count < EDGE_LIMIT if edges is None else edges
    SceneArtist(ax, drawn, view, x, edges, surfaces, effects, shading, depth_range,
                take).update(x, t)
    return note


def preview_frame_indices(frame_count: int, triangle_count: int, *,
                          max_frames: int = 60) -> np.ndarray:
    """Evenly spaced frame indices for a preview (first and last always included).

    Parameters
    ----------
    frame_count, triangle_count : int
        Frames available and triangles per frame.
    max_frames : int
        Upper bound.

    Returns
    -------
    ndarray of int
        At most ``max_frames`` and at most ``PREVIEW_TRIANGLE_BUDGET / triangle_count``
        indices (never fewer than 2 when there are 2 frames or more).
    """
    budget = PREVIEW_TRIANGLE_BUDGET // max(1, triangle_count)
    k = max(min(max_frames, budget, frame_count), min(2, frame_count))
    return np.unique(np.round(np.linspace(0, frame_count - 1, k)).astype(int))


def _figure(size: float, dpi: int):
    Figure, FigureCanvasAgg = _matplotlib()
    fig = Figure(figsize=(size, size), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.13, 0.1, 0.84, 0.82))
    return fig, ax


def write_preview(path, positions, mesh, *, times=None, effects=(), max_frames: int = 60,
                  size: float = 6.4, dpi: int = 80) -> Path:
    """Write an animated GIF of a trajectory, with its obstacles and pins.

    A cloth of more than ``MAX_TRIANGLES`` triangles is drawn decimated, and the title
    says so.

    Parameters
    ----------
    path : str or Path
        Output ``.gif``.
    positions : ndarray, shape (F, n, 3), or sequence of F arrays (n, 3)
        Positions of every frame [m] (a memory map, or a list of frames: only the frames
        drawn are read).
    mesh : Mesh
        Triangles and strands to draw.
    times : ndarray, shape (F,), optional
        Frame times [s], shown in the title.
    effects : iterable of Effect, optional
        Obstacles and pins to draw (see :func:`draw`).
    max_frames : int
        Upper bound on the frames drawn.
    size, dpi
        Figure size [inch] and resolution (default 512 × 512 px).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    data, count = _preview_gif(positions, mesh, times, effects, max_frames, size, dpi)
    _write(path, data)
    log.info("wrote %s (%d frames)", path, count)
    return path


def _preview_gif(positions, mesh, times, effects, max_frames: int, size: float,
                 dpi: int) -> tuple[bytes, int]:
    """:func:`write_preview`'s GIF file content, and the number of frames drawn."""
    drawn, take, note = picture_mesh(mesh, MAX_TRIANGLES)
    idx = preview_frame_indices(len(positions), drawn.triangle_count, max_frames=max_frames)
    X = [np.asarray(positions[i], dtype=np.float64) for i in idx]  # only these frames load
    fig, ax = _figure(size, dpi)
    view = View()
    shown = np.stack(X if take is None else [x[take] for x in X])  # the vertices drawn
    surfaces = obstacle_surfaces(effects, shown)
    depth_range = frame_axes(ax, view, shown, surfaces)
    art = SceneArtist(ax, drawn, view, X[0], mesh.triangle_count < EDGE_LIMIT, surfaces,
                      effects, True, depth_range, take)
    title = fig.suptitle(note, fontsize=9)

    def frame(j):
        t = float(times[idx[j]]) if times is not None else 0.0
        art.update(X[j], t)
        if times is not None:
            title.set_text(f"t = {t:.2f} s" + (f" ({note})" if note else ""))

    span = float(times[idx[-1]] - times[idx[0]]) if times is not None and len(idx) > 1 else 0
    fps = max(1.0, min(30.0, (len(idx) - 1) / span)) if span > 0 else 10.0
    out = io.BytesIO()
    _save_gif(fig, art.moving() + [title], frame, len(idx), out, fps)
    return out.getvalue(), len(idx)


def _write(path: Path, data: bytes) -> None:
    """Write a picture's bytes atomically (:func:`clothsim.io.common.atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def _save_gif(fig, moving: list, frame, count: int, path, fps: float) -> None:
    """Draw the figure's still parts (axes, ticks, planes) once, then for each frame only
    the ``moving`` artists over a copy of them (blitting), and save the frames as a looping
    GIF (Pillow, as :class:`matplotlib.animation.PillowWriter` does)."""
    from PIL import Image

    canvas = fig.canvas
    for a in moving:
        a.set_animated(True)
    canvas.draw()
    still = canvas.copy_from_bbox(fig.bbox)
    size = canvas.get_width_height()
    images = []
    for j in range(count):
        frame(j)
        canvas.restore_region(still)
        for a in sorted(moving, key=lambda a: a.get_zorder()):
            fig.draw_artist(a)
        rgba = Image.frombuffer("RGBA", size, canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
        images.append(rgba.convert("RGB"))  # a copy, GIF-friendly
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=int(1000 / fps), loop=0)


def write_final_image(path, positions, mesh, *, title: str = "", effects=(), t: float = 0.0,
                      size: float = 6.0, dpi: int = 100) -> Path:
    """Write one frame of ``mesh`` with its obstacles and pins as a PNG image.

    A cloth of more than ``MAX_TRIANGLES`` triangles is drawn decimated, and the title
    says so.

    Parameters
    ----------
    path : str or Path
        Output ``.png``.
    positions : ndarray, shape (n, 3)
        Vertex positions [m].
    mesh : Mesh
        Triangles and strands to draw.
    title : str
        Figure title.
    effects : iterable of Effect, optional
        Obstacles and pins to draw (see :func:`draw`).
    t : float
        Time of the frame [s].
    size, dpi
        Figure size [inch] and resolution (default 600 × 600 px).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    _write(path, _final_png(positions, mesh, title, effects, t, size, dpi))
    return path


def _final_png(positions, mesh, title: str, effects, t: float, size: float,
               dpi: int) -> bytes:
    """:func:`write_final_image`'s PNG file content."""
    fig, ax = _figure(size, dpi)
    note = _draw(ax, mesh, positions, effects, None, t, None, None, True, MAX_TRIANGLES)
    if title or note:
        fig.suptitle(", ".join(x for x in (title, note) if x), fontsize=10)
    out = io.BytesIO()
    fig.savefig(out, format="png")
    return out.getvalue()


def draw_run_pictures(positions, mesh, *, times, effects=(), title: str = "") -> dict:
    """A run's ``preview.gif`` and ``final.png``, drawn in memory (nothing is written).

    Parameters
    ----------
    positions : ndarray, shape (F, n, 3), or sequence of F arrays (n, 3)
        Every frame's positions [m] (see :func:`write_preview`); the last one is
        ``final.png``.
    mesh : Mesh
        Triangles and strands to draw.
    times : ndarray, shape (F,)
        Frame times [s].
    effects : iterable of Effect, optional
        Obstacles and pins to draw (see :func:`draw`).
    title : str
        ``final.png``'s title.

    Returns
    -------
    dict of str to bytes
        File name to file content, for :func:`write_run_pictures`.
    """
    gif, count = _preview_gif(positions, mesh, times, effects, 60, 6.4, 80)
    log.debug("drew preview.gif (%d frames)", count)
    png = _final_png(positions[-1], mesh, title, effects, float(times[-1]), 6.0, 100)
    return {"preview.gif": gif, "final.png": png}


def write_run_pictures(folder, pictures: dict) -> list[Path]:
    """Write pictures drawn by :func:`draw_run_pictures` into ``folder``, each atomically.

    Parameters
    ----------
    folder : str or Path
        The run folder.
    pictures : dict of str to bytes
        File name to content.

    Returns
    -------
    list of Path
        The files written.
    """
    paths = [Path(folder) / name for name in pictures]
    for path, data in zip(paths, pictures.values()):
        _write(path, data)
    log.info("wrote %s", ", ".join(str(p) for p in paths))
    return paths


__all__ = ["draw", "write_preview", "write_final_image", "draw_run_pictures",
           "write_run_pictures", "preview_frame_indices",
           "MAX_TRIANGLES", "EDGE_LIMIT", "PREVIEW_TRIANGLE_BUDGET"]
