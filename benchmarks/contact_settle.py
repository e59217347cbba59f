"""Which vertices keep a draped cloth from rest, and what holds vertices below a sphere's
equator (a diagnostic of the contact table's "at rest" and "below equator" columns).

Run from the repository root::

    .venv/bin/python -m benchmarks.contact_settle --size 65 --last 30
    .venv/bin/python -m benchmarks.contact_settle --size 257 --last 60   # ~30 min
    .venv/bin/python -m benchmarks.contact_settle --size 257 --resolve 107 --iterations 50 200

Runs a built-in obstacle scene in ``"hold"`` mode, as shipped, at ``size``² vertices and
prints, for each of the last frames, the largest speed [m/s] of four disjoint groups of
vertices: held by an obstacle in the step (``held``), free within :data:`HEM_RINGS` edges
of the cloth's border (``hem``), other free vertices within :data:`NEAR` of the sphere
(``near``), and the rest (``free``); how many vertices move at :data:`REST_SPEED` or
faster; and how many held vertices the step released (normal force < 0) and how many it
newly caught. At the end it prints the vertices held below the sphere's equator (the
table's column): how many, how far below, and their normal forces in units of their
weight m g and of the solve's unbalanced force per vertex (the forces' noise,
:attr:`clothsim.contacts.ContactSet.noise`); a force many times the noise is the cloth
pressing on the sphere (a fold's valley), not a contact that failed to release.
``--resolve F`` instead runs the scene up to frame F and solves that frame's step again
from the same state with each ``--iterations`` count (:func:`resolve`): whether a burst
is the truncated solve's (it shrinks with more iterations) or the cloth's. Writes nothing.
"""

from __future__ import annotations

import warnings

import numpy as np

from clothsim.effects.base import effect_states, restore_effect_states

from .contact import REST_SPEED, _scene
from .contact_chatter import scene_parser

#: Free vertices this many edges or fewer from the cloth's border count as its hem.
HEM_RINGS = 3
#: Free vertices this close to the sphere's contact surface [m] count as "near".
NEAR = 0.01


def border_band(mesh, rings: int) -> np.ndarray:
    """Vertices at most ``rings`` edges from the mesh's border (boolean mask).

    Parameters
    ----------
    mesh : Mesh
    rings : int
        0: the border vertices only.

    Returns
    -------
    ndarray of bool, shape (n,)
    """
    keys, _ = mesh.edge_triangles
    band = np.zeros(mesh.vertex_count, bool)
    if len(keys):
        edges, count = np.unique(keys, axis=0, return_counts=True)
        band[edges[count == 1].ravel()] = True
    e = mesh.edges
    for _ in range(rings):
        grow = band.copy()
        grow[e[band[e[:, 0]], 1]] = True
        grow[e[band[e[:, 1]], 0]] = True
        band = grow
    return band


