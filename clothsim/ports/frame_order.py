"""Is the port's output laid out as the scene's frames? Vertex order, first frame, repeats.

``check`` restarts clothsim from each of the port's states, so a port that writes its
vertices in another order, or starts its output at another frame, still has each step
judged, and the verdicts then name a symptom (a pinned vertex "moved" by a metre, every
step agreeing from a start that is not the scene's). These tests name the layout instead:

- :func:`start_mismatch`: the port's frame 0 against the scene's initial positions: the
  same positions in another vertex order (a transposed or mirrored grid is named), or
  clothsim's frame j of the scene (the output starts at frame j);
- :func:`repeated_frame`: a step whose answer is its start, x_{k+1} = x_k, where clothsim's
  step moves the cloth, and whose next frame is clothsim's step (a frame written twice:
  frame k printed as k + 1);
- :func:`velocity_cause`: velocities of the frame before, or of another h;
- :func:`not_finite`: a frame holding NaN or infinity (a run that blew up, or wrote NaN);
- :func:`stepped_from`: a step whose answer is clothsim's step from another state than
  the one the port wrote: frame 0's state from the scene's start, or the velocities of
  the frame after (v_{k+1} written at frame k).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import InputError
from ..simulation import State

#: Frames of the scene's own run a port's first frame is compared with.
MAX_START_FRAMES = 3


__all__ = ["not_finite", "port_frames", "repeated_frame", "start_mismatch", "stepped_from",
           "velocity_cause"]


def _grid_orders(sim):
    """Named vertex orders of a grid scene: {description: order (port i = scene order[i])}."""
    shape = _grid_shape(sim)
    if shape is None:
        return {}
    nx, ny = shape
    grid = np.arange(nx * ny).reshape(ny, nx)
    orders = {"rows in reverse order": grid[::-1].ravel(),
              "columns in reverse order": grid[:, ::-1].ravel(),
              "both reversed (the grid turned by 180°)": grid[::-1, ::-1].ravel()}
    if nx == ny:
        orders["the grid transposed: vertex (row i, column j) written at (j, i)"] = \
            grid.T.ravel()
    else:
        orders["column by column instead of row by row"] = grid.T.ravel()
    return orders


def _grid_shape(sim):
    """(nx, ny) of a grid cloth, from the vertices' positions (a regular lattice whose
    first row is nx vertices along one axis), or None."""
    x = sim.model.mesh.vertices
    n = len(x)
    if n < 4:
        return None
    step = x[1] - x[0]
    nx = 1
    while nx < n and np.allclose(x[nx] - x[nx - 1], step, atol=1e-9 * (1 + np.abs(x).max())):
        nx += 1
    return (nx, n // nx) if nx > 1 and n % nx == 0 and n // nx > 1 else None


def _scene_frames(sim, count):
    """Positions of clothsim's own run of the scene, frames 1 .. count."""
    frames = []
    for _ in range(count):
        sim.step()
        frames.append(sim.state.positions.copy())
    return frames


def start_mismatch(sim, x0, tol: float, fresh=None) -> str:
    """Why the port's first frame is not the scene's start, or "" when it is.

    Parameters
    ----------
    sim : Simulation
        The scene's simulation at its initial state (not stepped).
    x0 : ndarray, shape (n, 3)
        The port's frame 0 [m].
    tol : float
        Per-vertex distance within which two positions are the same [m] (the printed
        rounding included).
    fresh : callable, optional
        Returns a new simulation of the scene, run to compare the later frames with (a
        Simulation handed to ``check`` cannot be copied: without it, only the vertex order
        is tested).

    Returns
    -------
    str
        "" when frame 0 is the scene's start within ``tol``, or when it matches neither
        another vertex order nor a later frame (a port may start from its own state:
        the steps are judged from it); else the cause, one clause.
    """
    start = sim.state.positions
    err = np.linalg.norm(x0 - start, axis=1)
    if not np.isfinite(err).all() or err.max() <= tol:
        return ""
    dist, order = cKDTree(start).query(x0)
    if dist.max() <= tol and len(np.unique(order)) == len(order):
        named = next((what for what, o in _grid_orders(sim).items()
                      if np.array_equal(o, order)), "")
        moved = np.flatnonzero(order != np.arange(len(order)))
        i = int(moved[0])
        return (f"the port's frame 0 holds the scene's initial positions in another vertex "
                f"order{f' ({named})' if named else ''}: port vertex {i} is the scene's "
                f"vertex {int(order[i])}, {len(moved)} of {len(order)} vertices are "
                f"elsewhere; write the vertices in the scene's order (its steps are "
                f"judged as written, so its pins appear to move)")
    later = _scene_frames(fresh(), MAX_START_FRAMES) if fresh is not None else []
    for j, xj in enumerate(later, start=1):
        if np.linalg.norm(x0 - xj, axis=1).max() <= tol:
            return (f"the port's frame 0 is clothsim's frame {j} of the scene, not its "
                    f"initial state: the output starts at frame {j}; write the initial "
                    f"state (frame 0) first")
    return ""


