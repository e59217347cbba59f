"""The matplotlib artists of one picture of a scene: the cloth's triangles, strands and pins
and the obstacles, drawn in layers and depth-sorted (painter's algorithm), and updated frame
by frame; and the framing of the axes. :mod:`clothsim.plotting` makes the figures and files
with them; :mod:`clothsim.camera` decides the layers and the shading.

matplotlib is imported inside the functions, never at ``import clothsim``.
"""

from __future__ import annotations

import numpy as np

from .camera import View, depth_cue, hidden_triangles, shade
from .display import OBSTACLE_COLORS, PIN_COLOR, pinned_points

#: Colours (RGB in [0, 1]) of the cloth's faces and of its triangle edges.
FACE_COLOR = (0.35, 0.55, 0.85)
EDGE_COLOR = (0.15, 0.25, 0.45)


class SceneArtist:
    """The artists of one picture: cloth triangles (shaded, depth-sorted with the obstacles'
    camera-facing faces in three layers), strands, pins; planes drawn once, behind.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Target axes (already framed, see :func:`frame_axes`).
    mesh : Mesh
        Triangles and strands to draw (possibly decimated, on its own vertices: ``take``).
    view : clothsim.camera.View
        Camera and light.
    x : ndarray, shape (n, 3)
        Positions [m] of the cloth in a first frame (its size sets the tolerance of the
        hidden layer).
    edges : bool
        Draw the cloth's triangle edges.
    surfaces : sequence of clothsim.display.Surface
        Obstacles.
    effects : iterable of Effect
        For the pins (red dots).
    shading : bool
        Shade (light, depth cue) or draw flat colours.
    depth_range : (float, float), optional
        Depths [m] of the picture's nearest and farthest points, for the depth cue
        (default: those of ``x`` and the obstacles).
    take : ndarray of int, optional
        Indices in ``x`` of ``mesh``'s vertices (:func:`clothsim.display.picture_mesh`):
        only those are projected and shaded; default all, ``mesh`` indexes ``x``.
    """

    def __init__(self, ax, mesh, view: View, x: np.ndarray, edges: bool, surfaces=(),
                 effects=(), shading: bool = True, depth_range=None, take=None):
        from matplotlib.collections import LineCollection, PolyCollection

        self.take = take
        x = self._drawn(x)
        self.view = view
        self.tris = np.asarray(mesh.triangles)
        self.strands = np.asarray(mesh.strands)
        self.effects = list(effects)
        self.edges = edges
        self.shading = shading
        if depth_range is None:  # the cloth and the obstacles, as framed
            d = view.project(np.vstack([x.reshape(-1, 3)] + [s.vertices for s in surfaces]))
            depth_range = (float(d[:, 2].max()), float(d[:, 2].min()))
        self.depth_range = depth_range
        self.poly = self.lines = self.points = self.pins = None
        # static obstacles: planes drawn first (the ground is behind everything above it);
        # of the convex ones only the camera-facing faces, drawn between the cloth they hide
        # and the rest of the cloth (see update)
        solid, scol = [], []
        self.convex = [x for x in surfaces if x.kind != "plane"]
        for surf in surfaces:
            tri = surf.vertices[surf.triangles]
            color = np.asarray(OBSTACLE_COLORS[surf.kind]) * (
                shade(view, surf.vertices, surf.triangles, smooth=surf.kind == "sphere")[:, None]
                if shading else np.ones((len(tri), 1)))
            if surf.kind == "plane":
                ax.add_collection(PolyCollection(view.project(tri)[..., :2], facecolors=color,
                                                 edgecolors="face", linewidths=0.3,
                                                 zorder=0.5))
                continue
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            out = np.einsum("ij,ij->i", n, tri.mean(axis=1) - surf.vertices.mean(axis=0))
            front = (n @ view.toward) * np.sign(out) > 0  # camera-facing faces only
            solid.append(view.project(tri[front]))
            scol.append(color[front])
        self.solid = np.concatenate(solid) if solid else np.zeros((0, 3, 3))
        self.solid_color = np.concatenate(scol) if scol else np.zeros((0, 3))
        size = np.ptp(x.reshape(-1, 3), axis=0).max() if x.size else 1.0
        self.eps = 1e-3 * max(float(size), 1e-3)
        if len(self.tris) or len(self.solid):
            self.poly = PolyCollection([], linewidths=0.15 if edges else 0.3,
                                       antialiased=False, zorder=1)
            ax.add_collection(self.poly)
        if len(self.strands):
            self.lines = LineCollection([], colors="k", linewidths=1.0, zorder=2)
            ax.add_collection(self.lines)
            if not len(self.tris):  # a spring network: show the masses too
                self.points = ax.plot([], [], "o", ms=3, color="C3", zorder=3)[0]
        if any(getattr(e, "kind", "") == "pin" for e in self.effects):
            self.pins = ax.plot([], [], "o", ms=4, color=PIN_COLOR, zorder=4)[0]

    def _drawn(self, x: np.ndarray) -> np.ndarray:
        """The positions of the vertices drawn, from the cloth's."""
        return np.asarray(x) if self.take is None else np.asarray(x)[self.take]

    def moving(self) -> list:
        """The artists :meth:`update` changes (the rest of the figure stays as drawn).

        Returns
        -------
        list of matplotlib.artist.Artist
            The cloth-and-obstacle polygons, strands, points and pins that exist.
        """
        return [a for a in (self.poly, self.lines, self.points, self.pins) if a is not None]

    def update(self, x: np.ndarray, t: float = 0.0) -> None:
        """Draw the cloth at positions ``x`` and time ``t``.

        Parameters
        ----------
        x : ndarray, shape (n, 3)
            Positions [m] of the cloth.
        t : float
            Time [s] (pins released in time).
        """
        if self.pins is not None:  # pinned vertices, drawn or not
            q = self.view.project(pinned_points(self.effects, x, t))
            self.pins.set_data(q[:, 0], q[:, 1])
        x = self._drawn(x)
        p = self.view.project(x)
        if self.poly is not None:
            t3 = self.tris
            # layers: cloth hidden by an obstacle, obstacles' front faces, the rest of the
            # cloth; each layer depth-sorted far to near (painter's algorithm)
            hidden = hidden_triangles(self.convex, self.view, x, t3, self.eps)
            layer = np.concatenate([np.ones(len(self.solid)), np.where(hidden, 0.0, 2.0)])
            depth = np.concatenate([self.solid[..., 2].mean(axis=1),
                                    p[t3][..., 2].mean(axis=1)])
            order = np.lexsort((depth, layer))
            verts = np.concatenate([self.solid[..., :2], p[t3][..., :2]])
            light = np.ones(len(t3))
            if self.shading:
                near, far = self.depth_range
                light = shade(self.view, x, t3) * depth_cue(p[t3][..., 2].mean(axis=1), near,
                                                            far)
            face = np.concatenate([self.solid_color, light[:, None] * np.asarray(FACE_COLOR)])
            cloth = np.concatenate([np.zeros(len(self.solid), bool), np.ones(len(t3), bool)])
            fc = face[order]
            ec = np.where(cloth[order, None], np.asarray(EDGE_COLOR), fc) if self.edges else fc
            self.poly.set_verts(verts[order])
            self.poly.set_facecolor(fc)
            self.poly.set_edgecolor(ec)
        if self.lines is not None:
            self.lines.set_segments(p[self.strands][..., :2])
        if self.points is not None:
            self.points.set_data(p[:, 0], p[:, 1])