def held_forces(holding, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each held vertex's normal force in the step just solved, in units of its weight and
    of the forces' noise.

    Parameters
    ----------
    holding : Holding
        The holding the step was solved with (its planes' ``forces`` set).
    weight : ndarray, shape (n,)
        m g of every vertex [N].

    Returns
    -------
    vertices : ndarray of int, shape (c,)
    per_weight : ndarray, shape (c,)
        F_n / (m g).
    per_noise : ndarray, shape (c,)
        F_n / noise (inf where the noise is 0).
    """
    R = holding.reaction()
    fn = np.einsum("ij,ij->i", R, holding.normals)
    noise = holding.planes.noise
    per_noise = fn / noise if noise > 0 else np.where(fn < 0, -np.inf, np.inf)
    return holding.vertices, fn / weight[holding.vertices], per_noise


def _weights(sim) -> np.ndarray:
    """m g of every vertex [N] (g: the scene's gravity, 9.81 m/s² without one)."""
    g = next((np.linalg.norm(e.acceleration) for e in sim.effects if e.kind == "gravity"),
             9.81)
    return sim.model.vertex_mass * g


def _q(a: np.ndarray, qs=(10, 50, 90)) -> str:
    return "/".join(f"{q:.2g}" for q in np.percentile(a, qs)) if len(a) else "-"


def settle(scene: str = "drape-sphere", size: int = 65, frames: int | None = None,
           last: int = 30):
    """Yield the report's lines (module docstring) for the last ``last`` frames.

    Parameters
    ----------
    scene, size, frames, last
        As :func:`benchmarks.contact_chatter.chatter` (the scene as shipped at ``size``²,
        ``frames`` of it, the last ``last`` reported).

    Yields
    ------
    str
    """
    sc = _scene(scene, size, "hold")
    sim = sc.build_simulation()
    frames = sc.frames if frames is None else frames
    obstacles = [e for e in sim.effects if hasattr(e, "_holding")]
    spheres = [e for e in obstacles if e.kind == "sphere"]
    model = sim.model
    hem = border_band(model.mesh, HEM_RINGS)
    weight = _weights(sim)
    sim.expect_steps(frames * sc.substeps)
    before = []
    for f in range(frames):
        released = caught = 0
        for _ in range(sc.substeps):
            before = [e._holding for e in obstacles]
            sim.step()
            for e, h in zip(obstacles, before):
                now = set(e._holding.vertices.tolist())
                was = set(h.vertices.tolist())
                released += len(was - now)
                caught += len(now - was)
        if f < frames - last:
            continue
        x = sim.state.positions
        speed = np.linalg.norm(sim.state.velocities, axis=1)
        held = np.zeros(len(x), bool)
        for h in before:
            held[h.vertices] = True
        near = np.zeros(len(x), bool)
        for s in spheres:
            near |= np.linalg.norm(x - s.center, axis=1) - s.radius - s.margin < NEAR
        groups = {"held": held, "hem": ~held & hem, "near": ~held & ~hem & near,
                  "free": ~held & ~hem & ~near}
        parts = ", ".join(f"{k} {speed[m].max() if m.any() else 0.0:.4f}"
                          for k, m in groups.items())
        yield (f"frame {f:3d}: max |v| {speed.max():.4f} m/s ({parts}); "
               f"{int((speed >= REST_SPEED).sum())} vertices at {REST_SPEED} m/s or faster; "
               f"released {released}, caught {caught}")
    for s, h in ((s, h) for e, h in zip(obstacles, before) for s in spheres if e is s):
        v, per_weight, per_noise = held_forces(h, weight)
        below = x[v, 1] < s.center[1]
        depth = 1000 * (s.center[1] - x[v[below], 1])
        yield (f"held below the sphere's equator after the last step: {int(below.sum())} of "
               f"{len(v)} held (the step released {int((per_noise[below] < 0).sum())} "
               f"below it); depth below the equator [mm] 10/50/90th pct {_q(depth)}; normal "
               f"force / (m g) {_q(per_weight[below])}, / noise {_q(per_noise[below])} "
               f"(noise {h.planes.noise:.3g} N, weight per vertex {weight.mean():.3g} N)")


def resolve(scene: str, size: int, frame: int, iterations=(50, 200)):
    """Yield one line per iteration count: frame ``frame``'s step solved again from the
    state the scene reached, with the scene's solver method and that many iterations.

    Parameters
    ----------
    scene : {"drape-sphere", "drop-on-square"}
    size : int
        Vertices per side.
    frame : int
        The step to solve again (0-based; the steps before it run as the scene declares).
    iterations : sequence of int

    Yields
    ------
    str
        The step's iterations and residual, the largest speed of the whole cloth and of
        its hem (:data:`HEM_RINGS`) after it [m/s], how far [mm] its positions end from
        the first count's, and for a sphere the vertices held below its equator: the
        10/50/90th percentiles of their normal force in the step / (m g), how many the
        step found pulled away (force < 0), and the noise (whether a small force is the
        solve's truncation: it would change with the iterations).
    """
    sc = _scene(scene, size, "hold")
    sim = sc.build_simulation()
    sim.expect_steps(frame * sc.substeps, final=False)
    for _ in range(frame * sc.substeps):
        sim.step()
    start, carried = sim.state, effect_states(list(sim.effects))
    hem = border_band(sim.model.mesh, HEM_RINGS)
    weight = _weights(sim)
    first = None
    for count in iterations:
        again = _scene(scene, size, "hold", solver={"iterations": int(count)})
        other = again.build_simulation()
        restore_effect_states(list(other.effects), carried)
        other.state = start
        other.expect_steps(sc.substeps)
        spheres = [e for e in other.effects if e.kind == "sphere"]
        for _ in range(sc.substeps):
            before = [s._holding for s in spheres]
            record = other.step()
        x = other.state.positions
        speed = np.linalg.norm(other.state.velocities, axis=1)
        first = x if first is None else first
        below = ""
        for s, h in zip(spheres, before):
            v, per_weight, _ = held_forces(h, weight)
            under = start.positions[v, 1] < s.center[1]
            below += (f"; {int(under.sum())} held below the equator, normal force / (m g) "
                      f"{_q(per_weight[under])}, {int((per_weight[under] < 0).sum())} "
                      f"pulled away (noise {h.planes.noise / weight.mean():.2g} m g)")
        yield (f"frame {frame} solved with {count} iterations: residual "
               f"{record.residual:.3g}, max |v| {speed.max():.4f} m/s (hem "
               f"{speed[hem].max():.4f}), {int((speed >= REST_SPEED).sum())} vertices at "
               f"{REST_SPEED} m/s or faster; positions "
               f"{1000 * np.linalg.norm(x - first, axis=1).max():.3f} mm from the first"
               + below)


def main(argv=None) -> None:
    parser = scene_parser(__doc__.splitlines()[0], 30)
    parser.add_argument("--resolve", type=int, metavar="F", default=None,
                        help="solve frame F's step again with each --iterations count")
    parser.add_argument("--iterations", type=int, nargs="+", default=[50, 200])
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    lines = (resolve(args.scene, args.size, args.resolve, args.iterations)
             if args.resolve is not None else
             settle(args.scene, args.size, args.frames, args.last))
    for line in lines:
        print(line, flush=True)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