def repeated_frame(xs, vs, k: int, x_cs, err, tol: float, h: float) -> str:
    """The note of a step whose answer is its start while clothsim's step moves the cloth,
    and whose next frame is clothsim's step: a frame written twice, else "".

    A cloth at rest on the port's own floor also stays where it is (x_{k+1} = x_k); what
    tells a repeated frame is the frame after it: from the same state (x_{k+1}, v_{k+1}) =
    (x_k, v_k) the port then takes clothsim's step, x_{k+2} = clothsim's x_{k+1}.

    Parameters
    ----------
    xs, vs : ndarray, shape (frames, n, 3)
        The port's positions [m] and velocities [m/s].
    k : int
        The step k → k + 1.
    x_cs : ndarray, shape (n, 3)
        clothsim's x_{k+1} from the port's state k.
    err : ndarray, shape (n,)
        Per-vertex distance of clothsim's x_{k+1} from the port's [m].
    tol : float
        The step's tolerance [m] (velocities: 10 tol / h, as ``check`` compares them).
    h : float
        The scene's time step [s].

    Returns
    -------
    str
    """
    def apart(a, b):
        return float(np.linalg.norm(a - b, axis=1).max())

    if err.max() <= tol or k + 2 >= len(xs) or apart(xs[k + 1], xs[k]) > tol \
            or apart(vs[k + 1], vs[k]) > 10 * tol / h or apart(xs[k + 2], x_cs) > tol:
        return ""
    return (f"the port's frame {k + 1} is its frame {k} again, and its frame {k + 2} is "
            f"clothsim's step from that state ({apart(xs[k + 2], x_cs):.1e} m off): a frame "
            f"written twice (frame {k} printed as {k + 1}, the frames after it shifted by "
            f"one)")


def velocity_cause(xs, vs, k: int, h: float, x_cs, v_cs, tol_v: float) -> str:
    """Why the port's v_{k+1} differs from clothsim's where the positions agree, when the
    layout or the velocity update explains it, else "".

    Parameters
    ----------
    xs, vs : ndarray, shape (frames, n, 3)
        The port's positions [m] and velocities [m/s].
    k : int
        The step k → k + 1.
    h : float
        The scene's time step [s].
    x_cs, v_cs : ndarray, shape (n, 3)
        clothsim's x_{k+1} and v_{k+1} from the port's state k.
    tol_v : float
        Per-vertex velocity tolerance [m/s].

    Returns
    -------
    str
        The port's v_{k+1} is its v_k (written a frame late, or not updated), or it is
        (x_{k+1} − x_k) / h' with another h' (clothsim's own v is (x_{k+1} − x_k) / h:
        no effect changes velocities in this step); else "".
    """
    v = vs[k + 1]
    off = float(np.linalg.norm(v_cs - v, axis=1).max())
    if off <= tol_v:
        return ""
    if float(np.linalg.norm(v - vs[k], axis=1).max()) <= tol_v:
        return (f"the port's v_{k + 1} is its v_{k}: its velocities are those of the frame "
                f"before (written a frame late, or not updated in the step)")
    dx = xs[k + 1] - xs[k]
    if float(np.linalg.norm(v_cs - (x_cs - xs[k]) / h, axis=1).max()) > tol_v \
            or not np.any(dx):
        return ""
    c = float(np.vdot(v, dx) / np.vdot(dx, dx))   # v = c dx: dx / h' with h' = 1 / c
    if c <= 0 or float(np.linalg.norm(v - c * dx, axis=1).max()) > tol_v:
        return ""
    return (f"the port's v_{k + 1} is (x_{k + 1} - x_{k}) / {1 / c:.4g} s, not / h = "
            f"{h:.4g} s: another time step in its velocity update")


def not_finite(xs, vs, k: int):
    """``(vertex, note)`` when the port's frame k or k + 1 holds a NaN or an infinity (the
    step cannot be taken from it, or its answer is no position), else None.

    Parameters
    ----------
    xs, vs : ndarray, shape (frames, n, 3)
        The port's positions [m] and velocities [m/s].
    k : int
        The step k → k + 1.

    Returns
    -------
    tuple of (int, str) or None
    """
    for f, what in ((k, "start"), (k + 1, "answer")):
        bad = ~(np.isfinite(xs[f]).all(axis=1) & np.isfinite(vs[f]).all(axis=1))
        if bad.any():
            which = ("positions" if not np.isfinite(xs[f][bad]).all() else "velocities")
            first = next(j for j in range(len(xs)) if not (np.isfinite(xs[j]).all()
                                                             and np.isfinite(vs[j]).all()))
            return int(np.flatnonzero(bad)[0]), (
                f"the port's {which} of frame {f} (the step's {what}) are not finite (NaN "
                f"or inf) at {int(bad.sum())} of {len(bad)} vertices; its frames hold them "
                f"from frame {first} on: its run blew up there or wrote NaN")
    return None