def frame_axes(ax, view: View, X: np.ndarray, surfaces=()) -> tuple[float, float]:
    """Frame ``ax`` on points and obstacle surfaces: equal scale, axes in metres.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to frame (limits, aspect, labels).
    view : clothsim.camera.View
        Camera.
    X : ndarray, shape (..., 3)
        Points [m] to frame on (the cloth over the frames shown).
    surfaces : sequence of clothsim.display.Surface
        Obstacles (planes framed on their centres).

    Returns
    -------
    (float, float)
        Depths [m] of the nearest and the farthest framed point.
    """
    pts = [X.reshape(-1, 3)] + [s.vertices for s in surfaces if s.kind != "plane"]
    pts += [s.vertices[s.triangles].mean(axis=1) for s in surfaces if s.kind == "plane"]
    p = view.project(np.vstack(pts))
    lo, hi = p.min(axis=0), p.max(axis=0)
    mid = (lo + hi) / 2
    half = max(float(np.max((hi - lo)[:2])) / 2, 1e-6) * 1.1
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_aspect("equal")
    ax.set_xlabel(f"screen x [m] (view azimuth {view.azimuth:g}°)", fontsize=7)
    ax.set_ylabel(f"screen y [m] (elevation {view.elevation:g}°)", fontsize=7)
    ax.tick_params(labelsize=6)
    return float(hi[2]), float(lo[2])


__all__ = ["SceneArtist", "frame_axes", "FACE_COLOR", "EDGE_COLOR"]