def stepped_from(sim, start, xs, vs, k: int, t: float, tol: float) -> str:
    """The note of a failing step whose answer is clothsim's step from another state than
    the port's frame k as written, else "".

    Tried: for k = 0, the scene's initial state, and its positions or velocities alone
    with the port's other half (the port writes frame 0 otherwise than it starts: a state
    before its setup, velocities already stepped); for k ≥ 1, the port's x_k with its
    v_{k−1} (each frame's velocities are those of the frame after, v_{k+1} written at k).

    Parameters
    ----------
    sim : Simulation
        The scene's simulation (its state is replaced; its solver's carried state is
        kept).
    start : tuple of ndarray
        The scene's initial positions and velocities, (n, 3) each.
    xs, vs : ndarray, shape (frames, n, 3)
        The port's positions [m] and velocities [m/s].
    k : int
        The step k → k + 1.
    t : float
        The time of frame k [s].
    tol : float
        The step's tolerance [m].

    Returns
    -------
    str
    """
    if k == 0:
        x0, v0 = start
        off = [what for what, a, b in (("positions", xs[0], x0), ("velocities", vs[0], v0))
               if float(np.abs(a - b).max()) > 0]
        tries = [((x0, v0), f"the scene's initial state: the port's frame 0 holds other "
                  f"{' and '.join(off)} than the state it starts from"),
                 ((x0, vs[0]), "the scene's initial positions with the port's v_0: the "
                  "port's frame 0 holds other positions than the ones it starts from"),
                 ((xs[0], v0), "the port's x_0 with the scene's initial velocities: the "
                  "port's frame 0 holds other velocities than the ones it starts from")]
    else:
        tries = [((xs[k], vs[k - 1]), f"the port's x_{k} with its v_{k - 1}: its velocities "
                  f"are those of the frame after (v_{k + 1} written at frame {k}, so each "
                  f"frame's velocities are one step ahead of its positions)")]
    saved = sim.solver.get_state()
    for (x, v), words in tries:
        if np.array_equal(x, xs[k]) and np.array_equal(v, vs[k]):
            continue
        sim.state = State(x.copy(), v.copy(), t, k)
        sim.step()
        sim.solver.set_state(saved)
        off = float(np.linalg.norm(sim.state.positions - xs[k + 1], axis=1).max())
        if off <= tol:
            return (f"the port's x_{k + 1} is clothsim's step from {words} ({off:.1e} m off "
                    f"its answer)")
    return ""


def port_frames(sim, positions, velocities, steps):
    """The port's frames as (frames, n, 3) positions and velocities, validated.

    Parameters
    ----------
    sim : Simulation
        The scene's simulation (its vertex count and h).
    positions : array_like, shape (frames, n, 3) or (frames, 3 n)
        The port's x_k [m].
    velocities : array_like or None
        The port's v_k [m/s]; None: (x_k − x_{k−1}) / h, and 0 at frame 0.
    steps : int or None
        The steps to check (at most the frames written).

    Returns
    -------
    xs, vs : ndarray, shape (frames, n, 3)
    notes : list of str
        The note on derived velocities, if any.

    Raises
    ------
    InputError
        A shape that is not the scene's, fewer than 2 frames, or ``steps`` out of range.
    """
    xs = np.asarray(positions, np.float64)
    n = sim.model.vertex_count
    if xs.ndim == 2:
        xs = xs.reshape(len(xs), -1, 3)
    if xs.ndim != 3 or xs.shape[1:] != (n, 3):
        raise InputError(f"positions: expected (frames, {n}, 3), got {xs.shape}")
    if len(xs) < 2:
        raise InputError("positions: need at least 2 frames to check a step")
    if steps is not None and steps < 1:
        raise InputError(f"steps: must be >= 1, got {steps}")
    if steps is not None and steps > len(xs) - 1:
        raise InputError(f"steps: {steps} steps asked for, but the port has only {len(xs)} "
                         f"frames ({len(xs) - 1} steps)")
    if velocities is None:
        vs = np.concatenate([np.zeros_like(xs[:1]), np.diff(xs, axis=0) / sim.h])
        return xs, vs, ["no port velocities: v_k = (x_k - x_{k-1}) / h assumed"]
    vs = np.asarray(velocities, np.float64)
    if vs.size != xs.size:
        raise InputError(f"velocities: expected {xs.shape}, got {vs.shape}")
    return xs, vs.reshape(xs.shape), []
